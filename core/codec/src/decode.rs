//! Decoding (paper 003 §6.1): read the header, the tables and the index at the end, start from
//! one vertex at zero precision, and apply the cells' codes top-down. A cell that reaches its
//! full precision hands each child the part of its complex that belongs to it (§4, steps 7–8),
//! and the children continue independently from their own chunks.
//!
//! [`Tsc::decode`] decodes every cell up to a precision (`--max-bits`: any prefix of the
//! refinement, the whole file when it equals `p`).

use std::sync::Arc;

use rustc_hash::FxHashMap;

use crate::ahead::Geometry;
use crate::complex::{Complex, POINT, Simplex, Vertex};
use crate::entropy::SymbolReader;
use crate::error::CodecError;
use crate::format::{self, Header, ROOT_POINT, ROOT_TRIANGLE};
use crate::kd_cell::{key_prefix, morton_key};
use crate::kd_coder::{self, Limits, Span};
use crate::nsp_tree::Node;
use crate::positional_io;

/// An opened `.tsc` file: its header, models and tree, with the file's bytes.
pub struct Tsc {
    /// The header.
    pub header: Header,
    /// The nSP-tree, pre-order.
    pub nodes: Vec<Node>,
    pub(crate) bytes: Storage,
}

/// Where a `.tsc` file's chunks are read from: memory, or the file itself (one read per cell,
/// so that a decode's memory does not grow with the file).
pub(crate) enum Storage {
    Memory(Arc<[u8]>),
    File(std::fs::File, u64),
}

impl Storage {
    fn len(&self) -> u64 {
        match self {
            Storage::Memory(b) => b.len() as u64,
            Storage::File(_, len) => *len,
        }
    }

    /// `len` bytes at `offset` (already checked against the file's size).
    pub(crate) fn read(
        &self,
        offset: u64,
        len: u64,
    ) -> Result<std::borrow::Cow<'_, [u8]>, CodecError> {
        match self {
            Storage::Memory(b) => Ok(std::borrow::Cow::Borrowed(
                &b[offset as usize..(offset + len) as usize],
            )),
            Storage::File(f, _) => {
                let mut buf = vec![0u8; len as usize];
                positional_io::read_exact_at(f, &mut buf, offset).map_err(|e| {
                    CodecError::io(format!("reading {len} bytes at offset {offset}"), e)
                })?;
                Ok(std::borrow::Cow::Owned(buf))
            }
        }
    }
}

/// The fully coarsened mesh every decode starts from (§6.1): one vertex at zero precision with
/// the simplex kinds the header records.
pub(crate) fn root_complex(header: &Header) -> (Complex, Vec<u32>) {
    let mut root = Complex::default();
    let v = root.add_vertex(Vertex {
        corner: [0; 3],
        level: 0,
    });
    if header.flags & ROOT_TRIANGLE != 0 {
        root.add(Simplex::triangle(v, v, v));
    }
    if header.flags & ROOT_POINT != 0 {
        root.add(Simplex::point(v));
    }
    (root, vec![v])
}

/// What [`Tsc::visit`] hands over per finished cell: its index, its complex, its vertices in kd
/// order, and the geometry read ahead of its connectivity (§6.4), if any.
pub(crate) type CellFn<'a> =
    dyn FnMut(usize, &Complex, &[u32], Option<&Geometry>) -> Result<(), CodecError> + 'a;

/// A decoded mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Decoded {
    /// Precision in bits per coordinate of every vertex.
    pub bits: u32,
    /// Each vertex's cell: lower corner on the full-precision grid (the grid point itself at
    /// full precision), in kd order.
    pub corners: Vec<[u32; 3]>,
    /// Each vertex's position: the grid point; below full precision the cell's centre, or with
    /// geometry ahead (§6.4) the barycentre of the cells below it that the decode read.
    pub positions: Vec<[f64; 3]>,
    /// Oriented triangles; at full precision degenerate ones too, as the input had them.
    pub triangles: Vec<[u32; 3]>,
    /// Vertices no triangle uses (isolated points of the input).
    pub isolated: Vec<u32>,
    /// Bytes of the file the decode read: header, tables, index and the chunks it used.
    pub bytes_read: u64,
    /// nSP-cells decoded.
    pub cells: u64,
}

