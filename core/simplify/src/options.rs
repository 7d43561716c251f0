//! What the user chooses, as in the paper's AutoCAD dialog (section 6, figure 7): a partition
//! method with its numeric parameter, a representative, and the weighting of section 2.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// A length given either in model units or as a fraction of the object's largest dimension
/// (section 3: "soit une distance absolue, soit un pourcentage de la plus grande dimension").
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Length {
    /// Model units.
    Absolute(f64),
    /// Fraction (0.01 = 1 %) of the largest side of the bounding box.
    Relative(f64),
}

impl Length {
    /// The length in model units for an object whose largest dimension is `size`.
    pub fn resolve(self, size: f64) -> f64 {
        match self {
            Length::Absolute(d) => d,
            Length::Relative(f) => f * size,
        }
    }
}

/// A vertex count given absolutely or as a fraction of the input's referenced vertices
/// (section 4: "nombre de sommets à conserver ou pourcentage").
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Count {
    /// A number of vertices.
    Absolute(u64),
    /// Fraction (0.2 = 20 %) of the input's referenced vertices.
    Relative(f64),
}

impl Count {
    /// The count for an input of `vertices` referenced vertices (at least 1).
    pub fn resolve(self, vertices: u64) -> u64 {
        match self {
            Count::Absolute(n) => n,
            Count::Relative(f) => (f * vertices as f64).round().max(1.0) as u64,
        }
    }
}

/// The size of a regular grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridSize {
    /// This many cells along each axis of the bounding box (cells follow the box's proportions).
    CellsPerAxis(u32),
    /// Cubic cells of this side, in model units.
    CellSize(f64),
}

/// How the bounding volume is partitioned into cells.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Regular subdivision (section 2, Rossignac–Borrel).
    Grid(GridSize),
    /// Quality goal (section 3): split cells until no vertex moves more than this.
    Quality(Length),
    /// Complexity goal (section 4): split the worst cell until the output has this many
    /// vertices.
    Complexity(Count),
}

/// Where a cell's vertices merge to (section 2, "fusion des sommets").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Representative {
    /// The weighted barycentre: approximates the geometry.
    Barycenter,
    /// The heaviest vertex: keeps the most salient features.
    Heaviest,
    /// The point minimising the cell's summed plane quadrics (Lindstrom 2000), beyond the
    /// paper; falls back to the barycentre when the system is ill-conditioned or the point
    /// leaves the cell.
    Quadric,
}

/// The weight of a vertex (section 2, "pondération des sommets").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weighting {
    /// The length of the longest incident edge (the paper's example, and the default).
    LongestEdge,
    /// Rossignac–Borrel's curvature weight: 1 − cos of the largest angle between incident
    /// face normals, times the longest incident edge; favours sharp features.
    Curvature,
    /// Every vertex weighs 1.
    Uniform,
}

/// Progress callback: `(fraction, stage)`; return `false` to cancel.
pub type ProgressFn<'a> = dyn FnMut(f64, &str) -> bool + 'a;

/// Options of one simplification.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct SimplifyOptions {
    /// The partition method and its goal.
    pub method: Method,
    /// Where cells merge to.
    pub representative: Representative,
    /// Vertex weights.
    pub weighting: Weighting,
    /// Fan-triangulate polygons first (section 2: avoids non-planar polygons after merging).
    pub triangulate: bool,
    /// Keep boundary and feature vertices apart from interior ones: a cell never merges a
    /// boundary (or feature-edge) vertex with a vertex that is not.
    pub preserve_boundaries: bool,
    /// Dihedral angle (degrees) above which an edge counts as a feature edge when
    /// `preserve_boundaries` is set.
    pub feature_angle_deg: f64,
    /// Return the partition's cells (for "show partition").
    pub keep_partition: bool,
    /// Set from another thread to stop at the next checkpoint.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl SimplifyOptions {
    /// Options for `method` with the defaults: barycentre, longest-edge weights, polygons kept.
    pub fn new(method: Method) -> SimplifyOptions {
        SimplifyOptions {
            method,
            representative: Representative::Barycenter,
            weighting: Weighting::LongestEdge,
            triangulate: false,
            preserve_boundaries: false,
            feature_angle_deg: 60.0,
            keep_partition: false,
            cancel: None,
        }
    }

    /// Sets the representative.
    pub fn with_representative(mut self, r: Representative) -> Self {
        self.representative = r;
        self
    }

    /// Sets the weighting.
    pub fn with_weighting(mut self, w: Weighting) -> Self {
        self.weighting = w;
        self
    }

    /// Triangulates polygons first.
    pub fn with_triangulate(mut self, yes: bool) -> Self {
        self.triangulate = yes;
        self
    }

    /// Keeps boundary and feature vertices from merging with others.
    pub fn with_preserve_boundaries(mut self, yes: bool) -> Self {
        self.preserve_boundaries = yes;
        self
    }

    /// Returns the partition's cells with the result.
    pub fn with_partition(mut self, yes: bool) -> Self {
        self.keep_partition = yes;
        self
    }

    /// Stops when `flag` is set.
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }
}
