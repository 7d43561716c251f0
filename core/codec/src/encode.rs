//! Compression (paper 003 §5): quantise, partition into the nSP-tree, run the kd coder in every
//! cell in post-order (each cell's complex merged into its parent's, duplicates removed), keep
//! every cell's symbols in a semi-coded temporary file, then write the final file with the
//! probability tables first and the index last.

use std::io::{Read, Seek, SeekFrom, Write};
use std::time::Instant;

use rustc_hash::{FxHashMap, FxHashSet};

use crate::complex::{Complex, POINT, Simplex, Vertex};
use crate::entropy::{self, Counts};
use crate::error::CodecError;
use crate::format::{self, HEADER_LEN, Header, ROOT_POINT, ROOT_TRIANGLE};
use crate::kd_coder::{self, kd_key};
use crate::nsp_tree::{Node, Params};
use crate::quantize::Quantizer;
use crate::symbols::Symbol;

/// What a compression did, for the CLI and the benchmark.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressReport {
    /// Vertices of the input.
    pub input_vertices: u64,
    /// Triangles of the input.
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
    /// Simplices coded in more than one leaf (border duplication, §5.1).
    pub duplicated_simplices: u64,
    /// Bits spent on each symbol family ([`crate::symbols::Family`] order): geometry first.
    pub family_bits: [f64; crate::symbols::FAMILIES],
    /// Symbols of each family.
    pub family_symbols: [u64; crate::symbols::FAMILIES],
    /// Milliseconds per step: quantisation and partition, codes (§5.2), final write (§5.3).
    pub steps_ms: [f64; 3],
}

/// A mesh quantised to the grid: distinct points in kd order and simplices over them.
pub(crate) struct Quantised {
    pub grid: Quantizer,
    pub points: Vec<[u32; 3]>,
    pub simplices: Vec<Simplex>,
}

/// Quantises `positions` and re-indexes `triangles` onto the distinct grid points; a point no
/// triangle uses becomes an isolated-point simplex.
pub(crate) fn quantise(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    bits: u32,
) -> Result<Quantised, CodecError> {
    for (i, p) in positions.iter().enumerate() {
        if p.iter().any(|c| !c.is_finite()) {
            return Err(CodecError::Input(format!(
                "vertex {i} has a non-finite coordinate {p:?}"
            )));
        }
    }
    let n = positions.len() as u32;
    for (i, t) in triangles.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&x| x >= n) {
            return Err(CodecError::Input(format!(
                "triangle {i} uses vertex {bad}, but there are {n} vertices"
            )));
        }
    }
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for p in positions {
        for a in 0..3 {
            min[a] = min[a].min(p[a] as f64);
            max[a] = max[a].max(p[a] as f64);
        }
    }
    if positions.is_empty() {
        (min, max) = ([0.0; 3], [1.0; 3]);
    }
    let grid = Quantizer::new(min, max, bits)?;
    let q: Vec<[u32; 3]> = positions
        .iter()
        .map(|p| grid.quantize(p.map(f64::from)))
        .collect();
    let full = 3 * bits as usize;
    let mut order: Vec<(u64, u32)> = q
        .iter()
        .enumerate()
        .map(|(i, &c)| (kd_key(c, full, bits), i as u32))
        .collect();
    order.sort_unstable();
    let mut uid = vec![0u32; q.len()];
    let mut points: Vec<[u32; 3]> = Vec::new();
    let mut last = None;
    for &(key, i) in &order {
        if last != Some(key) {
            points.push(q[i as usize]);
            last = Some(key);
        }
        uid[i as usize] = points.len() as u32 - 1;
    }
    let mut simplices: Vec<Simplex> = triangles
        .iter()
        .map(|t| Simplex::triangle(uid[t[0] as usize], uid[t[1] as usize], uid[t[2] as usize]))
        .collect();
    let mut used = vec![false; points.len()];
    for s in &simplices {
        for &x in &s.v {
            used[x as usize] = true;
        }
    }
    simplices.extend(
        (0..points.len() as u32)
            .filter(|&i| !used[i as usize])
            .map(Simplex::point),
    );
    simplices.sort_unstable();
    simplices.dedup();
    Ok(Quantised {
        grid,
        points,
        simplices,
    })
}

/// The semi-coded temporary file (§5.2c): every cell's symbols, raw, in post-order.
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

    /// Appends `symbols`, returning their (offset, count) in symbols.
    fn put(&mut self, symbols: &[Symbol]) -> Result<(u64, u64), CodecError> {
        let at = self.written;
        let bytes: Vec<u8> = symbols.iter().flat_map(|s| s.0.to_le_bytes()).collect();
        self.file
            .write_all(&bytes)
            .map_err(|e| CodecError::io("writing the temporary code file", e))?;
        self.written += symbols.len() as u64;
        Ok((at, symbols.len() as u64))
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

/// State of the post-order pass.
struct Coder<'a> {
    params: Params,
    q: &'a Quantised,
    nodes: Vec<Node>,
    /// Simplex ids of each leaf (empty for inner cells).
    leaf_simplices: Vec<Vec<u32>>,
    spans: Vec<(u64, u64)>,
    counts: Counts,
    spill: Spill,
    progress: &'a mut dyn FnMut(f64),
    coded_leaf_simplices: u64,
}

