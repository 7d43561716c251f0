//! Property tests: no input makes a reader panic, whatever it returns is a valid mesh, and
//! random valid meshes survive every writer/reader pair.

use proptest::prelude::*;
use tessd_mesh::io::{self, Format, ReadOptions};
use tessd_mesh::{Mesh, stats};

const FORMATS: [Format; 4] = [Format::Obj, Format::Ply, Format::Stl, Format::Off];

/// Reads `bytes` as every format, with and without a known length; a mesh that comes back
/// must be valid and have computable stats.
fn read_all(bytes: &[u8]) {
    for format in FORMATS {
        for known in [false, true] {
            let mut o = ReadOptions::default().with_max_elements(1 << 20);
            o.input_len = known.then_some(bytes.len() as u64);
            if let Ok(m) = io::read(bytes, format, "fuzz", &o) {
                m.validate().expect("readers return valid meshes");
                let s = stats::compute(&m);
                assert_eq!(s.faces as usize, m.face_count());
            }
        }
    }
}

/// Headers that get random data past the format checks.
const PREFIXES: &[&str] = &[
    "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
     property float z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n",
    "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty short y\n\
     property float z\nproperty list uchar uchar junk\nelement face 2\nproperty uchar f\n\
     property list ushort uint vertex_indices\nelement edge 2\nproperty int a\nend_header\n",
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
     element face 1\nproperty list uchar int vertex_indices\nend_header\n",
    "OFF\n3 1 0\n",
    "solid x\nfacet normal 0 0 1\nouter loop\n",
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nf ",
];

fn small_mesh() -> Mesh {
    let positions = vec![
        [0.0; 3],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.5],
        [0.0, 1.0, -2.0],
        [0.5, 0.5, 1.0],
    ];
    let mut m = Mesh {
        positions,
        ..Mesh::default()
    };
    m.push_face(&[0, 1, 2, 3]);
    m.push_face(&[0, 1, 4]);
    m.push_face(&[2, 3, 4]);
    m
}

/// A random valid mesh: finite positions, faces of 3..8 distinct-or-not corners in range.
fn arb_mesh() -> impl Strategy<Value = Mesh> {
    (1usize..40).prop_flat_map(|nv| {
        let pos = prop::collection::vec(prop::array::uniform3(-1e6f32..1e6), nv);
        let faces = prop::collection::vec(prop::collection::vec(0..nv as u32, 3..8), 0..30);
        (pos, faces).prop_map(|(positions, faces)| {
            let mut m = Mesh {
                positions,
                ..Mesh::default()
            };
            for f in &faces {
                m.push_face(f);
            }
            m
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..3000)) {
        read_all(&bytes);
    }

    #[test]
    fn random_data_after_valid_headers_never_panics(
        prefix in 0..PREFIXES.len(),
        tail in prop::collection::vec(any::<u8>(), 0..600),
        text in "[-0-9 .eE/\n]{0,200}",
    ) {
        let mut bytes = PREFIXES[prefix].as_bytes().to_vec();
        bytes.extend_from_slice(&tail);
        read_all(&bytes);
        let mut bytes = PREFIXES[prefix].as_bytes().to_vec();
        bytes.extend_from_slice(text.as_bytes());
        read_all(&bytes);
    }

    #[test]
    fn mutated_valid_files_never_panic(
        format in 0..4usize,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
        cut in any::<prop::sample::Index>(),
    ) {
        let mut bytes = Vec::new();
        io::write(&small_mesh(), &mut bytes, FORMATS[format]).unwrap();
        for (at, b) in &edits {
            let i = at.index(bytes.len());
            bytes[i] = *b;
        }
        read_all(&bytes);
        bytes.truncate(cut.index(bytes.len()));
        read_all(&bytes);
    }

    #[test]
    fn random_meshes_round_trip(m in arb_mesh()) {
        for format in [Format::Obj, Format::Ply, Format::Off] {
            let mut bytes = Vec::new();
            io::write(&m, &mut bytes, format).unwrap();
            let back = io::read(&bytes[..], format, "rt", &ReadOptions::default()).unwrap();
            prop_assert_eq!(&back.positions, &m.positions);
            prop_assert_eq!(&back.face_offsets, &m.face_offsets);
            prop_assert_eq!(&back.face_indices, &m.face_indices);
        }
        let mut bytes = Vec::new();
        io::write(&m, &mut bytes, Format::Stl).unwrap();
        let back = io::read(&bytes[..], Format::Stl, "rt", &ReadOptions::default()).unwrap();
        prop_assert_eq!(back.triangle_count(), m.triangle_count());
        for (a, b) in back.faces().zip(m.faces().flat_map(|f| {
            (1..f.len() - 1).map(move |k| [f[0], f[k], f[k + 1]])
        })) {
            for (x, y) in a.iter().zip(b) {
                prop_assert_eq!(back.positions[*x as usize], m.positions[y as usize]);
            }
        }
    }
}

#[test]
fn cut_at_every_byte_never_panics() {
    for format in FORMATS {
        let mut bytes = Vec::new();
        io::write(&small_mesh(), &mut bytes, format).unwrap();
        for n in 0..bytes.len() {
            read_all(&bytes[..n]);
        }
    }
}
