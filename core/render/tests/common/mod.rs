//! What the render tests share: one renderer per test binary (opening a device and compiling
//! the shaders is the slow part on lavapipe), its adapter printed once, and the B-Rep
//! fixtures. A missing device fails the tests, as a missing fixture does.

#![allow(dead_code)]

use std::sync::OnceLock;

use tessd_render::Renderer;

/// The B-Rep fixtures the pipeline tests render: OCCT's bottle (B-splines, a thread), the
/// CrankArm part (planes, cylinders, fillets) and a FreeCAD body (drilled holes).
pub const PARTS: [&str; 3] = [
    "bottle.json",
    "CrankArm.json",
    "freecad_drilling1_body.json",
];

/// The test binary's renderer.
pub fn renderer() -> &'static Renderer {
    static R: OnceLock<Renderer> = OnceLock::new();
    R.get_or_init(|| {
        let r = Renderer::new().unwrap_or_else(|e| panic!("no GPU for the render tests: {e}"));
        println!("adapter: {}", r.adapter_info());
        r
    })
}

/// The B-Rep fixture `name` of core/tessellate/tests/data, parsed.
pub fn doc(name: &str) -> tessd_brep::Document {
    tessd_brep::Document::from_json(&tessd_testdata::brep_fixture_text(name)).unwrap()
}