impl Coder<'_> {
    /// Builds the tree below a cell at `depth` holding `ids` (pre-order), and returns its index.
    fn build(&mut self, depth: u32, cell: [u32; 3], ids: Vec<u32>) -> usize {
        let i = self.nodes.len();
        self.nodes.push(Node {
            depth,
            cell,
            ..Node::default()
        });
        self.leaf_simplices.push(Vec::new());
        let (_, end) = self.params.precision(depth);
        if end >= self.params.bits || (ids.len() as u64) < self.params.min_cell {
            self.leaf_simplices[i] = ids;
            return i;
        }
        let n3 = self.params.cell_split.pow(3) as usize;
        let mut parts: Vec<Vec<u32>> = vec![Vec::new(); n3];
        for id in ids {
            let s = &self.q.simplices[id as usize];
            let mut seen = [usize::MAX; 3];
            for (k, &x) in s.v.iter().enumerate() {
                let Some(c) = self.params.child_of(depth, cell, self.q.points[x as usize]) else {
                    continue;
                };
                if !seen.contains(&c) {
                    parts[c].push(id);
                }
                seen[k] = c;
            }
        }
        let mut mask = 0u64;
        let mut children = Vec::new();
        for (c, part) in parts.into_iter().enumerate() {
            if !part.is_empty() {
                mask |= 1 << c;
                children.push(self.build(depth + 1, self.params.child_cell(cell, c), part));
            }
        }
        self.nodes[i].child_mask = mask;
        self.nodes[i].children = children;
        i
    }

    /// Codes cell `i` and its subtree; returns its complex at its start precision, with the
    /// vertices in kd order.
    fn code(&mut self, i: usize) -> Result<(Complex, Vec<u32>), CodecError> {
        let bits = self.params.bits;
        let depth = self.nodes[i].depth;
        let (start, end) = if self.nodes[i].children.is_empty() {
            (self.params.precision(depth).0, bits)
        } else {
            self.params.precision(depth)
        };
        let (mut cx, mut alive) = if self.nodes[i].children.is_empty() {
            let ids = std::mem::take(&mut self.leaf_simplices[i]);
            self.coded_leaf_simplices += ids.len() as u64;
            leaf_complex(self.q, &ids, bits)
        } else {
            let mut parts = Vec::new();
            for c in self.nodes[i].children.clone() {
                parts.push(self.code(c)?);
            }
            union(parts, 3 * end as usize, bits)
        };
        self.nodes[i].end_vertices = alive.len() as u64;
        self.nodes[i].end_simplices = cx.live as u64;
        let symbols = kd_coder::encode(
            &mut cx,
            &mut alive,
            bits,
            3 * start as usize,
            3 * end as usize,
        );
        self.counts.add(&symbols);
        self.spans[i] = self.spill.put(&symbols)?;
        (self.progress)(self.coded_leaf_simplices as f64 / self.q.simplices.len().max(1) as f64);
        Ok(compact(&cx, &alive))
    }
}

/// The complex of a leaf: its simplices over its own copies of their vertices, in kd order.
fn leaf_complex(q: &Quantised, ids: &[u32], bits: u32) -> (Complex, Vec<u32>) {
    let mut uids: Vec<u32> = ids
        .iter()
        .flat_map(|&i| q.simplices[i as usize].v)
        .collect();
    uids.sort_unstable();
    uids.dedup();
    let mut cx = Complex::default();
    let mut local: FxHashMap<u32, u32> = FxHashMap::default();
    for &u in &uids {
        let id = cx.add_vertex(Vertex {
            corner: q.points[u as usize],
            level: (3 * bits) as u8,
        });
        local.insert(u, id);
    }
    for &i in ids {
        let s = q.simplices[i as usize];
        let m = |x: u32| local[&x];
        cx.add(s.map(m));
    }
    let alive = (0..uids.len() as u32).collect(); // uids are in kd order already
    (cx, alive)
}

/// Merges the children's complexes into their parent's (§5.2d): vertices with the same cell are
/// one, duplicated simplices disappear.
fn union(parts: Vec<(Complex, Vec<u32>)>, level: usize, bits: u32) -> (Complex, Vec<u32>) {
    let mut cx = Complex::default();
    let mut by_corner: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    let mut seen: FxHashSet<Simplex> = FxHashSet::default();
    for (part, alive) in &parts {
        let mut map = vec![u32::MAX; part.vertices.len()];
        for &v in alive {
            let vx = part.vertices[v as usize];
            map[v as usize] = *by_corner
                .entry(vx.corner)
                .or_insert_with(|| cx.add_vertex(vx));
        }
        for s in part.live_simplices() {
            let s = s.map(|x| map[x as usize]);
            if seen.insert(s) {
                cx.add(s);
            }
        }
    }
    let mut alive: Vec<u32> = (0..cx.vertices.len() as u32).collect();
    alive.sort_by_key(|&v| kd_key(cx.vertices[v as usize].corner, level, bits));
    (cx, alive)
}

