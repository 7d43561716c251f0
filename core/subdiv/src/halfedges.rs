//! Corner (half-edge) connectivity refined by index arithmetic, the topology phase of
//! Catmull–Clark without any sorting or hashing after the cage.
//!
//! A corner `h` of face `f` is the half-edge leaving `vert[h]` towards the next corner. After
//! one Catmull–Clark step, corner `h` becomes the quad `4h..4h + 4` (vertex point, edge
//! point, face point, previous edge point), so every array of the next level is a closed-form
//! function of this level's (Dupuy & Vanhoey, "A halfedge refinement rule for parallel
//! Catmull–Clark subdivision", HPG 2021): no search, one pass, trivially parallel. Only the cage
//! is sorted once (through [`Topology::build`]) to pair its corners into twins.

use crate::error::SubdivError;
use crate::sharpness::{INFINITELY_SHARP, decrement};
use crate::topology::{Faces, NONE, Topology};
use rayon::prelude::*;

/// Elements per parallel task: each is a few loads and stores.
const CHUNK: usize = 1 << 14;

/// Connectivity of one level, by corner.
#[derive(Clone, Debug, Default)]
pub struct Halfedges {
    /// The faces (corner `h`'s vertex is `faces.indices[h]`).
    pub faces: Faces,
    /// Face of each corner; empty when every face is a quad (then it is `h / 4`).
    corner_face: Vec<u32>,
    /// The opposite corner across each corner's edge; [`NONE`] on a boundary.
    pub twin: Vec<u32>,
    /// Edge of each corner.
    pub edge: Vec<u32>,
    /// One corner of each edge; the edge runs from its vertex to the next corner's.
    pub edge_corner: Vec<u32>,
    /// Sharpness of each edge ([`INFINITELY_SHARP`] on boundaries).
    pub edge_sharpness: Vec<f32>,
    /// One corner leaving each vertex; on a boundary the one whose edge is a boundary, so
    /// that turning with [`Halfedges::turn`] visits every face around it.
    pub vertex_corner: Vec<u32>,
    /// Vertices whose faces do not form a single fan (non-manifold): refined as corners.
    pub vertex_pinned: Vec<bool>,
}

impl Halfedges {
    /// The cage's connectivity: corners paired into twins through the sorted edge list.
    /// Edges whose two faces disagree on orientation are treated as infinitely sharp (their
    /// corners have no twin), as OpenSubdiv treats them as non-manifold.
    ///
    /// # Errors
    /// Those of [`Topology::build`], and isolated vertices (no face uses them).
    pub fn from_cage(faces: &Faces, creases: &[([u32; 2], f32)]) -> Result<Halfedges, SubdivError> {
        let topo = Topology::build(faces, creases)?;
        let corners = faces.indices.len();
        let ne = topo.edge_vertices.len();
        let mut h = Halfedges {
            faces: faces.clone(),
            corner_face: Vec::new(),
            twin: vec![NONE; corners],
            edge: topo.corner_edge.clone(),
            edge_corner: vec![NONE; ne],
            edge_sharpness: topo.edge_sharpness.clone(),
            vertex_corner: vec![NONE; faces.vertex_count as usize],
            vertex_pinned: vec![false; faces.vertex_count as usize],
        };
        if faces
            .offsets
            .iter()
            .enumerate()
            .any(|(f, &o)| o as usize != 4 * f)
        {
            h.corner_face = (0..faces.len() as u32)
                .flat_map(|f| {
                    let n = faces.offsets[f as usize + 1] - faces.offsets[f as usize];
                    std::iter::repeat_n(f, n as usize)
                })
                .collect();
        }
        for c in 0..corners as u32 {
            let e = h.edge[c as usize] as usize;
            match h.edge_corner[e] {
                NONE => h.edge_corner[e] = c,
                first if h.vert(first) != h.vert(c) => {
                    h.twin[first as usize] = c;
                    h.twin[c as usize] = first;
                }
                // Same direction in both faces: inconsistent orientation.
                _ => h.edge_sharpness[e] = INFINITELY_SHARP,
            }
        }
        let mut corners_at = vec![0u32; faces.vertex_count as usize];
        for c in 0..corners as u32 {
            let v = h.vert(c) as usize;
            corners_at[v] += 1;
            if h.vertex_corner[v] == NONE || h.twin[c as usize] == NONE {
                h.vertex_corner[v] = c;
            }
        }
        if let Some(v) = h.vertex_corner.iter().position(|&c| c == NONE) {
            return Err(SubdivError::IsolatedVertex { vertex: v });
        }
        let pinned: Vec<bool> = h
            .vertex_corner
            .iter()
            .zip(&corners_at)
            .map(|(&c, &n)| h.fan_len(c) != n as usize)
            .collect();
        h.vertex_pinned = pinned;
        Ok(h)
    }

