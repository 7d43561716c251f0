//! The indexed polygon mesh model and its validation.
//!
//! Faces are stored in compressed-row form (`face_offsets` + `face_indices`) so that n-gons cost
//! nothing extra and a 10 M-triangle mesh is three flat vectors. Normals and UVs are
//! *face-varying*: a value table plus one index per face corner, which is how OBJ stores them and
//! what subdivision needs for UV seams.

use crate::MeshError;
use crate::attribute::{Attribute, Domain};
use crate::block_scan::{first_at_or_above, first_non_finite, steps_at_least};

/// A face-varying attribute: `values`, and for each face corner (same order as
/// [`Mesh::face_indices`]) the index of its value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaceVarying<T> {
    /// Distinct values.
    pub values: Vec<T>,
    /// One index into `values` per face corner.
    pub indices: Vec<u32>,
}

/// A sharpness value on the edge between two vertices (Blender's edge crease, OpenSubdiv's
/// sharpness). `a` and `b` are vertex indices in either order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crease {
    /// First vertex of the edge.
    pub a: u32,
    /// Second vertex of the edge.
    pub b: u32,
    /// Sharpness: 0 smooth, 1 Blender's full crease; OpenSubdiv treats ≥ 10 as infinitely sharp.
    pub value: f32,
}

/// An indexed polygon mesh with n-gon faces.
///
/// Invariants (checked by [`Mesh::validate`]): `face_offsets` starts at 0, is non-decreasing and
/// ends at `face_indices.len()`; every face has ≥ 3 corners; every index is in range; every
/// coordinate is finite; attribute arrays have the lengths their docs say.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Face `f` uses corners `face_offsets[f]..face_offsets[f + 1]`; length = faces + 1.
    pub face_offsets: Vec<u32>,
    /// Vertex index of each face corner.
    pub face_indices: Vec<u32>,
    /// Optional face-varying normals.
    pub normals: Option<FaceVarying<[f32; 3]>>,
    /// Optional face-varying texture coordinates.
    pub uvs: Option<FaceVarying<[f32; 2]>>,
    /// Edge creases (empty when none).
    pub creases: Vec<Crease>,
    /// Per-face group index into `group_names` (empty when the mesh has no groups).
    pub face_groups: Vec<u32>,
    /// Names of the face groups (materials, CAD face ids).
    pub group_names: Vec<String>,
    /// Generic attributes on points, corners or faces (empty when none).
    pub attributes: Vec<Attribute>,
    /// Edges marked sharp for shading (Blender's `sharp_edge`): vertex pairs in either order.
    /// Unlike creases they do not change the subdivided surface; hosts split their shading
    /// normals there.
    pub sharp_edges: Vec<[u32; 2]>,
}

impl Default for Mesh {
    fn default() -> Self {
        Mesh {
            positions: Vec::new(),
            face_offsets: vec![0],
            face_indices: Vec::new(),
            normals: None,
            uvs: None,
            creases: Vec::new(),
            face_groups: Vec::new(),
            group_names: Vec::new(),
            attributes: Vec::new(),
            sharp_edges: Vec::new(),
        }
    }
}

impl Domain {
    /// How many rows an attribute of this domain has on `mesh` (here, beside the mesh it
    /// counts, so that `attribute.rs` needs nothing of the mesh).
    pub fn rows_on(self, mesh: &Mesh) -> usize {
        match self {
            Domain::Point => mesh.vertex_count(),
            Domain::Corner => mesh.face_indices.len(),
            Domain::Face => mesh.face_count(),
        }
    }
}

