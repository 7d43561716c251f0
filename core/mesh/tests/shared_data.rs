//! Every mesh of the shared test data, read and checked against the counts of
//! `shared/data/MANIFEST.md` (computed there by an independent parser), then written and read
//! back through every format.
//!
//! The data folder is `$TESSD_SHARED_DATA` or `../../../shared/data` from this crate.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tessd_mesh::io::{self, Format, ReadOptions};
use tessd_mesh::{Mesh, stats};

fn data_dir() -> PathBuf {
    tessd_testdata::shared("MANIFEST.md");
    tessd_testdata::shared_dir()
}

/// One MANIFEST entry. `None` where the manifest says nothing.
struct Expected {
    file: &'static str,
    vertices: u64,
    faces: u64,
    sizes: &'static [(u32, u64)],
    boundary_loops: u64,
    boundary_edges: u64,
    non_manifold_edges: u64,
    unreferenced: u64,
    euler: i64,
    components: Option<u64>,
}

#[allow(clippy::too_many_arguments)]
const fn e(
    file: &'static str,
    vertices: u64,
    faces: u64,
    sizes: &'static [(u32, u64)],
    (boundary_loops, boundary_edges): (u64, u64),
    non_manifold_edges: u64,
    unreferenced: u64,
    euler: i64,
    components: Option<u64>,
) -> Expected {
    Expected {
        file,
        vertices,
        faces,
        sizes,
        boundary_loops,
        boundary_edges,
        non_manifold_edges,
        unreferenced,
        euler,
        components,
    }
}

/// The MANIFEST's numbers ("closed" = no boundary): file, vertices, faces, face sizes,
/// (boundary loops, boundary edges), non-manifold edges, unreferenced vertices, Euler
/// characteristic, components where the MANIFEST states them.
#[rustfmt::skip]
const MANIFEST: &[Expected] = &[
    e("mesh/stanford_bunny.obj", 35947, 69451, &[(3, 69451)], (5, 223), 0, 1113, -3, None),
    e("mesh/bun_zipper.ply", 35947, 69451, &[(3, 69451)], (5, 223), 0, 1113, -3, None),
    e("mesh/spot_triangulated.obj", 2930, 5856, &[(3, 5856)], (0, 0), 0, 0, 2, None),
    e("mesh/spot_quadrangulated.obj", 2930, 2928, &[(4, 2928)], (0, 0), 0, 0, 2, None),
    e("mesh/spot_control_mesh.obj", 188, 180, &[(3, 4), (4, 160), (5, 16)], (0, 0), 0, 0, 2, None),
    e("mesh/fandisk.obj", 6475, 12946, &[(3, 12946)], (0, 0), 0, 0, 2, None),
    e("mesh/suzanne.obj", 507, 500, &[(3, 32), (4, 468)], (4, 42), 0, 0, 2, Some(3)),
    e("mesh/quadknot.obj", 1440, 1440, &[(4, 1440)], (0, 0), 0, 0, 0, None),
    e("mesh/double_torus.off", 231, 220, &[(4, 202), (5, 12), (6, 4), (7, 2)], (0, 0), 0, 0, -2, None),
    e("mesh/mpi_polygons.off", 90, 52,
      &[(3, 13), (4, 12), (5, 2), (6, 10), (7, 3), (8, 6), (9, 2), (10, 4)], (0, 0), 0, 0, 0, None),
    e("mesh/draco_test_nm.obj", 114, 170, &[(3, 170)], (3, 30), 0, 17, -3, None),
    e("mesh/draco_non_manifold_wrap.obj", 10, 12, &[(3, 12)], (2, 8), 1, 0, 1, None),
    e("subdiv/catmark_cube_level0.obj", 26, 24, &[(4, 24)], (0, 0), 0, 0, 2, None),
    e("subdiv/catmark_cube_level1.obj", 98, 96, &[(4, 96)], (0, 0), 0, 0, 2, None),
    e("subdiv/catmark_cube_level2.obj", 386, 384, &[(4, 384)], (0, 0), 0, 0, 2, None),
    e("subdiv/catmark_edgecorner_level0.obj", 156, 112, &[(4, 112)], (4, 80), 0, 0, 4, Some(4)),
    e("subdiv/catmark_edgecorner_level1.obj", 532, 448, &[(4, 448)], (4, 160), 0, 0, 4, Some(4)),
    e("subdiv/catmark_edgecorner_level2.obj", 1956, 1792, &[(4, 1792)], (4, 320), 0, 0, 4, Some(4)),
    e("subdiv/loop_icosahedron_level0.obj", 42, 80, &[(3, 80)], (0, 0), 0, 0, 2, None),
    e("subdiv/loop_icosahedron_level1.obj", 162, 320, &[(3, 320)], (0, 0), 0, 0, 2, None),
    e("subdiv/loop_icosahedron_level2.obj", 642, 1280, &[(3, 1280)], (0, 0), 0, 0, 2, None),
];

