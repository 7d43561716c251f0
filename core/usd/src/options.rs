//! Stage and mesh-prim options (builder style: `Default` plus `with_*` setters).

use tessd_mesh::Mesh;

/// The stage's up axis (`upAxis` layer metadata).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UpAxis {
    /// Y up (USD's own fallback, Maya, most game engines).
    Y,
    /// Z up (Blender, FreeCAD and most CAD tools). The default.
    #[default]
    Z,
}

impl UpAxis {
    /// The USD token: `"Y"` or `"Z"`.
    pub fn token(self) -> &'static str {
        match self {
            UpAxis::Y => "Y",
            UpAxis::Z => "Z",
        }
    }
}

/// A subdivision scheme for meshes that are subdivision cages (`subdivisionScheme`).
///
/// A mesh written without one gets `subdivisionScheme = "none"`: a plain polygon mesh whose
/// authored normals are used as they are. With a scheme, USD consumers subdivide the mesh and
/// ignore authored normals.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SubdivisionScheme {
    /// Catmull-Clark (quads; Blender's Subdivision Surface modifier).
    CatmullClark,
    /// Loop (triangle meshes only; checked before writing).
    Loop,
    /// Bilinear.
    Bilinear,
}

impl SubdivisionScheme {
    /// The USD token: `"catmullClark"`, `"loop"` or `"bilinear"`.
    pub fn token(self) -> &'static str {
        match self {
            SubdivisionScheme::CatmullClark => "catmullClark",
            SubdivisionScheme::Loop => "loop",
            SubdivisionScheme::Bilinear => "bilinear",
        }
    }
}

/// Options of the stage (the layer's metadata and the root prim).
///
/// ```
/// use tessd_usd::{StageOptions, UpAxis};
/// let stage = StageOptions::default().with_up_axis(UpAxis::Y).with_meters_per_unit(0.001);
/// assert_eq!(stage.default_prim, "Root");
/// ```
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct StageOptions {
    /// `upAxis`. Default [`UpAxis::Z`], because the hosts tessd serves (Blender, FreeCAD) are
    /// Z-up; pass [`UpAxis::Y`] for Y-up pipelines.
    pub up_axis: UpAxis,
    /// `metersPerUnit`: the length of one unit of the mesh coordinates in metres. Default `1.0`
    /// (Blender's metres); hosts should pass their real unit (FreeCAD's millimetres: `0.001`).
    /// Must be finite and > 0.
    pub meters_per_unit: f64,
    /// Name of the root `Xform` prim, which is also the layer's `defaultPrim`. Default `"Root"`;
    /// sanitized to a valid USD identifier (see [`crate::sanitize_identifier`]).
    pub default_prim: String,
    /// Optional layer `doc` string. Default `None`.
    pub doc: Option<String>,
}

impl Default for StageOptions {
    fn default() -> Self {
        StageOptions {
            up_axis: UpAxis::Z,
            meters_per_unit: 1.0,
            default_prim: "Root".to_string(),
            doc: None,
        }
    }
}

impl StageOptions {
    /// Sets [`StageOptions::up_axis`].
    pub fn with_up_axis(mut self, up_axis: UpAxis) -> Self {
        self.up_axis = up_axis;
        self
    }

    /// Sets [`StageOptions::meters_per_unit`].
    pub fn with_meters_per_unit(mut self, meters_per_unit: f64) -> Self {
        self.meters_per_unit = meters_per_unit;
        self
    }

    /// Sets [`StageOptions::default_prim`].
    pub fn with_default_prim(mut self, name: impl Into<String>) -> Self {
        self.default_prim = name.into();
        self
    }

    /// Sets [`StageOptions::doc`].
    pub fn with_doc(mut self, doc: impl Into<String>) -> Self {
        self.doc = Some(doc.into());
        self
    }
}