impl Mesh {
    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.face_offsets.len().saturating_sub(1)
    }

    /// Number of stored vertices (referenced or not).
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The vertex indices of face `f`.
    ///
    /// # Panics
    /// If `f` is out of range or the offsets are inconsistent (call [`Mesh::validate`] first on
    /// untrusted data).
    pub fn face(&self, f: usize) -> &[u32] {
        let (s, e) = (
            self.face_offsets[f] as usize,
            self.face_offsets[f + 1] as usize,
        );
        &self.face_indices[s..e]
    }

    /// The faces as index triples when every face is a triangle (`None` otherwise): the hot
    /// loops of simplification walk this flat view instead of the offsets.
    ///
    /// Decided by the corner count alone (`3 × faces`), which means "all triangles" only for
    /// offsets that [`Mesh::validate`] accepted (every face has ≥ 3 corners).
    pub fn triangles(&self) -> Option<&[[u32; 3]]> {
        (self.face_indices.len() == 3 * self.face_count())
            .then(|| bytemuck::cast_slice(&self.face_indices))
    }

    /// Iterates over the faces as slices of vertex indices.
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.face_offsets
            .windows(2)
            .map(|w| &self.face_indices[w[0] as usize..w[1] as usize])
    }

    /// Appends a face (no validation; see [`Mesh::validate`]).
    pub fn push_face(&mut self, vertices: &[u32]) {
        self.face_indices.extend_from_slice(vertices);
        self.face_offsets.push(self.face_indices.len() as u32);
    }

    /// Number of triangles after fan triangulation (a face of n corners gives n − 2).
    pub fn triangle_count(&self) -> usize {
        self.face_offsets
            .windows(2)
            .map(|w| (w[1] - w[0]).saturating_sub(2) as usize)
            .sum()
    }

    /// The fan triangulation [`Mesh::triangle_count`] counts: face `v0 v1 … vn` gives
    /// `(v0, vi, vi+1)` for i in 1..n−1, in face order.
    pub fn fan_triangles(&self) -> Vec<[u32; 3]> {
        let mut out = Vec::with_capacity(self.triangle_count());
        for f in self.faces() {
            for i in 1..f.len().saturating_sub(1) {
                out.push([f[0], f[i], f[i + 1]]);
            }
        }
        out
    }

    /// Axis-aligned bounds `(min, max)` of the *referenced* vertices, or `None` for a mesh with
    /// no faces.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        if self.face_indices.is_empty() {
            return None;
        }
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        for &v in &self.face_indices {
            let p = self.positions[v as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Some((lo, hi))
    }

    /// Checks every invariant of the model and returns the first violation, naming the element.
    ///
    /// # Errors
    /// [`MeshError::Invalid`] with a message such as "face 12 uses vertex 9000; the mesh has
    /// 8000 vertices".
    pub fn validate(&self) -> Result<(), MeshError> {
        self.check(false)
    }

    /// [`Mesh::validate`] for a mesh whose faces a reader has already checked as it built them
    /// (every face ≥ 3 corners, every index below the vertex count): skips those passes.
    pub(crate) fn validate_read(&self) -> Result<(), MeshError> {
        self.check(true)
    }

    fn check(&self, faces_checked: bool) -> Result<(), MeshError> {
        let bad = |m: String| Err(MeshError::Invalid(m));
        // Bulk passes first (a max-reduction per block); the element-wise walks below only run
        // to name what a failing pass found.
        if let Some(c) = first_non_finite(self.positions.as_flattened()) {
            let (i, k) = (c / 3, c % 3);
            return bad(format!(
                "vertex {i} has a non-finite coordinate {} = {}",
                ["x", "y", "z"][k],
                self.positions[i][k]
            ));
        }
        if self.face_offsets.first() != Some(&0) {
            return bad("face offsets must start with 0".into());
        }
        if *self.face_offsets.last().unwrap() as usize != self.face_indices.len() {
            return bad(format!(
                "face offsets end at {} but there are {} face corners",
                self.face_offsets.last().unwrap(),
                self.face_indices.len()
            ));
        }
        let nv = self.positions.len();
        let bound = u32::try_from(nv).unwrap_or(u32::MAX);
        let indices_ok = faces_checked
            || nv > u32::MAX as usize
            || first_at_or_above(&self.face_indices, bound).is_none();
        if !(indices_ok && (faces_checked || steps_at_least(&self.face_offsets, 3))) {
            self.name_face_error()?;
        }
        let corners = self.face_indices.len();
        if let Some(n) = &self.normals {
            check_face_varying("normal", n, corners)?;
            if let Some(c) = first_non_finite(n.values.as_flattened()) {
                return bad(format!("normal {} has a non-finite component", c / 3));
            }
        }
        if let Some(t) = &self.uvs {
            check_face_varying("uv", t, corners)?;
            if let Some(c) = first_non_finite(t.values.as_flattened()) {
                return bad(format!("uv {} has a non-finite component", c / 2));
            }
        }
        for (i, c) in self.creases.iter().enumerate() {
            if c.a as usize >= nv || c.b as usize >= nv {
                return bad(format!(
                    "crease {i} joins vertices {} and {}; the mesh has {nv} vertices",
                    c.a, c.b
                ));
            }
            if !c.value.is_finite() || c.value < 0.0 {
                return bad(format!(
                    "crease {i} has value {}; it must be finite and ≥ 0",
                    c.value
                ));
            }
        }
        if !self.face_groups.is_empty() {
            if self.face_groups.len() != self.face_count() {
                return bad(format!(
                    "{} face groups given for {} faces",
                    self.face_groups.len(),
                    self.face_count()
                ));
            }
            let ng = self.group_names.len();
            if let Some((f, g)) = self
                .face_groups
                .iter()
                .enumerate()
                .find(|(_, g)| **g as usize >= ng)
            {
                return bad(format!(
                    "face {f} is in group {g}; the mesh has {ng} groups"
                ));
            }
        }
        for a in &self.attributes {
            a.check(a.domain.rows_on(self))?;
        }
        if let Some((i, &v)) = self
            .sharp_edges
            .iter()
            .flatten()
            .enumerate()
            .find(|(_, v)| **v as usize >= nv)
        {
            return bad(format!(
                "sharp_edges[{}] names vertex {v}; the mesh has {nv}",
                i / 2
            ));
        }
        Ok(())
    }

    /// Walks the faces in order and returns the first bad one: offsets that decrease, fewer
    /// than 3 corners, a vertex index out of range. The slow path of [`Mesh::validate`], run
    /// only once its bulk passes have found something, so that the message names the face.
    fn name_face_error(&self) -> Result<(), MeshError> {
        let nv = self.positions.len();
        for (f, w) in self.face_offsets.windows(2).enumerate() {
            if w[1] < w[0] {
                return Err(MeshError::Invalid(format!(
                    "face offsets decrease at face {f}"
                )));
            }
            if w[1] - w[0] < 3 {
                return Err(MeshError::Invalid(format!(
                    "face {f} has {} vertices; a face needs at least 3",
                    w[1] - w[0]
                )));
            }
            if let Some(&v) = self.face_indices[w[0] as usize..w[1] as usize]
                .iter()
                .find(|&&v| v as usize >= nv)
            {
                return Err(MeshError::Invalid(format!(
                    "face {f} uses vertex {v}; the mesh has {nv} vertices"
                )));
            }
        }
        Ok(())
    }

    /// The protocol names of what this mesh carries besides positions and faces (`normals`,
    /// `uvs`, `crease_edges`, `face_groups`, `sharp_edges`, and each attribute's
    /// `domain:name`), for operations to report what an output could not hold.
    pub fn carried_names(&self) -> Vec<String> {
        let mut out = Vec::new();
        let fixed = [
            ("normals", self.normals.is_some()),
            ("uvs", self.uvs.is_some()),
            ("crease_edges", !self.creases.is_empty()),
            ("face_groups", !self.face_groups.is_empty()),
            ("sharp_edges", !self.sharp_edges.is_empty()),
        ];
        out.extend(fixed.iter().filter(|f| f.1).map(|f| f.0.to_string()));
        out.extend(self.attributes.iter().map(Attribute::label));
        out
    }
}

