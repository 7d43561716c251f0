//! The adjacency every scheme's topology phase reads: unique edges with their faces and
//! sharpness, and for each vertex its incident edges and faces.
//!
//! Built by one sort of the face corners' edge keys, so it costs O(corners log corners) and a
//! few flat arrays, no hashing.

use crate::boundary::Boundary;
use crate::error::SubdivError;
use crate::sharpness::INFINITELY_SHARP;

/// A polygon mesh's faces, without positions: what refinement changes level to level.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Faces {
    /// Face `f` uses `indices[offsets[f]..offsets[f + 1]]`.
    pub offsets: Vec<u32>,
    /// Vertex of each corner.
    pub indices: Vec<u32>,
    /// Vertices (some may be unused).
    pub vertex_count: u32,
}

impl Faces {
    /// Number of faces.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no faces.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The corners of face `f`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.indices[self.offsets[f] as usize..self.offsets[f + 1] as usize]
    }
}

/// Edges and incidence of one level.
#[derive(Clone, Debug, Default)]
pub struct Topology {
    /// Endpoints of each edge, lower index first.
    pub edge_vertices: Vec<[u32; 2]>,
    /// Faces of each edge: one (boundary) or two; `u32::MAX` marks a missing second face.
    pub edge_faces: Vec<[u32; 2]>,
    /// Sharpness of each edge (boundary edges: [`INFINITELY_SHARP`]).
    pub edge_sharpness: Vec<f32>,
    /// Edge of each face corner: corner `k` of face `f` (at `offsets[f] + k`) starts the edge
    /// to the next corner.
    pub corner_edge: Vec<u32>,
    /// Edges around each vertex, in CSR form (`vertex_edge_offsets` has vertices + 1 entries).
    pub vertex_edge_offsets: Vec<u32>,
    /// The edges listed by `vertex_edge_offsets`.
    pub vertex_edges: Vec<u32>,
    /// Faces around each vertex, in CSR form.
    pub vertex_face_offsets: Vec<u32>,
    /// The faces listed by `vertex_face_offsets`.
    pub vertex_faces: Vec<u32>,
}

/// No face.
pub const NONE: u32 = u32::MAX;

/// The faces around one vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VertexFan {
    /// Faces using the vertex.
    pub faces: usize,
    /// Boundary edges at the vertex.
    pub boundary_edges: usize,
    /// True when the faces form one fan: closed (interior) or open between two boundary
    /// edges.
    pub manifold: bool,
}

impl VertexFan {
    /// True when the vertex is a corner whatever the sharpness of its edges: not one fan, or a
    /// boundary vertex of a single face under [`Boundary::EdgeAndCorner`].
    pub fn is_corner(&self, boundary: Boundary) -> bool {
        !self.manifold
            || (boundary == Boundary::EdgeAndCorner && self.boundary_edges > 0 && self.faces == 1)
    }
}

impl Topology {
    /// Builds the adjacency of `faces`, with sharpness from `creases` ((a, b), sharpness).
    ///
    /// # Errors
    /// A degenerate face, an edge with more than two faces, or a crease on a non-edge.
    pub fn build(faces: &Faces, creases: &[([u32; 2], f32)]) -> Result<Topology, SubdivError> {
        let nv = faces.vertex_count as usize;
        // (edge key, corner) for every corner; sorting groups the corners of one edge.
        let mut keyed: Vec<(u64, u32)> = Vec::with_capacity(faces.indices.len());
        for f in 0..faces.len() {
            let c = faces.face(f);
            if c.len() < 3 {
                return Err(SubdivError::DegenerateFace {
                    face: f,
                    why: format!("{} corners", c.len()),
                });
            }
            let base = faces.offsets[f];
            for k in 0..c.len() {
                let (a, b) = (c[k], c[(k + 1) % c.len()]);
                if a == b || c[..k].contains(&a) {
                    return Err(SubdivError::DegenerateFace {
                        face: f,
                        why: format!("it uses vertex {a} twice"),
                    });
                }
                keyed.push((edge_key(a, b), base + k as u32));
            }
        }
        keyed.sort_unstable();
        let face_of_corner = corner_faces(faces);
        let mut t = Topology {
            corner_edge: vec![0; faces.indices.len()],
            ..Topology::default()
        };
        let mut i = 0;
        while i < keyed.len() {
            let key = keyed[i].0;
            let mut j = i;
            while j < keyed.len() && keyed[j].0 == key {
                j += 1;
            }
            let (a, b) = ((key >> 32) as u32, key as u32);
            if j - i > 2 {
                return Err(SubdivError::NonManifoldEdge { a, b, faces: j - i });
            }
            let e = t.edge_vertices.len() as u32;
            let mut ef = [NONE; 2];
            for (slot, &(_, corner)) in keyed[i..j].iter().enumerate() {
                t.corner_edge[corner as usize] = e;
                ef[slot] = face_of_corner[corner as usize];
            }
            t.edge_vertices.push([a, b]);
            t.edge_faces.push(ef);
            t.edge_sharpness
                .push(if j - i == 1 { INFINITELY_SHARP } else { 0.0 });
            i = j;
        }
        for (index, &([a, b], s)) in creases.iter().enumerate() {
            let key = edge_key(a, b);
            let e = t
                .edge_vertices
                .binary_search_by_key(&key, |v| edge_key(v[0], v[1]))
                .map_err(|_| SubdivError::CreaseNotAnEdge { index, a, b })?;
            let sh = &mut t.edge_sharpness[e];
            *sh = sh.max(s.clamp(0.0, INFINITELY_SHARP));
        }
        let (o, l) = csr(
            nv,
            t.edge_vertices
                .iter()
                .enumerate()
                .flat_map(|(e, v)| [(v[0], e as u32), (v[1], e as u32)]),
        );
        (t.vertex_edge_offsets, t.vertex_edges) = (o, l);
        let (o, l) = csr(
            nv,
            faces
                .indices
                .iter()
                .zip(&face_of_corner)
                .map(|(&v, &f)| (v, f)),
        );
        (t.vertex_face_offsets, t.vertex_faces) = (o, l);
        Ok(t)
    }

