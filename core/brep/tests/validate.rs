//! Validation: the fixtures validate; each kind of error, made by one edit of a fixture, is
//! refused with the element it names.

use serde_json::{Value, json};
use tessd_brep::bspline::KnotError;
use tessd_brep::{Document, Place, ValidationError};

fn fixture(name: &str) -> Value {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn cylinder() -> Value {
    fixture("cylinder_with_hole.json")
}

fn bspline() -> Value {
    fixture("bspline_face.json")
}

/// Sets the value at a JSON pointer of a fixture.
fn edit(mut doc: Value, pointer: &str, value: Value) -> Value {
    *doc.pointer_mut(pointer)
        .unwrap_or_else(|| panic!("no {pointer}")) = value;
    doc
}

/// The first error of a document (parsing or validation).
fn error_of(doc: &Value) -> ValidationError {
    match Document::from_value(doc) {
        Err(e) => e,
        Ok(d) => d.validate().expect_err("the document should be refused"),
    }
}

/// Asserts the error's message holds every fragment.
#[track_caller]
fn says(e: &ValidationError, fragments: &[&str]) {
    let m = e.to_string();
    for f in fragments {
        assert!(m.contains(f), "{m:?} does not mention {f:?}");
    }
}

#[test]
fn valid_documents_validate() {
    for name in ["cylinder_with_hole.json", "bspline_face.json"] {
        let text =
            std::fs::read_to_string(format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR")))
                .unwrap();
        let doc = Document::from_json(&text).unwrap();
        assert_eq!(doc.errors(), vec![], "{name}");
        // And survive a round trip.
        assert_eq!(Document::from_json(&doc.to_json()).unwrap(), doc);
    }
}

#[test]
fn stats_count_like_table_1() {
    let doc = Document::from_value(&cylinder()).unwrap();
    let s = doc.stats();
    assert_eq!(s.faces, 2);
    assert_eq!(s.faces_by_surface["cylinder"], 1);
    assert_eq!(s.faces_by_surface["plane"], 1);
    assert_eq!(s.faces_by_surface["torus"], 0);
    assert_eq!((s.loops, s.holes, s.trims), (3, 1, 6));
    assert_eq!(s.trims_by_curve["line"], 4);
    assert_eq!(s.trims_by_curve["circle"], 2);
    assert_eq!(s.reversed_faces, 1);
    assert_eq!(s.edges, 4);
    assert_eq!(s.edges_by_curve["none"], 1);
    let s = Document::from_value(&bspline()).unwrap().stats();
    assert_eq!(s.faces_by_surface["bspline"], 1);
    assert_eq!(s.bspline_surfaces_by_degree["2x1"], 1);
    assert_eq!((s.surface_poles, s.rational_surfaces), (6, 1));
    assert_eq!(s.bspline_trims_by_degree[&2], 1);
    assert_eq!((s.trim_poles, s.rational_trims), (3, 0));
    assert_eq!(s.edges, 0);
}

#[test]
fn not_json() {
    let e = Document::from_json("{\"format\": ").unwrap_err();
    assert!(matches!(e, ValidationError::Json { .. }), "{e:?}");
    says(&e, &["line 1"]);
}

#[test]
fn wrong_format() {
    let e = error_of(&edit(cylinder(), "/format", json!("step")));
    assert!(matches!(e, ValidationError::Format { .. }), "{e:?}");
    says(&e, &["\"step\""]);
}

#[test]
fn unsupported_version() {
    let e = error_of(&edit(cylinder(), "/version", json!(2)));
    assert!(matches!(e, ValidationError::Version { .. }), "{e:?}");
    says(&e, &["version` 2"]);
}

#[test]
fn unknown_surface_type() {
    let e = error_of(&edit(cylinder(), "/faces/1/surface/type", json!("offset")));
    assert!(matches!(e, ValidationError::Structure { .. }), "{e:?}");
    says(&e, &["face 2, surface", "offset"]);
}

#[test]
fn missing_field() {
    let mut doc = cylinder();
    doc.pointer_mut("/faces/0/surface")
        .unwrap()
        .as_object_mut()
        .unwrap()
        .remove("radius");
    let e = error_of(&doc);
    says(&e, &["face 1, surface", "missing field `radius`"]);
    // In a trim's curve: the loop and trim are named.
    let mut doc = cylinder();
    doc.pointer_mut("/faces/0/loops/0/edges/2/curve")
        .unwrap()
        .as_object_mut()
        .unwrap()
        .remove("dir");
    says(&error_of(&doc), &["face 1, loop 0, trim 2", "`dir`"]);
    // An unknown curve type.
    let doc = edit(
        cylinder(),
        "/faces/0/loops/1/edges/0/curve/type",
        json!("hyperbola"),
    );
    says(&error_of(&doc), &["face 1, loop 1, trim 0", "hyperbola"]);
}

#[test]
fn duplicate_face_id() {
    let e = error_of(&edit(cylinder(), "/faces/1/id", json!(1)));
    assert_eq!(
        e,
        ValidationError::DuplicateFaceId {
            face: 1,
            first: 0,
            second: 1
        }
    );
}

#[test]
fn duplicate_edge_id() {
    // Edge 4 becomes a second edge 3 (the window's trim then names a missing edge 4 too).
    let doc = edit(cylinder(), "/edges/3/id", json!(3));
    let errors = Document::from_value(&doc).unwrap().errors();
    assert!(
        errors.contains(&ValidationError::DuplicateEdgeId { edge: 3 }),
        "{errors:?}"
    );
    assert_eq!(
        errors.last().unwrap().to_string(),
        "edge 3: the id is used twice"
    );
}

#[test]
fn non_finite_number() {
    // JSON has no NaN; documents built in code (or from payload arrays) can.
    let mut doc = Document::from_value(&bspline()).unwrap();
    if let tessd_brep::Surface::Bspline(b) = &mut doc.faces[0].surface {
        b.poles[1][0][2] = f64::NAN;
    }
    let e = doc.validate().unwrap_err();
    assert!(matches!(e, ValidationError::NonFinite { .. }), "{e:?}");
    says(&e, &["face 7, surface", "pole [1][0]"]);
}

#[test]
fn non_unit_direction() {
    let e = error_of(&edit(
        cylinder(),
        "/faces/1/surface/x_dir",
        json!([2, 0, 0]),
    ));
    assert!(matches!(e, ValidationError::NotUnit { .. }), "{e:?}");
    says(&e, &["face 2, surface", "x_dir has length 2"]);
}

#[test]
fn non_orthogonal_frame() {
    let s = 0.5f64.sqrt();
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/surface/y_dir",
        json!([s, s, 0]),
    ));
    assert!(matches!(e, ValidationError::NotOrthogonal { .. }), "{e:?}");
    says(&e, &["face 1, surface", "orthogonal"]);
}

