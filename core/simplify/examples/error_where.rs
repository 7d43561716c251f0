//! Where a simplified mesh is far from its input: the distance from samples of each surface to
//! the other, the largest ones with their positions, and the input's squared error split by
//! the kind of surface its samples lie on (flat, curved, at a crease) — for finding what the
//! complexity goal gets wrong on a mesh (issue 33: fandisk).
//!
//! `cargo run --release -p tessd-simplify --example error_where -- INPUT OUTPUT [TOP]`

use tessd_compare::SurfaceIndex;
use tessd_mesh::Mesh;
use tessd_mesh::io::{ReadOptions, read_path};

/// Points of every fan triangle of `m` on a barycentric lattice of `n` steps, with their
/// triangle's first corner.
fn samples(m: &Mesh, n: usize) -> Vec<([f64; 3], u32)> {
    let mut out = Vec::new();
    for f in m.faces() {
        for k in 1..f.len() - 1 {
            let c = [f[0], f[k], f[k + 1]].map(|v| m.positions[v as usize].map(f64::from));
            for a in 0..=n {
                for b in 0..=n - a {
                    let w = [a, b, n - a - b].map(|x| x as f64 / n as f64);
                    let p = [0, 1, 2].map(|j| w[0] * c[0][j] + w[1] * c[1][j] + w[2] * c[2][j]);
                    out.push((p, f[0]));
                }
            }
        }
    }
    out
}

/// The largest angle (degrees) between the normals of faces sharing a vertex, per vertex.
fn turning(m: &Mesh) -> Vec<f32> {
    let mut normals: Vec<Vec<[f32; 3]>> = vec![Vec::new(); m.vertex_count()];
    for f in m.faces() {
        let p = |i: usize| m.positions[f[i] as usize];
        let (a, b, c) = (p(0), p(1), p(2));
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if l > 0.0 {
            f.iter()
                .for_each(|&v| normals[v as usize].push(n.map(|x| x / l)));
        }
    }
    normals
        .iter()
        .map(|ns| {
            let mut worst = 1f32;
            for a in ns {
                for b in ns {
                    worst = worst.min(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
                }
            }
            worst.clamp(-1.0, 1.0).acos().to_degrees()
        })
        .collect()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let read = |p: &str| read_path(p.as_ref(), &ReadOptions::default()).expect("reads");
    let (input, output) = (read(&args[1]), read(&args[2]));
    let top: usize = args.get(3).map_or(12, |s| s.parse().unwrap());
    let (ii, oi) = (
        SurfaceIndex::new(&input).unwrap(),
        SurfaceIndex::new(&output).unwrap(),
    );
    let turn = turning(&input);
    for (name, from, to, n) in [
        ("input->output", &input, &oi, 4),
        ("output->input", &output, &ii, 8),
    ] {
        let s = samples(from, n);
        let pts: Vec<[f64; 3]> = s.iter().map(|x| x.0).collect();
        let d = to.distances(&pts);
        let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
        let max = d.iter().cloned().fold(0.0, f64::max);
        println!("{name}: {} samples, max {max:.5}, rms {rms:.6}", d.len());
        let mut order: Vec<usize> = (0..d.len()).collect();
        order.sort_by(|&a, &b| d[b].total_cmp(&d[a]));
        let mut shown: Vec<[f64; 3]> = Vec::new();
        for &i in &order {
            let p = pts[i];
            // One line per place (0.1 apart).
            if shown
                .iter()
                .any(|q| (0..3).all(|k| (q[k] - p[k]).abs() < 0.1))
            {
                continue;
            }
            shown.push(p);
            let t = if std::ptr::eq(from, &input) {
                turn[s[i].1 as usize]
            } else {
                f32::NAN
            };
            println!(
                "  {:.5} at [{:.3}, {:.3}, {:.3}] corner turning {t:.0} deg",
                d[i], p[0], p[1], p[2]
            );
            if shown.len() == top {
                break;
            }
        }
        if std::ptr::eq(from, &input) {
            // Squared error by the kind of surface of the sample's triangle's first corner.
            let mut sums = [0f64; 4];
            let mut counts = [0usize; 4];
            for (k, x) in d.iter().enumerate() {
                let t = turn[s[k].1 as usize];
                let c = if t < 1.0 {
                    0
                } else if t < 15.0 {
                    1
                } else if t < 45.0 {
                    2
                } else {
                    3
                };
                sums[c] += x * x;
                counts[c] += 1;
            }
            let total: f64 = sums.iter().sum();
            for (c, name) in ["flat <1", "curved 1-15", "turning 15-45", "crease >45"]
                .iter()
                .enumerate()
            {
                println!(
                    "  {name} deg: {} samples, {:.1} % of the squared error, rms {:.6}",
                    counts[c],
                    100.0 * sums[c] / total,
                    (sums[c] / counts[c].max(1) as f64).sqrt()
                );
            }
        }
    }
}
