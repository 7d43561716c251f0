//! The trim structure of paper 000 (Claux et al., "Une structure de découpe efficace pour
//! l'affichage de grands modèles B-Rep"), one step per module:
//!
//! - [`tolerance`]: the world ε turned into a (u, v) tolerance (section 3.1), the surface's
//!   stretch sampled on a grid and in every knot span;
//! - [`quadratic_fit`], [`knot_removal`], [`approximate`]: trim curves sampled, fitted by a
//!   uniform quadratic B-spline, thinned by knot removal to the tolerance and split into
//!   connected quadratic Béziers, flat ones made lines (section 3.1), using [`bezier`];
//! - [`implicit`]: the Loop–Blinn implicit form and the one-curve point test (3.2, 5.1);
//! - [`patch_boundary`]: an outer loop that is the patch's own rectangle, left out of the
//!   quadtree (beyond the paper: the tessellated patch already stops there);
//! - [`quadtree`], [`separate`], [`winding`]: the quadtree with ≤ 2 curves per leaf,
//!   separating lines, coverage bits, the depth-13 failures and the level k_i (4, 5.2,
//!   5.3, 6, table 4);
//! - [`trim_source`]: what a classifier reads of either structure (node kinds and records,
//!   curve references, [`TrimSource`]);
//! - [`classify`]: the CPU classifier with the multiresolution stop (5.3), the reference for
//!   the GPU one, and triangle classification (6);
//! - [`pack`]: the flat layout for GPU storage buffers and its size (7, table 3);
//! - [`multi_pack`]: several faces' packed structures in one set of buffers with a per-face
//!   header table, the f32 walk the fragment shader runs over them (5, 7) and the hand-off
//!   from triangle classification (6).
//!
//! ```
//! let doc = tessd_brep::Document::from_json(r#"{
//!     "format": "tessd-brep", "version": 1, "units": "mm",
//!     "faces": [{"id": 0, "surface": {"type": "plane", "origin": [0, 0, 0],
//!                "x_dir": [1, 0, 0], "y_dir": [0, 1, 0]}, "bounds": [0, 2, 0, 1]}]
//! }"#).unwrap();
//! let trim = tessd_trim::TrimStructure::build(&doc.faces[0], 0.01).unwrap();
//! assert!(trim.classify(1.0, 0.5));
//! assert!(!trim.classify(2.5, 0.5));
//! ```

#![warn(missing_docs)]

pub mod approximate;
pub mod bezier;
pub mod classify;
pub mod implicit;
pub mod knot_removal;
pub mod multi_pack;
pub mod pack;
pub mod patch_boundary;
pub mod quadratic_fit;
pub mod quadtree;
pub mod separate;
pub mod tolerance;
pub mod trim_source;
pub mod winding;

pub use bezier::Quadratic;
pub use classify::Classification;
pub use multi_pack::{CellHandoff, FaceHeader, MultiPack};
pub use pack::PackedTrim;
pub use quadtree::{MAX_DEPTH, Quadtree};
pub use tolerance::UvTolerance;
pub use trim_source::{NodeKind, TrimSource};

use std::time::{Duration, Instant};
use tessd_brep::Face;

/// Why a face's trim structure could not be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TrimError {
    /// ε is not a positive finite number.
    #[error("the tolerance must be positive and finite, got {0}")]
    Tolerance(f64),
    /// The face's bounds are empty or not finite.
    #[error("face {face}: bounds {bounds:?} are not a finite non-empty rectangle")]
    Bounds {
        /// The face id.
        face: u64,
        /// Its bounds.
        bounds: [f64; 4],
    },
    /// A trim curve does not evaluate.
    #[error("face {face}, loop {lp}, trim {trim}: the curve does not evaluate to finite points")]
    Curve {
        /// The face id.
        face: u64,
        /// The loop index.
        lp: usize,
        /// The trim index.
        trim: usize,
    },
}

/// Figures of one built structure (tables 1, 3 and 4 of the paper).
#[derive(Clone, Debug, PartialEq)]
pub struct TrimStats {
    /// Pieces after approximation (curved + lines): table 1's "quadratics".
    pub quadratics: usize,
    /// How many of them are line segments.
    pub lines: usize,
    /// Quadtree nodes.
    pub nodes: usize,
    /// Leaves per depth.
    pub depth_histogram: Vec<u32>,
    /// The deepest leaf.
    pub max_depth: u32,
    /// Leaves that reached depth 13 without meeting the leaf rule (table 4).
    pub failures: u32,
    /// Separating lines.
    pub separating_lines: usize,
    /// The packed size in bytes (table 3).
    pub bytes: usize,
    /// The level k_i of section 6.
    pub k_i: Option<u32>,
    /// The largest measured (u, v) distance between a trim and its approximation; above
    /// ε_uv it is a warning ([`TrimStructure::warnings`]).
    pub max_fit_error_uv: f64,
    /// Wall time of the build.
    pub build_time: Duration,
}

