//! Trimmed tessellation of a B-Rep document (docs/brep-format.md): each face's basis surface
//! tessellated to a chordal tolerance and an angle, trimmed by its loops, with shared edges
//! discretised once so that neighbouring faces meet without cracks.
//!
//! One step per module: [`edges`] (each shared edge sampled once along its 3D curve),
//! [`boundary`] (each face's loops as (u, v) polylines reusing those samples), [`crossings`]
//! (polylines that cross in (u, v) split, on the shared edge), [`interior`]
//! (a curvature-driven grid of interior points), [`cdt`] (constrained Delaunay triangulation,
//! trimming and refinement), [`origin`] (what the f32 positions are relative to).
//! [`tessellate`] runs them, in parallel over faces, into one [`Mesh`] with a face group per
//! B-Rep face, named `face<id>`.
//!
//! ```
//! let doc = tessd_brep::Document::from_json(r#"{
//!     "format": "tessd-brep", "version": 1, "units": "mm",
//!     "faces": [{"id": 0, "surface": {"type": "plane", "origin": [0, 0, 0],
//!                "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]}, "bounds": [0, 1, 0, 1]}]
//! }"#).unwrap();
//! let out = tessd_tessellate::tessellate(&doc, &tessd_tessellate::Options::new(0.01)).unwrap();
//! assert_eq!(out.mesh.group_names, ["face0"]);
//! assert!(out.stats.triangles >= 2);
//! ```

#![warn(missing_docs)]

pub mod boundary;
pub mod cdt;
pub mod crossings;
pub mod edges;
pub mod interior;
pub mod origin;

pub use origin::{Origin, Placement};

use std::time::Instant;
use tessd_brep::{Document, ValidationError};
use tessd_mesh::Mesh;

/// Tessellation settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// The largest distance between the mesh and the surface (chordal error), world units.
    pub tolerance: f64,
    /// The angular deflection in radians, as OCP's BRepMesh means it: the largest angle between
    /// an edge chord and the curve at its ends (so neighbouring chords turn by up to twice
    /// this), and between a triangle's normal and the surface's at its centroid.
    pub angle: f64,
    /// What the mesh's f32 positions are relative to (default [`Origin::Auto`]).
    pub origin: Origin,
}

impl Options {
    /// The default angle (0.5 rad, OCP's default angular deflection).
    pub const DEFAULT_ANGLE: f64 = 0.5;

    /// Options with `tolerance` and the default angle.
    pub fn new(tolerance: f64) -> Options {
        Options {
            tolerance,
            angle: Options::DEFAULT_ANGLE,
            origin: Origin::Auto,
        }
    }
}

/// The finest tolerance accepted, relative to the part's largest coordinate: f64 positions
/// there are ~2·10⁻¹⁶ apart, and below ~10⁴ of those steps the chordal tests compare rounding
/// noise (found by fuzzing: a 2 mm cylinder at 3·10³³ mm from the origin refined every face to
/// the 400 000-point cap).
pub const MIN_RELATIVE_TOLERANCE: f64 = 1e-12;

/// Why a document cannot be tessellated.
#[derive(Debug)]
pub enum TessellateError {
    /// The document does not validate.
    Invalid(ValidationError),
    /// A tolerance or angle that is not a positive finite number, or a tolerance finer than
    /// [`MIN_RELATIVE_TOLERANCE`] of the part's coordinates.
    Options(String),
    /// The progress callback asked to stop (a cancelled job).
    Cancelled,
    /// The triangulation library gave up on a face (it panicked on the face's trims, e.g.
    /// loops that still cross after the crossing search ran out of budget): the face's id and
    /// the library's message.
    Face(u64, String),
}

impl std::fmt::Display for TessellateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TessellateError::Invalid(e) => write!(f, "{e}"),
            TessellateError::Options(m) => write!(f, "{m}"),
            TessellateError::Cancelled => write!(f, "cancelled"),
            TessellateError::Face(id, why) => write!(
                f,
                "face {id}: its trims cannot be triangulated (the triangulation failed: {why})"
            ),
        }
    }
}

