//! Feeds bytes to the frame decoder (`tessd_ipc::frame::read_frame`, the daemon's limits) as a
//! socket stream, then reads every decoded array as its dtype and takes it out.
//!
//! Must hold: no panic, no hang, no allocation the limits do not allow; a frame that decodes
//! has a JSON object, a table whose arrays fit the payload, each array readable as its own
//! dtype (and refused as another), and decoding a frame again from its re-encoding gives the
//! same JSON (numbers within an ulp or two: serde_json, without its `float_roundtrip` feature,
//! does not parse every float it prints back to the same bits) and the same arrays.
#![no_main]

use libfuzzer_sys::fuzz_target;
use serde_json::Value;
use tessd_ipc::arrays::{DType, Element};
use tessd_ipc::frame::{Frame, Limits, read_frame, write_frame};

/// Reads array `name` as `T`: its element count must match its length, and `T` the dtype.
fn view<T: Element>(frame: &Frame, name: &str, length: u64) {
    let (items, _shape) = frame.arrays.get::<T>(name).expect("listed").expect("dtype");
    assert_eq!(std::mem::size_of_val(items) as u64, length);
}

/// JSON equality, floats within a few ulps.
fn same(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) if x.is_f64() || y.is_f64() => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            x == y || (x - y).abs() <= 4.0 * f64::EPSILON * x.abs().max(y.abs())
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}

fuzz_target!(|data: &[u8]| {
    let mut stream = data;
    // Several frames back to back, as on a connection, until one fails.
    for _ in 0..4 {
        let Ok(frame) = read_frame(&mut stream, &Limits::default()) else {
            return;
        };
        let descs = frame.arrays.descs().to_vec();
        for d in &descs {
            assert!(d.offset + d.length <= frame.arrays.payload_len() as u64);
            match d.dtype {
                DType::U8 => view::<u8>(&frame, &d.name, d.length),
                DType::U16 => view::<u16>(&frame, &d.name, d.length),
                DType::U32 => view::<u32>(&frame, &d.name, d.length),
                DType::U64 => view::<u64>(&frame, &d.name, d.length),
                DType::I32 => view::<i32>(&frame, &d.name, d.length),
                DType::I64 => view::<i64>(&frame, &d.name, d.length),
                DType::F32 => view::<f32>(&frame, &d.name, d.length),
                DType::F64 => view::<f64>(&frame, &d.name, d.length),
            }
            if d.dtype != DType::U8 {
                assert!(frame.arrays.get::<u8>(&d.name).expect("listed").is_err());
            }
        }
        // Round trip: what the daemon would send back decodes to the same frame.
        let json = frame.json.clone();
        let owned = frame.arrays.into_owned();
        let mut bytes = Vec::new();
        write_frame(&mut bytes, json.clone(), &owned).expect("encode");
        let again = read_frame(&mut bytes.as_slice(), &Limits::default()).expect("re-decode");
        let mut expected = json;
        if !owned.is_empty() || expected.contains_key("arrays") {
            expected.insert(
                "arrays".into(),
                again.json.get("arrays").cloned().unwrap_or_default(),
            );
        }
        let (again_json, expected) = (Value::Object(again.json), Value::Object(expected));
        assert!(same(&again_json, &expected), "{again_json} != {expected}");
        let back = again.arrays.into_owned();
        assert_eq!(back.len(), owned.len());
        for (a, b) in owned.iter().zip(&back) {
            assert_eq!(a.name(), b.name());
            assert_eq!(a.bytes(), b.bytes());
        }
    }
});
