//! Outer loops that run along the patch's own boundary, which the quadtree can leave out.
//!
//! The renderer tessellates each face's patch — its `bounds` rectangle in (u, v) — and trims
//! what the tessellation covers (paper 000, sections 5–6). When a face's outer loop *is* that
//! rectangle (most planar faces of a CAD part: a cube side, a slot's wall), the tessellation
//! already stops where the loop runs, and quadtree cells along the four sides only repeat it:
//! a rectangle face costs 5 nodes, 4 curves and 4 separating lines (212 bytes packed) where
//! one "on" node says the same. Going beyond the paper, [`crate::TrimStructure::build`] drops
//! such a loop and lets the root's rectangle stand for it: points of the root that no
//! remaining curve surrounds start from winding number 1 instead of 0
//! ([`crate::Quadtree::base_winding`]), and points outside the root are off as before.

use crate::bezier::Quadratic;

/// Whether `pieces` (one closed loop, in (u, v)) runs once counter-clockwise around the
/// rectangle `bounds = [u0, u1, v0, v1]`: every piece lies along one of its sides — all
/// three control points within `eps_uv` of the side, hence the whole piece (convex hull) —
/// and the loop encloses the rectangle's area to within what those offsets can change
/// (`eps_uv` times the perimeter, twice). Such a loop adds nothing to the patch's own edge
/// beyond the approximation tolerance ε_uv the structure is built to anyway.
pub fn is_patch_boundary(pieces: &[Quadratic], bounds: [f64; 4], eps_uv: f64) -> bool {
    let [u0, u1, v0, v1] = bounds;
    let along_a_side = |q: &Quadratic| {
        let near = |f: &dyn Fn([f64; 2]) -> f64| q.p.iter().all(|&p| f(p) <= eps_uv);
        near(&|p| (p[0] - u0).abs())
            || near(&|p| (p[0] - u1).abs())
            || near(&|p| (p[1] - v0).abs())
            || near(&|p| (p[1] - v1).abs())
    };
    if pieces.is_empty() || !pieces.iter().all(along_a_side) {
        return false;
    }
    let (w, h) = (u1 - u0, v1 - v0);
    let slack = 2.0 * eps_uv * 2.0 * (w + h);
    (signed_area(pieces) - w * h).abs() <= slack
}

/// The signed area a closed chain of quadratic Béziers encloses (positive counter-clockwise):
/// Green's theorem, ½∮(u dv − v du), exact for quadratics — the chord's shoelace term plus
/// the parabolic segment's ⅔ of the triangle (p0, p1, p2).
pub fn signed_area(pieces: &[Quadratic]) -> f64 {
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    pieces
        .iter()
        .map(|q| {
            let [a, b, c] = q.p;
            let chord = 0.5 * cross(a, c);
            let bulge = cross([b[0] - a[0], b[1] - a[1]], [c[0] - a[0], c[1] - a[1]]) / 3.0;
            chord + bulge
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn polygon(c: &[[f64; 2]]) -> Vec<Quadratic> {
        (0..c.len())
            .map(|i| Quadratic::segment(c[i], c[(i + 1) % c.len()]))
            .collect()
    }

    #[test]
    fn the_area_of_a_parabolic_segment_is_two_thirds_of_its_triangle() {
        // The parabola from (0,0) via control (1,2) to (2,0) and back along the chord: the
        // region between them has area 2/3 · (triangle 2) = 4/3 (Archimedes), clockwise.
        let arc = Quadratic {
            p: [[0.0, 0.0], [1.0, 2.0], [2.0, 0.0]],
            line: false,
        };
        let back = Quadratic::segment([2.0, 0.0], [0.0, 0.0]);
        assert!((signed_area(&[arc, back]) + 4.0 / 3.0).abs() < 1e-12);
        let square = polygon(&[[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]]);
        assert!((signed_area(&square) - 6.0).abs() < 1e-12);
    }

    #[test]
    fn the_bounds_rectangle_split_anywhere_is_the_patch_boundary() {
        let b = [1.0, 3.0, -1.0, 0.5];
        let split = polygon(&[
            [1.0, -1.0],
            [2.2, -1.0],
            [3.0, -1.0],
            [3.0, 0.5],
            [1.0, 0.5],
            [1.0, 0.0],
        ]);
        assert!(is_patch_boundary(&split, b, 1e-6));
        // Within ε_uv of the sides still counts; beyond, not.
        let near = polygon(&[[1.0, -1.0], [3.0, -1.0], [3.0, 0.5], [1.0 + 1e-7, 0.5]]);
        assert!(is_patch_boundary(&near, b, 1e-6));
        assert!(!is_patch_boundary(&near, b, 1e-8));
    }

    #[test]
    fn other_loops_are_not() {
        let b = [0.0, 1.0, 0.0, 1.0];
        // Clockwise: a hole the size of the patch.
        let cw = polygon(&[[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]);
        assert!(!is_patch_boundary(&cw, b, 1e-6));
        // A corner cut off: one piece leaves the sides.
        let cut = polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.9], [0.9, 1.0], [0.0, 1.0]]);
        assert!(!is_patch_boundary(&cut, b, 1e-6));
        // Along the sides but only three of them, there and back: no area.
        let back = polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [1.0, 0.0]]);
        assert!(!is_patch_boundary(&back, b, 1e-6));
        // A curved piece bulging off a side.
        let mut bulge = polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        bulge[0] = Quadratic {
            p: [[0.0, 0.0], [0.5, 0.1], [1.0, 0.0]],
            line: false,
        };
        assert!(!is_patch_boundary(&bulge, b, 1e-6));
        assert!(!is_patch_boundary(&[], b, 1e-6));
    }
}
