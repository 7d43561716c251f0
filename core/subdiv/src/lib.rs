//! Subdivision surfaces (paper 002: Catmull–Clark on the CPU by the factored scheme, section
//! 5.4; the GPU part, section 6), split as OpenSubdiv splits it: a **topology phase**
//! ([`Refiner::new`]) that builds each level's faces and a [`StencilTable`] once per cage
//! topology, and an **apply phase** ([`Refiner::apply`]) that evaluates the tables on vertex
//! data — positions, any primvar, every frame of an animation.

#![warn(missing_docs)]

pub mod attributes;
pub mod bilinear;
pub mod boundary;
pub mod butterfly;
pub mod catmull_clark;
pub mod crease_rules;
pub mod doo_sabin;
pub mod error;
pub mod face_varying;
pub mod face_varying_rules;
pub mod halfedges;
pub mod level;
pub mod loop_scheme;
pub mod normals;
pub mod sharp_edges;
pub mod sharpness;
pub mod sqrt3;
pub mod stencil;
pub mod topology;

#[cfg(test)]
mod test_meshes;

pub use boundary::Boundary;
pub use error::SubdivError;
pub use face_varying_rules::UvInterpolation;
use halfedges::Halfedges;
pub use level::Level;
pub use stencil::StencilTable;
pub use topology::{Faces, Topology};

use tessd_mesh::{Crease, Mesh};

/// The refinement schemes (paper 002, section 1.4.7 surveys them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Scheme {
    /// Catmull–Clark (quads out; any polygon in), as OpenSubdiv's `SCHEME_CATMARK`.
    #[default]
    CatmullClark,
    /// Loop (triangles in and out), as OpenSubdiv's `SCHEME_LOOP`.
    Loop,
    /// Butterfly, interpolating (triangles).
    Butterfly,
    /// Doo–Sabin, dual (any polygon).
    DooSabin,
    /// Kobbelt's √3 (triangles; three faces per face per level).
    Sqrt3,
    /// Bilinear: Catmull–Clark's topology with linear interpolation (OpenSubdiv's
    /// `SCHEME_BILINEAR`; linear face-varying data).
    Bilinear,
}

impl Scheme {
    /// Every scheme, in CLI order.
    pub const ALL: [Scheme; 6] = [
        Scheme::CatmullClark,
        Scheme::Loop,
        Scheme::Butterfly,
        Scheme::DooSabin,
        Scheme::Sqrt3,
        Scheme::Bilinear,
    ];

    /// The name used by the CLI and the protocol.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::CatmullClark => "catmull-clark",
            Scheme::Loop => "loop",
            Scheme::Butterfly => "butterfly",
            Scheme::DooSabin => "doo-sabin",
            Scheme::Sqrt3 => "sqrt3",
            Scheme::Bilinear => "bilinear",
        }
    }

    /// The scheme called `name` (see [`Scheme::name`]).
    pub fn from_name(name: &str) -> Option<Scheme> {
        Scheme::ALL.into_iter().find(|s| s.name() == name)
    }

    /// True for the schemes defined on triangle meshes only.
    pub fn needs_triangles(self) -> bool {
        matches!(self, Scheme::Loop | Scheme::Butterfly | Scheme::Sqrt3)
    }

    /// Faces out per face in, per level, at most (the first Catmull–Clark or bilinear level
    /// makes one quad per corner instead): √3 makes 3 per face plus one per boundary or
    /// crease edge; Doo–Sabin one per face, edge and vertex (4 + χ/F on closed quad meshes,
    /// more on open ones and larger polygons).
    fn growth(self) -> u64 {
        match self {
            Scheme::Sqrt3 => 4,
            Scheme::DooSabin => 5,
            _ => 4,
        }
    }

    /// One level of this scheme.
    fn refine(
        self,
        faces: &Faces,
        topo: &Topology,
        boundary: Boundary,
    ) -> Result<Level, SubdivError> {
        match self {
            Scheme::CatmullClark => Err(SubdivError::InvalidOption(
                "Catmull–Clark refines through Halfedges, not level by level".to_string(),
            )),
            Scheme::Loop => loop_scheme::refine(faces, topo, boundary),
            Scheme::Butterfly => butterfly::refine(faces, topo, boundary),
            Scheme::DooSabin => doo_sabin::refine(faces, topo, boundary),
            Scheme::Sqrt3 => sqrt3::refine(faces, topo, boundary),
            Scheme::Bilinear => bilinear::refine(faces, topo, boundary),
        }
    }
}

/// What to refine and how.
#[derive(Clone, Debug, PartialEq)]
pub struct SubdivOptions {
    /// The scheme.
    pub scheme: Scheme,
    /// Refinement levels (1 or more).
    pub levels: u32,
    /// Boundary corner rule.
    pub boundary: Boundary,
    /// Refuse (before allocating) when tables and output are estimated above this many bytes.
    pub memory_limit: u64,
    /// How the cage's UVs are refined (Blender's default: corners kept).
    pub uv_interpolation: UvInterpolation,
    /// Give the refined mesh smooth shading normals ([`normals::smooth_normals`]).
    pub normals: bool,
}

