//! Sharp edges (Blender's `sharp_edge`: shading only, no effect on the surface) through
//! refinement: a sharp edge's two halves stay sharp at every level, so the refined mesh splits
//! its shading along the same lines as the cage.
//!
//! Only the schemes that split every edge at an edge point keep an edge's image as refined
//! edges — Catmull–Clark and bilinear (new vertices: face points, edge points, vertex points)
//! and Loop and Butterfly (edge points, vertex points). Doo–Sabin (a dual scheme: no refined
//! edge lies on a cage edge) and √3 (which flips the cage's edges) keep none, so they drop
//! sharp edges ([`carries_sharp_edges`]).
//!
//! Unlike creases, the halves are tracked apart from the stencils: marking an edge sharp for
//! shading must not change the refined positions.

use crate::Scheme;
use crate::halfedges::Halfedges;
use crate::topology::{Topology, edge_key};
use std::collections::HashSet;

/// Whether `scheme` keeps sharp edges (see the module docs).
pub fn carries_sharp_edges(scheme: Scheme) -> bool {
    matches!(
        scheme,
        Scheme::CatmullClark | Scheme::Bilinear | Scheme::Loop | Scheme::Butterfly
    )
}

/// One level of an edge-splitting scheme built on [`Topology`]: each sharp edge (a, b) of the
/// level becomes (vertex point of a, edge point) and (edge point, vertex point of b). Edge
/// point of edge `e` is `edge_points + e`, vertex point of `v` is `vertex_points + v`. Pairs
/// that are no edge of the level have no image and are left out.
pub(crate) fn split(
    topo: &Topology,
    sharp: &[[u32; 2]],
    edge_points: u32,
    vertex_points: u32,
) -> Vec<[u32; 2]> {
    let mut out = Vec::with_capacity(2 * sharp.len());
    for &[a, b] in sharp {
        let Some(&e) = topo
            .edges_of(a as usize)
            .iter()
            .find(|&&e| topo.other(e, a) == b)
        else {
            continue;
        };
        let m = edge_points + e;
        out.push([vertex_points + a, m]);
        out.push([m, vertex_points + b]);
    }
    out
}

/// The first level numbering of each edge-splitting scheme: (edge points, vertex points)
/// offsets for a level with `faces` faces and `edges` edges.
pub(crate) fn numbering(scheme: Scheme, faces: usize, edges: usize) -> (u32, u32) {
    match scheme {
        Scheme::Loop | Scheme::Butterfly => (0, edges as u32),
        _ => (faces as u32, (faces + edges) as u32),
    }
}

/// Catmull–Clark works on [`Halfedges`], whose edge `e` splits into edges `2e` and `2e + 1`
/// of the next level: sharp edges are followed as edge indices from the cage on.
pub(crate) struct HalfedgeSharp {
    /// Sharp edges of the current level, as edge indices.
    edges: Vec<u32>,
}

impl HalfedgeSharp {
    /// The edge indices of `sharp`'s pairs in the cage's halfedges (pairs that are no edge are
    /// left out; a pair given twice, in either order, counts once).
    pub(crate) fn new(h: &Halfedges, sharp: &[[u32; 2]]) -> HalfedgeSharp {
        let wanted: HashSet<u64> = sharp.iter().map(|&[a, b]| edge_key(a, b)).collect();
        let edges = (0..h.edge_count() as u32)
            .filter(|&e| {
                let c = h.edge_corner[e as usize];
                wanted.contains(&edge_key(h.vert(c), h.vert(h.next(c))))
            })
            .collect();
        HalfedgeSharp { edges }
    }

    /// Follows one refinement of the halfedges (not the last).
    pub(crate) fn refine(&mut self) {
        self.edges = self
            .edges
            .iter()
            .flat_map(|&e| [2 * e, 2 * e + 1])
            .collect();
    }

    /// The sharp edges of the level refined from `h` (the last one, which is built as faces
    /// only), as vertex pairs.
    pub(crate) fn last(&self, h: &Halfedges) -> Vec<[u32; 2]> {
        let (nf, ne) = (h.faces.len() as u32, h.edge_count() as u32);
        let mut out = Vec::with_capacity(2 * self.edges.len());
        for &e in &self.edges {
            let c = h.edge_corner[e as usize];
            let (a, b) = (h.vert(c), h.vert(h.next(c)));
            let m = nf + e;
            out.push([nf + ne + a, m]);
            out.push([m, nf + ne + b]);
        }
        out
    }
}
