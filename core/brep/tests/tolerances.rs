//! An edge's optional file tolerances (`tolerance`, `vertex_tolerances`): read, written back,
//! absent by default, and refused with the edge named when not finite, negative or of the
//! wrong length.

use serde_json::{Value, json};
use tessd_brep::{Document, Place, ValidationError};

fn cylinder() -> Value {
    let path = format!(
        "{}/tests/data/cylinder_with_hole.json",
        env!("CARGO_MANIFEST_DIR")
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The fixture with edge index 2 (id 3) given `fields`.
fn with_edge_fields(fields: Value) -> Value {
    let mut doc = cylinder();
    let edge = doc
        .pointer_mut("/edges/2")
        .unwrap()
        .as_object_mut()
        .unwrap();
    for (k, v) in fields.as_object().unwrap() {
        edge.insert(k.clone(), v.clone());
    }
    doc
}

fn error_of(doc: &Value) -> ValidationError {
    match Document::from_value(doc) {
        Err(e) => e,
        Ok(d) => d.validate().expect_err("the document should be refused"),
    }
}

#[test]
fn tolerances_are_optional_and_round_trip() {
    let plain = Document::from_value(&cylinder()).unwrap();
    assert!(
        plain
            .edges
            .iter()
            .flatten()
            .all(|e| e.tolerance.is_none() && e.vertex_tolerances.is_none())
    );
    // Absent fields are not written back.
    assert!(!plain.to_json().contains("tolerance"));

    let doc = Document::from_value(&with_edge_fields(
        json!({"tolerance": 1e-7, "vertex_tolerances": [0.001, 0.0]}),
    ))
    .unwrap();
    doc.validate().unwrap();
    let e = &doc.edges.as_ref().unwrap()[2];
    assert_eq!(e.id, 3);
    assert_eq!(e.tolerance, Some(1e-7));
    assert_eq!(e.vertex_tolerances, Some([0.001, 0.0]));
    assert_eq!(Document::from_json(&doc.to_json()).unwrap(), doc);
    // JSON null is the same as absent.
    let doc = Document::from_value(&with_edge_fields(
        json!({"tolerance": null, "vertex_tolerances": null}),
    ))
    .unwrap();
    doc.validate().unwrap();
}

#[test]
fn bad_tolerances_name_the_edge() {
    for (fields, field, value) in [
        (json!({"tolerance": -1e-3}), "tolerance", -1e-3),
        (
            json!({"vertex_tolerances": [-0.5, 0.01]}),
            "vertex_tolerances[0]",
            -0.5,
        ),
        (
            json!({"vertex_tolerances": [0.01, -2]}),
            "vertex_tolerances[1]",
            -2.0,
        ),
    ] {
        let e = error_of(&with_edge_fields(fields.clone()));
        assert_eq!(
            e,
            ValidationError::NegativeTolerance {
                at: Place::Edge { edge: 3 },
                field,
                value
            },
            "{fields}"
        );
        let m = e.to_string();
        assert!(m.starts_with("edge 3: "), "{m}");
        assert!(m.contains(field) && m.contains("≥ 0"), "{m}");
    }
    // Wrong lengths and types are structure errors naming the edge.
    for fields in [
        json!({"vertex_tolerances": [0.01]}),
        json!({"vertex_tolerances": [0.01, 0.02, 0.03]}),
        json!({"vertex_tolerances": 0.01}),
        json!({"tolerance": "small"}),
    ] {
        let e = error_of(&with_edge_fields(fields.clone()));
        assert!(
            matches!(&e, ValidationError::Structure { at, .. } if at == "edge 3"),
            "{fields}: {e:?}"
        );
    }
    // Non-finite values (possible from the Rust API; JSON has none).
    let mut doc = Document::from_value(&cylinder()).unwrap();
    doc.edges.as_mut().unwrap()[1].vertex_tolerances = Some([0.0, f64::INFINITY]);
    doc.edges.as_mut().unwrap()[3].tolerance = Some(f64::NAN);
    let errors = doc.errors();
    assert_eq!(
        errors,
        vec![
            ValidationError::NonFinite {
                at: Place::Edge { edge: 2 },
                field: "vertex_tolerances[1]".into()
            },
            ValidationError::NonFinite {
                at: Place::Edge { edge: 4 },
                field: "tolerance".into()
            },
        ]
    );
    assert_eq!(
        errors[0].to_string(),
        "edge 2: vertex_tolerances[1] is not finite"
    );
}