fn read(path: &Path) -> Mesh {
    io::read_path(path, &ReadOptions::default())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn every_mesh_file_is_in_the_table() {
    let dir = data_dir();
    for folder in ["mesh", "subdiv"] {
        for entry in std::fs::read_dir(dir.join(folder)).unwrap() {
            let name = format!("{folder}/{}", entry.unwrap().file_name().to_string_lossy());
            assert!(
                MANIFEST.iter().any(|e| e.file == name),
                "{name} has no expected counts"
            );
        }
    }
}

#[test]
fn counts_match_the_manifest() {
    let dir = data_dir();
    for exp in MANIFEST {
        let path = dir.join(exp.file);
        let t = Instant::now();
        let m = read(&path);
        let read_ms = t.elapsed().as_secs_f64() * 1e3;
        let s = stats::compute(&m);
        println!(
            "{:40} {:6} v ({:4} unreferenced) {:6} f  {:?}  boundary {} loops / {} edges, \
             {} non-manifold, {} components, χ = {}, read {read_ms:.1} ms",
            exp.file,
            s.stored_vertices,
            s.unreferenced_vertices,
            s.faces,
            s.face_size_histogram,
            s.boundary_loops,
            s.boundary_edges,
            s.non_manifold_edges,
            s.components,
            s.euler_characteristic(),
        );
        let f = exp.file;
        assert_eq!(s.stored_vertices, exp.vertices, "{f}: vertices");
        assert_eq!(s.faces, exp.faces, "{f}: faces");
        assert_eq!(
            s.face_size_histogram,
            exp.sizes.iter().copied().collect::<BTreeMap<_, _>>()
        );
        assert_eq!(s.boundary_loops, exp.boundary_loops, "{f}: boundary loops");
        assert_eq!(s.boundary_edges, exp.boundary_edges, "{f}: boundary edges");
        assert_eq!(
            s.non_manifold_edges, exp.non_manifold_edges,
            "{f}: non-manifold edges"
        );
        assert_eq!(
            s.unreferenced_vertices, exp.unreferenced,
            "{f}: unreferenced vertices"
        );
        assert_eq!(
            s.vertices + s.unreferenced_vertices,
            s.stored_vertices,
            "{f}"
        );
        assert_eq!(
            s.euler_characteristic(),
            exp.euler,
            "{f}: Euler characteristic"
        );
        if let Some(c) = exp.components {
            assert_eq!(s.components, c, "{f}: components");
        }
        let tris: u64 = exp.sizes.iter().map(|&(n, c)| (u64::from(n) - 2) * c).sum();
        assert_eq!(s.triangles, tris, "{f}: triangles");
        assert!(s.bounds.is_some());
    }
}

#[test]
fn attributes_and_groups_of_the_real_files() {
    let dir = data_dir();
    let spot = read(&dir.join("mesh/spot_triangulated.obj"));
    let uv = spot.uvs.as_ref().expect("spot has texture coordinates");
    assert_eq!((uv.values.len(), spot.normals.is_none()), (3225, true));
    let suzanne = read(&dir.join("mesh/suzanne.obj"));
    assert_eq!(suzanne.normals.as_ref().map(|n| n.values.len()), Some(507));
    let knot = read(&dir.join("mesh/quadknot.obj"));
    assert_eq!(knot.group_names, ["material_0"]);
    assert_eq!(knot.face_groups.len(), 1440);
    assert_eq!(knot.uvs.as_ref().map(|t| t.values.len()), Some(3));
    // First line: "v 4.512684 28.688660 -76.556808 0.752941 0.752941 0.752941" (colour ignored).
    let first = ["4.512684", "28.688660", "-76.556808"].map(|t| t.parse::<f32>().unwrap());
    assert_eq!(knot.positions[0], first);
    // The PLY and OBJ bunnies are the same geometry (the OBJ rounds to 6 decimals).
    let (a, b) = (
        read(&dir.join("mesh/bun_zipper.ply")),
        read(&dir.join("mesh/stanford_bunny.obj")),
    );
    assert_eq!(a.face_indices, b.face_indices);
    for (p, q) in a.positions.iter().zip(&b.positions) {
        assert!(
            p.iter().zip(q).all(|(x, y)| (x - y).abs() <= 1e-6),
            "{p:?} vs {q:?}"
        );
    }
}

/// The fan triangles of a mesh as position triples.
fn triangles(m: &Mesh) -> Vec<[[f32; 3]; 3]> {
    let mut out = Vec::new();
    for f in m.faces() {
        for k in 1..f.len() - 1 {
            out.push([f[0], f[k], f[k + 1]].map(|v| m.positions[v as usize]));
        }
    }
    out
}

fn same_geometry(a: &Mesh, b: &Mesh, what: &str) {
    assert_eq!(a.positions, b.positions, "{what}: positions");
    assert_eq!(a.face_offsets, b.face_offsets, "{what}: face sizes");
    assert_eq!(a.face_indices, b.face_indices, "{what}: faces");
}

/// Per-corner values of a face-varying attribute.
fn corners<T: Copy>(a: &tessd_mesh::FaceVarying<T>) -> Vec<T> {
    a.indices.iter().map(|&i| a.values[i as usize]).collect()
}

#[test]
fn round_trips_through_every_format() {
    let dir = data_dir();
    let tmp = tempfile::tempdir().unwrap();
    for exp in MANIFEST {
        let m = read(&dir.join(exp.file));
        let s = stats::compute(&m);
        let f = exp.file;
        let out = |ext: &str| tmp.path().join(format!("x.{ext}"));

        // OBJ → OBJ keeps everything the model holds except creases.
        io::write_path(&m, &out("obj")).unwrap();
        let obj = read(&out("obj"));
        assert_eq!(obj, m, "{f}: OBJ round trip");

        // → PLY → OBJ: geometry identical, every corner's normal and UV kept; a mesh whose
        // vertices carry several UVs or normals is split at those seams (the added vertices
        // follow the mesh's own, copies of their positions).
        io::write_path(&m, &out("ply")).unwrap();
        let ply = read(&out("ply"));
        let counts = io::written_counts(&m, io::Format::Ply);
        assert_eq!(ply.vertex_count(), counts.vertices, "{f} → PLY vertices");
        if let (Some(a), Some(b)) = (&m.normals, &ply.normals) {
            assert_eq!(corners(a), corners(b), "{f}: PLY normals");
        }
        if let (Some(a), Some(b)) = (&m.uvs, &ply.uvs) {
            assert_eq!(corners(a), corners(b), "{f}: PLY UVs");
        }
        assert_eq!(m.uvs.is_some(), ply.uvs.is_some(), "{f}: PLY UVs");
        assert_eq!(
            m.normals.is_some(),
            ply.normals.is_some(),
            "{f}: PLY normals"
        );
        if counts.split_vertices == 0 {
            same_geometry(&ply, &m, &format!("{f} → PLY"));
            assert_eq!(stats::compute(&ply), s, "{f} → PLY stats");
            io::write_path(&ply, &out("obj")).unwrap();
            same_geometry(&read(&out("obj")), &m, &format!("{f} → PLY → OBJ"));
        } else {
            assert_eq!(
                ply.positions[..m.vertex_count()],
                m.positions[..],
                "{f} → PLY"
            );
            assert_eq!(ply.face_offsets, m.face_offsets, "{f} → PLY face sizes");
            let at = |mesh: &Mesh| -> Vec<[f32; 3]> {
                mesh.face_indices
                    .iter()
                    .map(|&v| mesh.positions[v as usize])
                    .collect()
            };
            assert_eq!(at(&ply), at(&m), "{f} → PLY corner positions");
        }

        // → OFF.
        io::write_path(&m, &out("off")).unwrap();
        let off = read(&out("off"));
        same_geometry(&off, &m, &format!("{f} → OFF"));
        assert_eq!(stats::compute(&off), s, "{f} → OFF stats");

        // → STL: the same triangles, in order, vertices welded.
        io::write_path(&m, &out("stl")).unwrap();
        assert_eq!(
            std::fs::metadata(out("stl")).unwrap().len(),
            84 + 50 * s.triangles
        );
        let stl = read(&out("stl"));
        assert_eq!(triangles(&stl), triangles(&m), "{f} → STL triangles");
        let st = stats::compute(&stl);
        assert_eq!(
            (st.faces, st.unreferenced_vertices),
            (s.triangles, 0),
            "{f} → STL"
        );
        assert!(
            st.vertices <= s.vertices,
            "{f}: welding never adds vertices"
        );

        // In memory, through the reader/writer API.
        let mut bytes = Vec::new();
        io::write(&m, &mut bytes, Format::Ply).unwrap();
        let opts = ReadOptions::default().with_input_len(bytes.len() as u64);
        let mem = io::read(&bytes[..], Format::Ply, "<memory>", &opts).unwrap();
        assert_eq!(mem, ply, "{f} → PLY in memory: as the file");
    }
    // Nothing but the outputs is left in the folder (no temporary files).
    let mut names: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["x.obj", "x.off", "x.ply", "x.stl"]);
}
