//! Inputs the fuzzer (fuzz/fuzz_targets/brep.rs) found, each run as the target runs it: the
//! document read, validated, and tessellated at 0.5 % of its bounding-box diagonal.

use tessd_brep::{DVec2, Document};
use tessd_tessellate::crossings::{MIN_SPLIT_BUDGET, face_loops_uncrossed};
use tessd_tessellate::edges::{MAX_CURVE_SAMPLES, sample_chordal};
use tessd_tessellate::{Options, TessellateError, Tessellation, edges, tessellate};

fn document(name: &str) -> Document {
    let path = format!("{}/tests/data/fuzz/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let doc = Document::from_json(&text).unwrap();
    doc.validate().unwrap();
    doc
}

fn options(doc: &Document) -> Options {
    Options::new(0.005 * doc.bounding_box().unwrap().diagonal())
}

fn run(name: &str) -> Tessellation {
    let doc = document(name);
    let t = tessellate(&doc, &options(&doc)).unwrap();
    t.mesh.validate().unwrap();
    t
}

/// Whether `p` is inside the polygons `loops` (even-odd).
fn inside(loops: &[Vec<DVec2>], p: DVec2) -> bool {
    let mut odd = false;
    for lp in loops {
        for i in 0..lp.len() {
            let (a, b) = (lp[i], lp[(i + 1) % lp.len()]);
            if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                odd = !odd;
            }
        }
    }
    odd
}

/// face2.json with one edge's 3D circle moved 44 mm off its trim: the edge's polyline crosses
/// the face's other trims for good, and each round of splitting found more crossings than the
/// last (83 000 segments after the 24 rounds, then a panic in the triangulation). The splits
/// now stop at the budget and the face is reported unresolved; and the triangulation, whose
/// refinement assumed loops that do not cross (a debug assertion failed: triangles classified
/// inside that were not), classifies such a face again after each pass. Run it under
/// `cargo test` (debug assertions on) to check the second part.
#[test]
fn crossing_curves_stop_at_the_split_budget() {
    let t = run("face2_moved_circle.json");
    let c = &t.stats.crossings;
    assert_eq!(c.unresolved, [1], "{c:?}");
    // The budget, plus the last round's splits (at most as many as the segments then).
    assert!(c.splits <= 2 * MIN_SPLIT_BUDGET, "{c:?}");
    assert!(c.rounds < tessd_tessellate::crossings::ROUNDS, "{c:?}");
}

/// cylinder.json with a trim's range and an edge's parameters changed: refinement points went
/// into triangles outside the trim, and their new triangles were kept as inside (a debug
/// assertion of the triangulation failed; release builds kept 853 triangles outside the
/// face). Refinement now classifies again after each pass and adds none outside; the 17
/// triangles whose (u, v) centroid still falls outside the boundary polygons (even-odd) come
/// from the first classification of these degenerate loops (overlapping constraints count
/// once), which this does not change.
#[test]
fn refinement_keeps_no_triangle_outside_the_trim() {
    let doc = document("cylinder_mutant.json");
    let options = options(&doc);
    let mut table = edges::discretise(&doc, &options);
    let (loops, _) = face_loops_uncrossed(&doc, &mut table, &options);
    let t = tessellate(&doc, &options).unwrap();
    t.mesh.validate().unwrap();
    let mut outside = Vec::new();
    let polygons: Vec<Vec<Vec<DVec2>>> = loops
        .iter()
        .map(|face| {
            face.iter()
                .map(|l| l.iter().map(|b| b.uv).collect())
                .collect()
        })
        .collect();
    for (f, corners) in t.mesh.faces().enumerate() {
        let g = t.mesh.face_groups[f] as usize;
        let c = corners
            .iter()
            .map(|&v| DVec2::from(t.uvs[v as usize]))
            .sum::<DVec2>()
            / 3.0;
        if !inside(&polygons[g], c) {
            outside.push((g, f));
        }
    }
    assert!(
        outside.len() <= 17,
        "{} triangles outside their face: {outside:?}",
        outside.len()
    );
}

