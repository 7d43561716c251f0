//! `brep.load` through the registry the daemon and job files share: a fixture document from a
//! file and inline (with arrays by reference), bad documents and bad requests.

mod support;

use serde_json::{Map, Value, json};
use std::path::{Path, PathBuf};
use tessd_ipc::arrays::{Arrays, OwnedArray};
use tessd_ipc::error::{ErrorCode, OpError};
use tessd_ipc::job::{CancelToken, JobContext};
use tessd_ipc::registry::Request;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../brep/tests/data")
        .join(name)
}

fn fixture(name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(data(name)).unwrap()).unwrap()
}

fn call(params: Value, arrays: &[OwnedArray]) -> Result<Value, OpError> {
    support::run_op("brep.load", params, arrays)
}

#[test]
fn loads_a_document_from_a_file() {
    let r = call(json!({"input": data("cylinder_with_hole.json")}), &[]).unwrap();
    assert_eq!(r["faces"], json!([1, 2]));
    assert_eq!(r["edges"], json!([1, 2, 3, 4]));
    assert_eq!(r["units"], "mm");
    assert_eq!(r["version"], 1);
    let s = &r["stats"];
    assert_eq!(s["faces"], 2);
    assert_eq!(s["faces_by_surface"]["cylinder"], 1);
    assert_eq!(s["faces_by_surface"]["plane"], 1);
    assert_eq!(s["faces_by_surface"]["bspline"], 0);
    assert_eq!(
        s["trims_by_curve"],
        json!({"line": 4, "circle": 2, "ellipse": 0, "bspline": 0})
    );
    assert_eq!(
        (s["loops"].clone(), s["holes"].clone()),
        (json!(3), json!(1))
    );
}

#[test]
fn loads_inline_with_arrays_by_reference() {
    let by_file = call(json!({"input": data("bspline_face.json")}), &[]).unwrap();
    let mut doc = fixture("bspline_face.json");
    let surface = &mut doc["faces"][0]["surface"];
    let poles: Vec<f64> = surface["poles"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|row| row.as_array().unwrap().iter())
        .flat_map(|p| p.as_array().unwrap().iter().map(|c| c.as_f64().unwrap()))
        .collect();
    let weights: Vec<f64> = surface["weights"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|row| row.as_array().unwrap().iter().map(|w| w.as_f64().unwrap()))
        .collect();
    surface["poles"] = json!({"array": "f7_poles"});
    surface["weights"] = json!({"array": "f7_weights"});
    surface["mults_u"] = json!({"array": "f7_mults_u"});
    let arrays = [
        OwnedArray::new("f7_poles", vec![3, 2, 3], poles),
        OwnedArray::new(
            "f7_weights",
            vec![3, 2],
            weights.iter().map(|&w| w as f32).collect(),
        ),
        OwnedArray::new("f7_mults_u", vec![2], vec![3u32, 3]),
    ];
    let inline = call(json!({"brep": doc}), &arrays).unwrap();
    assert_eq!(inline["faces"], json!([7]));
    assert_eq!(inline["edges"], Value::Null);
    assert_eq!(inline["units"], "m");
    assert_eq!(inline["stats"], by_file["stats"]);
    assert_eq!(inline["stats"]["surface_poles"], 6);
    assert_eq!(inline["stats"]["bspline_trims_by_degree"], json!({"2": 1}));

    // A reference to an array the request does not carry.
    let mut doc = fixture("bspline_face.json");
    doc["faces"][0]["surface"]["poles"] = json!({"array": "nowhere"});
    let e = call(json!({"brep": doc}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidRequest);
    assert!(e.message.contains("\"nowhere\""), "{}", e.message);
    // A payload array of the wrong shape fails as the document's structure.
    let mut doc = fixture("bspline_face.json");
    doc["faces"][0]["surface"]["poles"] = json!({"array": "flat"});
    let e = call(
        json!({"brep": doc}),
        &[OwnedArray::new("flat", vec![18], vec![0.0f64; 18])],
    )
    .unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidBrep);
    assert!(e.message.starts_with("face 7, surface"), "{}", e.message);
}

#[test]
fn refuses_a_bad_document_naming_the_element() {
    // The window of face 1 turned counter-clockwise, and an edge naming a missing face.
    let mut doc = fixture("cylinder_with_hole.json");
    doc["faces"][0]["loops"][1]["edges"][0]["curve"]["y_dir"] = json!([0, 1]);
    doc["edges"][0]["faces"] = json!([1, 2, 9]);
    let e = call(json!({"brep": doc}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidBrep);
    assert!(
        e.message
            .starts_with("face 1, loop 1: the hole is counter-clockwise"),
        "{}",
        e.message
    );
    assert!(e.message.ends_with("(and 1 more error)"), "{}", e.message);

    // From a file: an open loop.
    let dir = tempfile::tempdir().unwrap();
    let mut doc = fixture("cylinder_with_hole.json");
    doc["faces"][0]["loops"][0]["edges"][1]["range"] = json!([0, 19]);
    let path = dir.path().join("open.json");
    std::fs::write(&path, doc.to_string()).unwrap();
    let e = call(json!({"input": path}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidBrep);
    assert!(
        e.message.starts_with(
            "face 1, loop 0: open loop: trim 1 ends 1.000e0 away from the start of trim 2"
        ),
        "{}",
        e.message
    );

    // Not JSON, and a future version.
    std::fs::write(&path, "{\"format\": \"tessd-brep\", ").unwrap();
    let e = call(json!({"input": path}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidBrep);
    assert!(e.message.contains("not JSON"), "{}", e.message);
    let mut doc = fixture("cylinder_with_hole.json");
    doc["version"] = json!(2);
    let e = call(json!({"brep": doc}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidBrep);
    assert!(
        e.message.contains("unsupported `version` 2"),
        "{}",
        e.message
    );
}

#[test]
fn refuses_bad_requests() {
    let e = call(json!({}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidRequest);
    assert!(e.message.contains("`input`") && e.message.contains("`brep`"));
    let e = call(
        json!({"input": data("bspline_face.json"), "brep": fixture("bspline_face.json")}),
        &[],
    )
    .unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidRequest);
    // A string is OpenCASCADE BREP text; anything else as a string is refused as such.
    let e = call(json!({"brep": "doc.json"}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidBrep);
    assert!(e.message.contains("OpenCASCADE BREP text"), "{}", e.message);
    let e = call(json!({"brep": 3}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::InvalidRequest);
    assert!(e.message.contains("a number"), "{}", e.message);
    let e = call(json!({"input": "/nonexistent/part.json"}), &[]).unwrap_err();
    assert_eq!(e.code, ErrorCode::Io);
    assert!(
        e.message.contains("/nonexistent/part.json"),
        "{}",
        e.message
    );
}

#[test]
fn relative_input_resolves_against_the_job_folder() {
    let request = Request {
        params: Map::from_iter([("input".to_string(), json!("cylinder_with_hole.json"))]),
        arrays: Arrays::default(),
        base_dir: Some(data("")),
    };
    let sink = |_| {};
    let ctx = JobContext::new(&sink, CancelToken::default());
    let r = tessd::ops::registry()
        .run("brep.load", request, &ctx)
        .unwrap();
    assert_eq!(r.result["faces"], json!([1, 2]));
    assert!(
        tessd::ops::registry()
            .names()
            .contains(&"brep.load".to_string())
    );
}
