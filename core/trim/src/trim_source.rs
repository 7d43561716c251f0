//! What a classifier reads of a trim structure, whichever holds it (the [`crate::quadtree`] or
//! the packed buffers of [`crate::pack`]): the kinds of node, one node's record, the curve
//! references leaves hold, and the [`TrimSource`] trait. It sits below both the structures and
//! the classifier ([`crate::classify`]), so the quadtree can run the leaf tests while it is
//! built without the classifier reaching back up into the quadtree.

use crate::implicit::{Implicit, ImplicitKind};

/// The bits of a curve reference that hold the curve's index; the two above hold its
/// [`ImplicitKind`] (see [`curve_ref`]).
pub const REF_INDEX_BITS: u32 = 30;

/// A reference to curve `index` of kind `kind`: `index | kind << 30`. Leaves refer to their
/// curves this way so that the packed layout needs no per-curve kind word (see
/// [`crate::pack`]): the map alone is stored per curve, the kind travels with the reference.
pub fn curve_ref(index: u32, kind: ImplicitKind) -> u32 {
    assert!(
        index < 1 << REF_INDEX_BITS,
        "curve index {index} does not fit a reference"
    );
    index | (kind as u32) << REF_INDEX_BITS
}

/// The curve index of a reference.
pub fn ref_index(r: u32) -> u32 {
    r & ((1 << REF_INDEX_BITS) - 1)
}

/// The curve kind of a reference.
pub fn ref_kind(r: u32) -> ImplicitKind {
    match r >> REF_INDEX_BITS {
        0 => ImplicitKind::Line,
        1 => ImplicitKind::Convex,
        _ => ImplicitKind::Concave,
    }
}

/// One node as the classifier needs it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeRecord {
    /// What the node is.
    pub kind: NodeKind,
    /// The coverage bit (section 5.3).
    pub covered: bool,
    /// The first of the four children (internal node), or the first curve's reference
    /// ([`curve_ref`]) in a leaf with curves; `u32::MAX` where absent.
    pub a: u32,
    /// The second curve's reference in a two-curve leaf; `u32::MAX` where absent.
    pub b: u32,
    /// The separating line of a two-curve leaf.
    pub line: u32,
}

/// Read access to a trim structure.
pub trait TrimSource {
    /// `[u0, u1, v0, v1]`, the (u, v) rectangle the root covers.
    fn domain(&self) -> [f64; 4];
    /// Node `i` (0 is the root; children are stored consecutively, in the order
    /// (lo u, lo v), (hi u, lo v), (lo u, hi v), (hi u, hi v)).
    fn node(&self, i: u32) -> NodeRecord;
    /// The implicit form of the curve with reference `r` ([`curve_ref`]), in the root's
    /// normalised coordinates.
    fn implicit(&self, r: u32) -> Implicit;
    /// Separating line `i`: `a s + b t + c ≥ 0` is the first curve's side.
    fn line(&self, i: u32) -> [f32; 3];
}

/// What a node is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NodeKind {
    /// Has four children.
    Internal = 0,
    /// A leaf entirely off the face.
    Off = 1,
    /// A leaf entirely on the face.
    On = 2,
    /// A leaf crossed by one curve.
    One = 3,
    /// A leaf crossed by two curves, with a separating line.
    Two = 4,
    /// A leaf at depth 13 still crossed by more than two curves, or by two without a
    /// separating line: a counted failure, answered by its coverage bit.
    Failed = 5,
}
