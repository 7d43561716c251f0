//! Plane quadrics and their minimiser (Garland & Heckbert 1997; Lindstrom 2000, "Out-of-core
//! simplification of large polygonal models", section 3.2): the point that minimises the summed
//! squared distances to the planes of a cluster's faces.

use glam::DVec3;

/// The quadric `E(x) = xᵀAx + 2bᵀx + c` of a set of planes, A symmetric (xx, xy, xz, yy, yz, zz).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Quadric {
    /// Upper triangle of A.
    pub a: [f64; 6],
    /// b.
    pub b: [f64; 3],
    /// c.
    pub c: f64,
}

impl Quadric {
    /// The quadric of the plane `n·x + d = 0` (`n` unit), weighted by `w` (e.g. the face area).
    #[inline] // Into the face passes, which build one a face.
    pub fn plane(n: [f64; 3], d: f64, w: f64) -> Quadric {
        Quadric {
            a: [
                n[0] * n[0],
                n[0] * n[1],
                n[0] * n[2],
                n[1] * n[1],
                n[1] * n[2],
                n[2] * n[2],
            ]
            .map(|x| x * w),
            b: n.map(|x| x * d * w),
            c: d * d * w,
        }
    }

    /// Adds `other`.
    #[inline]
    pub fn add(&mut self, other: &Quadric) {
        for k in 0..6 {
            self.a[k] += other.a[k];
        }
        for k in 0..3 {
            self.b[k] += other.b[k];
        }
        self.c += other.c;
    }

    /// E(x).
    pub fn error(&self, x: [f64; 3]) -> f64 {
        let ax = self.mul(x);
        x[0] * ax[0]
            + x[1] * ax[1]
            + x[2] * ax[2]
            + 2.0 * (self.b[0] * x[0] + self.b[1] * x[1] + self.b[2] * x[2])
            + self.c
    }

    fn mul(&self, x: [f64; 3]) -> [f64; 3] {
        let a = &self.a;
        [
            a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
            a[1] * x[0] + a[3] * x[1] + a[4] * x[2],
            a[2] * x[0] + a[4] * x[1] + a[5] * x[2],
        ]
    }

    /// The minimiser of E closest to `x0`: Lindstrom's pseudo-inverse solve `x = x0 + A⁺(−b −
    /// Ax0)`, dropping eigen-directions whose eigenvalue is below `1e-3` of the largest. On a
    /// flat region (A of rank 1) the point only moves along the normal; on a crease (rank 2)
    /// along the crease's cross-section; at a corner (rank 3) to the corner. Returns `x0` when
    /// A is zero.
    ///
    /// Closed form, no iteration (the grid solves one per cell): the eigenvalues from the
    /// trigonometric solution of the characteristic cubic (Smith 1961); rank 3 is a plain
    /// solve, rank 1 a projection on the one kept direction, rank 2 a solve with the dropped
    /// direction's eigenvalue replaced by the largest. Where an eigenvector cannot be told
    /// apart (two nearly equal eigenvalues across the threshold) it falls back to Jacobi
    /// rotations ([`eigen_symmetric`]).
    pub fn minimizer(&self, x0: [f64; 3]) -> [f64; 3] {
        let a = self.a;
        let r = -(DVec3::from_array(self.b) + DVec3::from_array(self.mul(x0)));
        let Some([l1, l2, l3]) = eigenvalues(a) else {
            return self.minimizer_jacobi(x0);
        };
        if l1 <= 0.0 || !l1.is_finite() {
            return x0;
        }
        let cut = 1e-3 * l1;
        let step = if l3 > cut {
            solve(a, r)
        } else if l2 > cut {
            // Crease: drop the direction of λ3 by raising its eigenvalue to λ1 and solving
            // for the part of r across it.
            eigenvector(a, l3, l1).and_then(|w| {
                let pr = r - w * w.dot(r);
                let s = l1 - l3;
                let b = [
                    a[0] + s * w[0] * w[0],
                    a[1] + s * w[0] * w[1],
                    a[2] + s * w[0] * w[2],
                    a[3] + s * w[1] * w[1],
                    a[4] + s * w[1] * w[2],
                    a[5] + s * w[2] * w[2],
                ];
                solve(b, pr)
            })
        } else {
            // Flat: move along the one kept direction.
            eigenvector(a, l1, l1).map(|u| u * (u.dot(r) / l1))
        };
        match step {
            Some(d) => (DVec3::from_array(x0) + d).to_array(),
            None => self.minimizer_jacobi(x0),
        }
    }

