//! Compression (paper 003 §5): partition the mesh into the nSP-tree out of core
//! ([`crate::partition`]), run the kd coder in every cell in post-order — a cell's complex merged
//! into its parent's with duplicates removed (§5.2d), sibling subtrees on different cores
//! (§5.4) — keep every cell's symbols in a semi-coded temporary file (§5.2c), then write the
//! final file: header, probability tables, one range-coded chunk per cell, index (§5.3).
//!
//! The output is the same whatever the number of threads: the tables are sums, and the chunks
//! are written in pre-order from the temporary file.

use std::io::{Read, Seek, SeekFrom, Write};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use crate::cell_complex::{compact, leaf_complex, union};
use crate::complex::{Complex, POINT};
use crate::entropy::{self, Counts};
use crate::error::CodecError;
use crate::format::{self, Header, ROOT_POINT, ROOT_TRIANGLE};
use crate::kd_coder;
use crate::nsp_tree::Params;
use crate::partition::{self, Partition};
use crate::quantize::Quantizer;
use crate::source::{MeshSource, Slices};
use crate::symbols::Symbol;

/// What a compression did, for the CLI and the benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressReport {
    /// Vertices of the input.
    pub input_vertices: u64,
    /// Triangles of the input (after fan triangulation).
    pub input_triangles: u64,
    /// Distinct quantised points.
    pub vertices: u64,
    /// Distinct oriented triangles after quantisation (degenerate ones included).
    pub triangles: u64,
    /// Size of the file.
    pub bytes: u64,
    /// The quantisation grid.
    pub grid: Quantizer,
    /// Cells of the nSP-tree.
    pub nsp_cells: u64,
    /// Simplex copies beyond one per distinct simplex: border duplication (§5.1), and repeated
    /// triangles of the input.
    pub duplicated_simplices: u64,
    /// Bits spent on each symbol family ([`crate::symbols::Family`] order): geometry first.
    pub family_bits: [f64; crate::symbols::FAMILIES],
    /// Symbols of each family.
    pub family_symbols: [u64; crate::symbols::FAMILIES],
    /// Milliseconds per step: partition (§5.1: box, quantisation, tree, raw index file), codes
    /// (§5.2), final write (§5.3).
    pub steps_ms: [f64; 3],
}

/// The semi-coded temporary file (§5.2c): every cell's symbols in completion order, each cell
/// deflated on its own (fast level: the contexts repeat, a cell shrinks several times), so that
/// a mesh of hundreds of millions of triangles does not need tens of gigabytes of scratch disk.
struct Spill {
    file: std::io::BufWriter<std::fs::File>,
    written: u64,
}

/// Where a cell's symbols are in the spill: byte offset, deflated length, symbol count.
type Span = (u64, u64, u64);

impl Spill {
    fn new() -> Result<Self, CodecError> {
        let file = tempfile::tempfile()
            .map_err(|e| CodecError::io("creating the temporary code file", e))?;
        Ok(Spill {
            file: std::io::BufWriter::new(file),
            written: 0,
        })
    }

    /// Appends `symbols` (deflated by the caller's thread: see [`deflate`]).
    fn put(&mut self, deflated: &[u8], symbols: u64) -> Result<Span, CodecError> {
        let at = self.written;
        self.file
            .write_all(deflated)
            .map_err(|e| CodecError::io("writing the temporary code file", e))?;
        self.written += deflated.len() as u64;
        Ok((at, deflated.len() as u64, symbols))
    }

    fn reader(self) -> Result<std::fs::File, CodecError> {
        let mut f = self
            .file
            .into_inner()
            .map_err(|e| CodecError::io("flushing the temporary code file", e.into_error()))?;
        f.seek(SeekFrom::Start(0))
            .map_err(|e| CodecError::io("rewinding the temporary code file", e))?;
        Ok(f)
    }
}