    /// Vertex at corner `h`.
    #[inline]
    pub fn vert(&self, h: u32) -> u32 {
        self.faces.indices[h as usize]
    }

    /// Face of corner `h`.
    #[inline]
    pub fn face(&self, h: u32) -> u32 {
        if self.corner_face.is_empty() {
            h >> 2
        } else {
            self.corner_face[h as usize]
        }
    }

    /// Corners of face `f`.
    #[inline]
    pub fn face_corners(&self, f: u32) -> std::ops::Range<u32> {
        if self.corner_face.is_empty() {
            4 * f..4 * f + 4
        } else {
            self.faces.offsets[f as usize]..self.faces.offsets[f as usize + 1]
        }
    }

    /// The next corner of the same face.
    #[inline]
    pub fn next(&self, h: u32) -> u32 {
        if self.corner_face.is_empty() {
            (h & !3) | ((h + 1) & 3)
        } else {
            let r = self.face_corners(self.face(h));
            if h + 1 == r.end { r.start } else { h + 1 }
        }
    }

    /// The previous corner of the same face.
    #[inline]
    pub fn prev(&self, h: u32) -> u32 {
        if self.corner_face.is_empty() {
            (h & !3) | (h.wrapping_sub(1) & 3)
        } else {
            let r = self.face_corners(self.face(h));
            if h == r.start { r.end - 1 } else { h - 1 }
        }
    }

    /// The next corner leaving the same vertex, turning across the previous edge; [`NONE`]
    /// past a boundary.
    #[inline]
    pub fn turn(&self, h: u32) -> u32 {
        self.twin[self.prev(h) as usize]
    }

    /// Faces visited turning from `start` until back or past a boundary.
    fn fan_len(&self, start: u32) -> usize {
        let mut n = 0;
        let mut h = start;
        loop {
            n += 1;
            h = self.turn(h);
            if h == NONE || h == start {
                return n;
            }
        }
    }

    /// True when edge `e` has one face (or two that disagree on orientation).
    #[inline]
    pub fn is_boundary(&self, e: u32) -> bool {
        self.twin[self.edge_corner[e as usize] as usize] == NONE
    }

    /// Number of edges.
    pub fn edge_count(&self) -> usize {
        self.edge_corner.len()
    }