impl std::error::Error for TessellateError {}

/// Counts and timings of one tessellation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Faces of the document.
    pub faces: usize,
    /// Faces that produced no triangle.
    pub empty_faces: Vec<u64>,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Vertices of the mesh (per face: edge vertices appear once per face using them).
    pub vertices: usize,
    /// Shared edges discretised.
    pub edges: usize,
    /// Points inserted by refinement.
    pub refined_points: usize,
    /// What splitting crossing boundary polylines did.
    pub crossings: crossings::CrossingStats,
    /// Edge ends merged onto a vertex only because of the file's vertex tolerances (farther
    /// than the chordal merge radius, [`edges::snap_radius`]).
    pub merged_by_file_tolerance: usize,
    /// The largest distance such a merge moved an edge end (0 without one).
    pub largest_file_tolerance_merge: f64,
    /// Wall time, milliseconds.
    pub time_ms: f64,
}

/// A tessellation: the mesh and its stats.
#[derive(Clone, Debug)]
pub struct Tessellation {
    /// Triangles, a face group per B-Rep face (in document order), named `face<id>`; the
    /// positions relative to `placement.origin` (f32).
    pub mesh: Mesh,
    /// The absolute f64 position of each mesh vertex (parallel to `mesh.positions`): what
    /// the f32 positions round, before the origin is taken off.
    pub points: Vec<[f64; 3]>,
    /// The origin of the f32 positions and their precision.
    pub placement: Placement,
    /// What a host should know about the f32 positions ([`Placement::warnings`]).
    pub warnings: Vec<String>,
    /// The (u, v) of each mesh vertex on its face's surface (parallel to `mesh.positions`).
    pub uvs: Vec<[f64; 2]>,
    /// Counts and timings.
    pub stats: Stats,
}

/// `f` over `items`, in parallel with the `parallel` feature; results in order.
fn map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        items.par_iter().map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.iter().map(f).collect()
    }
}

/// Tessellates every face of `doc`.
///
/// # Errors
/// [`TessellateError::Options`] for a tolerance or angle that is not positive and finite (or a
/// tolerance below [`MIN_RELATIVE_TOLERANCE`] of the coordinates),
/// [`TessellateError::Invalid`] for a document that does not validate.
pub fn tessellate(doc: &Document, options: &Options) -> Result<Tessellation, TessellateError> {
    tessellate_with_progress(doc, options, &|_, _| true)
}

