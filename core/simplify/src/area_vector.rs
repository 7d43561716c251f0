//! Twice the area vector of a face (its normal scaled by twice its area), in f64: one cross
//! product for a triangle, Newell's method for a polygon. Elimination tests it for zero
//! (zero-area faces); the quadric representative normalises it into a plane.

/// `(b − a) × (c − a)`.
pub(crate) fn triangle(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * w[2] - u[2] * w[1],
        u[2] * w[0] - u[0] * w[2],
        u[0] * w[1] - u[1] * w[0],
    ]
}

/// Newell's sum over the `n` corners `point(0..n)` of a polygon.
pub(crate) fn polygon(n: usize, point: impl Fn(usize) -> [f64; 3]) -> [f64; 3] {
    let mut s = [0f64; 3];
    for i in 0..n {
        let (p, q) = (point(i), point((i + 1) % n));
        s[0] += (p[1] - q[1]) * (p[2] + q[2]);
        s[1] += (p[2] - q[2]) * (p[0] + q[0]);
        s[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_and_polygon_agree() {
        let p = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]];
        assert_eq!(triangle(p[0], p[1], p[2]), [0.0, 0.0, 6.0]);
        assert_eq!(polygon(3, |i| p[i]), [0.0, 0.0, 6.0]);
    }
}