impl Tsc {
    /// Parses the header, tables and index of a `.tsc` file held in memory (copied).
    pub fn open(bytes: &[u8]) -> Result<Self, CodecError> {
        Tsc::from_shared(Arc::from(bytes))
    }

    /// As [`Tsc::open`], keeping `bytes` without a copy.
    pub fn from_shared(bytes: Arc<[u8]>) -> Result<Self, CodecError> {
        Tsc::from_storage(Storage::Memory(bytes))
    }

    /// Opens a `.tsc` file on disk, reading its header, tables and index now and each cell's
    /// chunk when a decode reaches it.
    pub fn open_file(path: &std::path::Path) -> Result<Self, CodecError> {
        let io = |e| CodecError::io(format!("reading {}", path.display()), e);
        let f = std::fs::File::open(path).map_err(io)?;
        let len = f.metadata().map_err(io)?.len();
        Tsc::from_storage(Storage::File(f, len))
    }

    fn from_storage(bytes: Storage) -> Result<Self, CodecError> {
        let len = bytes.len();
        let (header, nodes) = format::read(len, |o, l| bytes.read(o, l))?;
        if nodes.is_empty() != (header.vertices == 0) {
            return Err(CodecError::corrupt(
                header.index.0,
                "the index and the vertex count disagree on emptiness",
            ));
        }
        Ok(Tsc {
            header,
            nodes,
            bytes,
        })
    }

    /// Size of the whole file.
    pub fn bytes_len(&self) -> u64 {
        self.bytes.len()
    }

    /// A reader over cell `i`'s chunk.
    pub(crate) fn reader(&self, i: usize) -> Result<SymbolReader, CodecError> {
        let node = &self.nodes[i];
        // each cell's models start fresh: its chunk alone is enough (entropy.rs)
        Ok(SymbolReader::new(
            self.bytes.read(node.offset, node.len)?,
            node.offset,
        ))
    }

    /// The cell where grid point `q` stops on its way down from the root: the first cell `stop`
    /// accepts, else the deepest cell holding `q` (a leaf, or a cell without the child `q`
    /// would go to).
    pub(crate) fn descend(&self, q: [u32; 3], stop: impl Fn(usize) -> bool) -> usize {
        let mut i = 0usize;
        while !stop(i) {
            let node = &self.nodes[i];
            let Some(position) = self.header.params.child_of(node.depth, node.cell, q) else {
                break;
            };
            if node.child_mask & (1 << position) == 0 {
                break;
            }
            i = node.children[(node.child_mask & ((1u64 << position) - 1)).count_ones() as usize];
        }
        i
    }

    /// Bytes every decode reads: header, tables, index.
    fn fixed_bytes(&self) -> u64 {
        self.header.head_len + self.header.index.1
    }

    /// Decodes every cell up to `max_bits` bits per coordinate (the file's `p` when `None`).
    pub fn decode(&self, max_bits: Option<u32>) -> Result<Decoded, CodecError> {
        let p = self.header.params.bits;
        let bits = max_bits.unwrap_or(p).min(p);
        let mut out = Assembly::default();
        let (bytes_read, cells) = self.visit(bits, &mut |_, cx, _, geometry| {
            out.add(cx, geometry, p);
            Ok(())
        })?;
        Ok(out.finish(self, bits, bytes_read, cells))
    }