/// [`tessellate`], calling `progress(done, total)` as faces complete (from any thread), and
/// again with the same `done` while a face refines (every pass, and every thousand or so
/// points), so that a cancel does not wait for a slow face; once it returns `false` (a
/// cancelled job) the faces in progress stop, those not yet started are skipped, and the call
/// ends with [`TessellateError::Cancelled`].
///
/// # Errors
/// As [`tessellate`], and [`TessellateError::Cancelled`].
pub fn tessellate_with_progress(
    doc: &Document,
    options: &Options,
    progress: &(dyn Fn(usize, usize) -> bool + Sync),
) -> Result<Tessellation, TessellateError> {
    if !(options.tolerance.is_finite() && options.tolerance > 0.0) {
        return Err(TessellateError::Options(format!(
            "the tolerance must be a positive number, got {}",
            options.tolerance
        )));
    }
    if !(options.angle.is_finite() && options.angle > 0.0) {
        return Err(TessellateError::Options(format!(
            "the angle must be a positive number of radians, got {}",
            options.angle
        )));
    }
    doc.validate().map_err(TessellateError::Invalid)?;
    if let Some(b) = doc.bounding_box() {
        let largest = b.min.abs().max(b.max.abs()).max_element();
        let finest = largest * MIN_RELATIVE_TOLERANCE;
        if options.tolerance < finest {
            return Err(TessellateError::Options(format!(
                "the tolerance {} is finer than f64 resolves at the part's coordinates (up to {largest}): at least {finest}",
                options.tolerance
            )));
        }
    }
    let start = Instant::now();
    let (mut edges, merges) = edges::discretise_with_stats(doc, options);
    let (loops, crossing_stats) = crossings::face_loops_uncrossed(doc, &mut edges, options);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let total = doc.faces.len();
    let indices: Vec<usize> = (0..total).collect();
    let stop = std::sync::atomic::AtomicBool::new(false);
    // Asked by a face while it refines: the cancel is seen within one pass's slice of points.
    let keep_going = || {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            return false;
        }
        if !progress(done.load(std::sync::atomic::Ordering::Relaxed), total) {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
            return false;
        }
        true
    };
    let faces: Vec<Result<cdt::FaceTriangles, String>> = map(&indices, |&f| {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            return Ok(cdt::FaceTriangles::default());
        }
        let (face, loops) = (&doc.faces[f], &loops[f]);
        let plan = interior::plan(face, loops, options);
        let points = interior::grid(loops, &plan);
        // spade panics on some hostile trims (found by fuzzing: an edge turned 6·10¹⁶ radians
        // whose loops still cross); the face is refused with its id instead of taking the
        // caller down
        let t = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            cdt::triangulate(face, loops, &points, &plan, options, &keep_going)
        }))
        .map_err(|payload| {
            payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic without a message".into())
        });
        let Ok(Some(t)) = t else {
            // A stopped face has no triangles; the call ends `Cancelled` below.
            return t.map(Option::unwrap_or_default);
        };
        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        if !progress(n, total) {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        Ok(t)
    });
    if stop.into_inner() {
        return Err(TessellateError::Cancelled);
    }
    let faces = faces
        .into_iter()
        .zip(&doc.faces)
        .map(|(t, face)| t.map_err(|why| TessellateError::Face(face.id, why)))
        .collect::<Result<Vec<_>, _>>()?;

    let points: Vec<[f64; 3]> = faces
        .iter()
        .flat_map(|t| t.points.iter().copied())
        .collect();
    let placement = origin::place(&points, options.tolerance, options.origin);
    let o = placement.origin;
    let mut mesh = Mesh::default();
    let mut uvs = Vec::new();
    let mut stats = Stats {
        faces: total,
        edges: edges.len(),
        crossings: crossing_stats,
        merged_by_file_tolerance: merges.by_file_tolerance,
        largest_file_tolerance_merge: merges.largest_distance,
        ..Stats::default()
    };
    for (g, (face, t)) in doc.faces.iter().zip(&faces).enumerate() {
        mesh.group_names.push(format!("face{}", face.id));
        stats.refined_points += t.refined;
        let base = mesh.positions.len() as u32;
        // Relative to the origin in f64, then rounded: with the origin [0, 0, 0] exactly the
        // absolute positions rounded, as they always were.
        mesh.positions.extend(
            t.points
                .iter()
                .map(|p| [0, 1, 2].map(|k| (p[k] - o[k]) as f32)),
        );
        uvs.extend_from_slice(&t.uvs);
        let mut count = 0;
        for tri in &t.triangles {
            let ps = tri.map(|i| mesh.positions[(base + i) as usize]);
            // Triangles collapsed in 3D (at a pole, along a degenerate edge) are dropped.
            if ps[0] == ps[1] || ps[1] == ps[2] || ps[2] == ps[0] {
                continue;
            }
            let corners = if face.reversed {
                [tri[0], tri[2], tri[1]]
            } else {
                *tri
            };
            mesh.push_face(&corners.map(|i| base + i));
            mesh.face_groups.push(g as u32);
            count += 1;
        }
        if count == 0 {
            stats.empty_faces.push(face.id);
        }
    }
    stats.triangles = mesh.face_count();
    stats.vertices = mesh.vertex_count();
    stats.time_ms = start.elapsed().as_secs_f64() * 1e3;
    let warnings = placement.warnings(options.tolerance, doc.units.name());
    Ok(Tessellation {
        mesh,
        points,
        placement,
        warnings,
        uvs,
        stats,
    })
}
