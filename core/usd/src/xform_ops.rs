//! `UsdGeomXformable` transform operations (`xformOp:*`), for [`crate::reader`].
//!
//! Follows usd-core's `UsdGeomXformOp::GetOpTransform` and `UsdGeomXformable::
//! GetLocalTransformation`, in USD's `GfMatrix4d` convention: points are row vectors multiplied
//! on the left (`p' = p · M`), the translation is row 3, and a prim's local transform for
//! `xformOpOrder = [op0, op1, ..., opN]` is `M(opN) · ... · M(op1) · M(op0)`: the last op is
//! applied to the points first. Rotations are in degrees; `rotateXYZ` rotates about X first,
//! then Y, then Z; `orient` is a quaternion written `(real, i, j, k)`.

/// A 4×4 matrix, `m[row][col]`, row vectors on the left.
pub(crate) type Mat4 = [[f64; 4]; 4];

/// The identity matrix.
pub(crate) const IDENTITY: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// `a · b` (apply `a`, then `b`, to row vectors).
pub(crate) fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..4).map(|k| a[r][k] * b[k][c]).sum()))
}

/// The number of values an op of this kind takes (`None` for an unknown kind).
pub(crate) fn op_arity(kind: &str) -> Option<usize> {
    Some(match kind {
        "translate" | "scale" => 3,
        "translateX" | "translateY" | "translateZ" | "scaleX" | "scaleY" | "scaleZ" => 1,
        "rotateX" | "rotateY" | "rotateZ" => 1,
        "rotateXYZ" | "rotateXZY" | "rotateYXZ" | "rotateYZX" | "rotateZXY" | "rotateZYX" => 3,
        "orient" => 4,
        "transform" => 16,
        _ => return None,
    })
}

/// The matrix of one op: `kind` is the part of the attribute name after `xformOp:`
/// (`translate`, `rotateXYZ`, ...) and `v` its [`op_arity`] values (checked by the caller).
///
/// # Errors
/// A message for an unknown kind or a zero quaternion.
pub(crate) fn op_matrix(kind: &str, v: &[f64]) -> Result<Mat4, String> {
    let mut m = IDENTITY;
    match kind {
        "translate" => m[3][..3].copy_from_slice(&v[..3]),
        "translateX" | "translateY" | "translateZ" => m[3][axis(kind)] = v[0],
        "scale" => (0..3).for_each(|k| m[k][k] = v[k]),
        "scaleX" | "scaleY" | "scaleZ" => m[axis(kind)][axis(kind)] = v[0],
        "rotateX" | "rotateY" | "rotateZ" => m = rotation(axis(kind), v[0]),
        "transform" => {
            for (r, row) in m.iter_mut().enumerate() {
                row.copy_from_slice(&v[4 * r..4 * r + 4]);
            }
        }
        "orient" => m = quaternion(v)?,
        _ if kind.len() == 9 && kind.starts_with("rotate") => {
            // rotateABC: about A first, then B, then C.
            for (k, c) in kind[6..].chars().enumerate() {
                let a = "XYZ".find(c).ok_or_else(|| format!("unknown op {kind}"))?;
                m = mul(&m, &rotation(a, v[k]));
            }
        }
        _ => return Err(format!("unknown op {kind}")),
    }
    Ok(m)
}

/// 0, 1, 2 for a kind ending in X, Y, Z.
fn axis(kind: &str) -> usize {
    match kind.as_bytes().last() {
        Some(b'X') => 0,
        Some(b'Y') => 1,
        _ => 2,
    }
}

/// Rotation by `degrees` about axis `a` (row-vector form).
fn rotation(a: usize, degrees: f64) -> Mat4 {
    let (s, c) = degrees.to_radians().sin_cos();
    let (i, j) = ((a + 1) % 3, (a + 2) % 3);
    let mut m = IDENTITY;
    m[i][i] = c;
    m[i][j] = s;
    m[j][i] = -s;
    m[j][j] = c;
    m
}

/// The rotation of the quaternion `(real, i, j, k)`, normalized (row-vector form: the
/// transpose of the usual column-vector matrix).
fn quaternion(v: &[f64]) -> Result<Mat4, String> {
    let n = v[..4].iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err("the orient quaternion has zero or non-finite length".into());
    }
    let [w, x, y, z] = [v[0] / n, v[1] / n, v[2] / n, v[3] / n];
    let mut m = IDENTITY;
    m[0][..3].copy_from_slice(&[
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y + w * z),
        2.0 * (x * z - w * y),
    ]);
    m[1][..3].copy_from_slice(&[
        2.0 * (x * y - w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z + w * x),
    ]);
    m[2][..3].copy_from_slice(&[
        2.0 * (x * z + w * y),
        2.0 * (y * z - w * x),
        1.0 - 2.0 * (x * x + y * y),
    ]);
    Ok(m)
}

