//! A cancel reaches a face while it refines: a host's Cancel button must not wait for the
//! slowest face of a fine tessellation to finish.

use std::sync::Mutex;
use tessd_brep::Document;
use tessd_tessellate::{Options, TessellateError, tessellate, tessellate_with_progress};

/// One spherical face: its refinement inserts ~10 000 points at [`fine`] (~0.1 s).
fn sphere() -> Document {
    let path = format!("{}/tests/data/sphere.json", env!("CARGO_MANIFEST_DIR"));
    Document::from_json(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Fine enough that the face refines through several passes of thousands of points.
fn fine(doc: &Document) -> Options {
    Options::new(1e-4 * doc.bounding_box().unwrap().diagonal())
}

#[test]
fn a_cancel_stops_the_faces_in_progress() {
    let doc = sphere();
    let whole = tessellate(&doc, &fine(&doc)).unwrap();
    let faces = doc.faces.len();
    assert!(
        whole.stats.refined_points > 4 * 1024 * faces,
        "{}",
        whole.stats.refined_points
    );

    // Cancel at the first question: before any face has finished.
    let asked = Mutex::new(Vec::new());
    let result = tessellate_with_progress(&doc, &fine(&doc), &|done, total| {
        asked.lock().unwrap().push((done, total));
        false
    });
    assert!(
        matches!(result, Err(TessellateError::Cancelled)),
        "{result:?}"
    );
    let asked = asked.into_inner().unwrap();
    assert_eq!(
        asked[0],
        (0, faces),
        "asked first when no face was done: {asked:?}"
    );
    // Every face asks at most once more after the answer, when it stops.
    assert!(
        asked.len() <= faces,
        "{} questions after the cancel",
        asked.len()
    );
    assert!(
        asked.iter().all(|&(done, _)| done == 0),
        "a face finished after the cancel"
    );
}

#[test]
fn progress_counts_faces_and_repeats_while_one_refines() {
    let doc = sphere();
    let asked = Mutex::new(Vec::new());
    let t = tessellate_with_progress(&doc, &fine(&doc), &|done, total| {
        asked.lock().unwrap().push((done, total));
        true
    })
    .unwrap();
    let asked = asked.into_inner().unwrap();
    let faces = doc.faces.len();
    for k in 1..=faces {
        assert!(asked.iter().any(|a| a.0 == k), "no report of {k}");
    }
    assert!(
        asked
            .iter()
            .all(|&(done, total)| done <= total && total == faces)
    );
    // Asked during refinement too: more often than once a face.
    assert!(
        asked.len() > 2 * faces,
        "{} questions for {faces} faces",
        asked.len()
    );
    assert_eq!(
        t.mesh.face_count(),
        tessellate(&doc, &fine(&doc)).unwrap().mesh.face_count()
    );
}