impl Default for SubdivOptions {
    fn default() -> Self {
        SubdivOptions {
            scheme: Scheme::CatmullClark,
            levels: 1,
            boundary: Boundary::EdgeOnly,
            memory_limit: 8 << 30,
            uv_interpolation: UvInterpolation::default(),
            normals: true,
        }
    }
}

/// Estimated bytes per face of the last level: its quad (4 indices + offset + parent) and about
/// one vertex with ~9 stencil terms (index + weight) and its position.
const BYTES_PER_FACE: u64 = 24 + 12 + 9 * 8 + 4 + 12;

/// The topology phase's result: one stencil table per level and the last level's faces.
#[derive(Clone, Debug)]
pub struct Refiner {
    /// Level `i + 1` from level `i`.
    pub tables: Vec<StencilTable>,
    /// Faces of the last level.
    pub faces: Faces,
    /// Sharp edges of the last level ((a, b), sharpness).
    pub creases: Vec<([u32; 2], f32)>,
    /// The cage face each last-level face comes from.
    pub face_origin: Vec<u32>,
    /// Edges of the last level lying on the cage's sharp edges (empty when the cage has none
    /// or the scheme keeps none: [`sharp_edges::carries_sharp_edges`]).
    pub sharp_edges: Vec<[u32; 2]>,
    /// Vertices of the cage.
    pub cage_vertices: usize,
}

impl Refiner {
    /// Topology phase: refines the faces and creases of `cage` `options.levels` times.
    ///
    /// # Errors
    /// Bad cages (named element), zero levels, or an output estimated above the memory limit.
    pub fn new(cage: &Mesh, options: &SubdivOptions) -> Result<Refiner, SubdivError> {
        if options.levels == 0 {
            return Err(SubdivError::InvalidOption(
                "levels must be at least 1".to_string(),
            ));
        }
        if options.scheme.needs_triangles()
            && let Some(face) = (0..cage.face_count()).find(|&f| cage.face(f).len() != 3)
        {
            return Err(SubdivError::NotTriangles {
                scheme: options.scheme.name(),
                face,
                corners: cage.face(face).len(),
            });
        }
        cage.validate()
            .map_err(|e| SubdivError::InvalidMesh(e.to_string()))?;
        let mut used = vec![false; cage.positions.len()];
        cage.face_indices
            .iter()
            .for_each(|&v| used[v as usize] = true);
        if let Some(vertex) = used.iter().position(|&u| !u) {
            return Err(SubdivError::IsolatedVertex { vertex });
        }
        let g = options.scheme.growth();
        let first = match options.scheme {
            Scheme::CatmullClark | Scheme::Bilinear => cage.face_indices.len() as u64,
            // A face per face, edge and vertex: edges and vertices are at most the corners.
            Scheme::DooSabin => (cage.face_count() + 2 * cage.face_indices.len()) as u64,
            _ => (cage.face_count() as u64).saturating_mul(g),
        };
        let faces_out = (1..options.levels).fold(first, |f, _| f.saturating_mul(g));
        let bytes = faces_out.saturating_mul(BYTES_PER_FACE);
        if bytes > options.memory_limit {
            return Err(SubdivError::TooLarge {
                levels: options.levels,
                faces: faces_out,
                bytes,
                limit: options.memory_limit,
            });
        }
        let mut faces = Faces {
            offsets: cage.face_offsets.clone(),
            indices: cage.face_indices.clone(),
            vertex_count: cage.positions.len() as u32,
        };
        let mut creases: Vec<([u32; 2], f32)> =
            cage.creases.iter().map(|c| ([c.a, c.b], c.value)).collect();
        let mut origin: Vec<u32> = (0..faces.len() as u32).collect();
        let mut tables = Vec::with_capacity(options.levels as usize);
        // Sharp edges, each once, self-loops left out; none when the scheme cannot keep them.
        let mut sharp: Vec<[u32; 2]> = Vec::new();
        if sharp_edges::carries_sharp_edges(options.scheme) {
            sharp = cage
                .sharp_edges
                .iter()
                .filter(|e| e[0] != e[1])
                .map(|&[a, b]| [a.min(b), a.max(b)])
                .collect();
            sharp.sort_unstable();
            sharp.dedup();
        }
        if options.scheme == Scheme::CatmullClark {
            // Index arithmetic after the cage: no per-level adjacency rebuild.
            let mut h = Halfedges::from_cage(&faces, &creases)?;
            let mut tracked =
                (!sharp.is_empty()).then(|| sharp_edges::HalfedgeSharp::new(&h, &sharp));
            for level in 1..=options.levels {
                tables.push(catmull_clark::stencils(&h, options.boundary));
                // Child face c is parent corner c.
                origin = (0..h.faces.indices.len() as u32)
                    .map(|c| origin[h.face(c) as usize])
                    .collect();
                if level == options.levels {
                    // The last level needs its faces and creases only.
                    creases = h.refined_creases();
                    if let Some(t) = &tracked {
                        sharp = t.last(&h);
                    }
                    faces = h.refine_faces();
                } else {
                    h = h.refine();
                    if let Some(t) = tracked.as_mut() {
                        t.refine();
                    }
                }
            }
        } else {
            for _ in 0..options.levels {
                let topo = Topology::build(&faces, &creases)?;
                let level = options.scheme.refine(&faces, &topo, options.boundary)?;
                if !sharp.is_empty() {
                    let (ep, vp) = sharp_edges::numbering(
                        options.scheme,
                        faces.len(),
                        topo.edge_vertices.len(),
                    );
                    sharp = sharp_edges::split(&topo, &sharp, ep, vp);
                }
                origin = level
                    .face_parent
                    .iter()
                    .map(|&p| origin[p as usize])
                    .collect();
                tables.push(level.table);
                faces = level.faces;
                creases = level.creases;
            }
        }
        Ok(Refiner {
            tables,
            faces,
            creases,
            face_origin: origin,
            sharp_edges: sharp,
            cage_vertices: cage.positions.len(),
        })
    }