    /// [`Quadric::minimizer`] by Jacobi rotations: slower, for the cases the closed form
    /// cannot separate.
    fn minimizer_jacobi(&self, x0: [f64; 3]) -> [f64; 3] {
        let (vals, vecs) = eigen_symmetric(self.a);
        let max = vals.iter().cloned().fold(0.0, f64::max);
        if max <= 0.0 || !max.is_finite() {
            return x0;
        }
        let r = -(DVec3::from_array(self.b) + DVec3::from_array(self.mul(x0)));
        let mut x = x0;
        for i in 0..3 {
            if vals[i] > 1e-3 * max {
                let u = vecs[i];
                let t = (u[0] * r[0] + u[1] * r[1] + u[2] * r[2]) / vals[i];
                for k in 0..3 {
                    x[k] += t * u[k];
                }
            }
        }
        x
    }
}

/// Eigenvalues of a symmetric 3×3 matrix (upper triangle), largest first, by the
/// trigonometric solution of its characteristic polynomial; `None` if not finite.
fn eigenvalues(a: [f64; 6]) -> Option<[f64; 3]> {
    let p1 = a[1] * a[1] + a[2] * a[2] + a[4] * a[4];
    let q = (a[0] + a[3] + a[5]) / 3.0;
    let (d0, d1, d2) = (a[0] - q, a[3] - q, a[5] - q);
    let p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * p1;
    if !p2.is_finite() || !q.is_finite() {
        return None;
    }
    if p2 == 0.0 {
        return Some([q; 3]);
    }
    let p = (p2 / 6.0).sqrt();
    // det((A − qI) / p) / 2, clamped against rounding.
    let (b0, b1, b2, b3, b4, b5) = (d0 / p, a[1] / p, a[2] / p, d1 / p, a[4] / p, d2 / p);
    let det = b0 * (b3 * b5 - b4 * b4) - b1 * (b1 * b5 - b4 * b2) + b2 * (b1 * b4 - b3 * b2);
    let phi = (0.5 * det).clamp(-1.0, 1.0).acos() / 3.0;
    let l1 = q + 2.0 * p * phi.cos();
    let l3 = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    let l2 = 3.0 * q - l1 - l3;
    Some([l1, l2.clamp(l3, l1), l3])
}

/// The unit eigenvector of the eigenvalue `l` of `a` (upper triangle), `scale` the largest
/// eigenvalue: the largest cross product of two rows of `A − lI`, or `None` when every one is
/// too small to give a direction (`l` nearly repeated).
fn eigenvector(a: [f64; 6], l: f64, scale: f64) -> Option<DVec3> {
    let r0 = DVec3::new(a[0] - l, a[1], a[2]);
    let r1 = DVec3::new(a[1], a[3] - l, a[4]);
    let r2 = DVec3::new(a[2], a[4], a[5] - l);
    let c = [r0.cross(r1), r0.cross(r2), r1.cross(r2)];
    let n = c.map(DVec3::length_squared);
    let best = (0..3).fold(0, |b, i| if n[i] > n[b] { i } else { b });
    // (A NaN fails the comparison too.)
    if n[best].partial_cmp(&(1e-18 * scale.powi(4))) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    Some(c[best] / n[best].sqrt())
}

/// `A⁻¹ r` by the adjugate, `None` when A is singular to working precision.
fn solve(a: [f64; 6], r: DVec3) -> Option<DVec3> {
    let c00 = a[3] * a[5] - a[4] * a[4];
    let c01 = a[2] * a[4] - a[1] * a[5];
    let c02 = a[1] * a[4] - a[2] * a[3];
    let c11 = a[0] * a[5] - a[2] * a[2];
    let c12 = a[1] * a[2] - a[0] * a[4];
    let c22 = a[0] * a[3] - a[1] * a[1];
    let det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    Some(DVec3::new(
        (c00 * r.x + c01 * r.y + c02 * r.z) * inv,
        (c01 * r.x + c11 * r.y + c12 * r.z) * inv,
        (c02 * r.x + c12 * r.y + c22 * r.z) * inv,
    ))
}