#[test]
fn non_positive_radius() {
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/loops/1/edges/0/curve/radius",
        json!(0),
    ));
    assert!(matches!(e, ValidationError::Radius { .. }), "{e:?}");
    says(&e, &["face 1, loop 1, trim 0", "radius is 0"]);
}

fn cone(radius: f64, semi_angle: f64) -> Value {
    edit(
        cylinder(),
        "/faces/0/surface",
        json!({"type": "cone", "origin": [0, 0, 0], "x_dir": [1, 0, 0], "y_dir": [0, 1, 0],
               "radius": radius, "semi_angle": semi_angle}),
    )
}

#[test]
fn cone_radius_and_angle() {
    // A cone through its apex (radius 0) is fine; a negative radius is not.
    let doc = Document::from_value(&cone(0.0, 0.3)).unwrap();
    assert!(doc.surface_errors_only().is_empty());
    let e = error_of(&cone(-1.0, 0.3));
    assert!(matches!(e, ValidationError::ConeRadius { .. }), "{e:?}");
    says(&e, &["face 1, surface", "-1"]);
    let e = error_of(&cone(1.0, 0.0));
    assert!(matches!(e, ValidationError::SemiAngle { .. }), "{e:?}");
    says(&e, &["face 1, surface", "semi_angle is 0"]);
    let e = error_of(&cone(1.0, std::f64::consts::FRAC_PI_2));
    assert!(matches!(e, ValidationError::SemiAngle { .. }), "{e:?}");
}

