//! `tessellate` with a tolerance relative to the part (`"0.05%"`, of its bounding-box
//! diagonal), through a real daemon and the real binary, on real parts exported from the shared
//! data (core/tessellate/tests/data, `python -m tessd.brep export` of ../shared/data/brep): the
//! same part scaled by 1e-3 (coordinates as a part modelled in metres, or a 0.08-unit part)
//! gives the same mesh relative to its size, where an absolute `0.1mm` does not.

mod support;

use serde_json::{Value, json};
use std::ops::{Div, Mul};
use std::path::{Path, PathBuf};
use support::{Daemon, run_ok, tessd};
use tessd_brep::vector::Point;
use tessd_brep::{Curve, DVec2, DVec3, Document, Surface, Units};
use tessd_ipc::client::{Client, ClientError};
use tessd_ipc::error::ErrorCode;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tessellate/tests/data")
        .join(name)
}

fn load(name: &str) -> Document {
    Document::from_json(&std::fs::read_to_string(fixture(name)).unwrap()).unwrap()
}

/// A curve (3D edge or trim) under the map `p → (s₀·p₀, s₁·p₁, …)` about the origin, and the
/// factor its parameter range scales by: a line's parameter is a length, conics' and
/// B-splines' are not. Conics only under a uniform map (all `s` equal).
fn scale_curve<P>(c: &Curve<P>, s: P) -> (Curve<P>, f64)
where
    P: Point + Mul<Output = P> + Div<f64, Output = P>,
{
    let uniform = |what: &str| {
        assert!(
            s.coords().iter().all(|&x| x == s.coords()[0]),
            "{what} under an anisotropic map"
        );
        s.coords()[0]
    };
    let mut c = c.clone();
    let t = match &mut c {
        Curve::Line { origin, dir } => {
            *origin = *origin * s;
            let d = *dir * s;
            let len = d.length();
            *dir = d / len;
            len
        }
        Curve::Circle { center, radius, .. } => {
            *radius *= uniform("a circle");
            *center = *center * s;
            1.0
        }
        Curve::Ellipse {
            center,
            major_radius,
            minor_radius,
            ..
        } => {
            let k = uniform("an ellipse");
            *center = *center * s;
            *major_radius *= k;
            *minor_radius *= k;
            1.0
        }
        Curve::Bspline(b) => {
            b.poles = b.poles.iter().map(|&p| p * s).collect();
            1.0
        }
    };
    (c, t)
}

/// `doc` scaled by `s` about the origin and labelled `units`: every world coordinate and
/// radius, and the parameters that are lengths (a plane's u and v, a cylinder's or cone's v, a
/// line's t), so the surfaces keep their unit frames and the document still validates.
fn scaled(doc: &Document, s: f64, units: Units) -> Document {
    let mut doc = doc.clone();
    doc.units = units;
    for face in &mut doc.faces {
        let uv = match &mut face.surface {
            Surface::Plane { frame } => {
                frame.origin = frame.origin.map(|x| x * s);
                [s, s]
            }
            Surface::Cylinder { frame, radius } | Surface::Sphere { frame, radius } => {
                frame.origin = frame.origin.map(|x| x * s);
                *radius *= s;
                if matches!(face.surface, Surface::Cylinder { .. }) {
                    [1.0, s]
                } else {
                    [1.0, 1.0]
                }
            }
            Surface::Cone { frame, radius, .. } => {
                frame.origin = frame.origin.map(|x| x * s);
                *radius *= s;
                [1.0, s]
            }
            Surface::Torus {
                frame,
                major_radius,
                minor_radius,
            } => {
                frame.origin = frame.origin.map(|x| x * s);
                *major_radius *= s;
                *minor_radius *= s;
                [1.0, 1.0]
            }
            Surface::Revolution {
                axis_origin, curve, ..
            } => {
                *axis_origin = axis_origin.map(|x| x * s);
                let (c, t) = scale_curve(curve, DVec3::splat(s));
                **curve = c;
                [1.0, t]
            }
            Surface::Extrusion { curve, .. } => {
                let (c, t) = scale_curve(curve, DVec3::splat(s));
                **curve = c;
                [t, s]
            }
            Surface::Bspline(b) => {
                for row in &mut b.poles {
                    for p in row {
                        *p = p.map(|x| x * s);
                    }
                }
                [1.0, 1.0]
            }
        };
        let [u0, u1, v0, v1] = face.bounds;
        face.bounds = [u0 * uv[0], u1 * uv[0], v0 * uv[1], v1 * uv[1]];
        for trim in face.loops.iter_mut().flat_map(|l| &mut l.trims) {
            let (c, t) = scale_curve(&trim.curve, DVec2::from(uv));
            trim.curve = c;
            trim.range = trim.range.map(|x| x * t);
        }
    }
    for edge in doc.edges.iter_mut().flatten() {
        if let Some(curve) = &edge.curve {
            let (c, t) = scale_curve(curve, DVec3::splat(s));
            edge.curve = Some(c);
            edge.range = edge.range.map(|x| x * t);
        }
    }
    doc.validate().unwrap();
    doc
}