    /// Apply phase: evaluates every level on `data` (cage vertices × `stride` floats).
    ///
    /// # Errors
    /// When `data` does not hold one row per cage vertex.
    pub fn apply(&self, data: &[f32], stride: usize, what: &str) -> Result<Vec<f32>, SubdivError> {
        self.check_rows(data, stride, what)?;
        Ok(StencilTable::apply_chain(&self.tables, data, stride))
    }

    /// `data` must hold one row of `stride` floats per cage vertex.
    fn check_rows(&self, data: &[f32], stride: usize, what: &str) -> Result<(), SubdivError> {
        if stride == 0 || data.len() != self.cage_vertices * stride {
            return Err(SubdivError::VertexCount {
                what: what.to_string(),
                got: data.len().checked_div(stride).unwrap_or(0),
                expected: self.cage_vertices,
            });
        }
        Ok(())
    }

    /// [`Refiner::apply`] into `levels`, buffers kept between calls (see
    /// [`StencilTable::apply_chain_into`]): the steady state of an animation.
    ///
    /// # Errors
    /// When `data` does not hold one row per cage vertex.
    pub fn apply_into<'a>(
        &self,
        data: &'a [f32],
        stride: usize,
        what: &str,
        levels: &'a mut Vec<Vec<f32>>,
    ) -> Result<&'a [f32], SubdivError> {
        self.check_rows(data, stride, what)?;
        Ok(StencilTable::apply_chain_into(
            &self.tables,
            data,
            stride,
            levels,
        ))
    }

    /// Refined positions of `positions` (the cage's, or an animation frame's).
    ///
    /// # Errors
    /// When the vertex count differs from the cage's.
    pub fn apply_positions(
        &self,
        positions: &[[f32; 3]],
        what: &str,
    ) -> Result<Vec<[f32; 3]>, SubdivError> {
        let flat = self.apply(positions.as_flattened(), 3, what)?;
        Ok(flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect())
    }

    /// The refined mesh with `positions` (already refined): last level's faces, face groups
    /// of the cage carried to its faces, creases still sharp, the cage's UVs refined by
    /// `options.uv_interpolation` (schemes that carry them: [`face_varying::refine_uvs`]),
    /// its generic attributes ([`attributes::refine_attributes`]), its sharp edges' halves
    /// ([`sharp_edges`]) and, with `options.normals`, smooth shading normals.
    ///
    /// # Errors
    /// UVs that do not fit the cage, or a refiner built from another cage or options.
    pub fn mesh_with(
        &self,
        cage: &Mesh,
        positions: Vec<[f32; 3]>,
        options: &SubdivOptions,
    ) -> Result<Mesh, SubdivError> {
        let mut m = Mesh {
            positions,
            face_offsets: self.faces.offsets.clone(),
            face_indices: self.faces.indices.clone(),
            group_names: cage.group_names.clone(),
            ..Mesh::default()
        };
        if !cage.face_groups.is_empty() {
            m.face_groups = self
                .face_origin
                .iter()
                .map(|&f| cage.face_groups[f as usize])
                .collect();
        }
        m.creases = self
            .creases
            .iter()
            .map(|&([a, b], value)| Crease { a, b, value })
            .collect();
        m.uvs = face_varying::refine_uvs(cage, self, options)?;
        m.attributes = attributes::refine_attributes(cage, self, options)?;
        m.sharp_edges = self.sharp_edges.clone();
        if options.normals {
            m.normals = Some(normals::smooth_normals(&m));
        }
        Ok(m)
    }
}

/// Refines `cage` (topology and apply in one call).
///
/// # Errors
/// See [`Refiner::new`].
pub fn subdivide(cage: &Mesh, options: &SubdivOptions) -> Result<Mesh, SubdivError> {
    let refiner = Refiner::new(cage, options)?;
    let positions = refiner.apply_positions(&cage.positions, "the cage")?;
    refiner.mesh_with(cage, positions, options)
}
