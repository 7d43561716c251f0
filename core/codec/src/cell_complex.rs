//! The complexes a cell is coded from (paper 003 §5.2a, §5.2d): a leaf's, built from its raw
//! index entries, and a parent's, the union of its children's with equal vertices welded and
//! duplicated simplices removed; vertices listed in kd order.

use crate::complex::{Complex, Simplex, Vertex};
use crate::error::CodecError;
use crate::kd_cell::morton_key;
use crate::nsp_tree::Params;
use crate::partition::{POINT_MARK, Partition};

/// Sorts simplices and drops the repeated ones, on packed keys (ids and kind in one `u128`,
/// ordered as [`Simplex`]'s own order), so that no hash set is needed to weld cells.
fn sort_dedup(simplices: &mut Vec<Simplex>) {
    let pack = |s: &Simplex| {
        ((s.v[0] as u128) << 104)
            | ((s.v[1] as u128) << 72)
            | ((s.v[2] as u128) << 40)
            | s.kind as u128
    };
    simplices.sort_unstable_by_key(pack);
    simplices.dedup();
}

/// The complex of leaf `i` of `part` from its raw index entries: one vertex per grid point, each
/// oriented triangle once, isolated points that no triangle of the leaf uses. Also the
/// points and triangles the leaf owns (its own grid points; triangles whose first vertex in
/// kd order is its own), the entries read and the simplices it owns.
///
/// Vertices are numbered in kd order (one sort of the corners' cached Morton keys welds equal
/// grid points), so the returned `alive` is `0..n` and a triangle's first vertex in kd order is
/// its smallest id.
#[allow(clippy::type_complexity)]
pub(crate) fn leaf_complex(
    part: &Partition,
    params: &Params,
    i: usize,
) -> Result<(Complex, Vec<u32>, Option<(u64, u64, u64, u64)>), CodecError> {
    let bits = params.bits;
    let full = 3 * bits as usize;
    let node = &part.nodes[i];
    let entries = part.leaf(i)?;
    // every corner occurrence with its key; a point entry's occurrence is marked by its index
    let mut corners: Vec<[u32; 3]> = Vec::with_capacity(3 * entries.len());
    let mut triangles = 0usize;
    for e in entries.iter().filter(|e| e[1] != POINT_MARK) {
        corners.extend(e.map(|x| part.points.get(x)));
        triangles += 1;
    }
    let tri_corners = corners.len();
    corners.extend(
        entries
            .iter()
            .filter(|e| e[1] == POINT_MARK)
            .map(|e| part.points.get(e[0])),
    );
    let mut keys: Vec<(u64, u32)> = corners
        .iter()
        .enumerate()
        .map(|(k, &q)| (morton_key(q, bits), k as u32))
        .collect();
    keys.sort_unstable();
    let mut id_of = vec![0u32; corners.len()];
    let mut cx = Complex::default();
    // whether a vertex holds a triangle corner (else it is an isolated point)
    let mut in_triangle: Vec<bool> = Vec::new();
    for (k, &(key, at)) in keys.iter().enumerate() {
        if k == 0 || keys[k - 1].0 != key {
            cx.add_vertex(Vertex {
                corner: corners[at as usize],
                level: full as u8,
            });
            in_triangle.push(false);
        }
        let id = (cx.vertices.len() - 1) as u32;
        id_of[at as usize] = id;
        in_triangle[id as usize] |= (at as usize) < tri_corners;
    }
    drop(keys);
    let mut simplices: Vec<Simplex> = Vec::with_capacity(triangles);
    simplices.extend(
        id_of[..tri_corners]
            .chunks_exact(3)
            .map(|t| Simplex::triangle(t[0], t[1], t[2])),
    );
    sort_dedup(&mut simplices);
    let inside = |q: [u32; 3]| params.cell_at(node.depth, q) == node.cell;
    // every simplex is owned by one leaf: points by their own, triangles by their first
    // vertex's (in kd order: the smallest id, first in the canonical rotation)
    let owned_triangles = simplices
        .iter()
        .filter(|s| inside(cx.vertices[s.v[0] as usize].corner))
        .count() as u64;
    let before = simplices.len();
    simplices.extend(
        (0..cx.vertices.len() as u32)
            .filter(|&v| !in_triangle[v as usize])
            .map(Simplex::point),
    );
    let point_simplices = (simplices.len() - before) as u64;
    let owned_points = cx.vertices.iter().filter(|w| inside(w.corner)).count() as u64;
    let owned_simplices = owned_triangles + point_simplices;
    for s in simplices {
        cx.add(s);
    }
    let alive: Vec<u32> = (0..cx.vertices.len() as u32).collect();
    Ok((
        cx,
        alive,
        Some((
            owned_points,
            owned_triangles,
            entries.len() as u64,
            owned_simplices,
        )),
    ))
}

/// Merges the children's complexes into their parent's (§5.2d): vertices with the same cell are
/// one, duplicated simplices disappear. Each child lists its vertices in kd order, so one merge
/// of those sorted runs (a stable sort on cached keys finds and merges them) numbers the
/// parent's vertices in kd order and welds equal cells; the renamed simplices are de-duplicated
/// by sorting.
pub(crate) fn union(
    parts: Vec<(Complex, Vec<u32>)>,
    _level: usize,
    bits: u32,
) -> (Complex, Vec<u32>) {
    // (key, child, vertex), runs in child order; the stable sort keeps the first child first
    let mut all: Vec<(u64, u32, u32)> = Vec::with_capacity(parts.iter().map(|p| p.1.len()).sum());
    for (c, (part, alive)) in parts.iter().enumerate() {
        all.extend(alive.iter().map(|&v| {
            // a cell's lower corner has no bits below its level: its full key is its kd key
            (
                morton_key(part.vertices[v as usize].corner, bits),
                c as u32,
                v,
            )
        }));
    }
    all.sort_by_key(|e| e.0);
    let mut maps: Vec<Vec<u32>> = parts
        .iter()
        .map(|(part, _)| vec![u32::MAX; part.vertices.len()])
        .collect();
    let mut cx = Complex::default();
    for (k, &(key, c, v)) in all.iter().enumerate() {
        if k == 0 || all[k - 1].0 != key {
            cx.add_vertex(parts[c as usize].0.vertices[v as usize]);
        }
        maps[c as usize][v as usize] = (cx.vertices.len() - 1) as u32;
    }
    drop(all);
    let mut simplices: Vec<Simplex> = Vec::with_capacity(parts.iter().map(|p| p.0.live).sum());
    for ((part, _), map) in parts.iter().zip(&maps) {
        simplices.extend(part.live_simplices().map(|s| s.map(|x| map[x as usize])));
    }
    drop(maps);
    drop(parts);
    sort_dedup(&mut simplices);
    for s in simplices {
        cx.add(s);
    }
    let alive = (0..cx.vertices.len() as u32).collect();
    (cx, alive)
}

/// A fresh complex holding only the live part of `cx` (ids in `alive` order).
pub(crate) fn compact(cx: &Complex, alive: &[u32]) -> (Complex, Vec<u32>) {
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
