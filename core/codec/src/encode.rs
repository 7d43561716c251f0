//! Compression (paper 003 §5): partition the mesh into the nSP-tree out of core
//! ([`crate::partition`]), run the kd coder in every cell in post-order — a cell's complex merged
//! into its parent's with duplicates removed (§5.2d), sibling subtrees on different cores
//! (§5.4) — and range-code each cell's symbols as soon as they are known, in the cell's own
//! thread, with models that start fresh per cell ([`crate::entropy`]). The paper keeps every
//! cell's symbols in a semi-coded temporary file (§5.2c) until the whole file's tables are
//! known; with adaptive models there are no tables, so only the finished chunks wait: in memory,
//! or past [`HELD_BYTES`] in a temporary file. Then the final file (§5.3): head, every chunk in
//! pre-order, trailer (index).
//!
//! The output is the same whatever the number of threads: a chunk depends on its cell alone,
//! and the chunks are written in pre-order.

use std::io::{Read, Seek, SeekFrom, Write};
use std::sync::Mutex;
use std::time::Instant;

use rayon::prelude::*;

use crate::cell_complex::{compact, leaf_complex, union};
use crate::complex::{Complex, POINT};
use crate::entropy;
use crate::error::CodecError;
use crate::format::{self, Header, ROOT_POINT, ROOT_TRIANGLE};
use crate::kd_coder;
use crate::nsp_tree::Params;
use crate::partition::{self, Partition};
use crate::quantize::Quantizer;
use crate::source::{MeshSource, Slices};

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
    /// Bits spent on each symbol family ([`crate::symbols::Family`] order): geometry first. The
    /// real code lengths: `−log2 p` summed over every binary decision coded (the chunks are
    /// these totals rounded up to bytes).
    pub family_bits: [f64; crate::symbols::FAMILIES],
    /// Symbols of each family.
    pub family_symbols: [u64; crate::symbols::FAMILIES],
    /// Milliseconds per step: partition (§5.1: box, quantisation, tree, raw index file), codes
    /// (§5.2, each cell's range coding included), final write (§5.3: the chunks copied in
    /// pre-order, the trailer).
    pub steps_ms: [f64; 3],
}

/// Finished chunks held in memory up to this many bytes; later ones wait in a temporary file.
pub const HELD_BYTES: u64 = 64 << 20;

/// Where a finished chunk waits for the final write.
#[derive(Clone, Debug, Default)]
enum Chunk {
    /// Not coded yet (only while the post-order pass runs).
    #[default]
    Pending,
    /// In memory.
    Held(Vec<u8>),
    /// In the temporary file: offset and length.
    Spilled(u64, u64),
}

/// The temporary file of chunks past [`HELD_BYTES`], in completion order.
struct Spill {
    file: std::io::BufWriter<std::fs::File>,
    written: u64,
}

impl Spill {
    fn new() -> Result<Self, CodecError> {
        let file = tempfile::tempfile()
            .map_err(|e| CodecError::io("creating the temporary code file", e))?;
        Ok(Spill {
            file: std::io::BufWriter::new(file),
            written: 0,
        })
    }

