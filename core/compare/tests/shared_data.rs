//! Comparisons on the shared test meshes (`tessd_testdata::shared`: a missing file fails).

use tessd_compare::{CompareOptions, compare};
use tessd_mesh::Mesh;
use tessd_mesh::io::{ReadOptions, read_path};

fn shared(name: &str) -> Mesh {
    let path = tessd_testdata::shared(&format!("mesh/{name}"));
    read_path(&path, &ReadOptions::default()).unwrap()
}

#[test]
fn bunny_ply_and_obj_are_the_same_surface_up_to_obj_rounding() {
    // stanford_bunny.obj is bun_zipper.ply written with 6 decimals: every vertex moved by at
    // most 5e-7 per axis, so the surfaces are within √3 · 5e-7 ≈ 8.7e-7 of each other.
    let (ply, obj) = (shared("bun_zipper.ply"), shared("stanford_bunny.obj"));
    let c = compare(&ply, &obj, &CompareOptions::default().with_samples(50_000)).unwrap();
    assert!(c.hausdorff > 0.0 && c.hausdorff <= 8.7e-7, "{c:?}");
    assert!(
        (c.bbox_diagonal - 0.2502467).abs() < 1e-6,
        "{}",
        c.bbox_diagonal
    );
    // 1113 unreferenced vertices are not samples.
    assert_eq!(c.a_to_b.samples, 50_000 + 35_947 - 1_113);
}

#[test]
fn polygon_mesh_against_itself() {
    // n-gon faces (fan-triangulated on both sides).
    let m = shared("mpi_polygons.off");
    assert!(m.faces().any(|f| f.len() > 4));
    let c = compare(&m, &m, &CompareOptions::default().with_samples(20_000)).unwrap();
    assert!(c.hausdorff < 1e-9 * c.bbox_diagonal, "{c:?}");
}
