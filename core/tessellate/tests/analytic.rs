//! Analytic parts: every vertex on its surface within the tolerance, watertight after welding,
//! area within 0.5 % of the exact one, triangles inside the trims.

mod common;

use common::{area, load, open_edges, outside_triangles, run};
use std::f64::consts::PI;
use tessd_tessellate::Options;

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

/// A disc of radius 1 with an off-centre hole of radius 0.9, 0.005 from the rim at its closest:
/// sampled to 0.05, the rim's and the hole's polygons cross there (the rim's samples start
/// 0.3 rad round, so a chord of it, 0.014 inside there, passes the hole's vertex at
/// (0.995, 0)). The crossing step must split them — on the shared edges when the trims have
/// edges, on the trims themselves when not — until no boundary segment crosses another.
#[test]
fn crossing_boundaries_are_split() {
    use tessd_tessellate::{boundary, crossings, edges};
    for with_edges in [true, false] {
        let edge = |id: u32| {
            if with_edges {
                format!(r#", "edge": {id}"#)
            } else {
                String::new()
            }
        };
        let edges_json = if with_edges {
            r#", "edges": [
                {"id": 0, "curve": {"type": "circle", "center": [0, 0, 0],
                 "x_dir": [0.955336489125606, 0.29552020666134, 0],
                 "y_dir": [-0.29552020666134, 0.955336489125606, 0], "radius": 1},
                 "range": [0, 6.283185307179586], "faces": [0]},
                {"id": 1, "curve": {"type": "circle", "center": [0.095, 0, 0], "x_dir": [1, 0, 0],
                 "y_dir": [0, 1, 0], "radius": 0.9}, "range": [0, 6.283185307179586], "faces": [0]}]"#
        } else {
            ""
        };
        let json = format!(
            r#"{{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [{{"id": 0,
              "surface": {{"type": "plane", "origin": [0, 0, 0], "x_dir": [1, 0, 0],
                          "y_dir": [0, 1, 0]}}, "bounds": [-1, 1, -1, 1],
              "loops": [
                {{"edges": [{{"curve": {{"type": "circle", "center": [0, 0],
                  "x_dir": [0.955336489125606, 0.29552020666134],
                  "y_dir": [-0.29552020666134, 0.955336489125606], "radius": 1}},
                  "range": [0, 6.283185307179586]{}}}]}},
                {{"edges": [{{"curve": {{"type": "circle", "center": [0.095, 0], "x_dir": [1, 0],
                  "y_dir": [0, 1], "radius": 0.9}}, "range": [6.283185307179586, 0]{}}}]}}]}}]{}}}"#,
            edge(0),
            edge(1),
            edges_json
        );
        let doc = tessd_brep::Document::from_json(&json).unwrap();
        doc.validate().unwrap();
        let options = Options::new(0.05);
        let mut table = edges::discretise(&doc, &options);
        let first = boundary::face_loops(&doc.faces[0], &table, &Default::default(), &options);
        assert!(
            !crossings::crossing_segments(&first).is_empty(),
            "with edges {with_edges}: the polygons were meant to cross"
        );
        let (loops, stats) = crossings::face_loops_uncrossed(&doc, &mut table, &options);
        assert!(stats.splits > 0 && stats.unresolved.is_empty(), "{stats:?}");
        assert!(crossings::crossing_segments(&loops[0]).is_empty());
        let t = run(&doc, 0.05);
        assert_eq!(t.stats.crossings, stats);
        // Every triangle's centroid on the annulus, within the tolerance.
        for f in t.mesh.faces() {
            let c = [0, 1].map(|d| f.iter().map(|&v| t.uvs[v as usize][d]).sum::<f64>() / 3.0);
            let (r, hole) = (c[0].hypot(c[1]), (c[0] - 0.095).hypot(c[1]));
            assert!(
                r < 1.0 + 1e-9 && hole > 0.9 - 0.05,
                "with edges {with_edges}: centroid {c:?} off the face"
            );
        }
        let exact = PI * (1.0 - 0.81);
        let a = area(&t);
        assert!(
            (a - exact).abs() < 0.05 * exact,
            "with edges {with_edges}: area {a} vs {exact}"
        );
    }
}
