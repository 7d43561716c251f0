//! The little vector algebra the evaluators need, over plain `[f64; 2]` and `[f64; 3]`, so
//! that 2D trim curves and 3D edge curves share one curve evaluator and the document types
//! stay plain arrays (what serde reads and the exporter writes).

use std::fmt::Debug;

/// A point or vector of the parameter plane (`[f64; 2]`) or of space (`[f64; 3]`).
pub trait Vector: Copy + Debug + PartialEq + Send + Sync + 'static {
    /// The number of coordinates.
    const DIM: usize;

    /// The zero vector.
    fn zero() -> Self;

    /// The coordinates.
    fn coords(&self) -> &[f64];

    /// The coordinates, mutably.
    fn coords_mut(&mut self) -> &mut [f64];

    /// `self + o`.
    fn add(self, o: Self) -> Self {
        let mut r = self;
        for (a, b) in r.coords_mut().iter_mut().zip(o.coords()) {
            *a += b;
        }
        r
    }

    /// `self - o`.
    fn sub(self, o: Self) -> Self {
        self.add(o.scale(-1.0))
    }

    /// `s · self`.
    fn scale(self, s: f64) -> Self {
        let mut r = self;
        for a in r.coords_mut() {
            *a *= s;
        }
        r
    }

    /// The dot product.
    fn dot(self, o: Self) -> f64 {
        self.coords()
            .iter()
            .zip(o.coords())
            .map(|(a, b)| a * b)
            .sum()
    }

    /// The Euclidean length.
    fn norm(self) -> f64 {
        self.dot(self).sqrt()
    }

    /// Whether every coordinate is finite.
    fn is_finite(&self) -> bool {
        self.coords().iter().all(|c| c.is_finite())
    }
}

impl Vector for [f64; 2] {
    const DIM: usize = 2;
    fn zero() -> Self {
        [0.0; 2]
    }
    fn coords(&self) -> &[f64] {
        self
    }
    fn coords_mut(&mut self) -> &mut [f64] {
        self
    }
}

impl Vector for [f64; 3] {
    const DIM: usize = 3;
    fn zero() -> Self {
        [0.0; 3]
    }
    fn coords(&self) -> &[f64] {
        self
    }
    fn coords_mut(&mut self) -> &mut [f64] {
        self
    }
}

/// The cross product of two space vectors.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `Σ cᵢ·vᵢ`, the linear combinations the analytic surfaces are made of.
pub fn combine<V: Vector>(terms: &[(f64, V)]) -> V {
    terms
        .iter()
        .fold(V::zero(), |acc, (c, v)| acc.add(v.scale(*c)))
}