/// Options of one `Mesh` prim.
///
/// ```
/// use tessd_usd::{MeshPrimOptions, SubdivisionScheme};
/// let cage = MeshPrimOptions::default()
///     .with_name("Cube")
///     .with_subdivision_scheme(Some(SubdivisionScheme::CatmullClark));
/// assert_eq!(cage.uv_primvar_name, "st");
/// ```
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct MeshPrimOptions {
    /// Prim name. Default `"mesh"`; sanitized to a valid USD identifier and made unique among
    /// its siblings (`"Cube"`, `"Cube_1"`...).
    pub name: String,
    /// `None` (default) writes `subdivisionScheme = "none"`; `Some` marks the mesh as a
    /// subdivision cage.
    pub subdivision_scheme: Option<SubdivisionScheme>,
    /// `doubleSided`. Default `false`.
    pub double_sided: bool,
    /// Write the mesh's normals (if it has any) as the indexed face-varying primvar
    /// `primvars:normals`. Default `true`.
    pub write_normals: bool,
    /// Write the mesh's UVs (if it has any) as the indexed face-varying `texCoord2f[]` primvar
    /// named [`MeshPrimOptions::uv_primvar_name`]. Default `true`.
    pub write_uvs: bool,
    /// Name of the UV primvar. Default `"st"` (USD's convention, what Blender reads as the UV
    /// map); sanitized like prim names.
    pub uv_primvar_name: String,
    /// For cages: the `interpolateBoundary` token (`"none"`, `"edgeOnly"`, `"edgeAndCorner"`);
    /// `None` leaves USD's fallback (`"edgeAndCorner"`).
    pub interpolate_boundary: Option<&'static str>,
    /// For cages: the `faceVaryingLinearInterpolation` token (`"none"`, `"cornersOnly"`,
    /// `"cornersPlus1"`, `"cornersPlus2"`, `"boundaries"`, `"all"`); `None` leaves USD's
    /// fallback (`"cornersPlus1"`).
    pub face_varying_linear_interpolation: Option<&'static str>,
}

impl Default for MeshPrimOptions {
    fn default() -> Self {
        MeshPrimOptions {
            name: "mesh".to_string(),
            subdivision_scheme: None,
            double_sided: false,
            write_normals: true,
            write_uvs: true,
            uv_primvar_name: "st".to_string(),
            interpolate_boundary: None,
            face_varying_linear_interpolation: None,
        }
    }
}

impl MeshPrimOptions {
    /// Sets [`MeshPrimOptions::name`].
    pub fn with_name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// Sets [`MeshPrimOptions::subdivision_scheme`].
    pub fn with_subdivision_scheme(mut self, scheme: Option<SubdivisionScheme>) -> Self {
        self.subdivision_scheme = scheme;
        self
    }

    /// Sets [`MeshPrimOptions::double_sided`].
    pub fn with_double_sided(mut self, double_sided: bool) -> Self {
        self.double_sided = double_sided;
        self
    }

    /// Sets [`MeshPrimOptions::write_normals`].
    pub fn with_normals(mut self, write_normals: bool) -> Self {
        self.write_normals = write_normals;
        self
    }

    /// Sets [`MeshPrimOptions::write_uvs`].
    pub fn with_uvs(mut self, write_uvs: bool) -> Self {
        self.write_uvs = write_uvs;
        self
    }

    /// Sets [`MeshPrimOptions::interpolate_boundary`] and
    /// [`MeshPrimOptions::face_varying_linear_interpolation`] (cages only).
    pub fn with_cage_rules(
        mut self,
        interpolate_boundary: &'static str,
        face_varying_linear_interpolation: &'static str,
    ) -> Self {
        self.interpolate_boundary = Some(interpolate_boundary);
        self.face_varying_linear_interpolation = Some(face_varying_linear_interpolation);
        self
    }

    /// Sets [`MeshPrimOptions::uv_primvar_name`].
    pub fn with_uv_primvar_name(mut self, name: impl Into<String>) -> Self {
        self.uv_primvar_name = name.into();
        self
    }
}

