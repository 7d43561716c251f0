//! Small f64 vector helpers and the exact closest point on a triangle.

pub(crate) type V3 = [f64; 3];

#[inline(always)]
pub(crate) fn v64(p: [f32; 3]) -> V3 {
    [p[0] as f64, p[1] as f64, p[2] as f64]
}

#[inline(always)]
pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(crate) fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub(crate) fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline(always)]
pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline(always)]
pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
pub(crate) fn norm2(a: V3) -> f64 {
    dot(a, a)
}

/// Area of triangle `abc`.
#[inline]
pub(crate) fn triangle_area(a: V3, b: V3, c: V3) -> f64 {
    0.5 * norm2(cross(sub(b, a), sub(c, a))).sqrt()
}

/// Closest point to `p` on segment `ab`.
#[inline]
fn closest_on_segment(p: V3, a: V3, b: V3) -> V3 {
    let ab = sub(b, a);
    let l2 = norm2(ab);
    if l2 <= 0.0 {
        return a;
    }
    let t = (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0);
    add(a, scale(ab, t))
}

/// The point of triangle `abc` closest to `p` (Ericson, *Real-Time Collision Detection*,
/// §5.1.5: Voronoi-region tests on the vertices and edges, then the barycentric projection).
///
/// Degenerate (zero-area) triangles fall back to the closest of the three edges, so the result
/// is always a point of the (possibly flat) triangle.
#[inline(always)]
pub(crate) fn closest_on_triangle(p: V3, a: V3, b: V3, c: V3) -> V3 {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a; // vertex region A
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b; // vertex region B
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let den = d1 - d3;
        if den > 0.0 {
            return add(a, scale(ab, d1 / den)); // edge region AB
        }
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c; // vertex region C
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let den = d2 - d6;
        if den > 0.0 {
            return add(a, scale(ac, d2 / den)); // edge region AC
        }
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let den = (d4 - d3) + (d5 - d6);
        if den > 0.0 {
            return add(b, scale(sub(c, b), (d4 - d3) / den)); // edge region BC
        }
    }
    let den = va + vb + vc;
    if den > 0.0 && den.is_finite() {
        let inv = 1.0 / den;
        let v = vb * inv;
        let w = vc * inv;
        return add(a, add(scale(ab, v), scale(ac, w))); // face region
    }
    // Degenerate triangle (or one so thin the tests above were inconsistent): best edge point.
    let q1 = closest_on_segment(p, a, b);
    let q2 = closest_on_segment(p, b, c);
    let q3 = closest_on_segment(p, c, a);
    let (d1, d2, d3) = (norm2(sub(p, q1)), norm2(sub(p, q2)), norm2(sub(p, q3)));
    if d1 <= d2 && d1 <= d3 {
        q1
    } else if d2 <= d3 {
        q2
    } else {
        q3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: V3 = [0.0, 0.0, 0.0];
    const B: V3 = [1.0, 0.0, 0.0];
    const C: V3 = [0.0, 1.0, 0.0];

    fn close(a: V3, b: V3) -> bool {
        norm2(sub(a, b)) < 1e-28
    }

    #[test]
    fn regions() {
        // Face interior: projection.
        assert!(close(
            closest_on_triangle([0.2, 0.3, 5.0], A, B, C),
            [0.2, 0.3, 0.0]
        ));
        // Vertex regions.
        assert_eq!(closest_on_triangle([-1.0, -1.0, 2.0], A, B, C), A);
        assert_eq!(closest_on_triangle([3.0, -0.5, 0.0], A, B, C), B);
        assert_eq!(closest_on_triangle([-0.5, 3.0, 1.0], A, B, C), C);
        // Edge regions.
        assert!(close(
            closest_on_triangle([0.5, -2.0, 1.0], A, B, C),
            [0.5, 0.0, 0.0]
        ));
        assert!(close(
            closest_on_triangle([-2.0, 0.25, 0.0], A, B, C),
            [0.0, 0.25, 0.0]
        ));
        assert!(close(
            closest_on_triangle([1.0, 1.0, 0.0], A, B, C),
            [0.5, 0.5, 0.0]
        ));
    }

    #[test]
    fn degenerate_triangle_uses_edges() {
        // Collinear: the segment from (0,0,0) to (2,0,0).
        let q = closest_on_triangle([1.5, 1.0, 0.0], A, B, [2.0, 0.0, 0.0]);
        assert!(close(q, [1.5, 0.0, 0.0]));
        // All three corners equal.
        assert_eq!(closest_on_triangle([1.0, 1.0, 1.0], A, A, A), A);
    }

    #[test]
    fn matches_brute_force_on_a_grid() {
        // Compare with a dense parametric search over the triangle.
        let (a, b, c) = ([0.1, -0.2, 0.3], [1.3, 0.4, -0.2], [-0.4, 1.1, 0.6]);
        let n = 400;
        let mut s = 0x1234_5678_u64;
        for _ in 0..50 {
            let mut r = || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
            };
            let p = [r(), r(), r()];
            let q = closest_on_triangle(p, a, b, c);
            let dq = norm2(sub(p, q)).sqrt();
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let x = add(a, add(scale(sub(b, a), u), scale(sub(c, a), v)));
                    best = best.min(norm2(sub(p, x)).sqrt());
                }
            }
            assert!(dq <= best + 1e-12, "closest point worse than the grid");
            assert!(best - dq < 5e-3, "grid is much better: {best} vs {dq}");
        }
    }
}
