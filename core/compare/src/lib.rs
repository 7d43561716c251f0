//! # tessd-compare — Metro-style surface distance between two meshes
//!
//! The independent error measure of the pipeline: how far is surface `A` from surface `B`?
//! Following Metro (P. Cignoni, C. Rocchini, R. Scopigno, "Metro: measuring error on
//! simplified surfaces", *Computer Graphics Forum* 17(2), 1998), the one-sided distance
//! `d(A → B)` is estimated by densely sampling `A` (every vertex, optionally every edge, and
//! area-weighted points on every face) and measuring, for each sample, the exact Euclidean
//! distance to the closest point of `B`. The maximum over the samples estimates the one-sided
//! Hausdorff distance, and their mean and root mean square estimate the area-averaged `L1` and
//! `L2` distances. [`compare`] does both directions; the symmetric Hausdorff distance is the
//! larger of the two maxima.
//!
//! ```
//! use tessd_mesh::Mesh;
//! use tessd_compare::{compare, CompareOptions};
//!
//! // Two unit squares, the second lifted by 0.25.
//! let square = |z: f32| {
//!     let mut m = Mesh::default();
//!     m.positions = vec![[0.0, 0.0, z], [1.0, 0.0, z], [1.0, 1.0, z], [0.0, 1.0, z]];
//!     m.push_face(&[0, 1, 2, 3]);
//!     m
//! };
//! let opts = CompareOptions::default().with_samples(10_000);
//! let c = compare(&square(0.0), &square(0.25), &opts).unwrap();
//! assert!((c.hausdorff - 0.25).abs() < 1e-12);
//! assert!((c.rms - 0.25).abs() < 1e-12);
//! ```
//!
//! ## How it works
//!
//! * **Surface.** Faces are fan-triangulated (`v0, vi, vi+1`); triangles of zero area are
//!   skipped on both sides (they add no surface). Vertices not used by any face are ignored.
//! * **Sampling** ([`SampleCount`]). The triangles are put in Z-order (Morton order of their
//!   centroids) and face samples are *stratified* along their cumulative area: sample `k` of
//!   `n` falls at fraction `(k + u_k) / n` of the total area, so each triangle receives its
//!   area's share of samples to within one (far less variance than independent Monte Carlo
//!   draws, and spatially even); inside its triangle a sample is uniform. Vertex samples (all
//!   used vertices, as Metro does) are on by default; edge samples (distinct polygon edges, at
//!   density `√(face samples per unit area)` per unit length, Metro's rule) are optional.
//!   Mean and RMS treat every sample alike, as Metro and MeshLab do, so they are the
//!   area-weighted averages up to the (small, with the default counts) weight of the vertex
//!   and edge samples.
//! * **Closest point.** A bounding-volume hierarchy (binned SAH, built in parallel) over the
//!   target's triangles answers exact nearest-point queries (Ericson's closest point on a
//!   triangle, in `f64`) with nearest-first traversal and pruning; each query is seeded with
//!   the previous sample's triangle. Samples run in Morton order, so consecutive queries are
//!   close together whatever the element order of the input. Build O(n log n), queries
//!   O(log n) each for well-spread meshes, so a comparison costs O((n + s) log n); memory is
//!   about 130 bytes per target triangle during the build and 72 after.
//! * **Determinism.** Samples are generated and measured in fixed chunks, each with its own
//!   SplitMix64 stream derived from [`CompareOptions::seed`]; chunks run in parallel (rayon)
//!   and their partial sums are combined in chunk order, so the result is bit-for-bit the same
//!   for the same input whatever the number of threads.
//!
//! For many queries against one fixed surface (error-vs-size series, per-vertex displacement
//! checks) build a [`SurfaceIndex`] once and reuse it.
#![warn(missing_docs)]

mod bvh;
mod geom;
mod sample;

use bvh::{Bvh, Hit};
use geom::{V3, v64};
use rayon::prelude::*;
use sample::{Rng, point_in_triangle, stratified};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use tessd_mesh::{Mesh, MeshError};
use thiserror::Error;