    /// Decodes the tree depth first up to `bits` bits and hands each finished cell (a leaf, or
    /// a cell that stops below its last precision) to `f` with its complex and its vertices in
    /// kd order; only the cells on the way down are in memory. Returns the bytes read and the
    /// cells decoded.
    pub(crate) fn visit(&self, bits: u32, f: &mut CellFn<'_>) -> Result<(u64, u64), CodecError> {
        let p = self.header.params.bits;
        let mut bytes_read = self.fixed_bytes();
        let mut cells = 0;
        if self.nodes.is_empty() {
            return Ok((bytes_read, cells));
        }
        let (root, alive) = root_complex(&self.header);
        let mut stack = vec![(0usize, root, alive)];
        while let Some((i, mut cx, mut alive)) = stack.pop() {
            let node = &self.nodes[i];
            let leaf = node.children.is_empty();
            let (start, end) = self.header.params.precision(node.depth);
            let end = if leaf { p } else { end };
            let stop = end.min(bits);
            let reader = &mut self.reader(i)?;
            cells += 1;
            let limits = Limits {
                vertices: node.end_vertices as usize,
                simplices: node.end_simplices as usize,
            };
            let mut geometry = None;
            let span = Span {
                bits: p,
                lo: 3 * start as usize,
                hi: 3 * stop as usize,
                end: 3 * end as usize,
                advance: self.header.params.advance(),
            };
            kd_coder::decode(&mut cx, &mut alive, span, reader, limits, &mut geometry)?;
            // a cell stopped inside its chunk needed only the words read so far
            bytes_read += if stop < end {
                reader.consumed_bytes().min(node.len)
            } else {
                node.len
            };
            if stop == end
                && (alive.len() as u64 != node.end_vertices || cx.live as u64 != node.end_simplices)
            {
                return Err(CodecError::corrupt(
                    node.offset,
                    format!(
                        "cell {i} decodes to {} vertices and {} simplices, its index says {} and {}",
                        alive.len(),
                        cx.live,
                        node.end_vertices,
                        node.end_simplices
                    ),
                ));
            }
            if leaf || stop < end {
                f(i, &cx, &alive, geometry.as_ref())?;
                continue;
            }
            let parts = self.partition(i, &cx, &alive);
            drop(cx);
            for (child, part) in node.children.iter().zip(parts).rev() {
                stack.push((*child, part.0, part.1));
            }
        }
        Ok((bytes_read, cells))
    }

    /// Gives each child of cell `i` the simplices one of whose vertices lies in it, over fresh
    /// copies of their vertices (kd order kept).
    pub(crate) fn partition(
        &self,
        i: usize,
        cx: &Complex,
        alive: &[u32],
    ) -> Vec<(Complex, Vec<u32>)> {
        let node = &self.nodes[i];
        let params = &self.header.params;
        let positions: Vec<usize> = (0..64)
            .filter(|&c| node.child_mask & (1 << c) != 0)
            .collect();
        let slot_of: FxHashMap<usize, usize> =
            positions.iter().enumerate().map(|(k, &c)| (c, k)).collect();
        let mut lists: Vec<Vec<Simplex>> = vec![Vec::new(); positions.len()];
        for s in cx.live_simplices() {
            let mut seen = [usize::MAX; 3];
            for (k, &x) in s.v.iter().enumerate() {
                let Some(c) =
                    params.child_of(node.depth, node.cell, cx.vertices[x as usize].corner)
                else {
                    continue;
                };
                if let (false, Some(&slot)) = (seen.contains(&c), slot_of.get(&c)) {
                    lists[slot].push(s);
                }
                seen[k] = c;
            }
        }
        lists
            .into_iter()
            .map(|list| {
                let mut used = vec![false; cx.vertices.len()];
                for s in &list {
                    for &x in &s.v {
                        used[x as usize] = true;
                    }
                }
                let mut part = Complex::default();
                let mut map = vec![u32::MAX; cx.vertices.len()];
                let mut order = Vec::new();
                for &v in alive.iter().filter(|&&v| used[v as usize]) {
                    map[v as usize] = part.add_vertex(cx.vertices[v as usize]);
                    order.push(map[v as usize]);
                }
                for s in list {
                    part.add(rename(s, &map));
                }
                (part, order)
            })
            .collect()
    }
}

/// `s` over other vertex ids.
fn rename(s: Simplex, map: &[u32]) -> Simplex {
    s.map(|x| map[x as usize])
}

