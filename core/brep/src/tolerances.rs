//! The tolerances validation ([`crate::validate`]) holds a document to (docs/brep-format.md,
//! "Validation"), which its refusals ([`crate::validation_error`]) quote; below both.

/// Tolerance on unit lengths and orthogonality of directions and frames.
pub const DIRECTION_TOLERANCE: f64 = 1e-9;

/// Loop closure tolerance, relative to the diagonal of the face's `bounds`.
pub const CLOSURE_TOLERANCE: f64 = 1e-7;

/// How far (relative to the diagonal of `bounds`) a trim may stray outside the face's `bounds`.
pub const BOUNDS_TOLERANCE: f64 = 1e-7;

/// How far (relative to the knot span's length) a non-periodic B-spline trim's range may
/// extend beyond its knots.
pub const RANGE_TOLERANCE: f64 = 1e-9;