    /// The connectivity after one Catmull–Clark step. New vertices are numbered face points,
    /// then edge points (`F + e`), then vertex points (`F + E + v`); parent corner `h` gives
    /// the quad `4h..4h + 4` = (vertex point of `vert[h]`, edge point of `edge[h]`, face point,
    /// edge point of `edge[prev h]`); edge `e` splits into `2e` (the half at its
    /// `edge_corner`'s vertex) and `2e + 1`; corner `h` adds the edge `2E + h` from its edge
    /// point to its face point. Sharpness decreases by one per level (uniform creasing).
    pub fn refine(&self) -> Halfedges {
        let corners = self.faces.indices.len();
        let (nf, ne) = (self.faces.len() as u32, self.edge_count() as u32);
        let faces = self.refine_faces();
        let mut twin = vec![0u32; 4 * corners];
        let mut edge = vec![0u32; 4 * corners];
        // The half of edge `e` at vertex `v` (by vertex, not corner, so that edges whose faces
        // disagree on orientation split consistently too).
        let half = |e: u32, v: u32| 2 * e + u32::from(self.vert(self.edge_corner[e as usize]) != v);
        (
            twin.par_chunks_mut(4 * CHUNK),
            edge.par_chunks_mut(4 * CHUNK),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(task, (twin, edge))| {
                for (i, (t, e)) in twin
                    .chunks_exact_mut(4)
                    .zip(edge.chunks_exact_mut(4))
                    .enumerate()
                {
                    let h = (task * CHUNK + i) as u32;
                    let p = self.prev(h);
                    let (th, tp) = (self.twin[h as usize], self.twin[p as usize]);
                    t.copy_from_slice(&[
                        if th == NONE {
                            NONE
                        } else {
                            4 * self.next(th) + 3
                        },
                        4 * self.next(h) + 2,
                        4 * p + 1,
                        if tp == NONE { NONE } else { 4 * tp },
                    ]);
                    let at = self.vert(h);
                    e.copy_from_slice(&[
                        half(self.edge[h as usize], at),
                        2 * ne + h,
                        2 * ne + p,
                        half(self.edge[p as usize], at),
                    ]);
                }
            });
        let mut edge_corner = vec![0u32; 2 * ne as usize + corners];
        let mut edge_sharpness = vec![0.0f32; 2 * ne as usize + corners];
        for e in 0..ne as usize {
            let c = self.edge_corner[e];
            edge_corner[2 * e] = 4 * c;
            edge_corner[2 * e + 1] = 4 * self.next(c) + 3;
            let s = decrement(self.edge_sharpness[e]);
            edge_sharpness[2 * e] = s;
            edge_sharpness[2 * e + 1] = s;
        }
        for h in 0..corners {
            edge_corner[2 * ne as usize + h] = 4 * h as u32 + 1;
        }
        let mut vertex_corner = Vec::with_capacity(faces.vertex_count as usize);
        vertex_corner.extend((0..nf).map(|f| 4 * self.face_corners(f).start + 2));
        vertex_corner.extend(self.edge_corner.iter().map(|&c| {
            if self.twin[c as usize] == NONE {
                4 * self.next(c) + 3
            } else {
                4 * c + 1
            }
        }));
        vertex_corner.extend(self.vertex_corner.iter().map(|&c| 4 * c));
        let mut vertex_pinned = vec![false; (nf + ne) as usize];
        vertex_pinned.extend_from_slice(&self.vertex_pinned);
        Halfedges {
            faces,
            corner_face: Vec::new(),
            twin,
            edge,
            edge_corner,
            edge_sharpness,
            vertex_corner,
            vertex_pinned,
        }
    }

    /// Only the faces of [`Halfedges::refine`] (for the last level, where no further step
    /// needs the rest of the connectivity).
    pub fn refine_faces(&self) -> Faces {
        let corners = self.faces.indices.len();
        let (nf, ne) = (self.faces.len() as u32, self.edge_count() as u32);
        let (fp, ep, vp) = (0, nf, nf + ne);
        let mut vert = vec![0u32; 4 * corners];
        vert.par_chunks_mut(4 * CHUNK)
            .enumerate()
            .for_each(|(task, vert)| {
                for (i, v) in vert.chunks_exact_mut(4).enumerate() {
                    let h = (task * CHUNK + i) as u32;
                    let p = self.prev(h);
                    v.copy_from_slice(&[
                        vp + self.vert(h),
                        ep + self.edge[h as usize],
                        fp + self.face(h),
                        ep + self.edge[p as usize],
                    ]);
                }
            });
        Faces {
            offsets: (0..=4 * corners as u32).step_by(4).collect(),
            indices: vert,
            vertex_count: nf + ne + self.faces.vertex_count,
        }
    }

    /// The sharp edges [`Halfedges::refine`] would give, without building it: both halves
    /// of each sharp non-boundary edge, sharpness decremented.
    pub fn refined_creases(&self) -> Vec<([u32; 2], f32)> {
        let (ep, vp) = (
            self.faces.len() as u32,
            (self.faces.len() + self.edge_count()) as u32,
        );
        let mut out = Vec::new();
        for e in 0..self.edge_count() as u32 {
            let s = decrement(self.edge_sharpness[e as usize]);
            if s > 0.0 && !self.is_boundary(e) {
                let c = self.edge_corner[e as usize];
                let (a, b) = (self.vert(c), self.vert(self.next(c)));
                out.push(([vp + a, ep + e], s));
                out.push(([ep + e, vp + b], s));
            }
        }
        out
    }

