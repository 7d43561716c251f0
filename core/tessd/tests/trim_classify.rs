//! `trim.classify` through the registry the daemon and job files share: warnings (issue 20,
//! point 4) for a face whose trims the fitter cannot meet within ε_uv, none for normal faces.

mod support;

use serde_json::{Value, json};
use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::error::OpError;

fn call(params: Value, arrays: &[OwnedArray]) -> Result<Value, OpError> {
    support::run_op("trim.classify", params, arrays)
}

fn line(a: [f64; 2], b: [f64; 2]) -> Value {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len = d[0].hypot(d[1]);
    json!({"curve": {"type": "line", "origin": a, "dir": [d[0] / len, d[1] / len]},
           "range": [0.0, len]})
}

/// Two plane faces over [0, 2] × [0, 1]: face 12's bottom side is a rational quadratic whose
/// middle pole (1, 0.5) weighs `w` (for 1e12 it jumps to the pole and back between any two
/// of the fitter's samples: a fit error far above ε_uv), face 3 is the plain rectangle.
fn document(w: f64) -> Value {
    let plane = json!({"type": "plane", "origin": [0, 0, 0], "x_dir": [1, 0, 0],
                       "y_dir": [0, 1, 0]});
    let spike = json!({"curve": {"type": "bspline", "degree": 2,
                                 "poles": [[0.0, 0.0], [1.0, 0.5], [2.0, 0.0]],
                                 "weights": [1.0, w, 1.0], "knots": [0.0, 1.0], "mults": [3, 3]},
                       "range": [0.0, 1.0]});
    let sides = [
        line([2.0, 0.0], [2.0, 1.0]),
        line([2.0, 1.0], [0.0, 1.0]),
        line([0.0, 1.0], [0.0, 0.0]),
    ];
    let mut spiked = vec![spike];
    spiked.extend(sides.iter().cloned());
    let mut plain = vec![line([0.0, 0.0], [2.0, 0.0])];
    plain.extend(sides.iter().cloned());
    json!({"format": "tessd-brep", "version": 1, "units": "mm", "faces": [
        {"id": 12, "surface": plane, "bounds": [0, 2, 0, 1], "loops": [{"edges": spiked}]},
        {"id": 3, "surface": plane, "bounds": [0, 2, 0, 1], "loops": [{"edges": plain}]},
    ]})
}

fn points() -> OwnedArray {
    // Per face: well inside, below the bottom side, above the top.
    let uv = [1.0, 0.8, 1.0, -0.5, 1.0, 1.5];
    OwnedArray::new("uv", vec![2, 3, 2], [uv, uv].concat())
}

#[test]
fn a_fit_above_eps_uv_is_a_warning_not_an_error() {
    let r = call(
        json!({"brep": document(1e12), "tolerance": "0.01mm"}),
        &[points()],
    )
    .unwrap();
    let faces = r["faces"].as_array().unwrap();
    let (spiked, plain) = (&faces[0], &faces[1]);
    assert_eq!(spiked["id"], 12);
    let (fit, eps) = (
        spiked["max_fit_error_uv"].as_f64().unwrap(),
        spiked["eps_uv"].as_f64().unwrap(),
    );
    assert!(fit > eps, "{spiked}");
    let w = spiked["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1, "{spiked}");
    let text = w[0].as_str().unwrap();
    assert!(
        text.starts_with(&format!(
            "face 12: the trim fit error {fit:.1e} exceeds ε_uv {eps:.1e} ("
        )) && text.ends_with("×); classification near its boundary may be off by that much"),
        "{text}"
    );
    assert_eq!(plain["warnings"], json!([]), "{plain}");
    assert_eq!(r["warnings"], json!([text]));
    // Both faces classified: the inside point on, the others off.
    assert_eq!(r["on"], 2);
}

#[test]
fn normal_faces_have_no_warnings() {
    let r = call(
        json!({"brep": document(3.0), "tolerance": 0.01}),
        &[points()],
    )
    .unwrap();
    assert_eq!(r["warnings"], json!([]), "{r}");
    for f in r["faces"].as_array().unwrap() {
        assert_eq!(f["warnings"], json!([]), "{f}");
        assert!(f["eps_uv_samples"].as_u64().unwrap() >= 289, "{f}");
    }
    // The repository's B-spline fixture: no warnings either.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../brep/tests/data/bspline_face.json"
    );
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let n = doc["faces"].as_array().unwrap().len() as u64;
    let uv = OwnedArray::new("uv", vec![n, 1, 2], vec![0.0f64; 2 * n as usize]);
    let r = call(json!({"brep": doc, "tolerance": "0.01mm"}), &[uv]).unwrap();
    assert_eq!(r["warnings"], json!([]), "{r}");
}
