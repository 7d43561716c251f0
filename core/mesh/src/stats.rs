//! Topology statistics: counts, bounds, face sizes, edges, boundaries, components.
//!
//! Edges are found without hashing: every face side is filed under its smaller vertex (a
//! counting sort), then each vertex's short list of larger neighbours is sorted and run-length
//! counted. Connected components use a union-find. Time is linear in the corners apart from the
//! tiny per-vertex sorts; memory is about 4 bytes per corner plus 12 per vertex.

use crate::Mesh;
use std::collections::BTreeMap;

/// Counts and topology figures of a mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshStats {
    /// Vertices referenced by at least one face.
    pub vertices: u64,
    /// Vertices stored, referenced or not.
    pub stored_vertices: u64,
    /// Stored vertices that no face references.
    pub unreferenced_vertices: u64,
    /// Faces.
    pub faces: u64,
    /// Triangles after fan triangulation (a face of n corners gives n − 2).
    pub triangles: u64,
    /// Axis-aligned bounds `(min, max)` of the referenced vertices; `None` without faces.
    pub bounds: Option<([f32; 3], [f32; 3])>,
    /// Number of faces of each size (corner count).
    pub face_size_histogram: BTreeMap<u32, u64>,
    /// Distinct undirected edges (vertex pairs joined by a face side).
    pub edges: u64,
    /// Edges used by exactly one face side.
    pub boundary_edges: u64,
    /// Connected components of the graph formed by the boundary edges. For a manifold
    /// boundary this is the number of holes; two holes touching at a (non-manifold) vertex count
    /// as one.
    pub boundary_loops: u64,
    /// Edges used by three or more face sides.
    pub non_manifold_edges: u64,
    /// Connected components of faces, faces being connected when they share a vertex.
    pub components: u64,
}

impl MeshStats {
    /// Euler characteristic V − E + F over the referenced vertices (2 for a closed sphere-like
    /// surface, 2 − 2g for a closed surface of genus g).
    pub fn euler_characteristic(&self) -> i64 {
        self.vertices as i64 - self.edges as i64 + self.faces as i64
    }
}

/// A union-find with path halving.
struct Dsu(Vec<u32>);

impl Dsu {
    fn new(n: usize) -> Dsu {
        Dsu((0..n as u32).collect())
    }

    fn reset(&mut self) {
        for (i, p) in self.0.iter_mut().enumerate() {
            *p = i as u32;
        }
    }

    #[inline]
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let grand = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = grand;
            x = grand;
        }
        x
    }

    #[inline]
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            // Link the larger index under the smaller: deterministic and keeps trees shallow
            // for the usual vertex orders.
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

