//! Twice the area vector of a face (its normal scaled by twice its area), in f64: one cross
//! product for a triangle, Newell's method for a polygon. Elimination tests it for zero
//! (zero-area faces); the quadric representative normalises it into a plane.

use glam::DVec3;

/// `(b − a) × (c − a)`.
pub(crate) fn triangle(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a)
}

/// Newell's sum over the `n` corners `point(0..n)` of a polygon.
pub(crate) fn polygon(n: usize, point: impl Fn(usize) -> DVec3) -> DVec3 {
    let mut s = DVec3::ZERO;
    for i in 0..n {
        let (p, q) = (point(i), point((i + 1) % n));
        let (d, e) = (p - q, p + q);
        s += DVec3::new(d.y * e.z, d.z * e.x, d.x * e.y);
    }
    s
}

/// A mesh position in f64.
pub(crate) fn f64_point(p: [f32; 3]) -> DVec3 {
    glam::Vec3::from_array(p).as_dvec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_and_polygon_agree() {
        let p = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 3.0, 0.0),
        ];
        assert_eq!(triangle(p[0], p[1], p[2]), DVec3::new(0.0, 0.0, 6.0));
        assert_eq!(polygon(3, |i| p[i]), DVec3::new(0.0, 0.0, 6.0));
    }
}