fn check_face_varying<T>(what: &str, a: &FaceVarying<T>, corners: usize) -> Result<(), MeshError> {
    if a.indices.len() != corners {
        return Err(MeshError::Invalid(format!(
            "{} {what} indices given for {corners} face corners",
            a.indices.len()
        )));
    }
    let n = a.values.len();
    if let Some(c) = first_at_or_above(&a.indices, u32::try_from(n).unwrap_or(u32::MAX))
        .filter(|_| n <= u32::MAX as usize)
    {
        return Err(MeshError::Invalid(format!(
            "face corner {c} uses {what} {}; there are {n} {what}s",
            a.indices[c]
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Mesh {
        let mut m = Mesh {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
            ..Mesh::default()
        };
        m.push_face(&[0, 1, 2, 3]);
        m
    }

    #[test]
    fn valid_quad_counts() {
        let m = quad();
        m.validate().unwrap();
        assert_eq!((m.face_count(), m.triangle_count()), (1, 2));
        assert_eq!(m.bounds(), Some(([0.0; 3], [1.0, 1.0, 0.0])));
    }

    #[test]
    fn out_of_range_index_is_named() {
        let mut m = quad();
        m.push_face(&[0, 1, 9000]);
        let e = m.validate().unwrap_err().to_string();
        assert_eq!(e, "face 1 uses vertex 9000; the mesh has 4 vertices");
    }

    #[test]
    fn nan_and_small_faces_are_named() {
        let mut m = quad();
        m.positions[2][1] = f32::NAN;
        assert_eq!(
            m.validate().unwrap_err().to_string(),
            "vertex 2 has a non-finite coordinate y = NaN"
        );
        let mut m = quad();
        m.push_face(&[0, 1]);
        assert_eq!(
            m.validate().unwrap_err().to_string(),
            "face 1 has 2 vertices; a face needs at least 3"
        );
    }

    #[test]
    fn attributes_and_sharp_edges_are_checked() {
        use crate::{Attribute, Domain};
        let mut m = quad();
        m.sharp_edges = vec![[0, 1], [1, 2], [2, 3], [3, 99]];
        assert_eq!(
            m.validate().unwrap_err().to_string(),
            "sharp_edges[3] names vertex 99; the mesh has 4"
        );
        m.sharp_edges.pop();
        m.attributes = vec![Attribute::new("id", Domain::Face, 1, vec![0.0, 1.0])];
        assert_eq!(
            m.validate().unwrap_err().to_string(),
            "array \"face:id\" has 2 rows; the mesh has 1 faces"
        );
        m.attributes = vec![Attribute::new("uv", Domain::Corner, 2, vec![0.0; 8])];
        m.validate().unwrap();
        m.attributes[0].values[5] = f32::INFINITY;
        assert_eq!(
            m.validate().unwrap_err().to_string(),
            "corner:uv row 2 is inf"
        );
        assert_eq!(m.carried_names(), ["sharp_edges", "corner:uv"]);
    }

    #[test]
    fn face_varying_length_is_checked() {
        let mut m = quad();
        m.uvs = Some(FaceVarying {
            values: vec![[0.0; 2]],
            indices: vec![0, 0, 0],
        });
        assert_eq!(
            m.validate().unwrap_err().to_string(),
            "3 uv indices given for 4 face corners"
        );
    }
}