    /// Sharp edges that are not boundaries, as ((a, b), sharpness).
    pub fn creases(&self) -> Vec<([u32; 2], f32)> {
        (0..self.edge_count() as u32)
            .filter(|&e| self.edge_sharpness[e as usize] > 0.0 && !self.is_boundary(e))
            .map(|e| {
                let c = self.edge_corner[e as usize];
                (
                    [self.vert(c), self.vert(self.next(c))],
                    self.edge_sharpness[e as usize],
                )
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed cube: 6 quads.
    fn cube() -> Faces {
        Faces {
            offsets: (0..=24).step_by(4).collect(),
            indices: vec![
                0, 3, 2, 1, 4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7,
            ],
            vertex_count: 8,
        }
    }

    /// Every invariant the arithmetic must keep: twins are mutual and reversed, each corner's
    /// edge has it or its twin as `edge_corner`, and turning around every vertex visits all of
    /// its corners.
    fn check(h: &Halfedges) {
        let n = h.faces.indices.len() as u32;
        let mut seen_edge = vec![0; h.edge_count()];
        for c in 0..n {
            let t = h.twin[c as usize];
            if t != NONE {
                assert_eq!(h.twin[t as usize], c);
                assert_eq!(h.vert(t), h.vert(h.next(c)));
                assert_eq!(h.edge[t as usize], h.edge[c as usize]);
            }
            let e = h.edge[c as usize] as usize;
            seen_edge[e] += 1;
            let ec = h.edge_corner[e];
            assert!(ec == c || ec == t, "corner {c}: edge {e} has corner {ec}");
        }
        assert!(seen_edge.iter().all(|&k| k == 1 || k == 2));
        let mut at = vec![0; h.faces.vertex_count as usize];
        (0..n).for_each(|c| at[h.vert(c) as usize] += 1);
        for (v, &c) in h.vertex_corner.iter().enumerate() {
            assert_eq!(h.vert(c) as usize, v);
            assert_eq!(h.fan_len(c), at[v], "vertex {v}");
        }
    }

    #[test]
    fn refined_connectivity_equals_a_rebuilt_one() {
        // An open mesh with n-gons: the cube without its top, vertex 8 added on edge (1, 2)
        // so that the bottom and one side are pentagons.
        let faces = Faces {
            offsets: vec![0, 5, 9, 14, 18, 22],
            indices: vec![
                0, 3, 2, 8, 1, 0, 1, 5, 4, 1, 8, 2, 6, 5, 2, 3, 7, 6, 3, 0, 4, 7,
            ],
            vertex_count: 9,
        };
        let mut level = Halfedges::from_cage(&faces, &[([0, 1], 2.5)]).unwrap();
        for _ in 0..3 {
            check(&level);
            let next = level.refine();
            let rebuilt = Topology::build(&next.faces, &next.creases()).unwrap();
            assert_eq!(rebuilt.edge_vertices.len(), next.edge_count());
            let boundary = (0..next.edge_count() as u32)
                .filter(|&e| next.is_boundary(e))
                .count();
            let rebuilt_boundary = (0..rebuilt.edge_vertices.len() as u32)
                .filter(|&e| rebuilt.is_boundary(e))
                .count();
            assert_eq!(boundary, rebuilt_boundary);
            level = next;
        }
        check(&level);
    }

    #[test]
    fn cube_levels_count_like_euler() {
        let mut h = Halfedges::from_cage(&cube(), &[]).unwrap();
        for _ in 0..3 {
            h = h.refine();
            let (v, e, f) = (
                h.faces.vertex_count as i64,
                h.edge_count() as i64,
                h.faces.len() as i64,
            );
            assert_eq!(v - e + f, 2);
            assert!(h.twin.iter().all(|&t| t != NONE));
        }
        check(&h);
    }

    #[test]
    fn bowties_and_isolated_vertices() {
        // Two triangles meeting at vertex 0 only.
        let bowtie = Faces {
            offsets: vec![0, 3, 6],
            indices: vec![0, 1, 2, 0, 3, 4],
            vertex_count: 6,
        };
        assert_eq!(
            Halfedges::from_cage(&bowtie, &[]).unwrap_err(),
            SubdivError::IsolatedVertex { vertex: 5 }
        );
        let bowtie = Faces {
            vertex_count: 5,
            ..bowtie
        };
        let h = Halfedges::from_cage(&bowtie, &[]).unwrap();
        assert!(h.vertex_pinned[0] && !h.vertex_pinned[1]);
    }
}
