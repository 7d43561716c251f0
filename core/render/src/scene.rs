//! What the renderer draws: triangles with, per corner, a position (f32, relative to the
//! scene's f64 origin, so parts far from the world origin keep their precision), a shading
//! normal, a (u, v) and the triangle's face id; built from a [`Mesh`] or from a B-Rep document
//! tessellated on the CPU (the first path, until GPU trimming lands in issue 21 step 2).
//!
//! Triangles are not indexed: every corner is its own vertex, so the face id and the corner's
//! barycentric coordinate (for the edge overlay) travel as plain vertex attributes.

use crate::camera::{Bounds, Vec3};
use bytemuck::{Pod, Zeroable};
use glam::Vec3 as F3;
use tessd_mesh::Mesh;

/// One triangle corner as the vertex shader reads it (`shaders/render_surface.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    /// Position relative to [`Scene::origin`].
    pub position: [f32; 3],
    /// Face id + 1 (0 is the background).
    pub face_id: u32,
    /// Shading normal (unit length, or zero: the shader then uses the flat normal).
    pub normal: [f32; 3],
    /// (u, v).
    pub uv: [f32; 2],
    /// The corner's barycentric coordinate: (1, 0), (0, 1) or (0, 0).
    pub bary: [f32; 2],
}

/// Triangles ready to upload.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Three vertices per triangle.
    pub vertices: Vec<Vertex>,
    /// What the f32 positions are relative to (world coordinates).
    pub origin: Vec3,
    /// The world bounding box of the triangles (`None` without any).
    pub bounds: Option<Bounds>,
    /// The largest face id + 1 used.
    pub max_id: u32,
}

/// Corners whose smooth normal is further than this from their triangle's normal use the
/// triangle's (cos 45°): smooth shading on curved surfaces, sharp creases on boxes.
const CREASE_COS: f32 = std::f32::consts::FRAC_1_SQRT_2;

impl Scene {
    /// Triangles `triangles` (indices into `positions`, relative to `origin`), each with its
    /// id (`ids`, already + 1) and optional per-vertex (u, v). Normals: per-vertex, averaged
    /// by area over the triangles sharing the vertex index, except at creases (over 45° from
    /// the triangle's own normal) where the flat normal is kept.
    pub fn from_triangles(
        origin: Vec3,
        positions: &[[f32; 3]],
        triangles: &[[u32; 3]],
        ids: &[u32],
        uvs: Option<&[[f32; 2]]>,
    ) -> Scene {
        let face_normals: Vec<F3> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| F3::from_array(positions[i as usize]));
                (b - a).cross(c - a)
            })
            .collect();
        let mut vertex_normals = vec![F3::ZERO; positions.len()];
        for (t, n) in triangles.iter().zip(&face_normals) {
            for &i in t {
                vertex_normals[i as usize] += *n;
            }
        }
        let vertex_normals: Vec<F3> = vertex_normals.into_iter().map(unit3).collect();
        let mut scene = Scene {
            vertices: Vec::with_capacity(triangles.len() * 3),
            origin,
            bounds: None,
            max_id: 0,
        };
        const BARY: [[f32; 2]; 3] = [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]];
        for ((t, n), &id) in triangles.iter().zip(&face_normals).zip(ids) {
            let flat = unit3(*n);
            for (corner, &i) in t.iter().enumerate() {
                let smooth = vertex_normals[i as usize];
                let normal = if smooth.dot(flat) >= CREASE_COS {
                    smooth
                } else {
                    flat
                };
                scene.vertices.push(Vertex {
                    position: positions[i as usize],
                    face_id: id,
                    normal: normal.to_array(),
                    uv: uvs.map_or([0.0; 2], |u| u[i as usize]),
                    bary: BARY[corner],
                });
            }
            scene.max_id = scene.max_id.max(id);
        }
        scene.bounds = bounds_of(&scene.vertices, origin);
        scene
    }

    /// A mesh's faces, fan-triangulated. The face id of a face is its face group + 1 when the
    /// mesh has groups, else 1 for every face (issue 21: "face group if the mesh has groups,
    /// else 0", stored + 1). (u, v) are the mesh's face-varying uvs when it has them, else 0;
    /// normals the mesh's when it has them, else computed ([`from_triangles`](Self::from_triangles)).
    /// The mesh is trusted to be valid ([`Mesh::validate`]).
    pub fn from_mesh(mesh: &Mesh) -> Scene {
        let grouped = mesh.face_groups.len() == mesh.face_count();
        let mut triangles = Vec::new();
        let mut corners = Vec::new(); // corner index of each triangle corner
        let mut ids = Vec::new();
        for f in 0..mesh.face_count() {
            let start = mesh.face_offsets[f];
            let n = mesh.face_offsets[f + 1] - start;
            let id = if grouped { mesh.face_groups[f] + 1 } else { 1 };
            for k in 1..n.saturating_sub(1) {
                let cs = [start, start + k, start + k + 1];
                triangles.push(cs.map(|c| mesh.face_indices[c as usize]));
                corners.push(cs);
                ids.push(id);
            }
        }
        let mut scene = Scene::from_triangles(Vec3::ZERO, &mesh.positions, &triangles, &ids, None);
        // Face-varying attributes go per corner.
        for (t, cs) in corners.iter().enumerate() {
            for (k, &c) in cs.iter().enumerate() {
                let v = &mut scene.vertices[3 * t + k];
                if let Some(uv) = &mesh.uvs {
                    v.uv = uv.values[uv.indices[c as usize] as usize];
                }
                if let Some(n) = &mesh.normals {
                    v.normal =
                        unit3(F3::from_array(n.values[n.indices[c as usize] as usize])).to_array();
                }
            }
        }
        scene
    }

    /// A B-Rep tessellation: face id = the B-Rep face's index in document order + 1 (the
    /// tessellation's face group), (u, v) = the face's surface parameters at each vertex,
    /// positions relative to the tessellation's origin.
    pub fn from_tessellation(t: &tessd_tessellate::Tessellation) -> Scene {
        let mesh = &t.mesh;
        let triangles: Vec<[u32; 3]> = (0..mesh.face_count())
            .map(|f| {
                let c = mesh.face(f);
                [c[0], c[1], c[2]]
            })
            .collect();
        let ids: Vec<u32> = mesh.face_groups.iter().map(|g| g + 1).collect();
        let uvs: Vec<[f32; 2]> = t.uvs.iter().map(|u| u.map(|x| x as f32)).collect();
        Scene::from_triangles(
            t.placement.origin.into(),
            &mesh.positions,
            &triangles,
            &ids,
            Some(&uvs),
        )
    }

    /// Triangles in the scene.
    pub fn triangles(&self) -> usize {
        self.vertices.len() / 3
    }
}

