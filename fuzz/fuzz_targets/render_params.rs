//! Feeds bytes, as a JSON `params` object, to the render op's parameter checks and camera
//! placement (`tessd::ops::render::plan_cameras`: size, view or eye/target/up, fov, shading,
//! edges, cracks, raycast, output, face_ids, turntable, columns), for a part in the unit cube:
//! everything `render` does before it reads an input or opens the GPU.
//!
//! Must hold: no panic, no hang, no runaway allocation; accepted parameters give one camera
//! per turntable frame, each with a finite eye, target and up and a positive near < far;
//! refused ones an `invalid_request` or `unsupported` error with a message.
#![no_main]

use libfuzzer_sys::fuzz_target;
use serde_json::Value;
use tessd::ops::render::{MAX_FRAMES, plan_cameras};
use tessd_ipc::ErrorCode;
use tessd_ipc::registry::Request;
use tessd_render::Bounds;
use tessd_render::camera::Vec3;

fuzz_target!(|data: &[u8]| {
    let Ok(Value::Object(params)) = serde_json::from_slice::<Value>(data) else {
        return;
    };
    let request = Request {
        params,
        ..Request::default()
    };
    let bounds = Bounds {
        min: Vec3::new(0.0, 0.0, 0.0),
        max: Vec3::new(1.0, 1.0, 1.0),
    };
    match plan_cameras(&request, &bounds) {
        Ok(cameras) => {
            assert!(!cameras.is_empty() && cameras.len() as u64 <= MAX_FRAMES);
            for c in &cameras {
                for v in [c.eye, c.target, c.up] {
                    assert!(v.to_array().iter().all(|x| x.is_finite()), "{c:?}");
                }
                assert!(c.near > 0.0 && c.near < c.far, "{c:?}");
            }
        }
        Err(e) => {
            assert!(
                matches!(e.code, ErrorCode::InvalidRequest | ErrorCode::Unsupported),
                "{e:?}"
            );
            assert!(!e.message.is_empty());
        }
    }
});
