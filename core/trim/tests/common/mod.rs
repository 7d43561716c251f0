//! Helpers shared by the trim tests: a reproducible random stream, a plane, line trims, and
//! the even-odd reference the classifier is checked against.

#![allow(dead_code)]

use tessd_brep::{Curve, Face, Frame, Surface, Trim};

/// xorshift64*: a reproducible stream of numbers in [0, 1).
pub struct Rng(pub u64);

impl Rng {
    /// The next number in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The plane z = 0 with (u, v) = (x, y).
pub fn plane() -> Surface {
    Surface::Plane {
        frame: Frame {
            origin: [0.0, 0.0, 0.0].into(),
            x_dir: [1.0, 0.0, 0.0].into(),
            y_dir: [0.0, 1.0, 0.0].into(),
        },
    }
}

/// The line trim from `a` to `b`, parametrised by length.
pub fn line(a: [f64; 2], b: [f64; 2]) -> Trim {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len = d[0].hypot(d[1]);
    Trim {
        curve: Curve::Line {
            origin: a.into(),
            dir: [d[0] / len, d[1] / len].into(),
        },
        range: [0.0, len],
        edge: None,
    }
}

/// Even-odd over the polygons (closed, densely sampled loops), starting from `empty` (a face
/// without loops is all on), and the distance from `p` to the nearest polygon edge.
pub fn exact_inside(polys: &[Vec<[f64; 2]>], p: [f64; 2], empty: bool) -> (bool, f64) {
    let mut inside = empty;
    let mut dist = f64::INFINITY;
    for poly in polys {
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            if (a[1] > p[1]) != (b[1] > p[1])
                && p[0] < a[0] + (p[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
            {
                inside = !inside;
            }
            let d = [b[0] - a[0], b[1] - a[1]];
            let l2 = (d[0] * d[0] + d[1] * d[1]).max(1e-300);
            let s = (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0);
            dist = dist.min((p[0] - a[0] - s * d[0]).hypot(p[1] - a[1] - s * d[1]));
        }
    }
    (inside, dist)
}

/// Each loop of `face` as a closed polygon of `per_trim` points per trim, sampled straight
/// from the exact trim curves (the even-odd reference's input).
pub fn sampled_loops(face: &Face, per_trim: usize) -> Vec<Vec<[f64; 2]>> {
    face.loops
        .iter()
        .map(|l| {
            l.trims
                .iter()
                .flat_map(|tr| {
                    let [t0, t1] = tr.range;
                    (0..per_trim).map(move |i| {
                        tr.curve
                            .point(t0 + (t1 - t0) * i as f64 / per_trim as f64)
                            .to_array()
                    })
                })
                .collect()
        })
        .collect()
}