/// Smallest number of face samples [`SampleCount::Auto`] chooses.
pub const AUTO_MIN_SAMPLES: u64 = 1_000_000;
/// Largest number of face samples [`SampleCount::Auto`] chooses: at the 1–2 M samples/s
/// measured on two cores (`bench/compare/README.md`) this keeps one direction on a
/// 10 M-triangle mesh to tens of seconds, and vertex samples (every vertex) still cover
/// every triangle corner.
pub const AUTO_MAX_SAMPLES: u64 = 20_000_000;
/// Face samples per triangle for [`SampleCount::Auto`] (Metro's default).
pub const AUTO_SAMPLES_PER_TRIANGLE: u64 = 10;

/// Samples per work chunk: the unit of parallelism and of the deterministic reduction.
const CHUNK: u64 = 8192;

/// Errors from [`compare`], [`one_sided`] and [`SurfaceIndex`].
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CompareError {
    /// The mesh has no faces, so it has no surface to sample or measure against. `which` is
    /// `"a"`/`"b"` ([`compare`]) or `"from"`/`"to"` ([`one_sided`], [`SurfaceIndex`]).
    #[error("mesh {which} has no faces; a surface distance needs a surface")]
    EmptyMesh {
        /// Which input.
        which: &'static str,
    },
    /// The mesh has faces but every one of them has zero area.
    #[error("mesh {which} has {faces} faces but all of them have zero area")]
    DegenerateMesh {
        /// Which input.
        which: &'static str,
        /// Its number of faces.
        faces: usize,
    },
    /// The mesh breaks an invariant of [`Mesh`] (see [`Mesh::validate`]).
    #[error("mesh {which} is invalid: {source}")]
    InvalidMesh {
        /// Which input.
        which: &'static str,
        /// What is wrong.
        #[source]
        source: MeshError,
    },
    /// The options describe no samples at all (zero face samples and no vertex or edge
    /// samples), or a sample density that is negative or not finite.
    #[error("invalid options: {0}")]
    InvalidOptions(String),
    /// [`CompareOptions::cancel`] was set before the comparison finished.
    #[error("cancelled")]
    Cancelled,
}

/// A flag another thread sets to stop a comparison (the daemon's cancel token): checked
/// before and between the preparation steps, before every node split of the index's parallel
/// levels, and every [`CANCEL_EVERY`] samples, so a comparison stops within a few
/// milliseconds of work. Two flags are equal when they are the same flag.
#[derive(Clone, Debug, Default)]
pub struct CancelFlag(pub Arc<AtomicBool>);

impl PartialEq for CancelFlag {
    fn eq(&self, other: &CancelFlag) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl CancelFlag {
    /// Whether the flag is set.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Samples measured between two looks at the cancel flag (about 1 ms of work).
pub const CANCEL_EVERY: u64 = 1024;

/// How many points to sample on the faces of the `from` surface (vertex and edge samples
/// come on top of these).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum SampleCount {
    /// `10 × max(triangles of from, triangles of to)` (Metro's default: ten per face of the
    /// larger mesh), clamped to [`AUTO_MIN_SAMPLES`]..=[`AUTO_MAX_SAMPLES`] (1 M to 20 M).
    /// Both directions of [`compare`] therefore use the same count.
    Auto,
    /// Exactly this many face samples.
    Total(u64),
    /// This many face samples per unit of area (rounded to the nearest integer).
    PerUnitArea(f64),
}

/// Options of a comparison. Build with `CompareOptions::default().with_...(...)`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct CompareOptions {
    /// Number of face samples (default [`SampleCount::Auto`]).
    pub samples: SampleCount,
    /// Seed of the sample placement (default 0). Same inputs and seed → same result, bit for
    /// bit, whatever the thread count.
    pub seed: u64,
    /// Also sample every vertex used by a face (default `true`, as Metro does): the extreme
    /// points of a simplified surface are usually its vertices.
    pub include_vertices: bool,
    /// Also sample the distinct polygon edges at `√density` samples per unit length (default
    /// `false`; Metro's edge sampling).
    pub include_edges: bool,
    /// Stops the comparison with [`CompareError::Cancelled`] when set (default: none).
    pub cancel: Option<CancelFlag>,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            samples: SampleCount::Auto,
            seed: 0,
            include_vertices: true,
            include_edges: false,
            cancel: None,
        }
    }
}

