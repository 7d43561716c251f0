//! The modified Butterfly scheme (Zorin, Schröder, Sweldens 1996), one level (paper 002,
//! section 1.4.7, "Subdivision de Butterfly": interpolating, primal, triangles).
//!
//! Old vertices keep their positions; every edge gets one new point; triangles split in four
//! exactly as Loop's ([`crate::loop_scheme::split_triangles`]: edge points first, then the old
//! vertices). A vertex is *smooth* when it is interior, manifold, on no sharp edge, of valence
//! 3 or more. Edge points:
//! - both ends smooth of valence 6: the 8-point butterfly
//!   `1/2 (a + b) + 1/8 (c + d) − 1/16 (e + f + g + h)` (it reproduces cubics; section 1.4.7
//!   prints `1/3` for the `1/8` and `+1/16` for the `−1/16`);
//! - one smooth end of valence `k ≠ 6` (the other smooth of valence 6, or not smooth at all):
//!   Zorin's `k`-point stencil around it, `3/4` at the centre and `s_j` at the `j`-th
//!   neighbour counted from the edge's other end ([`extraordinary_weights`]);
//!   both ends smooth and extraordinary: the mean of their two stencils;
//! - sharp edges (boundary edges and creases): the 4-point curve rule
//!   `(−1, 9, 9, −1)/16` along the boundary / crease polyline, continued through vertices on
//!   exactly two sharp edges; where the polyline ends (a corner, a dart tip, three or more sharp
//!   edges, or a single-face vertex under [`Boundary::EdgeAndCorner`]) the edge takes its
//!   midpoint. Semi-sharp creases lose one per level and, in their last sharp level, blend the
//!   curve rule with the smooth one by their fractional sharpness, as Loop does.
//!
//! **Interior edges touching a boundary or crease** (our choice: the 1996 paper gives interior
//! rules only, and the later boundary masks are not used). An end that is smooth and
//! extraordinary still gives its `k`-point stencil, which reads only its own complete ring.
//! Otherwise the edge takes the 8-point butterfly on what it has, each missing wing — the far
//! corner of the triangle across a boundary or sharp edge `(x, y)` — replaced by its
//! regular-lattice ghost `x + y − o`, `o` the corner of the edge's own face opposite
//! `(x, y)`. Weights still sum to 1, linear data are reproduced exactly (the grid stays a
//! lattice up to its border), and the two sides of a crease never read each other.

use crate::boundary::Boundary;
use crate::crease_rules::{self, Phase, Rule};
use crate::error::SubdivError;
use crate::level::{Level, RowBuilder, table_for};
use crate::loop_scheme::{check_triangles, third, triangle_level};
use crate::topology::{Faces, NONE, Topology};

/// Zorin's weights `s_0 .. s_{k−1}` for the neighbours of a smooth extraordinary vertex of
/// valence `k ≥ 3`, `s_0` at the edge's other end, going round; the centre takes `3/4`.
/// `k = 3`: 5/12, −1/12, −1/12; `k = 4`: 3/8, 0, −1/8, 0; `k ≥ 5`:
/// `s_j = (1/4 + cos(2πj/k) + 1/2 cos(4πj/k)) / k`.
pub fn extraordinary_weights(k: usize) -> Vec<f64> {
    match k {
        0..=2 => Vec::new(),
        3 => vec![5.0 / 12.0, -1.0 / 12.0, -1.0 / 12.0],
        4 => vec![0.375, 0.0, -0.125, 0.0],
        _ => {
            let kf = k as f64;
            (0..k)
                .map(|j| {
                    let t = 2.0 * std::f64::consts::PI * j as f64 / kf;
                    (0.25 + t.cos() + 0.5 * (2.0 * t).cos()) / kf
                })
                .collect()
        }
    }
}

/// Refines the triangles `faces` (with adjacency `topo`) one level.
///
/// # Errors
/// [`SubdivError::NotTriangles`] when a face is not a triangle.
pub fn refine(faces: &Faces, topo: &Topology, boundary: Boundary) -> Result<Level, SubdivError> {
    check_triangles(faces, "butterfly")?;
    let (ne, nv) = (topo.edge_vertices.len(), faces.vertex_count as usize);
    let ctx = Ctx {
        faces,
        topo,
        boundary,
        rings: Rings::build(faces, topo, boundary),
    };
    let mut table = table_for(faces.vertex_count, ne + nv);
    let mut row = RowBuilder::default();
    for e in 0..ne {
        ctx.edge_point(e, &mut row);
        row.push_to(&mut table);
    }
    for v in 0..nv as u32 {
        row.add(v, 1.0);
        row.push_to(&mut table);
    }
    Ok(triangle_level(faces, topo, table))
}