/// What one tessellation gave: the op's result, the mesh's area and its vertices' box diagonal.
struct Tess {
    result: Value,
    triangles: f64,
    area: f64,
    mesh_diagonal: f64,
}

fn tessellate(c: &mut Client, doc: &Document, tolerance: Value) -> Result<Tess, ClientError> {
    let brep: Value = serde_json::from_str(&doc.to_json()).unwrap();
    let (result, arrays) = c.call(
        "tessellate",
        json!({"brep": brep, "tolerance": tolerance}),
        &[],
        |_| {},
    )?;
    let (pos, _) = arrays.get::<f32>("positions").unwrap().unwrap();
    let (idx, _) = arrays.get::<u32>("face_indices").unwrap().unwrap();
    let p = |i: u32| {
        let k = 3 * i as usize;
        [pos[k] as f64, pos[k + 1] as f64, pos[k + 2] as f64]
    };
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let mut area = 0.0;
    for t in idx.chunks(3) {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let (e, f) = (sub(b, a), sub(c, a));
        let n = [
            e[1] * f[2] - e[2] * f[1],
            e[2] * f[0] - e[0] * f[2],
            e[0] * f[1] - e[1] * f[0],
        ];
        area += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for i in 0..(pos.len() / 3) as u32 {
        let q = p(i);
        for k in 0..3 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    let d = sub(hi, lo);
    Ok(Tess {
        triangles: result["triangles"].as_f64().unwrap(),
        result,
        area,
        mesh_diagonal: (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt(),
    })
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn percent_of_the_diagonal_is_scale_free() {
    let dir = tempfile::tempdir().unwrap();
    let socket = support::endpoint(dir.path(), "tess.sock");
    let _daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();
    for name in [
        "Pump_Nut.json",
        "CrankArm.json",
        "freecad_drilling1_body.json",
    ] {
        let part = load(name);
        let tiny = scaled(&part, 1e-3, Units::Millimetres);
        let metres = scaled(&part, 1e-3, Units::Metres);

        let a = tessellate(&mut c, &part, json!("0.05%")).unwrap();
        let b = tessellate(&mut c, &tiny, json!("0.05%")).unwrap();
        let diag = |t: &Tess| t.result["diagonal"].as_f64().unwrap();
        let tol = |t: &Tess| t.result["tolerance"].as_f64().unwrap();
        // The absolute tolerance used: 0.0005 × the diagonal, in the document's units.
        for t in [&a, &b] {
            assert_eq!(t.result["tolerance_relative"], json!(0.0005), "{name}");
            assert!(
                rel(tol(t), 0.0005 * diag(t)) < 1e-12,
                "{name}: {}",
                t.result
            );
            // The box is of points on the part: the mesh's vertices (on the part too) span it
            // within a fraction of a percent.
            assert!(
                rel(t.mesh_diagonal, diag(t)) < 5e-3,
                "{name}: mesh box diagonal {} vs {}",
                t.mesh_diagonal,
                diag(t)
            );
        }
        assert!(rel(diag(&b), 1e-3 * diag(&a)) < 1e-9, "{name}");
        // The same mesh relative to the part: triangles within 3 %, area / diagonal² within
        // 0.5 %.
        let rel_area = |t: &Tess| t.area / diag(t).powi(2);
        eprintln!(
            "{name}: diagonal {:.4} mm: 0.05% = {:.5} mm: {} triangles, area {:.4} mm²; \
             ×1e-3: diagonal {:.6}, tolerance {:.3e}: {} triangles, area {:.6}",
            diag(&a),
            tol(&a),
            a.triangles,
            a.area,
            diag(&b),
            tol(&b),
            b.triangles,
            b.area
        );
        assert!(
            rel(b.triangles, a.triangles) < 0.03,
            "{name}: {} vs {} triangles",
            b.triangles,
            a.triangles
        );
        assert!(rel(rel_area(&b), rel_area(&a)) < 5e-3, "{name}");

        // An absolute 0.1 mm on the 0.08-unit part is nonsense (about the part's size); where
        // the document says metres it is the same 0.1 mm as on the part in millimetres.
        let abs_part = tessellate(&mut c, &part, json!("0.1mm")).unwrap();
        let abs_tiny = tessellate(&mut c, &tiny, json!("0.1mm")).unwrap();
        let abs_metres = tessellate(&mut c, &metres, json!("0.1mm")).unwrap();
        eprintln!(
            "{name}: 0.1mm: {} triangles, area {:.4}; on the ×1e-3 part in mm: {} triangles, \
             area {:.6} ({:+.1} % relative); in m: {} triangles",
            abs_part.triangles,
            abs_part.area,
            abs_tiny.triangles,
            abs_tiny.area,
            100.0 * (abs_tiny.area / (1e-6 * abs_part.area) - 1.0),
            abs_metres.triangles
        );
        assert!(abs_tiny.result.get("tolerance_relative").is_none());
        assert_eq!(abs_tiny.result["tolerance"], json!(0.1));
        assert!(
            abs_tiny.triangles < 0.5 * abs_part.triangles,
            "{name}: {} vs {}",
            abs_tiny.triangles,
            abs_part.triangles
        );
        assert!(rel(tol(&abs_metres), 1e-4) < 1e-12);
        assert!(
            rel(abs_metres.triangles, abs_part.triangles) < 0.03,
            "{name}"
        );
    }
}

#[test]
fn bad_relative_tolerances_name_the_value() {
    let dir = tempfile::tempdir().unwrap();
    let socket = support::endpoint(dir.path(), "bad.sock");
    let _daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();
    let part = load("cube.json");
    let mut empty = part.clone();
    empty.faces.clear();
    empty.edges = Some(Vec::new());
    for (doc, tolerance, says) in [
        (&part, json!("0%"), r#"got "0%""#),
        (&part, json!("-0.05%"), r#"got "-0.05%""#),
        (&part, json!("NaN%"), r#"got "NaN%""#),
        (&part, json!("%"), r#"got "%""#),
        (&part, json!("0.05 %%"), r#"got "0.05 %%""#),
        (&part, json!("0.1ft"), r#"got "0.1ft""#),
        (
            &empty,
            json!("0.05%"),
            r#"`tolerance` "0.05%" is a percentage"#,
        ),
    ] {
        let Err(ClientError::Op(e)) = tessellate(&mut c, doc, tolerance.clone()) else {
            panic!("{tolerance} was accepted")
        };
        assert_eq!(
            e.code,
            ErrorCode::InvalidRequest,
            "{tolerance}: {}",
            e.message
        );
        assert!(e.message.contains("`tolerance`"), "{}", e.message);
        assert!(e.message.contains(says), "{tolerance}: {}", e.message);
    }
    // An absolute tolerance on the empty document is fine: there is nothing to measure.
    let r = tessellate(&mut c, &empty, json!("0.1mm")).unwrap();
    assert_eq!(r.result["triangles"], 0);
}

#[test]
fn cli_prints_both_tolerances() {
    let dir = tempfile::tempdir().unwrap();
    let tiny = dir.path().join("tiny.json");
    std::fs::write(
        &tiny,
        scaled(&load("Pump_Nut.json"), 1e-3, Units::Millimetres).to_json(),
    )
    .unwrap();
    let usda = dir.path().join("tiny.usda");
    let out = run_ok(
        tessd()
            .arg("tessellate")
            .arg(&tiny)
            .arg(&usda)
            .args(["--tolerance", "0.05%"]),
    );
    let line = String::from_utf8(out.stdout).unwrap();
    eprint!("{line}");
    assert!(line.starts_with("tessellate: 25 faces, "), "{line}");
    assert!(line.contains(" % of the "), "{line}");
    assert!(line.contains(" mm diagonal) -> "), "{line}");
    assert!(usda.exists());
    let out = run_ok(tessd().arg("tessellate").arg(&tiny).arg(&usda).args([
        "--tolerance",
        "0.05%",
        "--json",
    ]));
    let r: Value = serde_json::from_slice(&out.stdout).unwrap();
    let d = r["diagonal"].as_f64().unwrap();
    assert_eq!(r["tolerance_relative"], json!(0.0005));
    assert!(rel(r["tolerance"].as_f64().unwrap(), 0.0005 * d) < 1e-12);
    // The line shows the absolute tolerance and the diagonal to 4 digits.
    let shown = |x: f64| {
        let s = format!("{x:.*}", (3 - x.log10().floor() as i64).max(0) as usize);
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    };
    let want = format!(
        "(tolerance {} mm, 0.05 % of the {} mm diagonal)",
        shown(r["tolerance"].as_f64().unwrap()),
        shown(d)
    );
    assert!(line.contains(&want), "{line} lacks {want}");
}