impl CompareOptions {
    /// Sets [`CompareOptions::samples`].
    pub fn with_sample_count(mut self, samples: SampleCount) -> Self {
        self.samples = samples;
        self
    }

    /// Exactly `n` face samples ([`SampleCount::Total`]).
    pub fn with_samples(self, n: u64) -> Self {
        self.with_sample_count(SampleCount::Total(n))
    }

    /// `density` face samples per unit area ([`SampleCount::PerUnitArea`]).
    pub fn with_samples_per_area(self, density: f64) -> Self {
        self.with_sample_count(SampleCount::PerUnitArea(density))
    }

    /// Sets [`CompareOptions::seed`].
    pub fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Sets [`CompareOptions::include_vertices`].
    pub fn with_vertices(mut self, include: bool) -> Self {
        self.include_vertices = include;
        self
    }

    /// Sets [`CompareOptions::include_edges`].
    pub fn with_edges(mut self, include: bool) -> Self {
        self.include_edges = include;
        self
    }

    /// Sets [`CompareOptions::cancel`].
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(CancelFlag(flag));
        self
    }

    /// `Err(Cancelled)` when the cancel flag is set.
    fn check_cancel(&self) -> Result<(), CompareError> {
        if self.cancel.as_ref().is_some_and(CancelFlag::is_set) {
            Err(CompareError::Cancelled)
        } else {
            Ok(())
        }
    }
}

/// The one-sided distance from the samples of one surface to another surface.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Distance {
    /// Largest sample distance: the one-sided Hausdorff distance (estimated from below).
    pub max: f64,
    /// Mean sample distance.
    pub mean: f64,
    /// Root mean square of the sample distances: `sqrt(Σ d² / samples)`.
    pub rms: f64,
    /// Number of samples (vertex + edge + face samples).
    pub samples: u64,
    /// The sample (on the `from` surface) at distance `max` (the first one, in sample order).
    pub argmax_point: [f64; 3],
    /// Its closest point on the `to` surface.
    pub argmax_closest: [f64; 3],
    /// Area of the `from` surface (sum of its non-degenerate fan triangles).
    pub area: f64,
}

/// Both one-sided distances between two surfaces and their symmetric summaries.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct Comparison {
    /// Samples of `a` measured against `b`.
    pub a_to_b: Distance,
    /// Samples of `b` measured against `a`.
    pub b_to_a: Distance,
    /// Symmetric Hausdorff distance: `max(a_to_b.max, b_to_a.max)`.
    pub hausdorff: f64,
    /// Symmetric mean: the sample-weighted mean over both directions,
    /// `(n_ab·mean_ab + n_ba·mean_ba) / (n_ab + n_ba)`.
    pub mean: f64,
    /// Symmetric RMS: the square root of the sample-weighted mean of squared distances over
    /// both directions, `sqrt((n_ab·rms_ab² + n_ba·rms_ba²) / (n_ab + n_ba))`, i.e. the RMS of
    /// the pooled samples of both directions.
    pub rms: f64,
    /// Diagonal of the bounding box of both meshes together (of their used vertices), the
    /// usual scale to report relative errors against.
    pub bbox_diagonal: f64,
}

impl Comparison {
    /// Assembles a comparison from its two one-sided distances (e.g. computed separately with
    /// [`one_sided`] or [`SurfaceIndex::distance_from`]) and the bounding-box diagonal (see
    /// [`bbox_diagonal`]); the symmetric fields are derived as documented on each field.
    pub fn from_directions(a_to_b: Distance, b_to_a: Distance, bbox_diagonal: f64) -> Comparison {
        let (na, nb) = (a_to_b.samples as f64, b_to_a.samples as f64);
        let n = (na + nb).max(1.0);
        let mean = (na * a_to_b.mean + nb * b_to_a.mean) / n;
        let rms = ((na * a_to_b.rms * a_to_b.rms + nb * b_to_a.rms * b_to_a.rms) / n).sqrt();
        Comparison {
            hausdorff: a_to_b.max.max(b_to_a.max),
            a_to_b,
            b_to_a,
            mean,
            rms,
            bbox_diagonal,
        }
    }