/// Eigenvalues and unit eigenvectors of a symmetric 3×3 matrix (upper triangle xx, xy, xz, yy,
/// yz, zz) by cyclic Jacobi rotations.
pub fn eigen_symmetric(a: [f64; 6]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut m = [[a[0], a[1], a[2]], [a[1], a[3], a[4]], [a[2], a[4], a[5]]];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _sweep in 0..32 {
        let off = m[0][1].abs() + m[0][2].abs() + m[1][2].abs();
        let scale = m[0][0].abs() + m[1][1].abs() + m[2][2].abs();
        if off <= 1e-15 * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if m[p][q] == 0.0 {
                continue;
            }
            let theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut m {
                let (mkp, mkq) = (row[p], row[q]);
                row[p] = c * mkp - s * mkq;
                row[q] = s * mkp + c * mkq;
            }
            let (rp, rq) = (m[p], m[q]);
            for k in 0..3 {
                m[p][k] = c * rp[k] - s * rq[k];
                m[q][k] = s * rp[k] + c * rq[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let vals = [m[0][0], m[1][1], m[2][2]];
    let vecs = std::array::from_fn(|i| [v[0][i], v[1][i], v[2][i]]);
    (vals, vecs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_of_three_planes() {
        let mut q = Quadric::default();
        q.add(&Quadric::plane([1.0, 0.0, 0.0], -1.0, 1.0)); // x = 1
        q.add(&Quadric::plane([0.0, 1.0, 0.0], -2.0, 1.0)); // y = 2
        q.add(&Quadric::plane([0.0, 0.0, 1.0], 3.0, 1.0)); // z = -3
        let x = q.minimizer([0.0; 3]);
        for (a, b) in x.iter().zip([1.0, 2.0, -3.0]) {
            assert!((a - b).abs() < 1e-9, "{x:?}");
        }
        assert!(q.error(x).abs() < 1e-12);
    }

    #[test]
    fn flat_region_moves_only_along_the_normal() {
        let q = Quadric::plane([0.0, 0.0, 1.0], -0.5, 2.0); // z = 0.5
        let x = q.minimizer([0.25, -4.0, 0.0]);
        assert!(
            (x[0] - 0.25).abs() < 1e-12 && (x[1] + 4.0).abs() < 1e-12 && (x[2] - 0.5).abs() < 1e-12
        );
    }

    #[test]
    fn closed_form_matches_jacobi() {
        // Flat, crease and corner clusters of noisy planes, and a tilted crease.
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let unit = |v: [f64; 3]| {
            let v = DVec3::from_array(v);
            (v / v.length()).to_array()
        };
        for case in 0..300 {
            let mut q = Quadric::default();
            let axes = case % 3 + 1;
            for _ in 0..6 {
                let k = (rnd() + 0.5) * axes as f64;
                let mut n = [0.0; 3];
                n[k as usize % 3] = 1.0;
                let n = unit([
                    n[0] + 0.01 * rnd(),
                    n[1] + 0.01 * rnd(),
                    n[2] + 0.01 * rnd(),
                ]);
                q.add(&Quadric::plane(n, rnd(), 0.5 + rnd()));
            }
            let x0 = [rnd(), rnd(), rnd()];
            let (a, b) = (q.minimizer(x0), q.minimizer_jacobi(x0));
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-6, "case {case}: {a:?} vs {b:?}");
            }
        }
    }

    #[test]
    fn eigen_decomposition_reconstructs() {
        let a = [4.0, 1.0, -2.0, 3.0, 0.5, 5.0];
        let (vals, vecs) = eigen_symmetric(a);
        let m = [[a[0], a[1], a[2]], [a[1], a[3], a[4]], [a[2], a[4], a[5]]];
        for i in 0..3 {
            for r in 0..3 {
                let mv: f64 = (0..3).map(|c| m[r][c] * vecs[i][c]).sum();
                assert!((mv - vals[i] * vecs[i][r]).abs() < 1e-9);
            }
        }
    }
}
