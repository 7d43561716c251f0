//! Plane quadrics and their minimiser (Garland & Heckbert 1997; Lindstrom 2000, "Out-of-core
//! simplification of large polygonal models", section 3.2): the point that minimises the summed
//! squared distances to the planes of a cluster's faces.

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
    pub fn minimizer(&self, x0: [f64; 3]) -> [f64; 3] {
        let (vals, vecs) = eigen_symmetric(self.a);
        let max = vals.iter().cloned().fold(0.0, f64::max);
        if max <= 0.0 || !max.is_finite() {
            return x0;
        }
        let ax0 = self.mul(x0);
        let r = [
            -(self.b[0] + ax0[0]),
            -(self.b[1] + ax0[1]),
            -(self.b[2] + ax0[2]),
        ];
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