    /// [`Comparison::hausdorff`] as a fraction of [`Comparison::bbox_diagonal`] (0 when the
    /// diagonal is 0).
    pub fn hausdorff_relative(&self) -> f64 {
        if self.bbox_diagonal > 0.0 {
            self.hausdorff / self.bbox_diagonal
        } else {
            0.0
        }
    }
}

/// The closest point of a surface to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ClosestPoint {
    /// The point of the surface.
    pub point: [f64; 3],
    /// Its distance to the query point.
    pub distance: f64,
}

/// A surface prepared for closest-point queries (a BVH over its triangles); build it once to
/// measure many meshes or points against the same surface.
pub struct SurfaceIndex {
    bvh: Bvh,
    area: f64,
}

impl std::fmt::Debug for SurfaceIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfaceIndex")
            .field("triangles", &self.bvh.len())
            .field("area", &self.area)
            .field("heap_bytes", &self.bvh.heap_bytes())
            .finish()
    }
}

impl SurfaceIndex {
    /// Validates `mesh` and builds the index over its non-degenerate fan triangles.
    ///
    /// # Errors
    /// [`CompareError::InvalidMesh`], [`CompareError::EmptyMesh`] or
    /// [`CompareError::DegenerateMesh`] (with `which = "to"`).
    pub fn new(mesh: &Mesh) -> Result<SurfaceIndex, CompareError> {
        check(mesh, "to")?;
        Self::build(mesh, "to")
    }

    fn build(mesh: &Mesh, which: &'static str) -> Result<SurfaceIndex, CompareError> {
        Self::build_with(mesh, which, &CompareOptions::default())
    }

    /// As [`SurfaceIndex::build`], stopping when `options`' cancel flag is set.
    fn build_with(
        mesh: &Mesh,
        which: &'static str,
        options: &CompareOptions,
    ) -> Result<SurfaceIndex, CompareError> {
        let t = usable(mesh, which)?;
        options.check_cancel()?;
        let area = t.areas.iter().sum();
        let cancel = options.cancel.as_ref().map(|c| &*c.0);
        let bvh = Bvh::build_cancellable(&mesh.positions, &t.tris, cancel)
            .ok_or(CompareError::Cancelled)?;
        Ok(SurfaceIndex { bvh, area })
    }

    /// Number of (non-degenerate, fan) triangles indexed.
    pub fn triangle_count(&self) -> usize {
        self.bvh.len()
    }

    /// Total area of the indexed surface.
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The exact closest point of the surface to `p`.
    pub fn closest_point(&self, p: [f64; 3]) -> ClosestPoint {
        let h = self
            .bvh
            .nearest(V3::from_array(p), None, &mut Vec::with_capacity(bvh::STACK));
        ClosestPoint {
            point: h.point.to_array(),
            distance: h.d2.sqrt(),
        }
    }

    /// The distance from each of `points` to the surface, computed in parallel, in order (e.g.
    /// the displacement of every vertex of a simplified mesh).
    pub fn distances(&self, points: &[[f64; 3]]) -> Vec<f64> {
        points
            .par_chunks(CHUNK as usize)
            .flat_map_iter(|c| {
                let mut seed = None;
                let mut stack = Vec::with_capacity(bvh::STACK);
                c.iter().map(move |&p| {
                    let h = self.bvh.nearest(V3::from_array(p), seed, &mut stack);
                    seed = Some(h.tri);
                    h.d2.sqrt()
                })
            })
            .collect()
    }

    /// The one-sided distance from the surface of `from` to this surface (see
    /// [`one_sided`]).
    ///
    /// # Errors
    /// As [`one_sided`], for `from`.
    pub fn distance_from(
        &self,
        from: &Mesh,
        options: &CompareOptions,
    ) -> Result<Distance, CompareError> {
        check(from, "from")?;
        self.measure(from, "from", options)
    }

    fn measure(
        &self,
        from: &Mesh,
        which: &'static str,
        options: &CompareOptions,
    ) -> Result<Distance, CompareError> {
        options.check_cancel()?;
        let t = usable(from, which)?;
        let plan = Plan::new(from, t, self.triangle_count(), options)?;
        options.check_cancel()?;
        plan.run(from, &self.bvh, options)
    }
}

