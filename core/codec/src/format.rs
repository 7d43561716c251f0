//! The `.tsc` file layout (paper 003 §5.1 "Ecriture de l'en-tête", §5.3 "Ecriture finale"):
//!
//! ```text
//! header (fixed 128 bytes)  magic, version, grid (origin, step, p), n, p_r, m (geometry ahead), N_min, counts,
//!                           offsets of the tables and of the index
//! probability tables        one per (family, kd level) context, as counts
//! code chunks               one range-coded chunk per nSP-cell
//! index                     the nSP-tree in pre-order: child mask, chunk offset and length,
//!                           the cell's final size (a decoder's bound)
//! ```
//!
//! The index sits at the end, as in the paper, so the encoder can write every chunk before it
//! knows the tree's final layout, and a reader can reach any cell's chunk directly.

use crate::error::CodecError;
use crate::nsp_tree::{Node, Params};
use crate::quantize::Quantizer;
use crate::varint;

/// First bytes of every `.tsc` file.
pub const MAGIC: [u8; 4] = *b"TSC\x1a";
/// Format version this crate writes and reads.
pub const VERSION: u16 = 1;
/// Size of the fixed header.
pub const HEADER_LEN: usize = 128;

/// The header's flag: the fully coarsened root holds a triangle.
pub const ROOT_TRIANGLE: u16 = 1;
/// The header's flag: the fully coarsened root holds an isolated point.
pub const ROOT_POINT: u16 = 2;

/// Everything the decoder needs before the first code (§5.1).
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// The quantisation grid.
    pub grid: Quantizer,
    /// Partition parameters (`bits` equals `grid.bits`).
    pub params: Params,
    /// [`ROOT_TRIANGLE`] | [`ROOT_POINT`].
    pub flags: u16,
    /// Vertices of the input file.
    pub input_vertices: u64,
    /// Triangles of the input file (after fan triangulation of polygons).
    pub input_triangles: u64,
    /// Distinct quantised points.
    pub vertices: u64,
    /// Distinct oriented triangles after quantisation.
    pub triangles: u64,
    /// Offset and length of the probability tables.
    pub tables: (u64, u64),
    /// Offset and length of the index.
    pub index: (u64, u64),
}

impl Header {
    /// The fixed-size encoding.
    pub fn to_bytes(&self) -> [u8; HEADER_LEN] {
        let mut b = Vec::with_capacity(HEADER_LEN);
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&self.flags.to_le_bytes());
        for o in self.grid.origin {
            b.extend_from_slice(&o.to_le_bytes());
        }
        b.extend_from_slice(&self.grid.step.to_le_bytes());
        b.extend_from_slice(&[
            self.params.bits as u8,
            self.params.cell_split as u8,
            self.params.root_bits as u8,
            self.params.ahead as u8,
        ]);
        b.extend_from_slice(&(self.params.min_cell.min(u32::MAX as u64) as u32).to_le_bytes());
        for v in [
            self.input_vertices,
            self.input_triangles,
            self.vertices,
            self.triangles,
            self.tables.0,
            self.tables.1,
            self.index.0,
            self.index.1,
        ] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.resize(HEADER_LEN, 0);
        b.try_into().unwrap()
    }

    /// Reads and checks a header; `file_len` bounds the offsets it may hold.
    pub fn from_bytes(b: &[u8], file_len: u64) -> Result<Self, CodecError> {
        if b.len() < HEADER_LEN {
            return Err(CodecError::corrupt(
                b.len() as u64,
                format!(
                    "the file is {} bytes, shorter than the {HEADER_LEN}-byte header",
                    b.len()
                ),
            ));
        }
        if b[0..4] != MAGIC {
            return Err(CodecError::corrupt(0, "not a .tsc file (bad magic)"));
        }
        let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]);
        let f64_at = |o: usize| f64::from_le_bytes(b[o..o + 8].try_into().unwrap());
        let u64_at = |o: usize| u64::from_le_bytes(b[o..o + 8].try_into().unwrap());
        let version = u16_at(4);
        if version != VERSION {
            return Err(CodecError::corrupt(
                4,
                format!("format version {version}, this reader knows {VERSION}"),
            ));
        }
        let flags = u16_at(6);
        let origin = [f64_at(8), f64_at(16), f64_at(24)];
        let step = f64_at(32);
        if origin.iter().any(|x| !x.is_finite()) || !(step.is_finite() && step > 0.0) {
            return Err(CodecError::corrupt(
                8,
                "the grid's origin or step is not a finite positive number",
            ));
        }
        let params = Params {
            bits: b[40] as u32,
            cell_split: b[41] as u32,
            root_bits: b[42] as u32,
            ahead: b[43] as u32,
            min_cell: u32::from_le_bytes(b[44..48].try_into().unwrap()) as u64,
        };
        params
            .validate()
            .map_err(|e| CodecError::corrupt(40, e.to_string()))?;
        let v = |i: usize| u64_at(48 + 8 * i);
        let header = Header {
            grid: Quantizer {
                origin,
                step,
                bits: params.bits,
            },
            params,
            flags,
            input_vertices: v(0),
            input_triangles: v(1),
            vertices: v(2),
            triangles: v(3),
            tables: (v(4), v(5)),
            index: (v(6), v(7)),
        };
        for (name, (o, l), at) in [
            ("tables", header.tables, 80u64),
            ("index", header.index, 96),
        ] {
            if o.checked_add(l).is_none_or(|end| end > file_len) || o < HEADER_LEN as u64 {
                return Err(CodecError::corrupt(
                    at,
                    format!("the {name} ({l} bytes at {o}) lie outside the {file_len}-byte file"),
                ));
            }
        }
        Ok(header)
    }
}

