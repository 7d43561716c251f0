//! The code alphabet shared by the kd coder, the entropy coder and the file: which family a symbol
//! belongs to, which prediction context it was coded in, at which level, and how many values it
//! can take.
//!
//! Paper 003 §5.3: "La fréquence des codes géométriques variant selon le niveau de détail, les
//! probabilités sont calculées indépendamment pour chaque niveau" — every (family, sub-context,
//! level) triple is its own context with its own probability table. Geometry codes use the kd
//! level; connectivity codes the precision in bits (a level of detail of the viewer).

/// Most kd-tree levels a file can have: 3 axes × [`crate::quantize::MAX_BITS`], rounded up.
pub const MAX_LEVELS: usize = 64;

/// What a symbol describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Family {
    /// kd-cell subdivision (§3): 0 = only the half the neighbours predict is non-empty, 1 = only
    /// the other half, 2 = both. Sub-context (`split_context`): the centroid's margin (7) ×
    /// collapsed triangle (2) × the star's parallelograms against the centroid (3); the level
    /// slot holds the neighbours' density (5) × the star's tangent plane (3) instead of the level.
    Split = 0,
    /// Where a triangle holding the split vertex once goes: 0 = the predicted child, 1 = the
    /// other, 2 = both; coded with the midpoints farthest from the split plane first. Sub-context: which children its other vertices are already linked to by
    /// decoded triangles, whether they are pivots, the midpoint's side and distance from the
    /// split plane, which child closes more of their unmatched fine edges, and which children hold
    /// a once-held triangle already; the level in four bands of precision.
    TriangleOnce = 1,
    /// The preimages of a triangle holding the split vertex twice, as a mask of four candidates
    /// minus one (those whose third vertex is linked to one child first). Sub-context: the links
    /// of its third vertex, the orientation its neighbours imply, whether `(v, v, v)` exists,
    /// and (third vertex linked to both) which children held a collapsed triangle before and
    /// how many once-held triangles of each child hold the third vertex (0, 1, 2+).
    Twice = 2,
    /// The preimages of a triangle made of the split vertex alone (mask of four, minus one).
    /// Sub-context: how many collapsed edges `(c, c, x)` each child holds (0–3+, from the
    /// twice-held triangles) and whether a twice-held triangle went to `(v1, v2, x)` or
    /// `(v2, v1, x)`; the level in four bands of precision.
    Thrice = 3,
    /// Where an isolated point goes (coded after the triangles): 0 = the predicted child, 1 =
    /// the other, 2 = both. Sub-context: which children the triangles already hold (a child
    /// none holds needs the point).
    Point = 4,
    /// kd-cell subdivision coded ahead of the connectivity (§6.4, `--ahead`): values as
    /// [`Family::Split`]. Contexts as [`Family::Split`]'s, on the star of the vertex holding the
    /// cell (its neighbours at their descendants' barycentres; "collapsed" = it holds several
    /// cells of the level).
    Ahead = 5,
}

/// Every family, in order.
pub const ALL: [Family; 6] = [
    Family::Split,
    Family::TriangleOnce,
    Family::Twice,
    Family::Thrice,
    Family::Point,
    Family::Ahead,
];

/// Number of families.
pub const FAMILIES: usize = ALL.len();

impl Family {
    /// Number of values a symbol of this family takes.
    pub const fn alphabet(self) -> usize {
        match self {
            Family::Twice | Family::Thrice => 15,
            _ => 3,
        }
    }

    /// Number of sub-contexts.
    pub const fn subs(self) -> usize {
        match self {
            Family::Split => 42, // split_context::SPLIT_SUBS
            Family::TriangleOnce => 4320,
            Family::Twice => 648,
            Family::Thrice => 32,
            Family::Point => 4,
            Family::Ahead => 42, // split_context::SPLIT_SUBS
        }
    }

    /// First context slot of this family (slots × [`MAX_LEVELS`] = contexts).
    const fn first_slot(self) -> usize {
        let mut slot = 0;
        let mut i = 0;
        while i < self as usize {
            slot += ALL[i].subs();
            i += 1;
        }
        slot
    }
}

/// Number of contexts.
pub const CONTEXTS: usize = (Family::Ahead.first_slot() + Family::Ahead.subs()) * MAX_LEVELS;

/// Widest alphabet.
pub const MAX_ALPHABET: usize = 16;

/// The context of a symbol of `family`, sub-context `sub`, emitted at kd level `level`.
pub fn context(family: Family, sub: usize, level: usize) -> usize {
    debug_assert!(sub < family.subs());
    let level = if matches!(family, Family::Split | Family::Ahead) {
        level
    } else {
        level / 3
    };
    (family.first_slot() + sub) * MAX_LEVELS + level
}

/// The context of a symbol whose caller bands the level itself (the once-held triangles: four
/// bands of precision, see `connectivity`); `band` < [`MAX_LEVELS`].
pub fn context_banded(family: Family, sub: usize, band: usize) -> usize {
    (family.first_slot() + sub) * MAX_LEVELS + band
}

/// The same family and sub-context one level (or band) coarser than `ctx`, if any: where an
/// adaptive model of `ctx` starts from ([`crate::entropy`]).
pub fn coarser(ctx: usize) -> Option<usize> {
    (!ctx.is_multiple_of(MAX_LEVELS)).then(|| ctx - 1)
}

/// The family of context `ctx`.
pub fn family_of(ctx: usize) -> Family {
    let slot = ctx / MAX_LEVELS;
    *ALL.iter().rev().find(|f| f.first_slot() <= slot).unwrap()
}

/// A symbol as stored in the semi-coded temporary stream (§5.2c): context (28 bits) and value
/// (4 bits) in 32 bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Symbol(pub u32);

impl Symbol {
    /// Packs a value in context `ctx`.
    pub fn new(ctx: usize, value: u8) -> Self {
        debug_assert!((value as usize) < family_of(ctx).alphabet());
        Symbol(((ctx as u32) << 4) | value as u32)
    }

    /// The symbol's context.
    pub fn context(self) -> usize {
        (self.0 >> 4) as usize
    }

    /// The symbol's value.
    pub fn value(self) -> u8 {
        (self.0 & 15) as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contexts_are_distinct_and_fit_a_symbol() {
        // a symbol keeps its context in 28 bits
        const { assert!(CONTEXTS <= 1 << 28) };
        let mut seen = std::collections::HashSet::new();
        for f in ALL {
            for sub in 0..f.subs() {
                for level in 0..MAX_LEVELS {
                    let c = context(f, sub, level);
                    assert_eq!(family_of(c), f);
                    if matches!(f, Family::Split | Family::Ahead) || level % 3 == 0 {
                        assert!(seen.insert(c), "{f:?} {sub} {level}");
                    }
                    assert!(c < CONTEXTS, "{c}");
                }
            }
        }
    }
}