/// The validation errors that are not about trims (a cone's face keeps the cylinder's loops,
/// which are fine in (u, v) too).
trait SurfaceErrors {
    fn surface_errors_only(&self) -> Vec<ValidationError>;
}

impl SurfaceErrors for Document {
    fn surface_errors_only(&self) -> Vec<ValidationError> {
        self.errors()
            .into_iter()
            .filter(|e| e.to_string().contains("surface"))
            .collect()
    }
}

fn knot_error(doc: &Value) -> (Place, &'static str, KnotError) {
    match error_of(doc) {
        ValidationError::Knots {
            at,
            direction,
            error,
        } => (at, direction, error),
        e => panic!("expected a knot error, got {e:?}"),
    }
}

#[test]
fn degree_below_one() {
    let doc = edit(bspline(), "/faces/0/loops/0/edges/0/curve/degree", json!(0));
    let (at, _, error) = knot_error(&doc);
    assert_eq!(
        at,
        Place::Trim {
            face: 7,
            loop_index: 0,
            trim: 0
        }
    );
    assert_eq!(error, KnotError::Degree { degree: 0 });
    says(&error_of(&doc), &["face 7, loop 0, trim 0", "degree 0"]);
}

#[test]
fn knots_not_increasing() {
    let doc = edit(bspline(), "/faces/0/surface/knots_v", json!([1, 0]));
    let (at, direction, error) = knot_error(&doc);
    assert_eq!((at, direction), (Place::Surface { face: 7 }, "v: "));
    assert!(matches!(error, KnotError::NotIncreasing { index: 1, .. }));
    says(
        &error_of(&doc),
        &["face 7, surface: v: knots are not strictly increasing: knot 1"],
    );
    // Equal knots (a multiplicity written as repetition) are refused as well.
    let doc = edit(
        bspline(),
        "/faces/0/loops/0/edges/0/curve/knots",
        json!([0, 0]),
    );
    says(&error_of(&doc), &["face 7, loop 0, trim 0", "knot 1"]);
}

#[test]
fn multiplicity_out_of_range() {
    // An end multiplicity above degree + 1.
    let doc = edit(
        bspline(),
        "/faces/0/loops/0/edges/0/curve/mults",
        json!([4, 3]),
    );
    let (_, _, error) = knot_error(&doc);
    assert_eq!(
        error,
        KnotError::Multiplicity {
            index: 0,
            mult: 4,
            max: 3
        }
    );
    // An interior multiplicity above the degree.
    let doc = edit(
        edit(bspline(), "/faces/0/surface/knots_u", json!([0, 0.5, 1])),
        "/faces/0/surface/mults_u",
        json!([3, 3, 3]),
    );
    says(
        &error_of(&doc),
        &["face 7, surface: u: multiplicity 1 is 3; it must be from 1 to 2"],
    );
    // Zero.
    let doc = edit(bspline(), "/faces/0/surface/mults_v", json!([0, 2]));
    says(&error_of(&doc), &["multiplicity 0 is 0"]);
}

#[test]
fn periodic_end_multiplicities_differ() {
    let doc = edit(
        edit(
            bspline(),
            "/faces/0/loops/0/edges/0/curve/periodic",
            json!(true),
        ),
        "/faces/0/loops/0/edges/0/curve/mults",
        json!([2, 1]),
    );
    let (_, _, error) = knot_error(&doc);
    assert_eq!(error, KnotError::PeriodicEnds { first: 2, last: 1 });
}

