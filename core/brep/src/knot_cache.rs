//! The knot vectors a B-spline of the model keeps once built. The model's types hold it as a
//! field and the evaluators fill it, so it sits below both ([`crate::model`] and
//! [`crate::surface`]), just above the [`KnotVector`] it caches.

use crate::bspline::KnotVector;

/// A B-spline's checked knot vectors (a surface's pair, a curve's one), built on the first
/// evaluation and kept for every later one (evaluation is the tessellator's inner loop, and
/// validation's: building them per point cost a fifth, resp. half, of their time). Equal
/// whatever it holds, so B-splines still compare by their data; a clone starts empty, so a
/// copy whose knots are then edited does not keep the original's.
pub struct KnotCache<T = (KnotVector, KnotVector)>(Box<std::sync::OnceLock<Option<T>>>);

impl<T> Default for KnotCache<T> {
    fn default() -> Self {
        KnotCache(Box::default())
    }
}

impl<T> KnotCache<T> {
    /// The cached value, built by `init` the first time.
    pub fn get_or_init(&self, init: impl FnOnce() -> Option<T>) -> Option<&T> {
        self.0.get_or_init(init).as_ref()
    }
}

impl<T> Clone for KnotCache<T> {
    fn clone(&self) -> Self {
        KnotCache::default()
    }
}

impl<T> PartialEq for KnotCache<T> {
    fn eq(&self, _: &KnotCache<T>) -> bool {
        true
    }
}

impl<T> std::fmt::Debug for KnotCache<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("KnotCache")
    }
}
