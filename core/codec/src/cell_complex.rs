//! The complexes a cell is coded from (paper 003 §5.2a, §5.2d): a leaf's, built from its raw
//! index entries, and a parent's, the union of its children's with equal vertices welded and
//! duplicated simplices removed; vertices listed in kd order.

use rustc_hash::{FxHashMap, FxHashSet};

use crate::complex::{Complex, Simplex, Vertex};
use crate::error::CodecError;
use crate::kd_cell::kd_key;
use crate::nsp_tree::Params;
use crate::partition::{POINT_MARK, Partition};

/// The complex of leaf `i` of `part` from its raw index entries: one vertex per grid point, each
/// oriented triangle once, isolated points that no triangle of the leaf uses. Also the
/// points and triangles the leaf owns (its own grid points; triangles whose first vertex in
/// kd order is its own), the entries read and the simplices it owns.
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
    let mut cx = Complex::default();
    let mut ids: FxHashMap<[u32; 3], u32> = FxHashMap::default();
    let id = |ids: &mut FxHashMap<[u32; 3], u32>, cx: &mut Complex, q: [u32; 3]| {
        *ids.entry(q).or_insert_with(|| {
            cx.add_vertex(Vertex {
                corner: q,
                level: full as u8,
            })
        })
    };
    let mut simplices: FxHashSet<Simplex> = FxHashSet::default();
    let mut points: Vec<[u32; 3]> = Vec::new();
    let mut owned_triangles = 0;
    let inside = |q: [u32; 3]| params.cell_at(node.depth, q) == node.cell;
    for e in &entries {
        if e[1] == POINT_MARK {
            points.push(part.points.get(e[0]));
            continue;
        }
        let q = e.map(|x| part.points.get(x));
        let s = Simplex::triangle(
            id(&mut ids, &mut cx, q[0]),
            id(&mut ids, &mut cx, q[1]),
            id(&mut ids, &mut cx, q[2]),
        );
        if simplices.insert(s) {
            let first = q.iter().min_by_key(|c| kd_key(**c, full, bits)).unwrap();
            owned_triangles += u64::from(inside(*first));
        }
    }
    let mut point_simplices = 0;
    for q in points {
        if !ids.contains_key(&q) {
            let v = id(&mut ids, &mut cx, q);
            simplices.insert(Simplex::point(v));
            point_simplices += 1;
        }
    }
    let owned_points = ids.keys().filter(|&&q| inside(q)).count() as u64;
    let mut sorted: Vec<Simplex> = simplices.into_iter().collect();
    sorted.sort_unstable();
    // every simplex is owned by one leaf: points by their own, triangles by their first
    // vertex's
    let owned_simplices = owned_triangles + point_simplices;
    for s in sorted {
        cx.add(s);
    }
    let mut alive: Vec<u32> = (0..cx.vertices.len() as u32).collect();
    alive.sort_by_key(|&v| kd_key(cx.vertices[v as usize].corner, full, bits));
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
/// one, duplicated simplices disappear.
pub(crate) fn union(
    parts: Vec<(Complex, Vec<u32>)>,
    level: usize,
    bits: u32,
) -> (Complex, Vec<u32>) {
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
