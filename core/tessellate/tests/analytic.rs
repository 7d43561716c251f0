//! Analytic parts: every vertex on its surface within the tolerance, watertight after welding,
//! area within 0.5 % of the exact one, triangles inside the trims.

mod common;

use common::{area, load, open_edges, outside_triangles, run};
use std::f64::consts::PI;

fn norm(p: [f32; 3]) -> f64 {
    p.iter().map(|&c| f64::from(c).powi(2)).sum::<f64>().sqrt()
}

#[test]
fn cube() {
    let doc = load("cube.json");
    let t = run(&doc, 0.01);
    assert_eq!(
        t.mesh.group_names,
        (0..6).map(|i| format!("face{i}")).collect::<Vec<_>>()
    );
    assert!(t.stats.empty_faces.is_empty());
    for (i, f) in t.mesh.faces().enumerate() {
        let g = t.mesh.face_groups[i];
        // Faces 0..6: z=0, z=1, y=0, y=1, x=0, x=1.
        let (axis, value) = ((2 - g / 2) as usize, f64::from(g % 2));
        for &v in f {
            let p = t.mesh.positions[v as usize];
            assert!(
                (f64::from(p[axis]) - value).abs() < 1e-6,
                "{p:?} off face {g}"
            );
        }
    }
    assert!(open_edges(&t).is_empty(), "{:?}", open_edges(&t));
    assert!((area(&t) - 6.0).abs() < 1e-5);
    assert_eq!(outside_triangles(&doc, &t), 0);
}

#[test]
fn cylinder() {
    let (r, h) = (2.0, 3.0);
    let doc = load("cylinder.json");
    for tol in [0.01, 0.002] {
        let t = run(&doc, tol);
        assert!(t.stats.empty_faces.is_empty());
        for (i, f) in t.mesh.faces().enumerate() {
            let g = t.mesh.face_groups[i];
            for &v in f {
                let p = t.mesh.positions[v as usize];
                let d = match g {
                    0 => {
                        let rho = f64::from(p[0]).hypot(f64::from(p[1]));
                        (rho - r)
                            .abs()
                            .max((f64::from(p[2]) - h / 2.0).abs() - h / 2.0)
                    }
                    1 => f64::from(p[2]).abs(),
                    _ => (f64::from(p[2]) - h).abs(),
                };
                assert!(d <= tol + 1e-5, "{p:?} off face {g} by {d}");
            }
        }
        assert!(open_edges(&t).is_empty(), "{:?}", &open_edges(&t)[..3]);
        let exact = 2.0 * PI * r * h + 2.0 * PI * r * r;
        let a = area(&t);
        assert!((a - exact).abs() / exact < 0.005, "area {a} vs {exact}");
        assert_eq!(outside_triangles(&doc, &t), 0);
        // Every vertex within the tolerance: the chordal deviation is checked at the
        // triangles' centroids too.
        for f in t.mesh.faces() {
            let c = [0, 1, 2].map(|d| {
                f.iter()
                    .map(|&v| f64::from(t.mesh.positions[v as usize][d]))
                    .sum::<f64>()
                    / 3.0
            });
            let rho = c[0].hypot(c[1]);
            let dev = if (c[2].abs() < 1e-6) || ((c[2] - h).abs() < 1e-6) {
                0.0
            } else {
                (rho - r).abs()
            };
            assert!(dev <= tol * 1.05, "centroid {c:?} off by {dev}");
        }
    }
}

#[test]
fn sphere() {
    let r = 1.5;
    let doc = load("sphere.json");
    for tol in [0.01, 0.003] {
        let t = run(&doc, tol);
        assert!(t.stats.empty_faces.is_empty());
        for &p in &t.mesh.positions {
            let d = (norm(p) - r).abs();
            assert!(d <= tol + 1e-5, "{p:?} off the sphere by {d}");
        }
        assert!(open_edges(&t).is_empty(), "{:?}", open_edges(&t));
        let exact = 4.0 * PI * r * r;
        let a = area(&t);
        assert!((a - exact).abs() / exact < 0.005, "area {a} vs {exact}");
        assert_eq!(outside_triangles(&doc, &t), 0);
    }
}

#[test]
fn bad_options_are_refused() {
    let doc = load("cube.json");
    for tol in [0.0, -1.0, f64::NAN] {
        assert!(tessd_tessellate::tessellate(&doc, &tessd_tessellate::Options::new(tol)).is_err());
    }
}
