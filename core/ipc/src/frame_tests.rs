//! Frame codec tests: round trips, each rejection, and never-panic properties.

use super::*;
use crate::arrays::OwnedArray;
use proptest::prelude::*;
use serde_json::json;

fn encode(json: Value, arrays: &[OwnedArray]) -> Vec<u8> {
    let Value::Object(m) = json else { panic!() };
    let mut out = Vec::new();
    write_frame(&mut out, m, arrays).unwrap();
    out
}

fn decode(bytes: &[u8]) -> Result<Frame, FrameError> {
    read_frame(&mut &bytes[..], &Limits::default())
}

#[test]
fn round_trip_with_arrays() {
    let arrays = [
        OwnedArray::rows("positions", vec![[1.0f32, 2.0, 3.0], [4.0, 5.0, 6.0]]),
        OwnedArray::new("flags", vec![3], vec![1u8, 2, 3]),
        OwnedArray::new("ids", vec![2], vec![7u64, 9]),
    ];
    let bytes = encode(json!({"id": 1, "op": "x"}), &arrays);
    assert_eq!(bytes.len() % 8, (HEADER_LEN + bytes.len() - HEADER_LEN) % 8);
    let f = decode(&bytes).unwrap();
    let (p, shape) = f.arrays.get::<f32>("positions").unwrap().unwrap();
    assert_eq!(
        (p, shape),
        (&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0][..], &[2u64, 3][..])
    );
    assert_eq!(f.arrays.get::<u8>("flags").unwrap().unwrap().0, &[1, 2, 3]);
    let ids = f.arrays.desc("ids").unwrap();
    assert_eq!(ids.offset % 8, 0);
    assert_eq!(f.arrays.get::<u64>("ids").unwrap().unwrap().0, &[7, 9]);
    assert!(f.arrays.get::<u32>("ids").unwrap().is_err());
}

#[test]
fn rejects_bad_headers_distinctly() {
    let good = encode(json!({"id": 1}), &[]);
    let mut b = good.clone();
    b[0] = b'X';
    assert!(matches!(decode(&b), Err(FrameError::BadMagic(_))));
    let mut b = good.clone();
    b[4] = 2;
    assert!(matches!(decode(&b), Err(FrameError::BadVersion(2))));
    let mut b = good.clone();
    b[6] = 1;
    assert!(matches!(
        decode(&b),
        Err(FrameError::Reserved { field: "flags", .. })
    ));
    let mut b = good.clone();
    b[12] = 1;
    assert!(matches!(
        decode(&b),
        Err(FrameError::Reserved {
            field: "reserved",
            ..
        })
    ));
    let mut b = good.clone();
    b[16..24].copy_from_slice(&(1u64 << 62).to_le_bytes());
    let e = decode(&b).unwrap_err();
    assert!(matches!(e, FrameError::PayloadTooLarge { .. }));
    assert_eq!(e.code(), "too_large");
    let mut b = good.clone();
    b[8..12].copy_from_slice(&0u32.to_le_bytes());
    assert!(matches!(
        decode(&b),
        Err(FrameError::JsonLength { len: 0, .. })
    ));
    assert!(matches!(
        decode(&good[..10]),
        Err(FrameError::Truncated { part: "header", .. })
    ));
    assert!(matches!(
        decode(&good[..good.len() - 1]),
        Err(FrameError::Truncated { part: "JSON", .. })
    ));
    assert!(matches!(decode(&[]), Err(FrameError::Closed)));
}

#[test]
fn rejects_non_objects_and_bad_tables() {
    for (text, want) in [
        ("[1]", "an array"),
        ("3", "a number"),
        ("null", "null"),
        ("\"s\"", "a string"),
    ] {
        let mut b = Header {
            json_len: text.len() as u32,
            payload_len: 0,
        }
        .encode()
        .to_vec();
        b.extend_from_slice(text.as_bytes());
        assert!(
            matches!(decode(&b), Err(FrameError::NotAnObject(k)) if k == want),
            "{text}"
        );
    }
    let table = |arrays: Value, payload: u64| {
        let text = serde_json::to_vec(&json!({"id": 1, "arrays": arrays})).unwrap();
        let mut b = Header {
            json_len: text.len() as u32,
            payload_len: payload,
        }
        .encode()
        .to_vec();
        b.extend_from_slice(&text);
        b.resize(b.len() + payload as usize, 0);
        match decode(&b) {
            Err(FrameError::BadArrays(m)) => m,
            other => panic!("expected a table error, got {other:?}"),
        }
    };
    let a = |name: &str, dtype: &str, shape: Value, offset: u64, length: u64| json!({"name": name, "dtype": dtype, "shape": shape, "offset": offset, "length": length});
    assert!(table(json!({}), 0).contains("must be a list"));
    assert!(table(json!([a("p", "f16", json!([1]), 0, 2)]), 8).contains("unknown dtype"));
    assert!(table(json!([a("p", "f32", json!([3]), 0, 8)]), 16).contains("needs 12"));
    assert!(table(json!([a("p", "u8", json!([4]), 4, 4)]), 16).contains("not a multiple of 8"));
    assert!(table(json!([a("p", "u8", json!([16]), 8, 16)]), 16).contains("payload has 16"));
    assert!(
        table(
            json!([
                a("p", "u8", json!([8]), 0, 8),
                a("p", "u8", json!([8]), 8, 8)
            ]),
            16
        )
        .contains("repeats")
    );
    assert!(
        table(
            json!([
                a("p", "u8", json!([16]), 0, 16),
                a("q", "u8", json!([8]), 8, 8)
            ]),
            16
        )
        .contains("overlap")
    );
    assert!(table(json!([a("p", "u64", json!([u64::MAX, 4]), 0, 8)]), 16).contains("overflows"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Random bytes never panic the decoder.
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
        let _ = decode(&bytes);
    }

    /// Valid frames with random mutations never panic the decoder, and unmutated ones decode.
    #[test]
    fn mutated_frames_never_panic(
        flips in proptest::collection::vec((any::<usize>(), any::<u8>()), 0..6),
        cut in any::<usize>(),
        n in 0usize..40,
    ) {
        let arrays = [
            OwnedArray::new("a", vec![n as u64], vec![1.5f32; n]),
            OwnedArray::new("b", vec![n as u64, 2], vec![3u32; 2 * n]),
        ];
        let good = encode(json!({"id": 5, "op": "mesh.stats", "params": {"x": [1, 2]}}), &arrays);
        prop_assert!(decode(&good).is_ok());
        let mut b = good.clone();
        for (i, v) in &flips {
            let k = i % b.len();
            b[k] = *v;
        }
        let _ = decode(&b);
        let _ = decode(&b[..cut % (b.len() + 1)]);
    }
}