/// The neighbours of every smooth vertex in cyclic order (CSR; an empty ring: not smooth).
struct Rings {
    offsets: Vec<u32>,
    ring: Vec<u32>,
}

impl Rings {
    fn build(faces: &Faces, topo: &Topology, boundary: Boundary) -> Rings {
        let nv = faces.vertex_count as usize;
        let mut r = Rings {
            offsets: Vec::with_capacity(nv + 1),
            ring: Vec::new(),
        };
        r.offsets.push(0);
        for v in 0..nv {
            let start = r.ring.len();
            if !walk_ring(faces, topo, v, boundary, &mut r.ring) {
                r.ring.truncate(start);
            }
            r.offsets.push(r.ring.len() as u32);
        }
        r
    }

    /// The ring of `v`, `None` when `v` is not smooth.
    fn of(&self, v: u32) -> Option<&[u32]> {
        let (s, e) = (
            self.offsets[v as usize] as usize,
            self.offsets[v as usize + 1] as usize,
        );
        (e > s).then(|| &self.ring[s..e])
    }
}

/// Appends the neighbours of `v` in cyclic order (either way round: the stencils are
/// symmetric) and returns true when `v` is smooth; false otherwise (what it appended is
/// dropped).
fn walk_ring(
    faces: &Faces,
    topo: &Topology,
    v: usize,
    boundary: Boundary,
    out: &mut Vec<u32>,
) -> bool {
    let edges = topo.edges_of(v);
    let adjacent = topo.faces_of(v);
    let k = edges.len();
    if k < 3
        || adjacent.len() != k
        || edges
            .iter()
            .any(|&e| topo.is_boundary(e) || topo.edge_sharpness[e as usize] > 0.0)
        || crease_rules::vertex_rule(topo, v, boundary, Phase::Parent) != Rule::Smooth
    {
        return false;
    }
    let vv = v as u32;
    let mut used = vec![false; k];
    let mut cur = topo.other(edges[0], vv);
    for _ in 0..k {
        out.push(cur);
        let next = adjacent.iter().enumerate().find_map(|(i, &f)| {
            let c = faces.face(f as usize);
            (!used[i] && c.contains(&cur)).then(|| (i, third(c, vv, cur)))
        });
        let Some((i, n)) = next else { return false };
        used[i] = true;
        cur = n;
    }
    // Closed after k steps, every neighbour once.
    let ring = &out[out.len() - k..];
    cur == ring[0] && (1..k).all(|i| !ring[..i].contains(&ring[i]))
}

struct Ctx<'a> {
    faces: &'a Faces,
    topo: &'a Topology,
    boundary: Boundary,
    rings: Rings,
}