#[test]
fn knot_and_multiplicity_counts_differ() {
    let doc = edit(bspline(), "/faces/0/surface/mults_u", json!([3, 3, 3]));
    let (_, direction, error) = knot_error(&doc);
    assert_eq!(direction, "u: ");
    assert_eq!(error, KnotError::Lengths { knots: 2, mults: 3 });
}

#[test]
fn wrong_pole_count() {
    let doc = edit(
        bspline(),
        "/faces/0/loops/0/edges/0/curve/poles",
        json!([[0, 0], [1, 0]]),
    );
    let e = error_of(&doc);
    assert!(
        matches!(
            e,
            ValidationError::PoleCount {
                got: 2,
                expected: 3,
                ..
            }
        ),
        "{e:?}"
    );
    says(&e, &["face 7, loop 0, trim 0", "2 poles", "need 3"]);
    // A surface row.
    let doc = edit(
        bspline(),
        "/faces/0/surface/poles/1",
        json!([[1, 1, 0], [1, 1, 1], [1, 1, 2]]),
    );
    says(
        &error_of(&doc),
        &["face 7, surface", "poles[1] (in v) has 3 poles"],
    );
}

#[test]
fn wrong_weight_count() {
    let doc = edit(
        bspline(),
        "/faces/0/loops/0/edges/0/curve/weights",
        json!([1, 1]),
    );
    let e = error_of(&doc);
    assert!(matches!(e, ValidationError::WeightCount { .. }), "{e:?}");
    says(&e, &["face 7, loop 0, trim 0", "2 weights for 3 poles"]);
}

#[test]
fn non_positive_weight() {
    let doc = edit(bspline(), "/faces/0/surface/weights/1/1", json!(-0.5));
    let e = error_of(&doc);
    assert!(matches!(e, ValidationError::Weight { .. }), "{e:?}");
    says(&e, &["face 7, surface", "pole [1][1] is -0.5"]);
    let doc = edit(
        bspline(),
        "/faces/0/loops/0/edges/0/curve/weights",
        json!([1, 0, 1]),
    );
    says(
        &error_of(&doc),
        &["face 7, loop 0, trim 0: the weight of pole 1 is 0"],
    );
}

#[test]
fn empty_bounds() {
    let e = error_of(&edit(
        cylinder(),
        "/faces/1/bounds",
        json!([10, -10, -10, 10]),
    ));
    assert!(
        matches!(e, ValidationError::Bounds { face: 2, .. }),
        "{e:?}"
    );
}

#[test]
fn empty_loop() {
    let e = error_of(&edit(cylinder(), "/faces/0/loops/1/edges", json!([])));
    assert_eq!(
        e,
        ValidationError::EmptyLoop {
            face: 1,
            loop_index: 1
        }
    );
}

#[test]
fn empty_range() {
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/loops/0/edges/1/range",
        json!([5, 5]),
    ));
    assert!(matches!(e, ValidationError::EmptyRange { .. }), "{e:?}");
    says(&e, &["face 1, loop 0, trim 1", "[5, 5] is empty"]);
}

#[test]
fn range_outside_knots() {
    let doc = edit(bspline(), "/faces/0/loops/0/edges/0/range", json!([0, 1.5]));
    let e = error_of(&doc);
    assert!(
        matches!(e, ValidationError::RangeOutsideKnots { .. }),
        "{e:?}"
    );
    says(&e, &["face 7, loop 0, trim 0", "[0, 1.5]", "[0, 1]"]);
}