    /// Edges around vertex `v`.
    pub fn edges_of(&self, v: usize) -> &[u32] {
        &self.vertex_edges
            [self.vertex_edge_offsets[v] as usize..self.vertex_edge_offsets[v + 1] as usize]
    }

    /// Faces around vertex `v`.
    pub fn faces_of(&self, v: usize) -> &[u32] {
        &self.vertex_faces
            [self.vertex_face_offsets[v] as usize..self.vertex_face_offsets[v + 1] as usize]
    }

    /// The other end of edge `e` seen from `v`.
    pub fn other(&self, e: u32, v: u32) -> u32 {
        let [a, b] = self.edge_vertices[e as usize];
        if a == v { b } else { a }
    }

    /// How the faces around vertex `v` lie.
    pub fn fan(&self, v: usize) -> VertexFan {
        let edges = self.edges_of(v);
        let faces = self.faces_of(v).len();
        let boundary_edges = edges.iter().filter(|&&e| self.is_boundary(e)).count();
        let manifold = if boundary_edges == 0 {
            faces == edges.len()
        } else {
            boundary_edges == 2 && faces + 1 == edges.len()
        };
        VertexFan {
            faces,
            boundary_edges,
            manifold,
        }
    }

    /// True when edge `e` has one face.
    pub fn is_boundary(&self, e: u32) -> bool {
        self.edge_faces[e as usize][1] == NONE
    }
}

/// The unordered key of edge (a, b).
pub fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    (u64::from(lo) << 32) | u64::from(hi)
}

/// The face of every corner.
fn corner_faces(faces: &Faces) -> Vec<u32> {
    let mut out = Vec::with_capacity(faces.indices.len());
    for f in 0..faces.len() {
        let n = (faces.offsets[f + 1] - faces.offsets[f]) as usize;
        out.extend(std::iter::repeat_n(f as u32, n));
    }
    out
}

/// Groups (key, value) pairs by key into CSR form, values in input order within a key.
fn csr(keys: usize, pairs: impl Iterator<Item = (u32, u32)> + Clone) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = vec![0u32; keys + 1];
    for (k, _) in pairs.clone() {
        offsets[k as usize + 1] += 1;
    }
    for i in 0..keys {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut list = vec![0u32; offsets[keys] as usize];
    for (k, v) in pairs {
        list[fill[k as usize] as usize] = v;
        fill[k as usize] += 1;
    }
    (offsets, list)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_pair() -> Faces {
        // Two quads sharing edge (1, 4).
        Faces {
            offsets: vec![0, 4, 8],
            indices: vec![0, 1, 4, 3, 1, 2, 5, 4],
            vertex_count: 6,
        }
    }

    #[test]
    fn edges_faces_and_boundaries() {
        let t = Topology::build(&quad_pair(), &[([4, 1], 2.0)]).unwrap();
        assert_eq!(t.edge_vertices.len(), 7);
        let shared = t.edge_vertices.iter().position(|e| *e == [1, 4]).unwrap();
        assert_eq!(t.edge_faces[shared], [0, 1]);
        assert_eq!(t.edge_sharpness[shared], 2.0);
        assert_eq!(
            (0..7).filter(|&e| t.is_boundary(e)).count(),
            6,
            "every other edge is a boundary"
        );
        assert_eq!(t.edges_of(1).len(), 3);
        assert_eq!(t.faces_of(4), &[0, 1]);
    }

    #[test]
    fn bad_cages_are_named() {
        let mut f = quad_pair();
        f.indices[2] = 0;
        assert!(matches!(
            Topology::build(&f, &[]),
            Err(SubdivError::DegenerateFace { face: 0, .. })
        ));
        let fan = Faces {
            offsets: vec![0, 3, 6, 9],
            indices: vec![0, 1, 2, 0, 1, 3, 0, 1, 4],
            vertex_count: 5,
        };
        assert_eq!(
            Topology::build(&fan, &[]).unwrap_err(),
            SubdivError::NonManifoldEdge {
                a: 0,
                b: 1,
                faces: 3
            }
        );
        assert_eq!(
            Topology::build(&quad_pair(), &[([0, 2], 1.0)]).unwrap_err(),
            SubdivError::CreaseNotAnEdge {
                index: 0,
                a: 0,
                b: 2
            }
        );
    }
}
