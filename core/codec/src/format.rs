//! The `.tsc` file layout, version 3 (version 2's layout, other connectivity codes; paper 003
//! §5.1 "Ecriture de l'en-tête", §5.3 "Ecriture finale"):
//!
//! ```text
//! head      written first, known before any code: magic, version (u16 at bytes 4..6), the packed
//!           parameters (p, n, p_r, m), the grid (origin, step: each an f32 where that is exact,
//!           else an f64), N_min as a varint                              32 bytes on the bunny
//! chunks    one range-coded chunk per nSP-cell
//! trailer   written last: flags, the counts, then the nSP-tree in
//!           pre-order: child mask, chunk offset (its distance from where the previous chunk
//!           ended: 0 when the chunks follow each other) and length, the cell's final size
//!           (a decoder's bound), all varints
//! tail      the trailer's length, u32 LE
//! ```
//!
//! The index sits at the end, as in the paper, so the encoder writes every chunk before it knows
//! the tree's final layout, never seeks back, and a reader still reaches any cell's chunk directly.
//! Version 1 had a fixed 128-byte header with u64 counts and offsets and an index with u64 child
//! masks and absolute offsets (issue 34 item 6: 128 + 726 bytes on the bunny).

use crate::error::CodecError;
use crate::nsp_tree::{Node, Params};
use crate::quantize::Quantizer;
use crate::varint;

/// First bytes of every `.tsc` file.
pub const MAGIC: [u8; 4] = *b"TSC\x1a";
/// Format version this crate writes and reads. Version 3 has version 2's layout; its
/// connectivity codes come in another order with other contexts (`connectivity`), so a
/// version-2 chunk would decode to garbage.
pub const VERSION: u16 = 3;
/// The longest head: magic, version, packed parameters, grid mask, four f64s and a 10-byte
/// varint.
pub const MAX_HEAD_LEN: usize = 9 + 32 + 10;
/// Bytes of the tail (the trailer's length).
pub const TAIL_LEN: usize = 4;

/// The header's flag: the fully coarsened root holds a triangle.
pub const ROOT_TRIANGLE: u16 = 1;
/// The header's flag: the fully coarsened root holds an isolated point.
pub const ROOT_POINT: u16 = 2;

/// Everything the decoder needs before the first code (§5.1), from the head and the trailer.
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
    /// Length of the head ([`head_bytes`]): where the first chunk starts.
    pub head_len: u64,
    /// Offset and length of the trailer, tail included (the index is its end).
    pub index: (u64, u64),
}

/// Packs `p - 1` (5 bits), `p_r` (5), `n == 4` (1) and `m` (3) into the head's u16.
fn pack(params: &Params) -> u16 {
    (params.bits.saturating_sub(1) & 31) as u16
        | ((params.root_bits & 31) as u16) << 5
        | ((params.cell_split == 4) as u16) << 10
        | ((params.ahead & 7) as u16) << 11
}

