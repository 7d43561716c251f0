//! Bad cages and bad frames get an error naming the element, for every scheme, and nothing
//! is allocated for outputs that would not fit.

use tessd_mesh::Mesh;
use tessd_subdiv::{Refiner, Scheme, SubdivError, SubdivOptions};

mod common;
use common::{pair, unit_quad};

fn options(scheme: Scheme, levels: u32) -> SubdivOptions {
    SubdivOptions {
        scheme,
        levels,
        ..SubdivOptions::default()
    }
}

fn refuse(m: &Mesh, scheme: Scheme) -> SubdivError {
    Refiner::new(m, &options(scheme, 2)).expect_err("a bad cage must be refused")
}

#[test]
fn the_valid_cage_refines_with_every_scheme() {
    for scheme in Scheme::ALL {
        let r = Refiner::new(&pair(), &options(scheme, 2)).unwrap();
        assert!(r.faces.len() > 2, "{}", scheme.name());
    }
}

#[test]
fn non_manifold_edges_are_named() {
    let mut m = pair();
    m.positions.push([0.0, 0.0, 1.0]);
    m.push_face(&[1, 2, 4]);
    for scheme in Scheme::ALL {
        let e = refuse(&m, scheme);
        assert_eq!(
            e,
            SubdivError::NonManifoldEdge {
                a: 1,
                b: 2,
                faces: 3
            },
            "{}",
            scheme.name()
        );
        assert!(e.to_string().contains("edge (1, 2) is shared by 3 faces"));
    }
}

#[test]
fn isolated_vertices_are_named() {
    let mut m = pair();
    m.positions.push([5.0, 5.0, 5.0]);
    for scheme in Scheme::ALL {
        assert_eq!(
            refuse(&m, scheme),
            SubdivError::IsolatedVertex { vertex: 4 }
        );
    }
}

#[test]
fn degenerate_faces_are_named() {
    let mut m = pair();
    m.face_indices[4] = 2; // face 1 = (2, 2, 3)
    for scheme in Scheme::ALL {
        match refuse(&m, scheme) {
            SubdivError::DegenerateFace { face: 1, why } => assert!(why.contains("twice"), "{why}"),
            other => panic!("{}: {other:?}", scheme.name()),
        }
    }
}

#[test]
fn out_of_range_indices_and_nan_are_refused_by_the_mesh_check() {
    let mut m = pair();
    m.face_indices[5] = 9;
    assert!(
        matches!(refuse(&m, Scheme::CatmullClark), SubdivError::InvalidMesh(s) if s.contains('9'))
    );
    let mut m = pair();
    m.positions[3][1] = f32::NAN;
    assert!(matches!(
        refuse(&m, Scheme::Loop),
        SubdivError::InvalidMesh(_)
    ));
}

#[test]
fn too_many_levels_are_refused_before_allocating() {
    // 10 levels of 2 triangles: 2·4¹⁰ ≈ 2 M faces fit; a 16 GiB limit of 1 KiB does not.
    let mut o = options(Scheme::CatmullClark, 10);
    o.memory_limit = 1024;
    match Refiner::new(&pair(), &o).unwrap_err() {
        SubdivError::TooLarge {
            levels: 10,
            faces,
            bytes,
            limit: 1024,
        } => {
            assert_eq!(faces, 6 * 4u64.pow(9));
            assert!(bytes > 1024);
        }
        other => panic!("{other:?}"),
    }
    // The default limit (8 GiB) refuses a 100 k-face cage at 10 levels at once.
    let mut big = Mesh::default();
    for i in 0..50_000u32 {
        big.positions.extend([
            [i as f32, 0.0, 0.0],
            [i as f32, 1.0, 0.0],
            [i as f32, 0.0, 1.0],
        ]);
        big.push_face(&[3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let t = std::time::Instant::now();
    assert!(matches!(
        Refiner::new(&big, &options(Scheme::Loop, 10)),
        Err(SubdivError::TooLarge { .. })
    ));
    assert!(t.elapsed().as_secs_f64() < 1.0, "the estimate comes first");
}

#[test]
fn frames_of_another_vertex_count_are_refused() {
    let r = Refiner::new(&pair(), &options(Scheme::CatmullClark, 1)).unwrap();
    let frame = vec![[0.0f32; 3]; 5];
    assert_eq!(
        r.apply_positions(&frame, "frame 3").unwrap_err(),
        SubdivError::VertexCount {
            what: "frame 3".into(),
            got: 5,
            expected: 4
        }
    );
    assert!(r.apply(&[0.0; 7], 3, "uvs").is_err());
    assert!(r.apply(&[], 0, "nothing").is_err());
}

#[test]
fn quads_are_refused_by_the_triangle_schemes() {
    let m = unit_quad();
    for scheme in Scheme::ALL.into_iter().filter(|s| s.needs_triangles()) {
        assert_eq!(
            refuse(&m, scheme),
            SubdivError::NotTriangles {
                scheme: scheme.name(),
                face: 0,
                corners: 4
            }
        );
    }
}