/// A face's trim structure: the approximated loops, the quadtree and its packed form.
#[derive(Clone, Debug)]
pub struct TrimStructure {
    /// The face id.
    pub face: u64,
    /// The tolerances used.
    pub tolerance: UvTolerance,
    /// The approximated loops in (u, v).
    pub loops: Vec<Vec<Quadratic>>,
    /// The quadtree (normalised coordinates).
    pub tree: Quadtree,
    /// The packed layout.
    pub packed: PackedTrim,
    /// Figures.
    pub stats: TrimStats,
}

impl TrimStructure {
    /// Builds the structure of `face` for the world tolerance `eps_world` (document units).
    ///
    /// # Errors
    /// [`TrimError`] for a bad tolerance, bad bounds, or a trim that does not evaluate.
    pub fn build(face: &Face, eps_world: f64) -> Result<TrimStructure, TrimError> {
        let start = Instant::now();
        if !(eps_world > 0.0 && eps_world.is_finite()) {
            return Err(TrimError::Tolerance(eps_world));
        }
        let [u0, u1, v0, v1] = face.bounds;
        if !(u0 < u1 && v0 < v1 && face.bounds.iter().all(|x| x.is_finite())) {
            return Err(TrimError::Bounds {
                face: face.id,
                bounds: face.bounds,
            });
        }
        let tolerance = tolerance::uv_tolerance(face, eps_world);
        let approximate::LoopsApprox {
            loops,
            max_error: max_fit_error_uv,
        } = approximate::approximate_loops(face, tolerance.eps_uv).map_err(|(lp, trim)| {
            TrimError::Curve {
                face: face.id,
                lp,
                trim,
            }
        })?;
        // An outer loop along the patch's rectangle is left to the root's rectangle.
        let skip =
            usize::from(loops.first().is_some_and(|l| {
                patch_boundary::is_patch_boundary(l, face.bounds, tolerance.eps_uv)
            }));
        let kept = &loops[skip..];
        // The root: the bounds, grown to hold every piece, plus a small margin (no larger than
        // ε_uv: with the outer loop left out, the margin is on the face).
        let mut d = [u0, u1, v0, v1];
        for q in kept.iter().flatten() {
            let b = q.control_box();
            d = [
                d[0].min(b[0]),
                d[1].max(b[1]),
                d[2].min(b[2]),
                d[3].max(b[3]),
            ];
        }
        let margin = |size: f64| (1e-6 * size).min(0.5 * tolerance.eps_uv);
        let (mu, mv) = (margin(d[1] - d[0]), margin(d[3] - d[2]));
        let domain = [d[0] - mu, d[1] + mu, d[2] - mv, d[3] + mv];
        let (w, h) = (domain[1] - domain[0], domain[3] - domain[2]);
        let normalised: Vec<Quadratic> = kept
            .iter()
            .flatten()
            .map(|q| q.map(|p| [(p[0] - domain[0]) / w, (p[1] - domain[2]) / h]))
            .collect();
        let lines = normalised.iter().filter(|q| q.line).count();
        let tree = Quadtree::build(domain, normalised, skip as i32);
        let packed = PackedTrim::pack(&tree);
        let stats = TrimStats {
            quadratics: tree.curves.len(),
            lines,
            nodes: tree.nodes.len(),
            depth_histogram: tree.leaves_per_depth.clone(),
            max_depth: tree
                .leaves_per_depth
                .iter()
                .rposition(|&n| n > 0)
                .unwrap_or(0) as u32,
            failures: tree.failures,
            separating_lines: tree.lines.len(),
            bytes: packed.bytes(),
            k_i: tree.k_i,
            max_fit_error_uv,
            build_time: start.elapsed(),
        };
        Ok(TrimStructure {
            face: face.id,
            tolerance,
            loops,
            tree,
            packed,
            stats,
        })
    }

    /// What the caller should know about this structure, as sentences naming the face; empty
    /// when all is well. Today one kind: the measured fit error
    /// ([`TrimStats::max_fit_error_uv`]) above ε_uv, which section 3.1 of paper 000 asks the
    /// approximation to meet. That happens where the fitter cannot follow a trim within its
    /// sample budget ([`approximate::MAX_SAMPLES`]: a curve that turns faster than the
    /// samples are spaced, an extreme rational weight); the structure is still built and used,
    /// never refused, and a point nearer to the trims than the error may be classified wrong.
    pub fn warnings(&self) -> Vec<String> {
        let (fit, eps) = (self.stats.max_fit_error_uv, self.tolerance.eps_uv);
        let mut out = Vec::new();
        if fit > eps {
            out.push(format!(
                "face {}: the trim fit error {fit:.1e} exceeds ε_uv {eps:.1e} ({:.1}×); \
                 classification near its boundary may be off by that much",
                self.face,
                fit / eps
            ));
        }
        out
    }

    /// Whether (u, v) is on the face (exact classification, no footprint).
    pub fn classify(&self, u: f64, v: f64) -> bool {
        classify::classify(&self.tree, u, v, [0.0, 0.0]).on
    }

    /// Classifies (u, v) with the multiresolution stop at `footprint` (section 5.3).
    pub fn classify_at(&self, u: f64, v: f64, footprint: [f64; 2]) -> Classification {
        classify::classify(&self.tree, u, v, footprint)
    }
}
