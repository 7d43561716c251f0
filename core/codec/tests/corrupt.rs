//! A corrupted or truncated `.tsc` file gives an error naming a byte offset, never a panic or an
//! unbounded allocation: every byte flip, truncation and random overwrite below is decoded.

use std::io::Cursor;

use proptest::prelude::*;
use tessd_codec::{CodecError, Params, Tsc, compress};

/// The sample file, with `ahead` bits of geometry ahead of the connectivity (§6.4).
fn sample(ahead: u32) -> Vec<u8> {
    let path = tessd_testdata::shared("mesh/spot_triangulated.obj");
    let mesh = tessd_mesh::io::read_path(&path, &Default::default()).unwrap();
    let tris: Vec<[u32; 3]> = mesh.faces().map(|f| [f[0], f[1], f[2]]).collect();
    let params = Params {
        bits: 10,
        min_cell: 1000,
        cell_split: 2,
        root_bits: 4,
        ahead,
    };
    let mut file = Cursor::new(Vec::new());
    compress(&mesh.positions, &tris, params, &mut file, &|_| true).unwrap();
    file.into_inner()
}

/// Decodes `bytes` whole; corruption may go unnoticed (a different mesh), but must not panic.
fn decode(bytes: &[u8]) -> Result<usize, CodecError> {
    let tsc = Tsc::open(bytes)?;
    Ok(tsc.decode(None)?.triangles.len())
}

#[test]
fn the_sample_decodes_and_has_several_cells() {
    for ahead in [0, 1] {
        let bytes = sample(ahead);
        let tsc = Tsc::open(&bytes).unwrap();
        assert!(tsc.nodes.len() > 4, "{} cells", tsc.nodes.len());
        assert_eq!(decode(&bytes).unwrap(), 5856);
    }
}

#[test]
fn every_truncation_is_an_error_naming_an_offset() {
    for ahead in [0, 1] {
        let bytes = sample(ahead);
        for len in (0..bytes.len()).step_by(7) {
            match decode(&bytes[..len]) {
                Err(CodecError::Corrupt { offset, .. }) => assert!(offset <= bytes.len() as u64),
                other => panic!("ahead {ahead}, truncated to {len} bytes: {other:?}"),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn flipped_and_overwritten_bytes_never_panic(
        flips in proptest::collection::vec((any::<prop::sample::Index>(), 1u8..=255), 1..6),
        ahead in 0u32..2,
    ) {
        let mut bytes = sample(ahead);
        let n = bytes.len();
        for (at, x) in flips {
            bytes[at.index(n)] ^= x;
        }
        if let Err(e) = decode(&bytes) {
            prop_assert!(matches!(e, CodecError::Corrupt { .. }), "{e}");
        }
    }
}
