//! The point and vector types of the B-Rep model: [`glam::DVec2`] for the parameter plane
//! (2D trim curves, `(u, v)`) and [`glam::DVec3`] for space (3D edge curves, surface points,
//! derivatives and normals, frames, poles), with glam's arithmetic (`+ - *`, `dot`, `cross`,
//! `length`, `is_finite`). With glam's `serde` feature they read and write the same JSON as
//! plain arrays (`[x, y]`, `[x, y, z]`), so the document types hold them directly.
//!
//! The only thing kept here is [`Point`], the small trait that lets one curve evaluator (and
//! the OCCT reader, validation and bounds sampling) serve both dimensions: it is implemented
//! for `DVec2` and `DVec3` by delegating to glam, and adds nothing glam does not have but the
//! coordinate count and slice access. [`combine`] is `Σ cᵢ·vᵢ` folded from zero in term order,
//! the exact sequence of IEEE operations the surfaces were written with (results are
//! bit-identical to the former `[f64; N]` code, which did the same operations per coordinate).

use glam::{DVec2, DVec3};
use std::fmt::Debug;
use std::ops::{Add, Mul, Sub};

/// A point of the parameter plane, (u, v) or a 2D curve's point; written `[u, v]` in JSON.
pub type Point2 = glam::DVec2;

/// A point or vector of space, in the document's units; written `[x, y, z]` in JSON.
pub type Point3 = glam::DVec3;

/// A point or vector of the parameter plane ([`DVec2`]) or of space ([`DVec3`]): glam's
/// operators, plus what a dimension-generic evaluator needs.
pub trait Point:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
{
    /// The number of coordinates.
    const DIM: usize;

    /// The zero vector.
    const ZERO: Self;

    /// Every coordinate NaN (what an evaluator returns for geometry that does not validate).
    const NAN: Self;

    /// The coordinates.
    fn coords(&self) -> &[f64];

    /// The coordinates, mutably.
    fn coords_mut(&mut self) -> &mut [f64];

    /// The dot product (glam's `dot`).
    fn dot(self, o: Self) -> f64;

    /// The Euclidean length (glam's `length`, `dot(self, self).sqrt()`).
    fn length(self) -> f64;

    /// Whether every coordinate is finite (glam's `is_finite`).
    fn is_finite(self) -> bool;
}

macro_rules! impl_point {
    ($t:ty, $n:literal) => {
        impl Point for $t {
            const DIM: usize = $n;
            const ZERO: Self = <$t>::ZERO;
            const NAN: Self = <$t>::NAN;
            fn coords(&self) -> &[f64] {
                AsRef::<[f64; $n]>::as_ref(self)
            }
            fn coords_mut(&mut self) -> &mut [f64] {
                AsMut::<[f64; $n]>::as_mut(self)
            }
            #[inline]
            fn dot(self, o: Self) -> f64 {
                <$t>::dot(self, o)
            }
            #[inline]
            fn length(self) -> f64 {
                <$t>::length(self)
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
        }
    };
}

impl_point!(DVec2, 2);
impl_point!(DVec3, 3);

/// `Σ cᵢ·vᵢ`, the linear combinations the analytic surfaces are made of: folded from zero in
/// the order of `terms` (`((0 + c₀v₀) + c₁v₁) + …`), which the results depend on to the bit.
#[inline]
pub fn combine<V: Point>(terms: &[(f64, V)]) -> V {
    terms.iter().fold(V::ZERO, |acc, &(c, v)| acc + v * c)
}
