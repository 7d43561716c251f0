//! # tessd-simplify — vertex clustering with quality and complexity goals
//!
//! The simplification stage of the mesh pipeline (`mesh → simplify`), after Belblidia &
//! Perrin, *Simplification de surfaces polygonales complexes* (paper 004), which extends
//! Rossignac & Borrel's clustering (1993). Clustering survives the messy topology CAD exports
//! have — duplicate facets, coincident vertices, stacked solids — because it never looks at
//! adjacency, only at where vertices are.
//!
//! The pipeline (section 2), one file per step:
//!
//! 1. [`weights`] — a weight per vertex (longest incident edge by default);
//! 2. [`triangulate`] — optional fan triangulation of polygons;
//! 3. a partition of the bounding volume — regular (`grid_cells.rs`: a dense table of
//!    4 × 4 × 4-cell bricks; `grid_partition.rs`'s hash where the box holds too many bricks), or
//!    adaptive binary splitting driven by a quality goal (`adaptive_quality.rs`) or a
//!    complexity goal (`adaptive_complexity.rs`) over what both share (`adaptive_partition.rs`,
//!    sections 3–5);
//! 4. a representative per cell — weighted barycentre or heaviest vertex (the paper), or the
//!    quadric minimiser (`representative.rs`, `quadric.rs`; Lindstrom 2000, every cluster's
//!    quadric summed in one pass over the faces). The grid streams its sums into per-cluster
//!    fixed-point slots in the pass that numbers its cells (`grid_sums.rs`); the adaptive
//!    partitions sum per-cell statistics (`cluster_stats.rs`) cluster by cluster as each is
//!    placed (docs/simplify.md, "Memory");
//! 5. elimination of what collapsed (`elimination.rs`; for triangles the pass that decides the
//!    faces' fates writes the kept ones);
//! 6. beyond the paper, for the quality goal: cells split further until every collapsed face's
//!    image lies on the output (`coverage.rs`), so the tolerance bounds the distance between the
//!    surfaces, and a verified bound of that distance for every method (`surface_bound.rs`),
//!    with how far another triangulation of the input's non-planar polygons may lie from the
//!    fan that bound holds for ([`polygon_twist`]);
//!
//! The passes over vertices, faces and clusters (weights, bounds, binning, statistics,
//! quadrics, representatives, elimination) run on every core of rayon's pool (`--threads` /
//! `RAYON_NUM_THREADS`) in blocks of a fixed size combined in block order (`blocks.rs`), so the
//! output is the same bytes whatever the thread count.
//!
//! and beyond the paper: boundary/feature preservation ([`features`]), normals, UVs, face
//! groups and generic attributes carried through (`attributes.rs`), sharp edges and creases
//! carried onto the output's edges (`edges.rs`), the partition as boxes for "show partition"
//! ([`partition_boxes`]), and LOD chains ([`lod`]).
//!
//! ```
//! use tessd_mesh::Mesh;
//! use tessd_simplify::{simplify, Count, Method, SimplifyOptions};
//!
//! // A 20 × 20 grid of quads.
//! let mut m = Mesh::default();
//! for j in 0..21 { for i in 0..21 { m.positions.push([i as f32, j as f32, 0.0]); } }
//! for j in 0..20 { for i in 0..20 { let v = j * 21 + i; m.push_face(&[v, v + 1, v + 22, v + 21]); } }
//!
//! let options = SimplifyOptions::new(Method::Complexity(Count::Relative(0.25)));
//! let out = simplify(&m, &options, &mut |_, _| true).unwrap();
//! assert_eq!(out.report.output_vertices, 110); // 25 % of 441
//! ```
#![warn(missing_docs)]