/// A cell's symbols, deflated for the spill.
fn deflate(symbols: &[Symbol]) -> Vec<u8> {
    let bytes: Vec<u8> = symbols.iter().flat_map(|s| s.0.to_le_bytes()).collect();
    let mut z = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(&bytes).expect("writing to memory");
    z.finish().expect("writing to memory")
}

/// What the post-order pass gathers, shared by the threads.
#[derive(Default)]
struct Gathered {
    counts: Counts,
    /// Per node: span in the temporary file, final vertex and simplex counts.
    spans: Vec<Span>,
    ends: Vec<(u64, u64)>,
    /// Distinct points and triangles owned by the leaves, simplex copies coded, simplices
    /// owned.
    points: u64,
    triangles: u64,
    copies: u64,
    owned: u64,
    /// Leaf entries done, for progress.
    done: u64,
}

/// The post-order pass over a partition.
struct Coder<'a> {
    params: Params,
    part: &'a Partition,
    shared: Mutex<(Gathered, Spill)>,
    total_entries: u64,
    progress: &'a (dyn Fn(f64) -> bool + Sync),
}

impl Coder<'_> {
    /// Codes cell `i` and its subtree; returns its complex at its start precision, with the
    /// vertices in kd order.
    fn code(&self, i: usize) -> Result<(Complex, Vec<u32>), CodecError> {
        let bits = self.params.bits;
        let node = &self.part.nodes[i];
        let leaf = node.children.is_empty();
        let (start, end) = if leaf {
            (self.params.precision(node.depth).0, bits)
        } else {
            self.params.precision(node.depth)
        };
        let (mut cx, mut alive, owned) = if leaf {
            leaf_complex(self.part, &self.params, i)?
        } else {
            let parts = node
                .children
                .par_iter()
                .map(|&c| self.code(c))
                .collect::<Result<Vec<_>, CodecError>>()?;
            let (cx, alive) = union(parts, 3 * end as usize, bits);
            (cx, alive, None)
        };
        let end_counts = (alive.len() as u64, cx.live as u64);
        let symbols = kd_coder::encode(
            &mut cx,
            &mut alive,
            bits,
            3 * start as usize,
            3 * end as usize,
            self.params.advance(),
        );
        let mut counts = Counts::default();
        counts.add(&symbols);
        let deflated = deflate(&symbols);
        drop(symbols);
        let mut guard = self.shared.lock().unwrap_or_else(|e| e.into_inner());
        let (g, spill) = &mut *guard;
        g.counts.merge(&counts);
        g.spans[i] = spill.put(&deflated, counts.total())?;
        g.ends[i] = end_counts;
        if let Some((points, triangles, copies, owned)) = owned {
            g.points += points;
            g.triangles += triangles;
            g.copies += copies;
            g.owned += owned;
            g.done += self.part.regions[i].1;
        }
        let fraction = g.done as f64 / self.total_entries.max(1) as f64;
        drop(guard);
        if !(self.progress)(0.5 + 0.45 * fraction) {
            return Err(CodecError::Cancelled);
        }
        Ok(compact(&cx, &alive))
    }
}

/// Compresses a triangle mesh held in memory into `out` (a `.tsc` stream).
pub fn compress<W: Write + Seek>(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    params: Params,
    out: &mut W,
    progress: &(dyn Fn(f64) -> bool + Sync),
) -> Result<CompressReport, CodecError> {
    compress_source(
        &mut Slices {
            positions,
            triangles,
        },
        params,
        out,
        progress,
    )
}