impl Ctx<'_> {
    fn edge_point(&self, e: usize, row: &mut RowBuilder) {
        let sharp = if self.topo.is_boundary(e as u32) {
            1.0
        } else {
            crease_rules::edge_sharp_weight(self.topo.edge_sharpness[e])
        };
        if sharp > 0.0 {
            self.curve(e, row, sharp);
        }
        if sharp < 1.0 {
            self.smooth(e, row, 1.0 - sharp);
        }
    }

    /// The next vertex after `v` along the sharp polyline through edge `e`, when `v` is on
    /// exactly two sharp edges (not a corner).
    fn along(&self, e: usize, v: u32) -> Option<u32> {
        let rule = crease_rules::vertex_rule(self.topo, v as usize, self.boundary, Phase::Parent);
        if rule != Rule::Crease {
            return None;
        }
        crease_rules::sharp_edges(self.topo, v as usize, Phase::Parent)
            .find(|&o| o as usize != e)
            .map(|o| self.topo.other(o, v))
    }

    /// Adds `w` times the 4-point rule along the sharp polyline (midpoint where it ends).
    fn curve(&self, e: usize, row: &mut RowBuilder, w: f64) {
        let [a, b] = self.topo.edge_vertices[e];
        match (self.along(e, a), self.along(e, b)) {
            (Some(p), Some(q)) => {
                row.add(p, -w / 16.0);
                row.add(a, 9.0 * w / 16.0);
                row.add(b, 9.0 * w / 16.0);
                row.add(q, -w / 16.0);
            }
            _ => {
                row.add(a, 0.5 * w);
                row.add(b, 0.5 * w);
            }
        }
    }

    /// Adds `w` times the smooth (butterfly) rule of the two-face edge `e`.
    fn smooth(&self, e: usize, row: &mut RowBuilder, w: f64) {
        let [a, b] = self.topo.edge_vertices[e];
        let odd = |v: u32| self.rings.of(v).filter(|r| r.len() != 6);
        match (odd(a), odd(b)) {
            (Some(ra), Some(rb)) => {
                self.zorin(a, ra, b, row, 0.5 * w);
                self.zorin(b, rb, a, row, 0.5 * w);
            }
            (Some(ra), None) => self.zorin(a, ra, b, row, w),
            (None, Some(rb)) => self.zorin(b, rb, a, row, w),
            (None, None) => self.butterfly(e, row, w),
        }
    }

    /// Adds `w` times Zorin's stencil of smooth vertex `v` (ring `ring`) for its edge to `to`.
    fn zorin(&self, v: u32, ring: &[u32], to: u32, row: &mut RowBuilder, w: f64) {
        let k = ring.len();
        let at = ring
            .iter()
            .position(|&x| x == to)
            .expect("a ring neighbour");
        row.add(v, 0.75 * w);
        for (j, s) in extraordinary_weights(k).into_iter().enumerate() {
            if s != 0.0 {
                row.add(ring[(at + j) % k], s * w);
            }
        }
    }

    /// Adds `w` times the 8-point butterfly, missing wings replaced by lattice ghosts.
    fn butterfly(&self, e: usize, row: &mut RowBuilder, w: f64) {
        let [a, b] = self.topo.edge_vertices[e];
        let [f0, f1] = self.topo.edge_faces[e];
        row.add(a, 0.5 * w);
        row.add(b, 0.5 * w);
        for f in [f0, f1] {
            let c = third(self.faces.face(f as usize), a, b);
            row.add(c, 0.125 * w);
            self.wing(f, a, c, b, row, -w / 16.0);
            self.wing(f, b, c, a, row, -w / 16.0);
        }
    }

    /// Adds `w` times the vertex across edge `(x, y)` of face `f` (whose third corner is
    /// `o`), or its ghost `x + y − o` when that edge is a boundary or sharp.
    fn wing(&self, f: u32, x: u32, y: u32, o: u32, row: &mut RowBuilder, w: f64) {
        let base = self.faces.offsets[f as usize] as usize;
        let edge = self.topo.corner_edge[base..base + 3]
            .iter()
            .copied()
            .find(|&g| {
                let [p, q] = self.topo.edge_vertices[g as usize];
                (p == x && q == y) || (p == y && q == x)
            })
            .expect("an edge of the face");
        let [g0, g1] = self.topo.edge_faces[edge as usize];
        let across = if g0 == f { g1 } else { g0 };
        if across == NONE || self.topo.edge_sharpness[edge as usize] > 0.0 {
            row.add(x, w);
            row.add(y, w);
            row.add(o, -w);
        } else {
            row.add(third(self.faces.face(across as usize), x, y), w);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extraordinary_weights_sum_to_a_quarter() {
        for k in 3..=12 {
            let s: f64 = extraordinary_weights(k).iter().sum();
            assert!((0.75 + s - 1.0).abs() < 1e-12, "k = {k}: {s}");
        }
        // At k = 6 the formula is symmetric with s_1 = 1/12.
        let s6 = extraordinary_weights(6);
        assert!((s6[1] - 1.0 / 12.0).abs() < 1e-12 && (s6[1] - s6[5]).abs() < 1e-12);
    }

    /// A regular octahedron's faces (valence 4 everywhere).
    fn octahedron() -> Faces {
        // Vertices: 0 +x, 1 −x, 2 +y, 3 −y, 4 +z, 5 −z.
        let tris: [[u32; 3]; 8] = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        Faces {
            offsets: (0..=8).map(|f| 3 * f).collect(),
            indices: tris.concat(),
            vertex_count: 6,
        }
    }

    #[test]
    fn valence_four_stencils_and_old_vertices() {
        let f = octahedron();
        let t = Topology::build(&f, &[]).unwrap();
        let level = refine(&f, &t, Boundary::EdgeOnly).unwrap();
        let ne = t.edge_vertices.len();
        for v in 0..6 {
            assert_eq!(
                level.table.row(ne + v).collect::<Vec<_>>(),
                vec![(v as u32, 1.0)]
            );
        }
        // Edge (0, 2): both ends valence 4, the mean of their stencils: each end
        // (3/4 + 3/8)/2 = 9/16, the far neighbour of each ring −1/8 · 1/2.
        let e = t.edge_vertices.iter().position(|&x| x == [0, 2]).unwrap();
        let r: Vec<(u32, f32)> = level.table.row(e).collect();
        assert_eq!(
            r,
            vec![(0, 0.5625), (1, -0.0625), (2, 0.5625), (3, -0.0625)]
        );
    }
}
