//! Shading normals of a refined mesh: smooth vertex normals, split along infinitely sharp
//! creases, as face-varying data.
//!
//! A vertex's normal is the angle-weighted sum of the unit normals of its faces (Thürmer and
//! Wüthrich), which Blender also uses for its vertex normals: unlike area weighting it does not
//! depend on how the faces around the vertex are split, and the refined faces around a vertex
//! are very uneven near extraordinary points. Face normals are Newell's, so n-gons and
//! non-planar quads get a sensible one.
//!
//! An infinitely sharp crease (sharpness ≥ [`INFINITELY_SHARP`]) is a crease in the limit
//! surface, so the faces on each side of it get their own normal: around a vertex on such a
//! crease, each fan of faces between sharp edges has one value. Semi-sharp creases are smooth
//! in the limit and boundaries have one side, so neither splits. These are normals of the
//! refined polygons, not limit normals; at level 2 and above they differ from the limit
//! surface's by well under a degree on smooth regions.

use std::collections::HashSet;

use crate::sharpness::INFINITELY_SHARP;
use crate::topology::edge_key;
use rayon::prelude::*;
use tessd_mesh::{FaceVarying, Mesh};

/// Newell's normal of a polygon, unit length (zero for a degenerate one).
fn face_normal(mesh: &Mesh, face: &[u32]) -> [f64; 3] {
    let mut n = [0.0f64; 3];
    for (k, &a) in face.iter().enumerate() {
        let p = mesh.positions[a as usize].map(f64::from);
        let q = mesh.positions[face[(k + 1) % face.len()] as usize].map(f64::from);
        n[0] += (p[1] - q[1]) * (p[2] + q[2]);
        n[1] += (p[2] - q[2]) * (p[0] + q[0]);
        n[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    normalized(n).unwrap_or([0.0; 3])
}

fn normalized(n: [f64; 3]) -> Option<[f64; 3]> {
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    (len > 0.0 && len.is_finite()).then(|| n.map(|x| x / len))
}

/// The interior angle of `face` at its corner `k`.
fn corner_angle(mesh: &Mesh, face: &[u32], k: usize) -> f64 {
    let n = face.len();
    let at = mesh.positions[face[k] as usize].map(f64::from);
    let prev = mesh.positions[face[(k + n - 1) % n] as usize].map(f64::from);
    let next = mesh.positions[face[(k + 1) % n] as usize].map(f64::from);
    let a = [prev[0] - at[0], prev[1] - at[1], prev[2] - at[2]];
    let b = [next[0] - at[0], next[1] - at[1], next[2] - at[2]];
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let sin = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
    let cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    if sin == 0.0 && cos == 0.0 {
        0.0
    } else {
        sin.atan2(cos)
    }
}

/// Smooth normals of `mesh` (any polygons), one value per vertex, or per fan of faces between
/// infinitely sharp creases (`mesh.creases` with value ≥ [`INFINITELY_SHARP`]) around a vertex
/// on one. Indices follow `mesh.face_indices`. A vertex whose faces cancel out gets the plain
/// sum of its face normals, or +Z when that vanishes too.
pub fn smooth_normals(mesh: &Mesh) -> FaceVarying<[f32; 3]> {
    let nf = mesh.face_count();
    let nv = mesh.positions.len();
    let face_normals: Vec<[f64; 3]> = (0..nf)
        .into_par_iter()
        .map(|f| face_normal(mesh, mesh.face(f)))
        .collect();
    let sharp: HashSet<u64> = mesh
        .creases
        .iter()
        .filter(|c| c.value >= INFINITELY_SHARP)
        .map(|c| edge_key(c.a, c.b))
        .collect();
    let mut split = vec![false; nv];
    for c in mesh.creases.iter().filter(|c| c.value >= INFINITELY_SHARP) {
        split[c.a as usize] = true;
        split[c.b as usize] = true;
    }
    // Per vertex (unsplit): angle-weighted and plain sums.
    let mut weighted = vec![[0.0f64; 3]; nv];
    let mut plain = vec![[0.0f64; 3]; nv];
    // Corners of split vertices: (vertex, corner, face).
    let mut split_corners: Vec<(u32, u32, u32)> = Vec::new();
    // Corner angles in parallel (rayon's collect keeps the corner order).
    let angles: Vec<f64> = (0..nf)
        .into_par_iter()
        .flat_map_iter(|f| {
            let face = mesh.face(f);
            (0..face.len()).map(move |k| corner_angle(mesh, face, k))
        })
        .collect();
    for (f, n) in face_normals.iter().enumerate() {
        let face = mesh.face(f);
        let base = mesh.face_offsets[f] as usize;
        for (k, &v) in face.iter().enumerate() {
            if split[v as usize] {
                split_corners.push((v, (base + k) as u32, f as u32));
                continue;
            }
            let a = angles[base + k];
            for i in 0..3 {
                weighted[v as usize][i] += a * n[i];
                plain[v as usize][i] += n[i];
            }
        }
    }
    let pick = |w: [f64; 3], p: [f64; 3]| -> [f32; 3] {
        normalized(w)
            .or_else(|| normalized(p))
            .unwrap_or([0.0, 0.0, 1.0])
            .map(|x| x as f32)
    };
    let mut values = Vec::with_capacity(nv);
    let mut vertex_value = vec![u32::MAX; nv];
    let mut indices = vec![0u32; mesh.face_indices.len()];
    for (c, &v) in mesh.face_indices.iter().enumerate() {
        let v = v as usize;
        if split[v] {
            continue;
        }
        if vertex_value[v] == u32::MAX {
            vertex_value[v] = values.len() as u32;
            values.push(pick(weighted[v], plain[v]));
        }
        indices[c] = vertex_value[v];
    }
    split_corners.sort_unstable();
    let mut start = 0;
    while start < split_corners.len() {
        let v = split_corners[start].0;
        let mut end = start;
        while end < split_corners.len() && split_corners[end].0 == v {
            end += 1;
        }
        let group = &split_corners[start..end];
        for fan in fans(mesh, v, group, &sharp) {
            let (mut w, mut p) = ([0.0f64; 3], [0.0f64; 3]);
            for &i in &fan {
                let (_, c, f) = group[i];
                let a = angles[c as usize];
                for j in 0..3 {
                    w[j] += a * face_normals[f as usize][j];
                    p[j] += face_normals[f as usize][j];
                }
            }
            let value = values.len() as u32;
            values.push(pick(w, p));
            for &i in &fan {
                indices[group[i].1 as usize] = value;
            }
        }
        start = end;
    }
    FaceVarying { values, indices }
}

/// The corners of vertex `v` (`group`: (v, corner, face)) grouped into fans: two corners are in
/// one fan when their faces share an edge at `v` that is not in `sharp`.
fn fans(mesh: &Mesh, v: u32, group: &[(u32, u32, u32)], sharp: &HashSet<u64>) -> Vec<Vec<usize>> {
    // The two neighbours of `v` in the face of each corner.
    let neighbours: Vec<[u32; 2]> = group
        .iter()
        .map(|&(_, c, f)| {
            let face = mesh.face(f as usize);
            let n = face.len();
            let k = c as usize - mesh.face_offsets[f as usize] as usize;
            [face[(k + n - 1) % n], face[(k + 1) % n]]
        })
        .collect();
    let mut parent: Vec<usize> = (0..group.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..group.len() {
        for j in i + 1..group.len() {
            let joined = neighbours[i]
                .iter()
                .any(|w| neighbours[j].contains(w) && !sharp.contains(&edge_key(v, *w)));
            if joined {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                parent[a] = b;
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut slot = vec![usize::MAX; group.len()];
    for i in 0..group.len() {
        let r = root(&mut parent, i);
        if slot[r] == usize::MAX {
            slot[r] = out.len();
            out.push(Vec::new());
        }
        out[slot[r]].push(i);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_meshes::cube;
    use tessd_mesh::Crease;

    fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    #[test]
    fn smooth_cube_corners_point_along_the_diagonal() {
        let m = cube();
        let n = smooth_normals(&m);
        assert_eq!(n.values.len(), 8);
        assert_eq!(n.indices.len(), 24);
        for (c, &v) in m.face_indices.iter().enumerate() {
            let p = m.positions[v as usize].map(|x| 2.0 * x - 1.0);
            let want = p.map(|x| x / 3f32.sqrt());
            let got = n.values[n.indices[c] as usize];
            assert!(dot(got, want) > 1.0 - 1e-6, "{got:?} vs {want:?}");
        }
    }

    #[test]
    fn sharp_edges_split_the_normals() {
        let mut m = cube();
        // Every edge infinitely sharp: each corner gets its own face's normal.
        let mut edges = HashSet::new();
        for f in m.faces() {
            for k in 0..4 {
                edges.insert(edge_key(f[k], f[(k + 1) % 4]));
            }
        }
        m.creases = edges
            .iter()
            .map(|&k| Crease {
                a: (k >> 32) as u32,
                b: k as u32,
                value: 10.0,
            })
            .collect();
        let n = smooth_normals(&m);
        assert_eq!(n.values.len(), 24);
        let f0 = n.values[n.indices[0] as usize];
        assert!(dot(f0, [0.0, 0.0, -1.0]) > 1.0 - 1e-6, "{f0:?}");
        // Semi-sharp creases do not split.
        m.creases.iter_mut().for_each(|c| c.value = 3.0);
        assert_eq!(smooth_normals(&m).values.len(), 8);
    }
}