    /// Appends a chunk; returns where it is.
    fn put(&mut self, chunk: &[u8]) -> Result<Chunk, CodecError> {
        let at = self.written;
        self.file
            .write_all(chunk)
            .map_err(|e| CodecError::io("writing the temporary code file", e))?;
        self.written += chunk.len() as u64;
        Ok(Chunk::Spilled(at, chunk.len() as u64))
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

/// What the post-order pass gathers, shared by the threads.
#[derive(Default)]
struct Gathered {
    /// Per node: its chunk, final vertex and simplex counts.
    chunks: Vec<Chunk>,
    ends: Vec<(u64, u64)>,
    /// Bytes of the chunks held in memory.
    held: u64,
    /// The temporary file, once a chunk goes past [`HELD_BYTES`].
    spill: Option<Spill>,
    /// Bits and symbols per family (sums of multiples of `2^-16`: exact in any order).
    family_bits: [f64; crate::symbols::FAMILIES],
    family_symbols: [u64; crate::symbols::FAMILIES],
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
    shared: Mutex<Gathered>,
    /// Chunks are held in memory up to this many bytes ([`HELD_BYTES`]).
    held_limit: u64,
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
        let code = entropy::encode(&symbols);
        drop(symbols);
        let mut guard = self.shared.lock().unwrap_or_else(|e| e.into_inner());
        let g = &mut *guard;
        for f in 0..crate::symbols::FAMILIES {
            g.family_bits[f] += code.family_bits[f];
            g.family_symbols[f] += code.family_symbols[f];
        }
        let len = code.bytes.len() as u64;
        g.chunks[i] = if g.held + len <= self.held_limit {
            g.held += len;
            // held at its length, not at the coder's guess of it: at 200 M triangles the spare
            // capacity of the held chunks was ~0.7 GB of the peak
            let mut bytes = code.bytes;
            bytes.shrink_to_fit();
            Chunk::Held(bytes)
        } else {
            if g.spill.is_none() {
                g.spill = Some(Spill::new()?);
            }
            g.spill.as_mut().expect("made above").put(&code.bytes)?
        };
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
    compress_holding(src, params, out, progress, HELD_BYTES)
}

/// [`compress_source`], holding at most `held_limit` bytes of chunks in memory.
fn compress_holding<W: Write + Seek>(
    src: &mut dyn MeshSource,
    params: Params,
    out: &mut W,
    progress: &(dyn Fn(f64) -> bool + Sync),
    held_limit: u64,
) -> Result<CompressReport, CodecError> {
    params.validate()?;
    let t0 = Instant::now();
    let part = partition::build(src, params, progress)?;
    let t1 = Instant::now();
    let n = part.nodes.len();
    let coder = Coder {
        params,
        part: &part,
        shared: Mutex::new(Gathered {
            chunks: vec![Chunk::Pending; n],
            ends: vec![(0, 0); n],
            ..Gathered::default()
        }),
        held_limit,
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
    let mut gathered = coder.shared.into_inner().unwrap_or_else(|e| e.into_inner());
    let t2 = Instant::now();
    let mut nodes = part.nodes.clone();
    for (node, &(v, s)) in nodes.iter_mut().zip(&gathered.ends) {
        node.end_vertices = v;
        node.end_simplices = s;
    }
    let w = |e| CodecError::io("writing the compressed file", e);
    // the head first, the trailer (counts and index) last: no seeking back (format.rs)
    let head = format::head_bytes(&part.grid, &params);
    out.write_all(&head).map_err(w)?;
    let mut pos = head.len() as u64;
    let mut temp = gathered.spill.take().map(Spill::reader).transpose()?;
    let mut buf = Vec::new();
    // chunks in pre-order, from memory or the temporary file
    for (node, chunk) in nodes.iter_mut().zip(std::mem::take(&mut gathered.chunks)) {
        let bytes = match chunk {
            Chunk::Pending => Vec::new(),
            Chunk::Held(bytes) => bytes,
            Chunk::Spilled(at, len) => {
                let r = |e| CodecError::io("reading the temporary code file", e);
                let f = temp.as_mut().expect("a spilled chunk has a file");
                buf.resize(len as usize, 0);
                f.seek(SeekFrom::Start(at)).map_err(r)?;
                f.read_exact(&mut buf).map_err(r)?;
                std::mem::take(&mut buf)
            }
        };
        out.write_all(&bytes).map_err(w)?;
        node.offset = pos;
        node.len = bytes.len() as u64;
        pos += bytes.len() as u64;
        buf = bytes;
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
        family_bits: gathered.family_bits,
        family_symbols: gathered.family_symbols,
        steps_ms: [ms(t0, t1), ms(t1, t2), ms(t2, t3)],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wavy 80 × 80 grid of quads, two triangles each.
    fn grid() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let n = 80u32;
        let positions = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32, (i / n) as f32);
                [x, y, (x * 0.3).sin() * (y * 0.2).cos() * 4.0]
            })
            .collect();
        let mut triangles = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let v = y * n + x;
                triangles.push([v, v + 1, v + n + 1]);
                triangles.push([v, v + n + 1, v + n]);
            }
        }
        (positions, triangles)
    }

    #[test]
    fn spilled_chunks_give_the_same_file_as_held_ones() {
        let (positions, triangles) = grid();
        let params = Params {
            bits: 12,
            min_cell: 800,
            ..Params::default()
        };
        let run = |held_limit| {
            let mut src = Slices {
                positions: &positions,
                triangles: &triangles,
            };
            let mut out = std::io::Cursor::new(Vec::new());
            let r = compress_holding(&mut src, params, &mut out, &|_| true, held_limit).unwrap();
            (out.into_inner(), r)
        };
        let (held, report) = run(u64::MAX);
        assert!(report.nsp_cells > 4, "{} cells", report.nsp_cells);
        // every chunk spilled, and about half of them
        for limit in [0, held.len() as u64 / 2] {
            let (spilled, _) = run(limit);
            assert!(spilled == held, "held up to {limit} bytes: another file");
        }
        let tsc = crate::Tsc::open(&held).unwrap();
        let decoded = tsc.decode(None).unwrap();
        assert_eq!(decoded.triangles.len(), triangles.len());
        // the report's bits are the chunks' real lengths, within each chunk's last bytes
        let bits: f64 = report.family_bits.iter().sum();
        let chunk_bits = 8.0 * tsc.nodes.iter().map(|n| n.len).sum::<u64>() as f64;
        let slack = 40.0 * report.nsp_cells as f64;
        assert!(
            (chunk_bits - bits).abs() <= slack,
            "{bits} bits coded, {chunk_bits} in the chunks"
        );
    }
}