/// The world box of the vertices.
fn bounds_of(vertices: &[Vertex], origin: Vec3) -> Option<Bounds> {
    let first = vertices.first()?;
    let at = |v: &Vertex| glam::Vec3::from_array(v.position).as_dvec3();
    let (min, max) = vertices.iter().fold((at(first), at(first)), |(lo, hi), v| {
        (lo.min(at(v)), hi.max(at(v)))
    });
    Some(Bounds {
        min: min + origin,
        max: max + origin,
    })
}

/// `a / |a|`, zero for a zero or non-finite length (divided, as the normals always were).
fn unit3(a: F3) -> F3 {
    let n = a.length();
    if n > 0.0 && n.is_finite() {
        a / n
    } else {
        F3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quads_fan_and_groups_become_ids() {
        let mut m = Mesh {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2, 3]);
        m.push_face(&[0, 2, 1]);
        let s = Scene::from_mesh(&m);
        assert_eq!(s.triangles(), 3);
        assert!(s.vertices.iter().all(|v| v.face_id == 1));
        m.face_groups = vec![4, 0];
        m.group_names = (0..5).map(|i| format!("g{i}")).collect();
        let s = Scene::from_mesh(&m);
        let ids: Vec<u32> = s.vertices.iter().map(|v| v.face_id).collect();
        assert_eq!(ids, [5, 5, 5, 5, 5, 5, 1, 1, 1]);
        assert_eq!(s.max_id, 5);
        let b = s.bounds.unwrap();
        assert_eq!(
            (b.min.to_array(), b.max.to_array()),
            ([0.0; 3], [1.0, 1.0, 0.0])
        );
    }

    #[test]
    fn creases_keep_flat_normals() {
        // Two triangles folded sharply (~170°) along the x axis: corners on the fold keep
        // their triangle's flat normal.
        let p = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 0.2],
        ];
        let s = Scene::from_triangles(Vec3::ZERO, &p, &[[0, 1, 2], [1, 0, 3]], &[1, 2], None);
        assert_eq!(s.vertices[0].normal, [0.0, 0.0, 1.0]);
        assert!(s.vertices[3].normal[2] < -0.9, "{:?}", s.vertices[3].normal);
    }
}