/// The inverse of `m` (for `!invert!` ops), or `None` when it is singular.
pub(crate) fn invert(m: &Mat4) -> Option<Mat4> {
    // Gauss-Jordan elimination with partial pivoting.
    let mut a = *m;
    let mut inv = IDENTITY;
    for col in 0..4 {
        let p = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[p][col].abs() < 1e-300 || !a[p][col].is_finite() {
            return None;
        }
        a.swap(col, p);
        inv.swap(col, p);
        let d = a[col][col];
        for k in 0..4 {
            a[col][k] /= d;
            inv[col][k] /= d;
        }
        for r in 0..4 {
            if r != col {
                let f = a[r][col];
                for k in 0..4 {
                    a[r][k] -= f * a[col][k];
                    inv[r][k] -= f * inv[col][k];
                }
            }
        }
    }
    Some(inv)
}

/// `p · m` with the projective divide (as `GfMatrix4d::Transform`).
pub(crate) fn transform_point(m: &Mat4, p: [f64; 3]) -> [f64; 3] {
    let h: [f64; 4] =
        std::array::from_fn(|c| (0..3).map(|k| p[k] * m[k][c]).sum::<f64>() + m[3][c]);
    if h[3] == 1.0 || h[3] == 0.0 {
        [h[0], h[1], h[2]]
    } else {
        [h[0] / h[3], h[1] / h[3], h[2] / h[3]]
    }
}

/// The matrix that carries normals through `m`: the inverse transpose of its 3×3 part, or
/// `None` when that is singular.
pub(crate) fn normal_matrix(m: &Mat4) -> Option<[[f64; 3]; 3]> {
    let mut a = IDENTITY;
    for r in 0..3 {
        a[r][..3].copy_from_slice(&m[r][..3]);
    }
    let inv = invert(&a)?;
    Some(std::array::from_fn(|r| std::array::from_fn(|c| inv[c][r])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (0..3).all(|k| (a[k] - b[k]).abs() < 1e-12)
    }

    #[test]
    fn rotations_follow_usd() {
        let p = [1.0, 0.0, 0.0];
        let z90 = op_matrix("rotateZ", &[90.0]).unwrap();
        assert!(close(transform_point(&z90, p), [0.0, 1.0, 0.0]));
        let x90 = op_matrix("rotateX", &[90.0]).unwrap();
        assert!(close(
            transform_point(&x90, [0.0, 1.0, 0.0]),
            [0.0, 0.0, 1.0]
        ));
        let y90 = op_matrix("rotateY", &[90.0]).unwrap();
        assert!(close(
            transform_point(&y90, [0.0, 0.0, 1.0]),
            [1.0, 0.0, 0.0]
        ));
        // rotateXYZ = X first, then Y, then Z.
        let xyz = op_matrix("rotateXYZ", &[90.0, 0.0, 90.0]).unwrap();
        assert!(close(
            transform_point(&xyz, [0.0, 1.0, 0.0]),
            [0.0, 0.0, 1.0]
        ));
        assert!(close(
            transform_point(&xyz, [1.0, 0.0, 0.0]),
            [0.0, 1.0, 0.0]
        ));
        // The quaternion of 90° about Z, (cos 45°, 0, 0, sin 45°), unnormalized.
        let q = op_matrix("orient", &[2.0, 0.0, 0.0, 2.0]).unwrap();
        assert!(close(transform_point(&q, p), [0.0, 1.0, 0.0]));
        assert!(op_matrix("orient", &[0.0; 4]).is_err());
        assert!(op_matrix("rotateXYW", &[0.0; 3]).is_err());
    }

    #[test]
    fn translate_scale_invert() {
        let t = op_matrix("translate", &[1.0, 2.0, 3.0]).unwrap();
        let s = op_matrix("scale", &[2.0, 2.0, 2.0]).unwrap();
        // Order [translate, scale]: scale first.
        let m = mul(&s, &t);
        assert!(close(transform_point(&m, [1.0, 1.0, 1.0]), [3.0, 4.0, 5.0]));
        let back = transform_point(&invert(&m).unwrap(), [3.0, 4.0, 5.0]);
        assert!(close(back, [1.0, 1.0, 1.0]));
        assert!(invert(&op_matrix("scale", &[1.0, 0.0, 1.0]).unwrap()).is_none());
        let n = normal_matrix(&op_matrix("scale", &[2.0, 1.0, 1.0]).unwrap()).unwrap();
        assert_eq!(n[0][0], 0.5);
        let tx = op_matrix("translateY", &[4.0]).unwrap();
        assert!(close(transform_point(&tx, [0.0; 3]), [0.0, 4.0, 0.0]));
    }
}