mod adaptive_complexity;
mod adaptive_partition;
mod adaptive_quality;
mod area_vector;
mod attributes;
mod blocks;
mod cell_table;
mod cluster_stats;
mod coverage;
mod edges;
mod elimination;
mod error;
mod feature_priority;
pub mod features;
mod grid_cells;
mod grid_frame;
mod grid_partition;
mod grid_quadrics;
mod grid_sums;
#[cfg(test)]
mod grid_tests;
mod kd;
pub mod lod;
mod options;
mod partition;
pub mod partition_boxes;
pub mod polygon_twist;
mod quadric;
mod representative;
mod split_queue;
mod surface_bound;
mod tangent_key;
pub mod triangulate;
pub mod weights;

pub use error::SimplifyError;
pub use options::{
    Count, GridSize, Length, Method, ProgressFn, Representative, SimplifyOptions, Weighting,
};
pub use partition::{Cell, Partition};
pub use quadric::Quadric;

use adaptive_partition::{Adaptive, LeafView, Stop};
use partition::{UNUSED, referenced_bounds};
use rayon::prelude::*;
use representative::Source::{Leaves, Members};
use std::borrow::Cow;
use std::sync::atomic::Ordering;
use tessd_mesh::{Domain, Mesh};

/// Figures about one simplification.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Report {
    /// Referenced input vertices.
    pub input_vertices: u64,
    /// Input faces (after the optional triangulation).
    pub input_faces: u64,
    /// Output vertices.
    pub output_vertices: u64,
    /// Output faces.
    pub output_faces: u64,
    /// Cells of the partition that hold vertices.
    pub clusters: u64,
    /// Faces removed because they collapsed.
    pub degenerate_faces: u64,
    /// Faces removed as duplicates.
    pub duplicate_faces: u64,
    /// Largest distance from an input vertex to the representative it merged into.
    pub max_displacement: f64,
    /// A verified upper bound on the symmetric Hausdorff distance between the input and the
    /// output surfaces (every point of either within this distance of the other; see
    /// `surface_bound.rs`). Quality and complexity goals; `None` for the grid goal (the fast
    /// path) and when the output has no faces left.
    pub surface_error: Option<f64>,
    /// Quality goal: rounds of splitting cells whose collapsed faces' images were not on the
    /// output (see `coverage.rs`); 0 when the paper's partition already covered the input.
    pub refinement_rounds: u32,
    /// Input faces whose image is not on the output (collapsed onto a segment that is no
    /// output edge or a point that is no output vertex). The quality goal refines until there
    /// are none, unless the cells involved cannot be split (their vertices coincide).
    pub uncovered_faces: u64,
    /// The quality goal's tolerance in model units, when that method was used.
    pub tolerance: Option<f64>,
    /// The complexity goal's vertex count, when that method was used.
    pub target_vertices: Option<u64>,
    /// Quality and complexity goals: the largest distance between an input polygon's fan
    /// triangulation (the one tessd bounds the surfaces for: first corner to every other
    /// edge) and any other triangulation of it; exact for quads, an upper bound for polygons
    /// of five corners or more, 0 for triangles (see `polygon_twist.rs`). Another reader's
    /// split of the input may lie up to this much farther from the output than
    /// `surface_error`. `None` for the grid goal.
    pub polygon_twist: Option<f64>,
    /// Input polygons twisted by more than the tolerance (quality goal) or the surface error
    /// reached (complexity goal); [`Report::twist_note`] speaks of them.
    pub twisted_polygons: u64,
}

/// The simplified mesh, its partition's cells (when asked for) and the figures.
#[derive(Clone, Debug)]
pub struct Simplified {
    /// The result.
    pub mesh: Mesh,
    /// Non-empty cells of the partition (empty unless `keep_partition` was set).
    pub cells: Vec<Cell>,
    /// Figures.
    pub report: Report,
}

/// Simplifies `mesh` as `options` say. `progress(fraction, stage)` is called between stages;
/// returning `false` cancels.
///
/// # Errors
/// [`SimplifyError::InvalidMesh`] for a mesh that fails validation, [`SimplifyError::Empty`]
/// for one without faces, [`SimplifyError::InvalidOption`] for a tolerance ≤ 0, a target that
/// is not below the input's vertex count, or a grid size ≤ 0; [`SimplifyError::Cancelled`].
pub fn simplify(
    mesh: &Mesh,
    options: &SimplifyOptions,
    progress: &mut ProgressFn,
) -> Result<Simplified, SimplifyError> {
    let prepared = Prepared::new(mesh, options, needs_triangles(options.method))?;
    prepared.run(options, progress)
}

