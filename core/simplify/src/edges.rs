//! Sharp edges and creases through clustering: an input edge (a, b) becomes the output edge
//! between the output vertices of a's and b's clusters — when those differ and when the output
//! still has that edge in one of its faces. Clustering moves whole feature lines onto the
//! output's edges (the quality goal even keeps them within the tolerance), so a sharp or
//! creased line survives as the output edges it collapsed onto; edges that collapsed to a
//! point, or whose image is no output edge, have nothing left to mark.

use crate::partition::UNUSED;
use std::collections::HashMap;
use tessd_mesh::attribute::edge_key;
use tessd_mesh::{Crease, Mesh};

/// The edges of `out` that the input `edges` map onto through `vertex_of` (output vertex of an
/// input vertex, or [`UNUSED`]), each once, with their values merged by `merge` when several
/// input edges land on one output edge. Output order: as the edges first appear in `out`'s
/// faces, oriented as there.
pub(crate) fn carry_edges<T: Copy>(
    edges: impl Iterator<Item = ([u32; 2], T)>,
    vertex_of: impl Fn(u32) -> u32,
    out: &Mesh,
    merge: impl Fn(T, T) -> T,
) -> Vec<([u32; 2], T)> {
    let mut mapped: HashMap<u64, T> = HashMap::new();
    for ([a, b], value) in edges {
        let (na, nb) = (vertex_of(a), vertex_of(b));
        if na == UNUSED || nb == UNUSED || na == nb {
            continue;
        }
        mapped
            .entry(edge_key(na, nb))
            .and_modify(|v| *v = merge(*v, value))
            .or_insert(value);
    }
    let mut found = Vec::new();
    if mapped.is_empty() {
        return found;
    }
    for face in out.faces() {
        for (k, &a) in face.iter().enumerate() {
            let b = face[(k + 1) % face.len()];
            if let Some(value) = mapped.remove(&edge_key(a, b)) {
                found.push(([a, b], value));
                if mapped.is_empty() {
                    return found;
                }
            }
        }
    }
    found
}

/// The sharp edges of `out` (see [`carry_edges`]).
pub(crate) fn carry_sharp_edges(
    input: &Mesh,
    vertex_of: impl Fn(u32) -> u32,
    out: &Mesh,
) -> Vec<[u32; 2]> {
    carry_edges(
        input.sharp_edges.iter().map(|&e| (e, ())),
        vertex_of,
        out,
        |(), ()| (),
    )
    .into_iter()
    .map(|(e, ())| e)
    .collect()
}

/// The creases of `out` (see [`carry_edges`]); where several land on one edge, the sharpest.
pub(crate) fn carry_creases(
    input: &Mesh,
    vertex_of: impl Fn(u32) -> u32,
    out: &Mesh,
) -> Vec<Crease> {
    carry_edges(
        input.creases.iter().map(|c| ([c.a, c.b], c.value)),
        vertex_of,
        out,
        f32::max,
    )
    .into_iter()
    .map(|([a, b], value)| Crease { a, b, value })
    .collect()
}