/// The one-sided distance from the surface of `from` to the surface of `to`: `from` is
/// sampled (see [`CompareOptions`]) and every sample is measured against the closest point of
/// `to`.
///
/// # Errors
/// [`CompareError::InvalidMesh`] when a mesh fails [`Mesh::validate`],
/// [`CompareError::EmptyMesh`] / [`CompareError::DegenerateMesh`] when one has no faces / no
/// face of non-zero area (`which` is `"from"` or `"to"`), [`CompareError::InvalidOptions`]
/// when the options give no samples.
pub fn one_sided(
    from: &Mesh,
    to: &Mesh,
    options: &CompareOptions,
) -> Result<Distance, CompareError> {
    check(from, "from")?;
    check(to, "to")?;
    usable_quick(from, "from")?;
    let index = SurfaceIndex::build_with(to, "to", options)?;
    index.measure(from, "from", options)
}

/// Compares two surfaces in both directions: [`one_sided`] `a → b` and `b → a`, the
/// symmetric Hausdorff distance (the larger maximum) and the sample-weighted symmetric mean
/// and RMS (see [`Comparison`]). With [`SampleCount::Auto`] both directions use the same
/// number of face samples.
///
/// # Errors
/// As [`one_sided`], with `which` = `"a"` or `"b"`.
pub fn compare(a: &Mesh, b: &Mesh, options: &CompareOptions) -> Result<Comparison, CompareError> {
    check(a, "a")?;
    check(b, "b")?;
    usable_quick(a, "a")?;
    usable_quick(b, "b")?;
    let a_to_b = SurfaceIndex::build_with(b, "b", options)?.measure(a, "a", options)?;
    let b_to_a = SurfaceIndex::build_with(a, "a", options)?.measure(b, "b", options)?;
    Ok(Comparison::from_directions(
        a_to_b,
        b_to_a,
        bbox_diagonal(a, b),
    ))
}

/// Diagonal of the bounding box of the used vertices of both meshes (0 if neither has faces).
pub fn bbox_diagonal(a: &Mesh, b: &Mesh) -> f64 {
    let (lo, hi) = match (a.bounds(), b.bounds()) {
        (Some((lo1, hi1)), Some((lo2, hi2))) => (
            [lo1[0].min(lo2[0]), lo1[1].min(lo2[1]), lo1[2].min(lo2[2])],
            [hi1[0].max(hi2[0]), hi1[1].max(hi2[1]), hi1[2].max(hi2[2])],
        ),
        (Some(b), None) | (None, Some(b)) => b,
        (None, None) => return 0.0,
    };
    v64(hi).distance(v64(lo))
}

fn check(mesh: &Mesh, which: &'static str) -> Result<(), CompareError> {
    mesh.validate()
        .map_err(|source| CompareError::InvalidMesh { which, source })?;
    if mesh.face_count() == 0 {
        return Err(CompareError::EmptyMesh { which });
    }
    Ok(())
}

/// Cheap early check (before any index is built) that a mesh has a face of non-zero area.
fn usable_quick(mesh: &Mesh, which: &'static str) -> Result<(), CompareError> {
    let pos = &mesh.positions;
    let any = mesh.faces().any(|f| {
        (1..f.len() - 1).any(|i| {
            let a = geom::triangle_area(
                v64(pos[f[0] as usize]),
                v64(pos[f[i] as usize]),
                v64(pos[f[i + 1] as usize]),
            );
            a > 0.0 && a.is_finite()
        })
    });
    if any {
        Ok(())
    } else {
        Err(CompareError::DegenerateMesh {
            which,
            faces: mesh.face_count(),
        })
    }
}

fn usable(mesh: &Mesh, which: &'static str) -> Result<sample::Triangles, CompareError> {
    let t = sample::triangulate(mesh);
    if t.tris.is_empty() {
        return Err(CompareError::DegenerateMesh {
            which,
            faces: mesh.face_count(),
        });
    }
    Ok(t)
}

/// The kinds of samples, in the order they are generated and reduced.
#[derive(Clone, Copy)]
enum Kind {
    Vertex = 1,
    Edge = 2,
    Face = 3,
}