/// What every level of a simplification shares: the (triangulated) working mesh, vertex
/// weights, bounds and feature classes. [`lod::lod_chain`] computes it once for all levels.
pub(crate) struct Prepared<'a> {
    work: Cow<'a, Mesh>,
    weights: Vec<f32>,
    bounds: Cell,
    size: f64,
    classes: Option<Vec<u8>>,
    input_vertices: u64,
    /// The input polygons' twists, measured when the fan triangulation was forced.
    twists: polygon_twist::Twists,
}

impl<'a> Prepared<'a> {
    /// Validates `mesh` and prepares it as `options` say (triangulation, weighting, features);
    /// `force_triangles`: fan-triangulate polygons whatever `options.triangulate` says.
    pub(crate) fn new(
        mesh: &'a Mesh,
        options: &SimplifyOptions,
        force_triangles: bool,
    ) -> Result<Self, SimplifyError> {
        if let Some(p) = Self::plain_triangles(mesh, options) {
            return Ok(p);
        }
        mesh.validate()?;
        if mesh.face_count() == 0 {
            return Err(SimplifyError::Empty);
        }
        let triangulate = options.triangulate || force_triangles;
        let polygons = mesh.faces().any(|f| f.len() > 3);
        // The bounded goals report how far another split of the polygons may lie.
        let twists = if force_triangles && polygons {
            polygon_twist::Twists::of(mesh)
        } else {
            polygon_twist::Twists::default()
        };
        let work: Cow<Mesh> = if triangulate && polygons {
            Cow::Owned(triangulate::triangulate(mesh))
        } else {
            Cow::Borrowed(mesh)
        };
        let weights = weights::vertex_weights(&work, options.weighting);
        let referenced =
            referenced_bounds(&work.positions, &weights).ok_or(SimplifyError::Empty)?;
        Ok(Self::of(work, weights, referenced, options, twists))
    }

    /// The preparation of `work`, from its weights and its referenced bounds and vertex count:
    /// the size the relative lengths scale with and the feature classes.
    fn of(
        work: Cow<'a, Mesh>,
        weights: Vec<f32>,
        (bounds, input_vertices): (Cell, u64),
        options: &SimplifyOptions,
        twists: polygon_twist::Twists,
    ) -> Self {
        let size = (0..3)
            .map(|k| f64::from(bounds.max[k] - bounds.min[k]))
            .fold(0.0, f64::max);
        let classes = options
            .preserve_boundaries
            .then(|| features::feature_classes(&work, options.feature_angle_deg));
        Prepared {
            work,
            weights,
            bounds,
            size,
            classes,
            input_vertices,
            twists,
        }
    }

    /// [`Prepared::new`] for a mesh of triangles and positions alone (the usual large input),
    /// checked inside the passes it needs anyway rather than by [`Mesh::validate`]'s own
    /// (issue 33): offsets and indices in the weights' face pass, finite coordinates in the
    /// bounds' vertex pass. `None` for any other mesh, or where a check fails: then
    /// [`Mesh::validate`] runs and names the fault with its usual words.
    fn plain_triangles(mesh: &'a Mesh, options: &SimplifyOptions) -> Option<Self> {
        let plain = mesh.face_count() > 0
            && mesh.triangles().is_some()
            && mesh.face_offsets.first() == Some(&0)
            && mesh.face_offsets.last().map(|&o| o as usize) == Some(mesh.face_indices.len())
            && mesh.normals.is_none()
            && mesh.uvs.is_none()
            && mesh.creases.is_empty()
            && mesh.face_groups.is_empty()
            && mesh.attributes.is_empty()
            && mesh.sharp_edges.is_empty();
        if !plain {
            return None;
        }
        let weights = weights::checked_triangle_weights(mesh, options.weighting)?;
        let (bounds, finite) = partition::checked_bounds(&mesh.positions, &weights);
        let referenced = bounds.filter(|_| finite)?;
        let twists = polygon_twist::Twists::default();
        Some(Self::of(
            Cow::Borrowed(mesh),
            weights,
            referenced,
            options,
            twists,
        ))
    }