/// One mesh of a multi-object stage (see [`crate::write_stage`]).
#[derive(Clone, Debug)]
pub struct MeshPrim<'a> {
    /// The mesh.
    pub mesh: &'a Mesh,
    /// Its prim options.
    pub options: MeshPrimOptions,
    /// Optional local transform, authored as `xformOp:transform` on the Mesh prim.
    ///
    /// In USD's (`GfMatrix4d`) convention: `transform[row][col]`, points are *row* vectors
    /// multiplied on the left (`p' = p · M`), so the translation is `transform[3][0..3]`. This
    /// is the **transpose** of Blender's `Object.matrix_world` (pass
    /// `matrix_world.transposed()`). Every entry must be finite.
    pub transform: Option<[[f64; 4]; 4]>,
    /// Optional translation, authored as `double3 xformOp:translate` on the Mesh prim, after
    /// `xformOp:transform` in `xformOpOrder` (so the points are translated first): the origin
    /// the mesh's f32 points are relative to, in f64, so readers compute exact absolute
    /// positions for parts far from their model's origin. Every coordinate must be finite.
    pub translate: Option<[f64; 3]>,
    /// Animated points: frame `k` (0-based) is authored at time code `k + 1` as
    /// `points.timeSamples` (and `extent.timeSamples`); each frame has one point per vertex of
    /// `mesh`. The stage then gets `startTimeCode = 1` and `endTimeCode` = the frame count.
    pub point_samples: Option<&'a [Vec<[f32; 3]>]>,
}

impl<'a> MeshPrim<'a> {
    /// A prim for `mesh` with default options and no transform.
    pub fn new(mesh: &'a Mesh) -> Self {
        MeshPrim {
            mesh,
            options: MeshPrimOptions::default(),
            transform: None,
            translate: None,
            point_samples: None,
        }
    }

    /// Sets [`MeshPrim::options`].
    pub fn with_options(mut self, options: MeshPrimOptions) -> Self {
        self.options = options;
        self
    }

    /// Sets [`MeshPrim::transform`].
    pub fn with_transform(mut self, transform: [[f64; 4]; 4]) -> Self {
        self.transform = Some(transform);
        self
    }

    /// Sets [`MeshPrim::translate`].
    pub fn with_translate(mut self, translate: [f64; 3]) -> Self {
        self.translate = Some(translate);
        self
    }

    /// Sets [`MeshPrim::point_samples`].
    pub fn with_point_samples(mut self, frames: &'a [Vec<[f32; 3]>]) -> Self {
        self.point_samples = Some(frames);
        self
    }
}

/// Options of a stage written with the native `UsdLod` schema (see [`crate::write_lod_schema`]).
///
/// ```
/// use tessd_usd::LodSchemaOptions;
/// let lod = LodSchemaOptions::default().with_screen_size_thresholds(vec![0.25, 0.1]);
/// assert_eq!(lod.default_index, 0);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct LodSchemaOptions {
    /// `lod:default:index`: the level a renderer uses when it understands no heuristic, and the
    /// only level left visible (`visibility = "inherited"`; the others are `"invisible"`) so
    /// that renderers which do not know `UsdLod` show just that one. Default `0`.
    pub default_index: usize,
    /// `thresholds` of the `LODScreenSizeHeuristic`: one fewer than the levels, descending
    /// fractions of the viewport (level `k + 1` is used once the root covers at most
    /// `thresholds[k]`). `None` (default) derives them from the vertex counts:
    /// `thresholds[k] = 0.5 × vertices(level k + 1) / vertices(level 0)`, so that the vertices
    /// per covered pixel never exceed what level 0 has at half the viewport (for levels of
    /// 50 %, 20 % and 5 % this is `[0.25, 0.1, 0.025]`).
    pub screen_size_thresholds: Option<Vec<f32>>,
}

impl LodSchemaOptions {
    /// Sets [`LodSchemaOptions::default_index`].
    pub fn with_default_index(mut self, index: usize) -> Self {
        self.default_index = index;
        self
    }

    /// Sets [`LodSchemaOptions::screen_size_thresholds`].
    pub fn with_screen_size_thresholds(mut self, thresholds: Vec<f32>) -> Self {
        self.screen_size_thresholds = Some(thresholds);
        self
    }
}