/// The union of the cells' complexes, duplicates along borders removed: every cell's vertices
/// and simplices are appended as they come (a vertex once per cell that holds it), then one sort
/// on cached kd keys welds equal corners and puts the vertices in kd order, and one sort of the
/// renamed simplices removes the duplicates (no hash maps: issue 34's flat decoder).
#[derive(Default)]
struct Assembly {
    /// Per vertex occurrence (a vertex of one cell), in arrival order: its full kd key and its
    /// arrival number (the first arrival of a corner is the one kept).
    keys: Vec<(u64, u32)>,
    corners: Vec<[u32; 3]>,
    /// Where each occurrence is drawn, in grid units.
    positions: Vec<[f64; 3]>,
    /// Simplices over occurrence numbers.
    simplices: Vec<Simplex>,
}

impl Assembly {
    fn add(&mut self, cx: &Complex, geometry: Option<&Geometry>, p: u32) {
        let mut map = vec![u32::MAX; cx.vertices.len()];
        for v in cx.used_vertices() {
            let vx = cx.vertices[v as usize];
            let n = self.corners.len() as u32;
            map[v as usize] = n;
            self.keys.push((morton_key(vx.corner, p), n));
            self.corners.push(vx.corner);
            self.positions
                .push(geometry.map_or_else(|| vx.centre(p), |g| g.position(&vx, p)));
        }
        self.simplices
            .extend(cx.live_simplices().map(|s| rename(s, &map)));
    }

    fn finish(self, tsc: &Tsc, bits: u32, bytes_read: u64, cells: u64) -> Decoded {
        let p = tsc.header.params.bits;
        let full = bits == p;
        let level = 3 * bits as usize;
        let Assembly {
            mut keys,
            corners: all_corners,
            positions: all_positions,
            simplices: all_simplices,
        } = self;
        // weld: equal corners have equal full keys; the first arrival stands for them all
        keys.sort_unstable();
        let mut first: Vec<u32> = Vec::new();
        let mut weld = vec![0u32; keys.len()];
        for (i, &(key, n)) in keys.iter().enumerate() {
            if i == 0 || keys[i - 1].0 != key {
                first.push(n);
            }
            weld[n as usize] = (first.len() - 1) as u32;
        }
        // kd order at the decoded level, ties in arrival order
        let mut order: Vec<u32> = (0..first.len() as u32).collect();
        if !full {
            order.sort_unstable_by_key(|&u| {
                let n = first[u as usize];
                (key_prefix(morton_key(all_corners[n as usize], p), level), n)
            });
        }
        let mut rank = vec![0u32; order.len()];
        for (r, &u) in order.iter().enumerate() {
            rank[u as usize] = r as u32;
        }
        for w in weld.iter_mut() {
            *w = rank[*w as usize];
        }
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        let mut isolated: Vec<u32> = Vec::new();
        let mut used = vec![false; order.len()];
        let mut simplices: Vec<Simplex> = all_simplices
            .into_iter()
            .map(|s| rename(s, &weld))
            .collect();
        simplices.sort_unstable();
        simplices.dedup();
        for s in simplices {
            if s.kind == POINT {
                if full {
                    isolated.push(s.v[0]);
                    used[s.v[0] as usize] = true;
                }
            } else if full || (s.v[0] != s.v[1] && s.v[1] != s.v[2] && s.v[2] != s.v[0]) {
                triangles.push(s.v);
                for x in s.v {
                    used[x as usize] = true;
                }
            }
        }
        // below full precision, drop the vertices only degenerate simplices used
        let keep: Vec<u32> = (0..order.len() as u32)
            .filter(|&r| used[r as usize])
            .collect();
        let mut new_id = vec![u32::MAX; order.len()];
        for (i, &r) in keep.iter().enumerate() {
            new_id[r as usize] = i as u32;
        }
        let arrival = |r: u32| first[order[r as usize] as usize] as usize;
        let corners: Vec<[u32; 3]> = keep.iter().map(|&r| all_corners[arrival(r)]).collect();
        let positions = keep
            .iter()
            .map(|&r| tsc.header.grid.position(all_positions[arrival(r)]))
            .collect();
        Decoded {
            bits,
            corners,
            positions,
            triangles: triangles
                .iter()
                .map(|t| t.map(|x| new_id[x as usize]))
                .collect(),
            isolated: isolated.iter().map(|&x| new_id[x as usize]).collect(),
            bytes_read,
            cells,
        }
    }
}