    /// Runs one simplification (the method, representative and partition flag of `options`;
    /// the preparation options were fixed by [`Prepared::new`]).
    pub(crate) fn run(
        &self,
        options: &SimplifyOptions,
        progress: &mut ProgressFn,
    ) -> Result<Simplified, SimplifyError> {
        let cancel = options.cancel.as_deref();
        // The passes name themselves as they run; some run again in later rounds (placing and
        // counting, coverage), so the fraction reported is the furthest reached: a status bar
        // fed by it never goes back.
        let mut reached = 0f64;
        let mut step = |fraction: f64, stage: &str| -> Result<(), SimplifyError> {
            reached = reached.max(fraction);
            let stop = cancel.is_some_and(|c| c.load(Ordering::Relaxed));
            if stop || !progress(reached, stage) {
                Err(SimplifyError::Cancelled)
            } else {
                Ok(())
            }
        };
        let (work, weights, bounds) = (&*self.work, &self.weights[..], &self.bounds);
        let classes = self.classes.as_deref();
        let mut report = Report {
            input_vertices: self.input_vertices,
            input_faces: work.face_count() as u64,
            ..Report::default()
        };
        step(0.1, "partition")?;
        let adaptive = Adaptive::new(
            &work.positions,
            weights,
            options.representative,
            options.keep_partition,
            cancel,
        );
        let stopped = |_: Stop| SimplifyError::Cancelled;
        // The quality goal's refinement, kept for the coverage rounds below.
        let mut refinable = None;
        // The grid's clusters' vertices, listed for placing their representatives.
        let mut members = None;
        // The complexity goal places the representatives of its last partition to count what
        // survives: they are kept for the output.
        let mut placed = None;
        // The grid's face pass, when it ran before the representatives (quadrics).
        let mut faced = None;
        let (mut partition, tolerance) = match options.method {
            Method::Grid(grid) => {
                let ok = match grid {
                    GridSize::CellsPerAxis(n) => n >= 1,
                    GridSize::CellSize(s) => s.is_finite() && s > 0.0,
                };
                if !ok {
                    return Err(SimplifyError::InvalidOption(format!(
                        "grid size {grid:?} must be positive"
                    )));
                }
                // The fused passes (grid_cells.rs, grid_sums.rs), each named to the progress
                // callback; the hash and member lists only where the box holds too many bricks.
                step(0.15, "cells")?;
                let keep = options.keep_partition;
                let positions = &work.positions;
                // The quadric representative's bounds are taken in the cell pass where its
                // quadrics are summed in the face pass (few clusters: little memory).
                let quadric = options.representative == Representative::Quadric;
                let most = grid_quadrics::most_clusters(positions.len());
                let q = if quadric { most } else { 0 };
                let cells =
                    grid_cells::grid_cells(positions, weights, classes, bounds, grid, keep, q);
                match cells {
                    Some((p, sums)) => {
                        let (g, _) = grid_frame::Grid::new(bounds, grid);
                        let rep = options.representative;
                        // Quadrics: summed in the face pass (F before C, the area test after
                        // C), where every cluster's quadric can be held at once.
                        let fused = work
                            .triangles()
                            .filter(|_| rep == Representative::Quadric)
                            .filter(|_| p.clusters <= most);
                        let mut quadrics = None;
                        if let Some(triangles) = fused {
                            step(0.3, "faces")?;
                            let (f, q) = grid_quadrics::faces_and_quadrics(
                                positions,
                                triangles,
                                &p.cluster_of,
                                p.clusters,
                            );
                            (faced, quadrics) = (Some(f), Some(q));
                        }
                        step(0.45, "representatives")?;
                        let reps = grid_sums::grid_representatives(
                            work,
                            &p.cluster_of,
                            sums,
                            &g,
                            rep,
                            quadrics,
                        );
                        placed = Some(reps);
                        (p, None)
                    }
                    None => {
                        let (p, m) = grid_partition::grid_partition(
                            positions, weights, classes, bounds, grid, keep,
                        );
                        members = Some(m);
                        (p, None)
                    }
                }
            }
            Method::Quality(length) => {
                let tol = length.resolve(self.size);
                if !(tol.is_finite() && tol > 0.0) {
                    let why = match length {
                        Length::Relative(f) => format!(
                            "{}% of the object's largest dimension ({}) is {tol}{}",
                            f * 100.0,
                            self.size,
                            if self.size == 0.0 {
                                "; give an absolute distance"
                            } else {
                                ""
                            }
                        ),
                        Length::Absolute(d) => format!("got {d}"),
                    };
                    return Err(SimplifyError::InvalidOption(format!(
                        "the tolerance must be positive: {why}"
                    )));
                }
                report.tolerance = Some(tol);
                // Keep a margin for rounding the representatives to f32.
                let inner = tol - 4.0 * f64::from(f32::EPSILON) * max_abs(bounds);
                step(0.12, "kd")?;
                let r = adaptive
                    .quality(classes, bounds, inner.max(tol * 0.5))
                    .map_err(stopped)?;
                step(0.5, "label")?;
                let p = adaptive.partition(&r);
                refinable = Some(r);
                (p, Some(tol))
            }
            Method::Complexity(count) => {
                let target = count.resolve(self.input_vertices);
                if target == 0 || target >= self.input_vertices {
                    return Err(SimplifyError::InvalidOption(format!(
                        "the target of {target} vertices must be between 1 and the input's {} (exclusive)",
                        self.input_vertices
                    )));
                }
                report.target_vertices = Some(target);
                // Cells are split by their surface-error estimate, not their displacement
                // alone (feature_priority.rs): CAD creases and curved strips get the vertices.
                step(0.11, "normals")?;
                let normals = feature_priority::vertex_normals(work, weights);
                let rep = options.representative;
                step(0.12, "kd")?;
                let mut cancelled = false;
                let more = |p: &Partition, leaves: LeafView| {
                    // The output loses clusters whose faces all collapsed: count what survives
                    // (the last partition's representatives go first).
                    placed = None;
                    cancelled = step(0.4, "place").is_err();
                    if cancelled {
                        return 0;
                    }
                    let (cluster_of, n) = (&p.cluster_of, p.clusters);
                    let reps =
                        representative::place(work, cluster_of, n, Leaves(leaves), rep, None);
                    cancelled = step(0.45, "count").is_err();
                    let used = elimination::count_used(work, cluster_of, &reps);
                    placed = Some(reps);
                    // Any further splitting is the partition's again.
                    cancelled = cancelled || step(0.5, "kd").is_err();
                    if cancelled {
                        return 0;
                    }
                    target.saturating_sub(used as u64)
                };
                let p = adaptive.complexity(classes, bounds, target, Some(normals), more);
                if cancelled {
                    return Err(SimplifyError::Cancelled);
                }
                (p.map_err(stopped)?, None)
            }
        };
        step(0.6, "merge")?;
        let corner_attributes = work.attributes.iter().any(|a| a.domain == Domain::Corner);
        let attributes = work.normals.is_some() || work.uvs.is_some() || corner_attributes;
        // Coverage rounds (quality goal): while some collapsed input face's image is off the
        // output, split the cells of its uncovered segments and points and check again. Each
        // round splits at least one cell, and cells whose vertices coincide cannot split, so
        // at most (distinct positions − clusters) rounds can follow; in practice 0 to 5 (see
        // bench/results/simplify_guarantee.md). The rounds read the clusters alone
        // (`coverage::gaps_by_clusters`); the output after placing and eliminating is checked
        // again only where that can differ: faces whose representatives came out collinear.
        // The adaptive goals work on triangles (`needs_triangles`) and bound the surfaces.
        let bounded = needs_triangles(options.method);
        let quality = refinable.is_some();
        let mut stuck = false;
        let (reps, kept, gaps) = loop {
            if let Some(r) = refinable.as_mut() {
                let mut moved = None;
                loop {
                    step(0.6, "cover")?;
                    let (cluster_of, n) = (&partition.cluster_of, partition.clusters);
                    let gaps = coverage::gaps_by_clusters(work, cluster_of, n, moved.as_deref());
                    if gaps.is_empty() {
                        break;
                    }
                    moved = Some(coverage::vertices_of(cluster_of, &gaps.clusters, n));
                    step(0.6, "kd")?;
                    if adaptive
                        .split_clusters(r, &gaps.clusters)
                        .map_err(stopped)?
                        == 0
                    {
                        stuck = true;
                        break;
                    }
                    step(0.6, "label")?;
                    partition = adaptive.partition(r);
                    report.refinement_rounds += 1;
                }
            }
            // The complexity goal placed its last partition already.
            if placed.is_none() {
                step(0.6, "place")?;
            }
            let reps = placed.take().unwrap_or_else(|| {
                let source = match (&members, &refinable) {
                    (Some(m), _) => Members(m, &work.positions, weights),
                    (None, Some(r)) => Leaves(r.view(weights)),
                    (None, None) => unreachable!("the complexity goal places its clusters"),
                };
                let (cluster_of, n) = (&partition.cluster_of, partition.clusters);
                representative::place(
                    work,
                    cluster_of,
                    n,
                    source,
                    options.representative,
                    tolerance,
                )
            });
            members = None;
            step(0.65, "faces")?;
            let fates = faced
                .take()
                .unwrap_or_else(|| elimination::fates(work, &partition.cluster_of, &reps));
            if refinable.is_some() && !stuck && fates.flattened() == 0 {
                // The clusters alone decided the coverage (above): this is the last round,
                // and the partition's vertex order can go before the faces are written.
                refinable = None;
            }
            let kept = fates.eliminate(work, &partition.cluster_of, &reps, attributes);
            // The grid goal is the fast path: it reports no surface bound.
            let check = bounded && (!quality || stuck || kept.flattened > 0);
            let gaps = if check {
                step(0.7, "cover")?;
                coverage::find_gaps(work, &partition.cluster_of, &kept, partition.clusters)
            } else {
                coverage::Gaps::default()
            };
            let Some(r) = refinable.as_mut().filter(|_| !gaps.is_empty() && !stuck) else {
                break (reps, kept, gaps);
            };
            step(0.6, "kd")?;
            if adaptive
                .split_clusters(r, &gaps.clusters)
                .map_err(stopped)?
                == 0
            {
                break (reps, kept, gaps);
            }
            step(0.6, "label")?;
            partition = adaptive.partition(r);
            report.refinement_rounds += 1;
        };
        // The partition's vertex order is not needed any more.
        drop(refinable);
        step(0.75, "eliminate")?;
        let (new_id, used) = used_clusters(&kept, partition.clusters);
        step(0.9, "attributes")?;
        let cluster_of = &partition.cluster_of;
        // Attributes read the elimination's bookkeeping; then its buffers become the mesh.
        let slots = attributes.then(|| attributes::CornerSlots::new(work, cluster_of, &kept));
        let normals = work
            .normals
            .as_ref()
            .zip(slots.as_ref())
            .map(|(n, s)| attributes::carry_face_varying(n, s, true));
        let uvs = work
            .uvs
            .as_ref()
            .zip(slots.as_ref())
            .map(|(t, s)| attributes::carry_face_varying(t, s, false));
        let face_groups = attributes::carry_groups(work, &kept);
        let generic =
            attributes::carry_attributes(work, cluster_of, &new_id, used, &kept, slots.as_ref());
        drop(slots);
        let (degenerate, duplicates) = (kept.degenerate, kept.duplicates);
        let mut face_indices = kept.face_indices;
        face_indices
            .par_iter_mut()
            .for_each(|c| *c = new_id[*c as usize]);
        let mut out = Mesh {
            positions: (0..partition.clusters)
                .filter(|&c| new_id[c] != UNUSED)
                .map(|c| reps[c])
                .collect(),
            face_offsets: kept.face_offsets,
            face_indices,
            normals,
            uvs,
            creases: Vec::new(),
            face_groups,
            group_names: if work.face_groups.is_empty() {
                Vec::new()
            } else {
                work.group_names.clone()
            },
            attributes: generic,
            sharp_edges: Vec::new(),
        };
        // Sharp edges and creases need the output's faces to tell which images are edges.
        let vertex_of = |v: u32| match cluster_of[v as usize] {
            UNUSED => UNUSED,
            c => new_id[c as usize],
        };
        if !work.sharp_edges.is_empty() {
            out.sharp_edges = edges::carry_sharp_edges(work, vertex_of, &out);
        }
        if !work.creases.is_empty() {
            out.creases = edges::carry_creases(work, vertex_of, &out);
        }
        // A maximum: the same whatever order the cores take it in. Squared, rooted once (the
        // root is monotonic, so this is the largest root to the bit).
        let largest = blocks::map(cluster_of.len(), |r| {
            let mut top = 0f64;
            for (p, &c) in work.positions[r.clone()].iter().zip(&cluster_of[r]) {
                if c != UNUSED {
                    top = top.max(dist2(*p, reps[c as usize]));
                }
            }
            top
        });
        report.max_displacement = largest.into_iter().fold(0.0, f64::max).sqrt();
        report.uncovered_faces = gaps.faces.len() as u64;
        report.surface_error = if bounded {
            surface_bound::surface_bound(
                work,
                cluster_of,
                &reps,
                &out,
                &gaps,
                report.max_displacement,
            )
        } else {
            None
        };
        if bounded {
            report.polygon_twist = Some(self.twists.max());
            let limit = report.tolerance.or(report.surface_error);
            report.twisted_polygons = limit.map_or(0, |l| self.twists.count_above(l));
        }
        report.clusters = partition.clusters as u64;
        report.output_vertices = used as u64;
        report.output_faces = out.face_count() as u64;
        report.degenerate_faces = degenerate;
        report.duplicate_faces = duplicates;
        let cells = if options.keep_partition {
            partition.cells
        } else {
            Vec::new()
        };
        step(1.0, "done")?;
        Ok(Simplified {
            mesh: out,
            cells,
            report,
        })
    }
}

