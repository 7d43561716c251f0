//! Edge sharpness as OpenSubdiv's *uniform* creasing method reads it: the level that counts as
//! infinitely sharp and how sharpness falls by one per level. Shared by the adjacency
//! ([`crate::topology`], [`crate::halfedges`]), the crease rules and every scheme, so it sits
//! below all of them.

/// Sharpness at or above which an edge is infinitely sharp (OpenSubdiv's
/// `Sdc::Crease::SHARPNESS_INFINITE`); boundary edges get it.
pub const INFINITELY_SHARP: f32 = 10.0;

/// Sharpness one level down (uniform creasing: minus one, infinite stays infinite).
pub fn decrement(s: f32) -> f32 {
    if s >= INFINITELY_SHARP {
        INFINITELY_SHARP
    } else {
        (s - 1.0).max(0.0)
    }
}