/// Compresses a mesh read in passes from `src` into `out`; `progress` receives the fraction
/// done and returns `false` to cancel.
pub fn compress_source<W: Write + Seek>(
    src: &mut dyn MeshSource,
    params: Params,
    out: &mut W,
    progress: &(dyn Fn(f64) -> bool + Sync),
) -> Result<CompressReport, CodecError> {
    params.validate()?;
    let t0 = Instant::now();
    let part = partition::build(src, params, progress)?;
    let t1 = Instant::now();
    let n = part.nodes.len();
    let coder = Coder {
        params,
        part: &part,
        shared: Mutex::new((
            Gathered {
                spans: vec![(0, 0, 0); n],
                ends: vec![(0, 0); n],
                ..Gathered::default()
            },
            Spill::new()?,
        )),
        total_entries: part.regions.iter().map(|r| r.1).sum(),
        progress,
    };
    let mut flags = 0;
    if n > 0 {
        let (root, _) = coder.code(0)?;
        for s in root.live_simplices() {
            flags |= if s.kind == POINT {
                ROOT_POINT
            } else {
                ROOT_TRIANGLE
            };
        }
    }
    let (gathered, spill) = coder.shared.into_inner().unwrap_or_else(|e| e.into_inner());
    let t2 = Instant::now();
    let mut nodes = part.nodes.clone();
    for (node, &(v, s)) in nodes.iter_mut().zip(&gathered.ends) {
        node.end_vertices = v;
        node.end_simplices = s;
    }
    let family_bits = gathered.counts.family_bits();
    let family_symbols = gathered.counts.family_symbols();
    let counts = gathered.counts.quantised();
    let tables = counts.to_bytes();
    let models = counts.models();
    let w = |e| CodecError::io("writing the compressed file", e);
    // the head first, the trailer (counts and index) last: no seeking back (format.rs)
    let head = format::head_bytes(&part.grid, &params);
    out.write_all(&head).map_err(w)?;
    out.write_all(&tables).map_err(w)?;
    let mut pos = (head.len() + tables.len()) as u64;
    let mut temp = spill.reader()?;
    let mut deflated = Vec::new();
    // chunks in pre-order, each read back from the temporary file and range-coded
    for (node, &(at, len, count)) in nodes.iter_mut().zip(&gathered.spans) {
        deflated.resize(len as usize, 0);
        let r = |e| CodecError::io("reading the temporary code file", e);
        temp.seek(SeekFrom::Start(at)).map_err(r)?;
        temp.read_exact(&mut deflated).map_err(r)?;
        let mut raw = Vec::with_capacity(4 * count as usize);
        flate2::read::DeflateDecoder::new(&deflated[..])
            .read_to_end(&mut raw)
            .map_err(r)?;
        if raw.len() != 4 * count as usize {
            return Err(CodecError::io(
                "reading the temporary code file",
                std::io::Error::other("a cell's symbols came back short"),
            ));
        }
        let symbols: Vec<Symbol> = raw
            .chunks_exact(4)
            .map(|b| Symbol(u32::from_le_bytes([b[0], b[1], b[2], b[3]])))
            .collect();
        let chunk = entropy::encode(&symbols, &models);
        out.write_all(&chunk).map_err(w)?;
        node.offset = pos;
        node.len = chunk.len() as u64;
        pos += chunk.len() as u64;
    }
    let header = Header {
        grid: part.grid,
        params,
        flags,
        input_vertices: part.input_vertices,
        input_triangles: part.input_triangles,
        vertices: gathered.points,
        triangles: gathered.triangles,
        head_len: head.len() as u64,
        tables: (head.len() as u64, tables.len() as u64),
        index: (pos, 0),
    };
    let trailer = header.trailer_bytes(&nodes);
    out.write_all(&trailer).map_err(w)?;
    let end = pos + trailer.len() as u64;
    let t3 = Instant::now();
    progress(1.0);
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    Ok(CompressReport {
        input_vertices: part.input_vertices,
        input_triangles: part.input_triangles,
        vertices: gathered.points,
        triangles: gathered.triangles,
        bytes: end,
        grid: part.grid,
        nsp_cells: n as u64,
        duplicated_simplices: gathered.copies.saturating_sub(gathered.owned),
        family_bits,
        family_symbols,
        steps_ms: [ms(t0, t1), ms(t1, t2), ms(t2, t3)],
    })
}
