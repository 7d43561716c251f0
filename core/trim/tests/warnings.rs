//! Issue 20, point 4: a trim fit error above ε_uv (paper 000, section 3.1: the approximation
//! is to meet the parameter-space error computed from ε) is reported as a warning, never
//! refused; faces the fitter follows have none.

mod common;

use common::{line, plane};
use tessd_brep::{BSplineCurve, Curve, DVec2, Document, Face, Loop, Trim};
use tessd_trim::TrimStructure;

/// The rectangle [0, 2] × [0, 1] whose bottom side is a rational quadratic from (0, 0) to
/// (2, 0) with its middle pole at (1, 0.5) weighted `w`: for a large `w` the curve leaves
/// (0, 0) for the pole within a parameter step of ~1/w, stays there, and comes back in the
/// last ~1/w — two jumps between any two of the fitter's uniformly spaced samples.
pub fn spiked_face(w: f64) -> Face {
    let spike = Trim {
        curve: Curve::Bspline(BSplineCurve {
            degree: 2,
            poles: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.5),
                DVec2::new(2.0, 0.0),
            ],
            weights: Some(vec![1.0, w, 1.0]),
            knots: vec![0.0, 1.0],
            mults: vec![3, 3],
            periodic: false,
            cache: Default::default(),
        }),
        range: [0.0, 1.0],
        edge: None,
    };
    Face {
        id: 12,
        reversed: false,
        surface: plane(),
        bounds: [0.0, 2.0, 0.0, 1.0],
        loops: vec![Loop {
            trims: vec![
                spike,
                line([2.0, 0.0], [2.0, 1.0]),
                line([2.0, 1.0], [0.0, 1.0]),
                line([0.0, 1.0], [0.0, 0.0]),
            ],
        }],
    }
}

#[test]
fn a_fit_the_fitter_cannot_meet_is_a_warning() {
    let t = TrimStructure::build(&spiked_face(1e12), 0.01).expect("built, not refused");
    let (fit, eps) = (t.stats.max_fit_error_uv, t.tolerance.eps_uv);
    eprintln!("{:?} ({:?})", t.warnings(), t.stats.build_time);
    assert!(fit > eps, "the fit met ε_uv: {fit} ≤ {eps}");
    let w = t.warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with("face 12: the trim fit error ")
            && w[0].contains(&format!("exceeds ε_uv {eps:.1e} ("))
            && w[0].contains("×); classification near its boundary may be off by that much"),
        "{}",
        w[0]
    );
    // The structure still classifies: well inside is on, outside is off.
    assert!(t.classify(1.0, 0.8));
    assert!(!t.classify(1.0, -0.5));
}

#[test]
fn faces_the_fitter_follows_have_no_warning() {
    // A moderate weight: the same shape, well sampled.
    let t = TrimStructure::build(&spiked_face(3.0), 0.01).unwrap();
    assert!(t.stats.max_fit_error_uv <= t.tolerance.eps_uv);
    assert!(t.warnings().is_empty(), "{:?}", t.warnings());
    // Every face of the bottle at both tolerances.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/bottle.json");
    let doc = Document::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
    for eps in [0.1, 0.01] {
        for face in &doc.faces {
            let t = TrimStructure::build(face, eps).unwrap();
            assert!(t.warnings().is_empty(), "ε {eps}: {:?}", t.warnings());
        }
    }
}