/// The index: every node in pre-order.
pub fn index_to_bytes(nodes: &[Node]) -> Vec<u8> {
    let mut out = Vec::new();
    varint::put(&mut out, nodes.len() as u64);
    for n in nodes {
        out.extend_from_slice(&n.child_mask.to_le_bytes());
        for x in [n.offset, n.len, n.end_vertices, n.end_simplices] {
            varint::put(&mut out, x);
        }
    }
    out
}

/// Reads the index at file offset `base`, checking every chunk lies within `chunks` (the byte
/// range between the tables and the index) and the tree's shape.
pub fn index_from_bytes(
    b: &[u8],
    base: u64,
    params: &Params,
    chunks: (u64, u64),
) -> Result<Vec<Node>, CodecError> {
    let mut at = 0usize;
    let count = varint::get(b, &mut at, base)?;
    if count > (b.len() as u64) / 12 + 1 {
        return Err(CodecError::corrupt(
            base,
            format!("an index of {count} cells in {} bytes", b.len()),
        ));
    }
    let mut nodes: Vec<Node> = Vec::with_capacity(count as usize);
    for i in 0..count {
        let here = base + at as u64;
        let Some(mask) = b.get(at..at + 8) else {
            return Err(CodecError::corrupt(
                here,
                format!("truncated index entry of cell {i}"),
            ));
        };
        let child_mask = u64::from_le_bytes(mask.try_into().unwrap());
        at += 8;
        let mut f = [0u64; 4];
        for x in &mut f {
            *x = varint::get(b, &mut at, base)?;
        }
        if f[0] < chunks.0 || f[0].checked_add(f[1]).is_none_or(|e| e > chunks.1) {
            return Err(CodecError::corrupt(
                here,
                format!(
                    "cell {i}'s code chunk ({} bytes at {}) lies outside the chunk area",
                    f[1], f[0]
                ),
            ));
        }
        nodes.push(Node {
            depth: 0,
            cell: [0; 3],
            child_mask,
            children: Vec::new(),
            offset: f[0],
            len: f[1],
            end_vertices: f[2],
            end_simplices: f[3],
        });
    }
    // rebuild the tree from the pre-order list and the masks
    let n3 = params.cell_split.pow(3);
    if nodes.is_empty() {
        return Ok(nodes);
    }
    if skip_subtree(&nodes, 0, n3)? != nodes.len() {
        return Err(CodecError::corrupt(
            base,
            "the index lists more cells than its masks use",
        ));
    }
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let mask = nodes[i].child_mask;
        if n3 < 64 && mask >> n3 != 0 {
            return Err(CodecError::corrupt(
                base,
                format!("cell {i} has children beyond the {n3} positions"),
            ));
        }
        let depth = nodes[i].depth + 1;
        if mask != 0 && params.precision(nodes[i].depth).1 >= params.bits {
            return Err(CodecError::corrupt(
                base,
                format!("cell {i} ends at full precision yet has children"),
            ));
        }
        let mut kids = Vec::new();
        let mut next = i + 1;
        for position in (0..64).filter(|&c| mask & (1u64 << c) != 0) {
            kids.push(next);
            nodes[next].depth = depth;
            nodes[next].cell = params.child_cell(nodes[i].cell, position);
            // pre-order: a child's whole subtree comes before its next sibling
            next = skip_subtree(&nodes, next, n3)?;
        }
        for &k in kids.iter().rev() {
            stack.push(k);
        }
        nodes[i].children = kids;
    }
    Ok(nodes)
}

/// The position after the subtree starting at `i` in a pre-order list.
fn skip_subtree(nodes: &[Node], i: usize, n3: u32) -> Result<usize, CodecError> {
    let mut pending = 1u64;
    let mut j = i;
    while pending > 0 {
        let Some(n) = nodes.get(j) else {
            return Err(CodecError::corrupt(
                0,
                "the index lists fewer cells than its masks need",
            ));
        };
        let mask = if n3 < 64 {
            n.child_mask & ((1u64 << n3) - 1)
        } else {
            n.child_mask
        };
        pending = pending - 1 + mask.count_ones() as u64;
        j += 1;
    }
    Ok(j)
}
