//! What a refused document is told: the element at fault ([`Place`]) and why
//! ([`ValidationError`]), one variant per rule of docs/brep-format.md ("Validation"), so a host
//! can point its user at the broken element rather than at "bad input". The rules themselves
//! are checked in [`crate::validate`]; reading a document ([`crate::Document::from_json`])
//! refuses with the same type.

use crate::bspline::KnotError;
use crate::model::{FORMAT, VERSION};
use crate::tolerances::DIRECTION_TOLERANCE;
use crate::vector::Point2;
use std::fmt;
use thiserror::Error;

/// The element an error is about.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Place {
    /// The document as a whole.
    Document,
    /// A face, by id.
    Face {
        /// The face id.
        face: u64,
    },
    /// A face's surface.
    Surface {
        /// The face id.
        face: u64,
    },
    /// The curve a revolution or extrusion surface sweeps.
    SurfaceCurve {
        /// The face id.
        face: u64,
    },
    /// A loop of a face (0 is the outer loop).
    Loop {
        /// The face id.
        face: u64,
        /// Index among the face's loops.
        loop_index: usize,
    },
    /// A trim of a loop.
    Trim {
        /// The face id.
        face: u64,
        /// Index among the face's loops.
        loop_index: usize,
        /// Index among the loop's trims.
        trim: usize,
    },
    /// A shared edge, by id.
    Edge {
        /// The edge id.
        edge: u64,
    },
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Document => write!(f, "document"),
            Place::Face { face } => write!(f, "face {face}"),
            Place::Surface { face } => write!(f, "face {face}, surface"),
            Place::SurfaceCurve { face } => write!(f, "face {face}, surface curve"),
            Place::Loop { face, loop_index } => write!(f, "face {face}, loop {loop_index}"),
            Place::Trim {
                face,
                loop_index,
                trim,
            } => write!(f, "face {face}, loop {loop_index}, trim {trim}"),
            Place::Edge { edge } => write!(f, "edge {edge}"),
        }
    }
}