/// The head, written before the first chunk: everything here is known once the grid is.
pub fn head_bytes(grid: &Quantizer, params: &Params) -> Vec<u8> {
    let mut b = Vec::with_capacity(MAX_HEAD_LEN);
    b.extend_from_slice(&MAGIC);
    b.extend_from_slice(&VERSION.to_le_bytes());
    b.extend_from_slice(&pack(params).to_le_bytes());
    let values = [grid.origin[0], grid.origin[1], grid.origin[2], grid.step];
    // an f32 only where it gives back the same f64: the grid stays exact (lossless at p bits)
    let narrow = |x: f64| (x as f32) as f64 == x;
    let mask = (0..4).fold(0u8, |m, i| m | (narrow(values[i]) as u8) << i);
    b.push(mask);
    for (i, x) in values.into_iter().enumerate() {
        if mask & (1 << i) != 0 {
            b.extend_from_slice(&(x as f32).to_le_bytes());
        } else {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    varint::put(&mut b, params.min_cell);
    b
}

/// Reads the head: the grid, the parameters and the head's length. The version is checked
/// before anything else, so that an old or truncated file still names its version.
fn read_head(b: &[u8]) -> Result<(Quantizer, Params, u64), CodecError> {
    let m = b.len().min(4);
    if b[..m] != MAGIC[..m] {
        return Err(CodecError::corrupt(0, "not a .tsc file (bad magic)"));
    }
    if b.len() < 6 {
        return Err(CodecError::corrupt(
            b.len() as u64,
            format!(
                "the file is {} bytes, shorter than magic and version",
                b.len()
            ),
        ));
    }
    let version = u16::from_le_bytes([b[4], b[5]]);
    if version != VERSION {
        let who = if version < VERSION {
            "an older tessd"
        } else {
            "a newer tessd"
        };
        return Err(CodecError::corrupt(
            4,
            format!(
                "written by format version {version} ({who}); this reader reads version \
                 {VERSION}: compress the mesh again"
            ),
        ));
    }
    let short = |at: usize| {
        CodecError::corrupt(
            b.len() as u64,
            format!(
                "the file is {} bytes, shorter than its head ({at} bytes or more)",
                b.len()
            ),
        )
    };
    if b.len() < 9 {
        return Err(short(9));
    }
    let packed = u16::from_le_bytes([b[6], b[7]]);
    let mask = b[8];
    if packed >> 14 != 0 || mask >> 4 != 0 {
        return Err(CodecError::corrupt(
            6,
            "unknown bits in the packed parameters",
        ));
    }
    let mut at = 9usize;
    let mut values = [0f64; 4];
    for (i, x) in values.iter_mut().enumerate() {
        let w = if mask & (1 << i) != 0 { 4 } else { 8 };
        let Some(v) = b.get(at..at + w) else {
            return Err(short(at + w));
        };
        *x = if w == 4 {
            f32::from_le_bytes(v.try_into().unwrap()) as f64
        } else {
            f64::from_le_bytes(v.try_into().unwrap())
        };
        at += w;
    }
    let (origin, step) = ([values[0], values[1], values[2]], values[3]);
    if origin.iter().any(|x| !x.is_finite()) || !(step.is_finite() && step > 0.0) {
        return Err(CodecError::corrupt(
            9,
            "the grid's origin or step is not a finite positive number",
        ));
    }
    let min_cell = varint::get(b, &mut at, 0)?;
    let params = Params {
        bits: (packed & 31) as u32 + 1,
        root_bits: (packed >> 5 & 31) as u32,
        cell_split: if packed >> 10 & 1 != 0 { 4 } else { 2 },
        ahead: (packed >> 11 & 7) as u32,
        min_cell,
    };
    params
        .validate()
        .map_err(|e| CodecError::corrupt(6, e.to_string()))?;
    let grid = Quantizer {
        origin,
        step,
        bits: params.bits,
    };
    Ok((grid, params, at as u64))
}

impl Header {
    /// The trailer and the tail, written after the last chunk: the flags and counts known only
    /// once every cell is coded, then the index of `nodes` (pre-order). `self.index` is not
    /// read.
    pub fn trailer_bytes(&self, nodes: &[Node]) -> Vec<u8> {
        let mut out = Vec::new();
        for v in [
            self.flags as u64,
            self.input_vertices,
            self.input_triangles,
            self.vertices,
            self.triangles,
        ] {
            varint::put(&mut out, v);
        }
        varint::put(&mut out, nodes.len() as u64);
        let mut expected = self.head_len;
        for n in nodes {
            // zigzag: a chunk may sit before the previous one's end in another writer's order
            let gap = n.offset.wrapping_sub(expected) as i64;
            let zigzag = ((gap << 1) ^ (gap >> 63)) as u64;
            for x in [n.child_mask, zigzag, n.len, n.end_vertices, n.end_simplices] {
                varint::put(&mut out, x);
            }
            expected = n.offset + n.len;
        }
        let len = u32::try_from(out.len()).expect("an index under 4 GiB");
        out.extend_from_slice(&len.to_le_bytes());
        out
    }
}

/// Reads and checks a file's head, trailer and index; `read(offset, len)` returns that many
/// bytes of the `file_len`-byte file.
pub fn read<B: AsRef<[u8]>>(
    file_len: u64,
    mut read: impl FnMut(u64, u64) -> Result<B, CodecError>,
) -> Result<(Header, Vec<Node>), CodecError> {
    let head = read(0, file_len.min(MAX_HEAD_LEN as u64))?;
    let (grid, params, head_len) = read_head(head.as_ref())?;
    if file_len < head_len + TAIL_LEN as u64 {
        return Err(CodecError::corrupt(
            file_len,
            format!("the file is {file_len} bytes, too short for its head and tail"),
        ));
    }
    let tail_at = file_len - TAIL_LEN as u64;
    let tail = read(tail_at, TAIL_LEN as u64)?;
    let trailer_len = u32::from_le_bytes(tail.as_ref().try_into().unwrap()) as u64;
    if trailer_len > tail_at - head_len {
        return Err(CodecError::corrupt(
            tail_at,
            format!(
                "a trailer of {trailer_len} bytes in a {file_len}-byte file (a truncated file?)"
            ),
        ));
    }
    let base = tail_at - trailer_len;
    let trailer = read(base, trailer_len)?;
    let b = trailer.as_ref();
    let mut at = 0usize;
    let mut f = [0u64; 5];
    for x in &mut f {
        *x = varint::get(b, &mut at, base)?;
    }
    if f[0] > (ROOT_TRIANGLE | ROOT_POINT) as u64 {
        return Err(CodecError::corrupt(base, format!("unknown flags {}", f[0])));
    }
    let header = Header {
        grid,
        params,
        flags: f[0] as u16,
        input_vertices: f[1],
        input_triangles: f[2],
        vertices: f[3],
        triangles: f[4],
        head_len,
        index: (base, trailer_len + TAIL_LEN as u64),
    };
    let nodes = index_from_bytes(b, &mut at, base, &params, (head_len, base))?;
    if at != b.len() {
        return Err(CodecError::corrupt(
            base + at as u64,
            format!("{} bytes after the index", b.len() - at),
        ));
    }
    Ok((header, nodes))
}

/// Reads the index at `b[*at..]` (file offset `base`), checking every chunk lies within
/// `chunks` (the byte range between the head and the trailer) and the tree's shape.
fn index_from_bytes(
    b: &[u8],
    at: &mut usize,
    base: u64,
    params: &Params,
    chunks: (u64, u64),
) -> Result<Vec<Node>, CodecError> {
    let count = varint::get(b, at, base)?;
    // an entry takes five bytes or more
    if count > (b.len() as u64) / 5 + 1 {
        return Err(CodecError::corrupt(
            base,
            format!("an index of {count} cells in {} bytes", b.len()),
        ));
    }
    let mut nodes: Vec<Node> = Vec::with_capacity(count as usize);
    let mut expected = chunks.0;
    for i in 0..count {
        let here = base + *at as u64;
        let mut f = [0u64; 5];
        for x in &mut f {
            *x = varint::get(b, at, base)?;
        }
        let gap = ((f[1] >> 1) as i64) ^ -((f[1] & 1) as i64);
        let offset = expected.wrapping_add(gap as u64);
        if offset < chunks.0 || offset.checked_add(f[2]).is_none_or(|e| e > chunks.1) {
            return Err(CodecError::corrupt(
                here,
                format!(
                    "cell {i}'s code chunk ({} bytes at {}) lies outside the chunk area",
                    f[2], offset as i64
                ),
            ));
        }
        expected = offset + f[2];
        nodes.push(Node {
            depth: 0,
            cell: [0; 3],
            child_mask: f[0],
            children: Vec::new(),
            offset,
            len: f[2],
            end_vertices: f[3],
            end_simplices: f[4],
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
