//! Generated inputs for the size scaling: a bumpy torus with scan-like noise.

use tessd_mesh::Mesh;

/// A closed torus (genus 1, no boundary) of about `triangles` triangles: major radius 1,
/// minor radius 0.4 modulated by three periodic bump frequencies, plus a deterministic
/// per-vertex radial jitter of 10 % of the edge length (like scan noise, so the fine scale is
/// not perfectly smooth at any resolution). Vertices in row order (the order a scanner or a
/// tessellator produces), two triangles per grid quad.
pub fn bumpy_torus(triangles: u64) -> Mesh {
    let ratio = 2.5; // around-the-hole vs around-the-tube resolution, ~ R / r
    let nv = ((triangles as f64 / (2.0 * ratio)).sqrt().round() as u32).max(3);
    let nu = ((triangles as f64 / (2.0 * f64::from(nv))).round() as u32).max(3);
    let (big_r, small_r) = (1.0f64, 0.4f64);
    let edge = std::f64::consts::TAU * small_r / f64::from(nv);
    let mut m = Mesh::default();
    m.positions.reserve(nu as usize * nv as usize);
    let tau = std::f64::consts::TAU;
    for i in 0..nu {
        let u = tau * f64::from(i) / f64::from(nu);
        for j in 0..nv {
            let v = tau * f64::from(j) / f64::from(nv);
            let bumps = 0.10 * (6.0 * u).sin() * (4.0 * v).cos()
                + 0.04 * (17.0 * u + 9.0 * v).sin()
                + 0.015 * (53.0 * u - 31.0 * v).sin();
            let noise = 0.1 * edge * hash_unit(i, j);
            let r = small_r * (1.0 + bumps) + noise;
            let ring = big_r + r * v.cos();
            m.positions.push([
                (ring * u.cos()) as f32,
                (ring * u.sin()) as f32,
                (r * v.sin()) as f32,
            ]);
        }
    }
    m.face_offsets.reserve(2 * nu as usize * nv as usize);
    m.face_indices.reserve(6 * nu as usize * nv as usize);
    for i in 0..nu {
        let i1 = (i + 1) % nu;
        for j in 0..nv {
            let j1 = (j + 1) % nv;
            let (a, b, c, d) = (i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1);
            m.push_face(&[a, b, c]);
            m.push_face(&[a, c, d]);
        }
    }
    m
}

/// A deterministic value in [-1, 1) from two integers (SplitMix64 finaliser).
fn hash_unit(i: u32, j: u32) -> f64 {
    let mut z = (u64::from(i) << 32 | u64::from(j)).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torus_is_closed_and_sized() {
        let m = bumpy_torus(20_000);
        m.validate().unwrap();
        let t = m.triangle_count() as f64;
        assert!((t / 20_000.0 - 1.0).abs() < 0.05, "{t}");
        // Closed genus-1 grid: V = T / 2.
        assert_eq!(2 * m.positions.len(), m.triangle_count());
    }
}