/// Why a document is refused. Messages start with the element (`face 17, loop 1, trim 2: …`).
#[derive(Clone, Debug, PartialEq, Error)]
pub enum ValidationError {
    /// The text is not JSON.
    #[error("not JSON: {message}")]
    Json {
        /// serde_json's message, with line and column.
        message: String,
    },
    /// JSON that does not have the document's structure: a missing field, a mistyped value,
    /// an unknown `type`.
    #[error("{at}: {message}")]
    Structure {
        /// Where (`face 17, loop 0, trim 3`, or `face at index 2` when the id is unreadable).
        at: String,
        /// serde's message (`missing field \`radius\``, `unknown variant \`offset\`, …`).
        message: String,
    },
    /// `format` is not `"tessd-brep"`.
    #[error("document: `format` must be \"{FORMAT}\", got {found}")]
    Format {
        /// What was there (JSON text, `missing` when absent).
        found: String,
    },
    /// `version` is not one this crate reads.
    #[error("document: unsupported `version` {found}; this reader supports version {VERSION}")]
    Version {
        /// What was there (JSON text, `missing` when absent).
        found: String,
    },
    /// Two faces share an id.
    #[error("face {face}: the id is used by faces at index {first} and {second}")]
    DuplicateFaceId {
        /// The id.
        face: u64,
        /// Index of the first face with it.
        first: usize,
        /// Index of the second.
        second: usize,
    },
    /// Two edges share an id.
    #[error("edge {edge}: the id is used twice")]
    DuplicateEdgeId {
        /// The id.
        edge: u64,
    },
    /// A NaN or infinite number.
    #[error("{at}: {field} is not finite")]
    NonFinite {
        /// The element.
        at: Place,
        /// The field, with indices (`origin`, `poles[3][1]`, `range`).
        field: String,
    },
    /// A direction that is not of unit length.
    #[error(
        "{at}: {field} has length {length}; it must be a unit vector (within {DIRECTION_TOLERANCE})"
    )]
    NotUnit {
        /// The element.
        at: Place,
        /// The field.
        field: &'static str,
        /// Its length.
        length: f64,
    },
    /// A frame whose axes are not orthogonal.
    #[error(
        "{at}: x_dir · y_dir = {dot}; the axes must be orthogonal (within {DIRECTION_TOLERANCE})"
    )]
    NotOrthogonal {
        /// The element.
        at: Place,
        /// The dot product.
        dot: f64,
    },
    /// A radius ≤ 0 (< 0 for a cone's reference radius).
    #[error("{at}: {field} is {value}; it must be positive")]
    Radius {
        /// The element.
        at: Place,
        /// The field.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// An edge's `tolerance` or one of its `vertex_tolerances` below 0.
    #[error("{at}: {field} is {value}; a tolerance must be ≥ 0")]
    NegativeTolerance {
        /// The edge.
        at: Place,
        /// `tolerance`, `vertex_tolerances[0]` or `vertex_tolerances[1]`.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// A cone's reference radius below 0.
    #[error("{at}: radius is {value}; a cone's radius must be ≥ 0")]
    ConeRadius {
        /// The element.
        at: Place,
        /// The value.
        value: f64,
    },
    /// A cone's semi-angle outside 0 < |a| < π/2.
    #[error("{at}: semi_angle is {value}; it must satisfy 0 < |semi_angle| < π/2")]
    SemiAngle {
        /// The element.
        at: Place,
        /// The value.
        value: f64,
    },
    /// A B-spline's degree, knots or multiplicities break a rule.
    #[error("{at}: {direction}{error}")]
    Knots {
        /// The element.
        at: Place,
        /// `"u: "`, `"v: "` for surfaces, empty for curves.
        direction: &'static str,
        /// The rule broken.
        error: KnotError,
    },
    /// A B-spline with another number of poles than its knots imply.
    #[error("{at}: {what} has {got} poles; the knots and degree need {expected}")]
    PoleCount {
        /// The element.
        at: Place,
        /// `poles`, or `poles[i]` for a row of a surface's poles.
        what: String,
        /// Poles given.
        got: usize,
        /// Poles needed.
        expected: usize,
    },
    /// Weights of another count than the poles.
    #[error("{at}: {what} has {got} weights for {expected} poles")]
    WeightCount {
        /// The element.
        at: Place,
        /// `weights`, or `weights[i]`.
        what: String,
        /// Weights given.
        got: usize,
        /// Poles there.
        expected: usize,
    },
    /// A weight ≤ 0.
    #[error("{at}: the weight of pole {pole} is {value}; weights must be positive")]
    Weight {
        /// The element.
        at: Place,
        /// The pole index (`3`, or `[3][1]` for surfaces).
        pole: String,
        /// The weight.
        value: f64,
    },
    /// A face whose `bounds` are not an interval in each direction.
    #[error("face {face}: bounds {bounds:?} must have u0 < u1 and v0 < v1")]
    Bounds {
        /// The face id.
        face: u64,
        /// The bounds.
        bounds: [f64; 4],
    },
    /// A loop without trims.
    #[error("face {face}, loop {loop_index}: the loop has no trims")]
    EmptyLoop {
        /// The face id.
        face: u64,
        /// The loop.
        loop_index: usize,
    },
    /// A trim with `t0 == t1`.
    #[error("{at}: range [{t}, {t}] is empty")]
    EmptyRange {
        /// The trim or edge.
        at: Place,
        /// The parameter.
        t: f64,
    },
    /// A B-spline curve's range outside its knots.
    #[error("{at}: range [{}, {}] lies outside the curve's knot span [{}, {}]", range[0], range[1], domain[0], domain[1])]
    RangeOutsideKnots {
        /// The trim or edge.
        at: Place,
        /// The range.
        range: [f64; 2],
        /// The first and last knot.
        domain: [f64; 2],
    },
    /// A gap between the end of one trim and the start of the next.
    #[error(
        "face {face}, loop {loop_index}: open loop: trim {trim} ends {gap:.3e} away from the start of trim {next} (tolerance {tolerance:.3e})"
    )]
    OpenLoop {
        /// The face id.
        face: u64,
        /// The loop.
        loop_index: usize,
        /// The trim whose end is off.
        trim: usize,
        /// The trim that should start there.
        next: usize,
        /// The distance in (u, v).
        gap: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// A trim passing outside the face's bounds.
    #[error("face {face}, loop {loop_index}, trim {trim}: point ({}, {}) at t = {t} lies outside the face's bounds {bounds:?}", point[0], point[1])]
    OutsideBounds {
        /// The face id.
        face: u64,
        /// The loop.
        loop_index: usize,
        /// The trim.
        trim: usize,
        /// The trim's parameter there.
        t: f64,
        /// The point in (u, v).
        point: Point2,
        /// The face's bounds.
        bounds: [f64; 4],
    },
    /// An outer loop (loop 0) that turns clockwise.
    #[error(
        "face {face}, loop 0: the outer loop is clockwise (signed area {area:.3e}); it must be counter-clockwise in (u, v)"
    )]
    OuterClockwise {
        /// The face id.
        face: u64,
        /// The signed area.
        area: f64,
    },
    /// A hole that turns counter-clockwise.
    #[error(
        "face {face}, loop {loop_index}: the hole is counter-clockwise (signed area {area:.3e}); holes must be clockwise in (u, v)"
    )]
    HoleCounterClockwise {
        /// The face id.
        face: u64,
        /// The loop.
        loop_index: usize,
        /// The signed area.
        area: f64,
    },
    /// A trim naming an edge id no edge has.
    #[error("face {face}, loop {loop_index}, trim {trim}: edge {edge} does not exist")]
    UnknownEdge {
        /// The face id.
        face: u64,
        /// The loop.
        loop_index: usize,
        /// The trim.
        trim: usize,
        /// The edge id.
        edge: u64,
    },
    /// An edge naming a face id no face has.
    #[error("edge {edge}: face {face} does not exist")]
    UnknownFace {
        /// The edge id.
        edge: u64,
        /// The face id.
        face: u64,
    },
}
