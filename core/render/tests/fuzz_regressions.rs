//! Inputs the fuzzer (fuzz/fuzz_targets/render_params.rs) found, through the camera placement
//! the render op does before any GPU work.

use tessd_render::camera::Vec3;
use tessd_render::{Bounds, Camera};

fn unit_box() -> Bounds {
    Bounds {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    }
}

/// `{"eye": [0.25, 184467440737095516150.2, 0]}` for a part in the unit cube: the box's depth
/// range (1.7) vanished in the eye's distance (1.8·10²⁰), and the near plane came out equal to
/// the far one. It is now below it.
#[test]
fn far_eye_keeps_near_below_far() {
    let camera = Camera::new(
        [0.25, 184467440737095516150.2, 0.0],
        unit_box().center(),
        Vec3::Z,
        30.0,
    );
    camera.check().unwrap();
    let c = camera.clipped_to(&unit_box());
    assert!(c.near > 0.0 && c.near < c.far && c.far.is_finite(), "{c:?}");
}

/// An ordinary camera keeps the planes it had: the box's depth range widened by 1 %.
#[test]
fn near_camera_planes_are_unchanged() {
    let c =
        Camera::new([3.0, 0.5, 0.5], unit_box().center(), Vec3::Z, 30.0).clipped_to(&unit_box());
    let span = 1.0f64.max(unit_box().radius());
    assert!((c.near - (2.0 - 0.01 * span)).abs() < 1e-12, "{c:?}");
    assert!((c.far - (3.0 + 0.01 * span)).abs() < 1e-12, "{c:?}");
}
