//! Feeds bytes to the `tessd-brep` document reader (`Document::from_json`), validates what
//! parses, and tessellates what validates at 0.5 % of the part's bounding-box diagonal (the
//! daemon's `tolerance: "0.5%"`, through its own `absolute_tolerance`), with OCP's default angle.
//!
//! Must hold: no panic, no hang, no runaway allocation; a document that validates either
//! tessellates into a valid mesh (one face group per face, one (u, v) and one f64 point per
//! vertex) or is refused with a clear error. The work is bounded only by the document's own
//! limits (the validator's checks, the tessellator's per-face point caps): nothing is skipped
//! here, so a small document that takes long is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use tessd::ops::tessellate::{Tolerance, absolute_tolerance};
use tessd_brep::Document;
use tessd_tessellate::{Options, tessellate};

static DEFAULT_HOOK: std::sync::Once = std::sync::Once::new();

fuzz_target!(|data: &[u8]| {
    // libfuzzer-sys aborts on every panic, caught or not; the tessellator contains spade's
    // panics on hostile trims (a face refused with its id), so only an uncaught panic — which
    // libfuzzer-sys still turns into an abort — is a finding here
    DEFAULT_HOOK.call_once(|| drop(std::panic::take_hook()));
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(doc) = Document::from_json(text) else {
        return;
    };
    let _ = doc.stats();
    if doc.validate().is_err() {
        return;
    }
    let Ok((tolerance, _)) = absolute_tolerance(Tolerance::Percent(0.5), &doc) else {
        return;
    };
    if let Ok(t) = tessellate(&doc, &Options::new(tolerance)) {
        t.mesh.validate().expect("a tessellation is a valid mesh");
        assert_eq!(t.mesh.group_names.len(), doc.faces.len());
        assert_eq!(t.uvs.len(), t.mesh.positions.len());
        assert_eq!(t.points.len(), t.mesh.positions.len());
    }
});