#[test]
fn open_loop_names_both_trims() {
    // Trim 1 (the seam at u = 2π) stops at v = 19.9: a gap before trim 2.
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/loops/0/edges/1/range",
        json!([0, 19.9]),
    ));
    match &e {
        ValidationError::OpenLoop {
            face: 1,
            loop_index: 0,
            trim: 1,
            next: 2,
            gap,
            ..
        } => assert!((gap - 0.1).abs() < 1e-9),
        _ => panic!("{e:?}"),
    }
    says(&e, &["face 1, loop 0: open loop: trim 1", "trim 2"]);
    // Within the tolerance (1e-7 × the bounds' diagonal ≈ 2.1e-6) is closed.
    let ok = edit(
        cylinder(),
        "/faces/0/loops/0/edges/1/range",
        json!([0, 20.0 - 1e-6]),
    );
    assert_eq!(Document::from_value(&ok).unwrap().errors(), vec![]);
}

#[test]
fn trim_outside_bounds() {
    // The window moved up to v = 19 reaches v = 21 > 20.
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/loops/1/edges/0/curve/center",
        json!([std::f64::consts::PI, 19]),
    ));
    assert!(
        matches!(
            e,
            ValidationError::OutsideBounds {
                face: 1,
                loop_index: 1,
                trim: 0,
                ..
            }
        ),
        "{e:?}"
    );
    says(&e, &["outside the face's bounds"]);
}

#[test]
fn clockwise_outer_loop() {
    // The disk's circle turned clockwise.
    let e = error_of(&edit(
        cylinder(),
        "/faces/1/loops/0/edges/0/curve/y_dir",
        json!([0, -1]),
    ));
    match e {
        ValidationError::OuterClockwise { face: 2, area } => {
            // The sampled 32-gon's area, about −π r².
            assert!((area + 100.0 * std::f64::consts::PI).abs() < 3.0, "{area}");
        }
        e => panic!("{e:?}"),
    }
}

#[test]
fn counter_clockwise_hole() {
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/loops/1/edges/0/curve/y_dir",
        json!([0, 1]),
    ));
    assert!(
        matches!(
            e,
            ValidationError::HoleCounterClockwise {
                face: 1,
                loop_index: 1,
                ..
            }
        ),
        "{e:?}"
    );
    says(&e, &["face 1, loop 1", "counter-clockwise"]);
    // The whole loop reversed (trims in the other order, each walked backwards) as well.
    let mut doc = cylinder();
    let outer = doc.pointer_mut("/faces/0/loops/0/edges").unwrap();
    let mut trims = outer.as_array().unwrap().clone();
    trims.reverse();
    for t in &mut trims {
        let r = t["range"].as_array().unwrap().clone();
        t["range"] = json!([r[1], r[0]]);
    }
    *outer = Value::Array(trims);
    let e = error_of(&doc);
    assert!(
        matches!(e, ValidationError::OuterClockwise { face: 1, .. }),
        "{e:?}"
    );
}

#[test]
fn unknown_edge_id() {
    let e = error_of(&edit(
        cylinder(),
        "/faces/0/loops/0/edges/3/edge",
        json!(99),
    ));
    assert_eq!(
        e,
        ValidationError::UnknownEdge {
            face: 1,
            loop_index: 0,
            trim: 3,
            edge: 99
        }
    );
    says(&e, &["face 1, loop 0, trim 3: edge 99 does not exist"]);
}

#[test]
fn edge_naming_unknown_face() {
    let e = error_of(&edit(cylinder(), "/edges/1/faces", json!([1, 5])));
    assert_eq!(e, ValidationError::UnknownFace { edge: 2, face: 5 });
}

#[test]
fn all_errors_are_listed() {
    let doc = edit(
        edit(cylinder(), "/edges/1/faces", json!([1, 5])),
        "/faces/0/surface/radius",
        json!(-3),
    );
    let errors = Document::from_value(&doc).unwrap().errors();
    assert_eq!(errors.len(), 2, "{errors:?}");
    assert!(matches!(errors[0], ValidationError::Radius { .. }));
}