/// One unit of work: samples `start..end` of one kind.
#[derive(Clone, Copy)]
struct Job {
    kind: Kind,
    chunk: u64,
    start: u64,
    end: u64,
}

/// Everything needed to generate the samples of a `from` surface.
struct Plan {
    tris: Vec<[u32; 3]>,
    area_cum: Vec<f64>,
    area: f64,
    face_samples: u64,
    vertices: Vec<u32>,
    edges: Vec<[u32; 2]>,
    edge_cum: Vec<f64>,
    edge_samples: u64,
}

impl Plan {
    fn new(
        from: &Mesh,
        t: sample::Triangles,
        to_triangles: usize,
        options: &CompareOptions,
    ) -> Result<Plan, CompareError> {
        // Sample (and so query) in Morton order of the triangles and vertices: coherent
        // queries are several times faster than queries in an arbitrary element order.
        let pos = &from.positions;
        let order = sample::morton_order(t.tris.len(), |i| {
            let [a, b, c] = t.tris[i].map(|v| v64(pos[v as usize]));
            (a + b + c) * (1.0 / 3.0)
        });
        options.check_cancel()?;
        let tris: Vec<[u32; 3]> = order.par_iter().map(|&i| t.tris[i as usize]).collect();
        let areas: Vec<f64> = order.par_iter().map(|&i| t.areas[i as usize]).collect();
        drop((order, t));
        let area_cum = sample::cumulative(&areas);
        drop(areas);
        let area = *area_cum.last().unwrap_or(&0.0);
        let face_samples = match options.samples {
            SampleCount::Auto => (AUTO_SAMPLES_PER_TRIANGLE * tris.len().max(to_triangles) as u64)
                .clamp(AUTO_MIN_SAMPLES, AUTO_MAX_SAMPLES),
            SampleCount::Total(n) => n,
            SampleCount::PerUnitArea(d) => {
                if !(d.is_finite() && d >= 0.0) {
                    return Err(CompareError::InvalidOptions(format!(
                        "sample density {d} per unit area; it must be finite and ≥ 0"
                    )));
                }
                (d * area).round() as u64
            }
        };
        options.check_cancel()?;
        let vertices = if options.include_vertices {
            let v = sample::referenced_vertices(from);
            sample::morton_order(v.len(), |i| v64(pos[v[i] as usize]))
                .into_par_iter()
                .map(|i| v[i as usize])
                .collect()
        } else {
            Vec::new()
        };
        let (edges, edge_cum, edge_samples) = if options.include_edges && face_samples > 0 {
            let (e, len) = sample::polygon_edges(from);
            let order = sample::morton_order(e.len(), |i| {
                v64(pos[e[i][0] as usize]) + v64(pos[e[i][1] as usize])
            });
            let e: Vec<[u32; 2]> = order.iter().map(|&i| e[i as usize]).collect();
            let len: Vec<f64> = order.iter().map(|&i| len[i as usize]).collect();
            let cum = sample::cumulative(&len);
            let total = *cum.last().unwrap_or(&0.0);
            let n = ((face_samples as f64 / area).sqrt() * total).round() as u64;
            (e, cum, if total > 0.0 { n } else { 0 })
        } else {
            (Vec::new(), Vec::new(), 0)
        };
        options.check_cancel()?;
        if face_samples + edge_samples + vertices.len() as u64 == 0 {
            return Err(CompareError::InvalidOptions(
                "no samples: zero face samples and no vertex or edge samples".into(),
            ));
        }
        Ok(Plan {
            tris,
            area_cum,
            area,
            face_samples,
            vertices,
            edges,
            edge_cum,
            edge_samples,
        })
    }

    fn jobs(&self) -> Vec<Job> {
        let mut jobs = Vec::new();
        for (kind, n) in [
            (Kind::Vertex, self.vertices.len() as u64),
            (Kind::Edge, self.edge_samples),
            (Kind::Face, self.face_samples),
        ] {
            let chunks = n.div_ceil(CHUNK);
            jobs.extend((0..chunks).map(|c| Job {
                kind,
                chunk: c,
                start: c * CHUNK,
                end: ((c + 1) * CHUNK).min(n),
            }));
        }
        jobs
    }