/// A fresh complex holding only the live part of `cx` (ids in `alive` order).
fn compact(cx: &Complex, alive: &[u32]) -> (Complex, Vec<u32>) {
    let mut out = Complex::default();
    let mut map = vec![u32::MAX; cx.vertices.len()];
    for &v in alive {
        map[v as usize] = out.add_vertex(cx.vertices[v as usize]);
    }
    for s in cx.live_simplices() {
        out.add(s.map(|x| map[x as usize]));
    }
    let alive = (0..alive.len() as u32).collect();
    (out, alive)
}

/// Compresses a triangle mesh into `out` (a `.tsc` stream). `progress` receives the fraction of
/// the coding done.
pub fn compress<W: Write + Seek>(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    params: Params,
    out: &mut W,
    progress: &mut dyn FnMut(f64),
) -> Result<CompressReport, CodecError> {
    params.validate()?;
    let t0 = Instant::now();
    let q = quantise(positions, triangles, params.bits)?;
    let triangle_count = q.simplices.iter().filter(|s| s.kind != POINT).count() as u64;
    let mut coder = Coder {
        params,
        q: &q,
        nodes: Vec::new(),
        leaf_simplices: Vec::new(),
        spans: Vec::new(),
        counts: Counts::default(),
        spill: Spill::new()?,
        progress,
        coded_leaf_simplices: 0,
    };
    let mut flags = 0;
    if !q.points.is_empty() {
        coder.build(0, [0; 3], (0..q.simplices.len() as u32).collect());
    }
    coder.spans = vec![(0, 0); coder.nodes.len()];
    let t1 = Instant::now();
    if !q.points.is_empty() {
        let (root, _) = coder.code(0)?;
        for s in root.live_simplices() {
            flags |= if s.kind == POINT {
                ROOT_POINT
            } else {
                ROOT_TRIANGLE
            };
        }
    }
    let t2 = Instant::now();
    let Coder {
        mut nodes,
        spans,
        counts,
        spill,
        coded_leaf_simplices,
        ..
    } = coder;
    let family_bits = counts.family_bits();
    let family_symbols = counts.family_symbols();
    let counts = counts.quantised();
    let tables = counts.to_bytes();
    let models = counts.models();
    let w = |e| CodecError::io("writing the compressed file", e);
    let start = out.stream_position().map_err(w)?;
    out.write_all(&[0u8; HEADER_LEN]).map_err(w)?;
    out.write_all(&tables).map_err(w)?;
    let mut pos = (HEADER_LEN + tables.len()) as u64;
    let mut temp = spill.reader()?;
    let mut raw = Vec::new();
    // chunks in pre-order, each read back from the temporary file and range-coded
    for (node, &(at, count)) in nodes.iter_mut().zip(&spans) {
        raw.resize(2 * count as usize, 0);
        temp.seek(SeekFrom::Start(2 * at))
            .map_err(|e| CodecError::io("reading the temporary code file", e))?;
        temp.read_exact(&mut raw)
            .map_err(|e| CodecError::io("reading the temporary code file", e))?;
        let symbols: Vec<Symbol> = raw
            .chunks_exact(2)
            .map(|b| Symbol(u16::from_le_bytes([b[0], b[1]])))
            .collect();
        let chunk = entropy::encode(&symbols, &models);
        out.write_all(&chunk).map_err(w)?;
        node.offset = pos;
        node.len = chunk.len() as u64;
        pos += chunk.len() as u64;
    }
    let index = format::index_to_bytes(&nodes);
    out.write_all(&index).map_err(w)?;
    let header = Header {
        grid: q.grid,
        params,
        flags,
        input_vertices: positions.len() as u64,
        input_triangles: triangles.len() as u64,
        vertices: q.points.len() as u64,
        triangles: triangle_count,
        tables: (HEADER_LEN as u64, tables.len() as u64),
        index: (pos, index.len() as u64),
    };
    let end = pos + index.len() as u64;
    out.seek(SeekFrom::Start(start)).map_err(w)?;
    out.write_all(&header.to_bytes()).map_err(w)?;
    out.seek(SeekFrom::Start(start + end)).map_err(w)?;
    let t3 = Instant::now();
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    Ok(CompressReport {
        input_vertices: positions.len() as u64,
        input_triangles: triangles.len() as u64,
        vertices: q.points.len() as u64,
        triangles: triangle_count,
        bytes: end,
        grid: q.grid,
        nsp_cells: nodes.len() as u64,
        duplicated_simplices: coded_leaf_simplices.saturating_sub(q.simplices.len() as u64),
        family_bits,
        family_symbols,
        steps_ms: [ms(t0, t1), ms(t1, t2), ms(t2, t3)],
    })
}
