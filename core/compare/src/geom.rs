//! The exact closest point on a triangle, over glam's `DVec3`: distances are measured in f64
//! whatever the meshes' f32 positions.

pub(crate) use glam::DVec3 as V3;

/// A mesh position in f64.
#[inline(always)]
pub(crate) fn v64(p: [f32; 3]) -> V3 {
    glam::Vec3::from_array(p).as_dvec3()
}

/// Area of triangle `abc`.
#[inline]
pub(crate) fn triangle_area(a: V3, b: V3, c: V3) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}

/// Closest point to `p` on segment `ab`.
#[inline]
fn closest_on_segment(p: V3, a: V3, b: V3) -> V3 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(ab) / l2).clamp(0.0, 1.0);
    a + ab * t
}

/// The point of triangle `abc` closest to `p` (Ericson, *Real-Time Collision Detection*,
/// §5.1.5: Voronoi-region tests on the vertices and edges, then the barycentric projection).
///
/// Degenerate (zero-area) triangles fall back to the closest of the three edges, so the result
/// is always a point of the (possibly flat) triangle.
#[inline(always)]
pub(crate) fn closest_on_triangle(p: V3, a: V3, b: V3, c: V3) -> V3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a; // vertex region A
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b; // vertex region B
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let den = d1 - d3;
        if den > 0.0 {
            return a + ab * (d1 / den); // edge region AB
        }
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c; // vertex region C
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let den = d2 - d6;
        if den > 0.0 {
            return a + ac * (d2 / den); // edge region AC
        }
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let den = (d4 - d3) + (d5 - d6);
        if den > 0.0 {
            return b + (c - b) * ((d4 - d3) / den); // edge region BC
        }
    }
    let den = va + vb + vc;
    if den > 0.0 && den.is_finite() {
        let inv = 1.0 / den;
        let v = vb * inv;
        let w = vc * inv;
        return a + (ab * v + ac * w); // face region
    }
    // Degenerate triangle (or one so thin the tests above were inconsistent): best edge point.
    let q1 = closest_on_segment(p, a, b);
    let q2 = closest_on_segment(p, b, c);
    let q3 = closest_on_segment(p, c, a);
    let (d1, d2, d3) = (
        p.distance_squared(q1),
        p.distance_squared(q2),
        p.distance_squared(q3),
    );
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

    const A: V3 = V3::new(0.0, 0.0, 0.0);
    const B: V3 = V3::new(1.0, 0.0, 0.0);
    const C: V3 = V3::new(0.0, 1.0, 0.0);

    fn close(a: V3, b: V3) -> bool {
        a.distance_squared(b) < 1e-28
    }

    #[test]
    fn regions() {
        // Face interior: projection.
        assert!(close(
            closest_on_triangle(V3::new(0.2, 0.3, 5.0), A, B, C),
            V3::new(0.2, 0.3, 0.0)
        ));
        // Vertex regions.
        assert_eq!(closest_on_triangle(V3::new(-1.0, -1.0, 2.0), A, B, C), A);
        assert_eq!(closest_on_triangle(V3::new(3.0, -0.5, 0.0), A, B, C), B);
        assert_eq!(closest_on_triangle(V3::new(-0.5, 3.0, 1.0), A, B, C), C);
        // Edge regions.
        assert!(close(
            closest_on_triangle(V3::new(0.5, -2.0, 1.0), A, B, C),
            V3::new(0.5, 0.0, 0.0)
        ));
        assert!(close(
            closest_on_triangle(V3::new(-2.0, 0.25, 0.0), A, B, C),
            V3::new(0.0, 0.25, 0.0)
        ));
        assert!(close(
            closest_on_triangle(V3::new(1.0, 1.0, 0.0), A, B, C),
            V3::new(0.5, 0.5, 0.0)
        ));
    }

    #[test]
    fn degenerate_triangle_uses_edges() {
        // Collinear: the segment from (0,0,0) to (2,0,0).
        let q = closest_on_triangle(V3::new(1.5, 1.0, 0.0), A, B, V3::new(2.0, 0.0, 0.0));
        assert!(close(q, V3::new(1.5, 0.0, 0.0)));
        // All three corners equal.
        assert_eq!(closest_on_triangle(V3::new(1.0, 1.0, 1.0), A, A, A), A);
    }

    #[test]
    fn matches_brute_force_on_a_grid() {
        // Compare with a dense parametric search over the triangle.
        let (a, b, c) = (
            V3::new(0.1, -0.2, 0.3),
            V3::new(1.3, 0.4, -0.2),
            V3::new(-0.4, 1.1, 0.6),
        );
        let n = 400;
        let mut s = 0x1234_5678_u64;
        for _ in 0..50 {
            let mut r = || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
            };
            let p = V3::new(r(), r(), r());
            let q = closest_on_triangle(p, a, b, c);
            let dq = p.distance(q);
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let x = a + ((b - a) * u + (c - a) * v);
                    best = best.min(p.distance(x));
                }
            }
            assert!(dq <= best + 1e-12, "closest point worse than the grid");
            assert!(best - dq < 5e-3, "grid is much better: {best} vs {dq}");
        }
    }
}