    /// Measures every job's samples; each job looks at the cancel flag before it starts and
    /// every [`CANCEL_EVERY`] samples, and skips the rest of its samples once it is set.
    fn run(
        &self,
        from: &Mesh,
        bvh: &Bvh,
        options: &CompareOptions,
    ) -> Result<Distance, CompareError> {
        let cancel = options.cancel.as_ref();
        let stats: Vec<Stats> = self
            .jobs()
            .par_iter()
            .map(|job| {
                if cancel.is_some_and(CancelFlag::is_set) {
                    Stats::new()
                } else {
                    self.run_job(job, from, bvh, options.seed, cancel)
                }
            })
            .collect();
        options.check_cancel()?;
        let mut total = Stats::new();
        for s in &stats {
            total.merge(s);
        }
        let n = total.n.max(1) as f64;
        Ok(Distance {
            max: total.max.max(0.0),
            mean: total.sum / n,
            rms: (total.sum2 / n).sqrt(),
            samples: total.n,
            argmax_point: total.argmax.to_array(),
            argmax_closest: total.argmax_closest.to_array(),
            area: self.area,
        })
    }

    fn run_job(
        &self,
        job: &Job,
        from: &Mesh,
        bvh: &Bvh,
        seed: u64,
        cancel: Option<&CancelFlag>,
    ) -> Stats {
        let pos = &from.positions;
        let mut rng = Rng::new(seed, ((job.kind as u64) << 48) | job.chunk);
        let mut st = Stats::new();
        let mut hint = None;
        let mut stack = Vec::with_capacity(bvh::STACK);
        let (mut count, mut stopped) = (0u64, false);
        let mut measure = |p: V3| {
            if stopped {
                return;
            }
            count += 1;
            if count.is_multiple_of(CANCEL_EVERY) && cancel.is_some_and(CancelFlag::is_set) {
                stopped = true;
                return;
            }
            let h = bvh.nearest(p, hint, &mut stack);
            hint = Some(h.tri);
            st.add(p, &h);
        };
        match job.kind {
            Kind::Vertex => {
                for &v in &self.vertices[job.start as usize..job.end as usize] {
                    measure(v64(pos[v as usize]));
                }
            }
            Kind::Edge => stratified(
                &self.edge_cum,
                self.edge_samples,
                job.start,
                job.end,
                &mut rng,
                |j, f, _| {
                    let e = self.edges[j];
                    let (a, b) = (v64(pos[e[0] as usize]), v64(pos[e[1] as usize]));
                    measure(a + (b - a) * f);
                },
            ),
            Kind::Face => stratified(
                &self.area_cum,
                self.face_samples,
                job.start,
                job.end,
                &mut rng,
                |j, f, rng| {
                    let t = self.tris[j];
                    let r2 = rng.f64();
                    measure(point_in_triangle(
                        v64(pos[t[0] as usize]),
                        v64(pos[t[1] as usize]),
                        v64(pos[t[2] as usize]),
                        f,
                        r2,
                    ));
                },
            ),
        }
        st
    }
}

/// Partial sums of one chunk of samples.
struct Stats {
    n: u64,
    sum: f64,
    sum2: f64,
    max: f64,
    argmax: V3,
    argmax_closest: V3,
}

impl Stats {
    fn new() -> Stats {
        Stats {
            n: 0,
            sum: 0.0,
            sum2: 0.0,
            max: f64::NEG_INFINITY,
            argmax: V3::ZERO,
            argmax_closest: V3::ZERO,
        }
    }

    #[inline(always)]
    fn add(&mut self, p: V3, h: &Hit) {
        let d = h.d2.sqrt();
        self.n += 1;
        self.sum += d;
        self.sum2 += h.d2;
        if d > self.max {
            self.max = d;
            self.argmax = p;
            self.argmax_closest = h.point;
        }
    }

    fn merge(&mut self, o: &Stats) {
        self.n += o.n;
        self.sum += o.sum;
        self.sum2 += o.sum2;
        if o.max > self.max {
            self.max = o.max;
            self.argmax = o.argmax;
            self.argmax_closest = o.argmax_closest;
        }
    }
}