/// A 2 mm cylinder 3·10³³ mm from the origin: its points are f64 noise at 0.5 % of its size, so
/// every chordal test failed and the face was refined to the 400 000-point cap (2.6 s, and
/// ~50 s under the fuzzer's sanitizer). Such a tolerance is now refused, naming it.
#[test]
fn tolerance_below_f64_resolution_is_refused() {
    let text = r#"{"format": "tessd-brep", "version": 1, "units": "mm", "faces": [{"id": 0, "surface": {"type": "cylinder", "origin": [3333333333333333333333333333333330, 0, 0], "x_dir": [1, 0, 0], "y_dir": [0, 1, 0], "radius": 2.0}, "bounds": [0, 6.283185307179586, 0, 3.0], "loopRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRRs": [0]}]}"#;
    let doc = Document::from_json(text).unwrap();
    doc.validate().unwrap();
    match tessellate(&doc, &options(&doc)) {
        Err(TessellateError::Options(m)) => {
            assert!(m.contains("finer than f64 resolves"), "{m}")
        }
        other => panic!("{:?}", other.map(|t| t.stats)),
    }
}

/// A curve the tolerance cannot be met on (a circle turned 10¹⁶ radians, as the cylinder of
/// brep's `bounds_beyond_one_turn_are_refused` had before validation refused it): sampling
/// halved each of its 4 096 starting segments 24 times (~7·10¹⁰ samples). It now stops at
/// the per-curve budget.
#[test]
fn curve_sampling_stops_at_its_budget() {
    let circle = |t: f64| tessd_brep::DVec3::new(2.0 * t.cos(), 2.0 * t.sin(), 0.0);
    let ts = sample_chordal(&circle, 0.0, 3.1e16, 4096, 1e-3, 0.5);
    assert!(ts.len() <= MAX_CURVE_SAMPLES + 1, "{}", ts.len());
    assert_eq!((ts[0], *ts.last().unwrap()), (0.0, 3.1e16));
}

/// cylinder.json with its bottom edge's 3D circle given the range 0..6·10¹⁶: sampled to the
/// per-curve budget, the edge's polyline scribbles across the faces' (u, v), and the crossing
/// search collected its ~n² pairs (a 2 GB allocation). The search now stops at the split
/// budget (`crossing_segments_at_most`). The loops still cross, and spade then panics
/// ("Failed to locate position") triangulating the face: that panic is contained, and the face
/// is refused with its id.
#[test]
fn scribbling_edge_is_refused_naming_its_face() {
    let doc = document("edge_turns.json");
    match tessellate(&doc, &options(&doc)) {
        Err(TessellateError::Face(id, why)) => {
            assert!(doc.faces.iter().any(|f| f.id == id), "face {id}");
            assert!(!why.is_empty());
        }
        Ok(t) => {
            // a future triangulation that copes must still give a valid mesh
            t.mesh.validate().unwrap();
            let c = &t.stats.crossings;
            assert!(
                c.splits <= 2 * MIN_SPLIT_BUDGET.max(4 * MAX_CURVE_SAMPLES),
                "{c:?}"
            );
        }
        Err(e) => panic!("{e}"),
    }
}

/// The crossing search of that document on its own: bounded by the limit it is given.
#[test]
fn crossing_search_stops_at_its_limit() {
    let doc = document("edge_turns.json");
    let options = options(&doc);
    let table = edges::discretise(&doc, &options);
    let most = doc
        .faces
        .iter()
        .map(|face| {
            let loops =
                tessd_tessellate::boundary::face_loops(face, &table, &Default::default(), &options);
            tessd_tessellate::crossings::crossing_segments_at_most(&loops, 1000).len()
        })
        .max();
    assert_eq!(most, Some(1000));
}