/// Whether `method` works on triangles only: the adaptive goals bound and report the distance
/// between the surfaces, which needs a surface that does not depend on how a reader splits
/// the polygons that merging made non-planar (the paper, section 2, triangulates for that
/// reason). Polygons are fan-triangulated, as `tessd compare` and most readers do.
pub(crate) fn needs_triangles(method: Method) -> bool {
    !matches!(method, Method::Grid(_))
}

/// New index of every cluster that surviving faces use (in cluster order), and their count.
fn used_clusters(kept: &elimination::Eliminated, clusters: usize) -> (Vec<u32>, usize) {
    let mut new_id = vec![UNUSED; clusters];
    for &c in &kept.face_indices {
        new_id[c as usize] = 0;
    }
    let mut n = 0u32;
    for id in new_id.iter_mut().filter(|id| **id == 0) {
        *id = n;
        n += 1;
    }
    (new_id, n as usize)
}

fn max_abs(b: &Cell) -> f64 {
    (0..3)
        .map(|k| f64::from(b.min[k].abs().max(b.max[k].abs())))
        .fold(0.0, f64::max)
}

fn dist2(a: [f32; 3], b: [f32; 3]) -> f64 {
    (0..3)
        .map(|k| (f64::from(a[k]) - f64::from(b[k])).powi(2))
        .sum::<f64>()
}