/// Computes the statistics of a mesh.
///
/// # Panics
/// If the mesh is not valid (an index out of range); check untrusted meshes with
/// [`Mesh::validate`] first (every reader of this crate already does).
pub fn compute(mesh: &Mesh) -> MeshStats {
    let nv = mesh.positions.len();
    let mut stats = MeshStats {
        stored_vertices: nv as u64,
        faces: mesh.face_count() as u64,
        triangles: mesh.triangle_count() as u64,
        bounds: mesh.bounds(),
        ..MeshStats::default()
    };

    // Face sizes: an array for the usual sizes, the map only at the end.
    let mut small = [0u64; 64];
    for w in mesh.face_offsets.windows(2) {
        let n = w[1] - w[0];
        match small.get_mut(n as usize) {
            Some(c) => *c += 1,
            None => *stats.face_size_histogram.entry(n).or_default() += 1,
        }
    }
    for (n, &c) in small.iter().enumerate().filter(|(_, c)| **c > 0) {
        stats.face_size_histogram.insert(n as u32, c);
    }

    // Referenced vertices and face components.
    let mut dsu = Dsu::new(nv);
    let mut referenced = vec![false; nv];
    for face in mesh.faces() {
        for &v in face {
            referenced[v as usize] = true;
            dsu.union(face[0], v);
        }
    }
    stats.vertices = referenced.iter().filter(|&&r| r).count() as u64;
    stats.unreferenced_vertices = nv as u64 - stats.vertices;
    stats.components = (0..nv as u32)
        .filter(|&v| referenced[v as usize] && dsu.find(v) == v)
        .count() as u64;

    // Edges: file each face side under its smaller vertex (counting sort).
    let sides = |f: &mut dyn FnMut(u32, u32)| {
        for face in mesh.faces() {
            let mut prev = face[face.len() - 1];
            for &v in face {
                f(prev.min(v), prev.max(v));
                prev = v;
            }
        }
    };
    // end[v] ends bucket v after counting; filling walks it back to the bucket's start.
    let mut end = vec![0u32; nv + 1];
    sides(&mut |lo, _| end[lo as usize] += 1);
    let mut total = 0u32;
    for e in end.iter_mut() {
        total += *e;
        *e = total;
    }
    let mut other = vec![0u32; total as usize];
    sides(&mut |lo, hi| {
        end[lo as usize] -= 1;
        other[end[lo as usize] as usize] = hi;
    });

    dsu.reset();
    let mut on_boundary = referenced; // reused as the "has a boundary edge" flag
    on_boundary.fill(false);
    for v in 0..nv {
        let bucket = &mut other[end[v] as usize..end[v + 1] as usize];
        bucket.sort_unstable();
        let mut i = 0;
        while i < bucket.len() {
            let hi = bucket[i];
            let mut j = i + 1;
            while j < bucket.len() && bucket[j] == hi {
                j += 1;
            }
            stats.edges += 1;
            match j - i {
                1 => {
                    stats.boundary_edges += 1;
                    on_boundary[v] = true;
                    on_boundary[hi as usize] = true;
                    dsu.union(v as u32, hi);
                }
                2 => {}
                _ => stats.non_manifold_edges += 1,
            }
            i = j;
        }
    }
    stats.boundary_loops = (0..nv as u32)
        .filter(|&v| on_boundary[v as usize] && dsu.find(v) == v)
        .count() as u64;
    stats
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(positions: usize, faces: &[&[u32]]) -> Mesh {
        let mut m = Mesh {
            positions: (0..positions)
                .map(|i| [i as f32, (i * i) as f32, 0.0])
                .collect(),
            ..Mesh::default()
        };
        for f in faces {
            m.push_face(f);
        }
        m
    }

    #[test]
    fn tetrahedron_is_closed() {
        let s = compute(&mesh(4, &[&[0, 1, 2], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]]));
        assert_eq!(
            (s.vertices, s.edges, s.faces, s.boundary_edges),
            (4, 6, 4, 0)
        );
        assert_eq!(
            (s.boundary_loops, s.components, s.euler_characteristic()),
            (0, 1, 2)
        );
        assert_eq!(s.face_size_histogram, BTreeMap::from([(3, 4)]));
    }

    #[test]
    fn open_quads_unreferenced_and_fins() {
        // Two quads sharing an edge, a separate triangle, an unused vertex, and a fin edge.
        let s = compute(&mesh(
            11,
            &[&[0, 1, 2, 3], &[1, 4, 5, 2], &[6, 7, 8], &[1, 2, 9]],
        ));
        assert_eq!(
            (s.stored_vertices, s.vertices, s.unreferenced_vertices),
            (11, 10, 1)
        );
        assert_eq!((s.faces, s.triangles, s.components), (4, 6, 2));
        assert_eq!(s.non_manifold_edges, 1);
        assert_eq!(s.edges, 4 + 3 + 3 + 2);
        assert_eq!(s.boundary_edges, 6 + 3 + 2);
        assert_eq!(s.boundary_loops, 2);
        assert_eq!(s.face_size_histogram, BTreeMap::from([(3, 2), (4, 2)]));
    }

    #[test]
    fn empty_mesh() {
        let s = compute(&Mesh::default());
        assert_eq!(s, MeshStats::default());
    }
}
