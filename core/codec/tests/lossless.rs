//! decode(encode(m)) equals the quantised m on every shared mesh: the set of grid points, the set
//! of oriented triangles (degenerate ones included) and the isolated points, with one cell and with
//! an nSP-tree of many cells. The expectation is computed here from the input, independently of
//! the codec's own quantisation and re-indexing.

use std::collections::BTreeSet;
use std::io::Cursor;

use tessd_codec::{Params, Quantizer, Tsc, compress};

type P = [u32; 3];

fn canonical(t: [P; 3]) -> [P; 3] {
    *[t, [t[1], t[2], t[0]], [t[2], t[0], t[1]]]
        .iter()
        .min()
        .unwrap()
}

/// What a lossless decode must give: points, triangles and isolated points on the grid.
fn expected(
    positions: &[[f32; 3]],
    tris: &[[u32; 3]],
    bits: u32,
) -> (BTreeSet<P>, BTreeSet<[P; 3]>, BTreeSet<P>) {
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for p in positions {
        for a in 0..3 {
            min[a] = min[a].min(p[a] as f64);
            max[a] = max[a].max(p[a] as f64);
        }
    }
    if positions.is_empty() {
        (min, max) = ([0.0; 3], [1.0; 3]);
    }
    let grid = Quantizer::new(min, max, bits).unwrap();
    let q: Vec<P> = positions
        .iter()
        .map(|p| grid.quantize(p.map(f64::from)))
        .collect();
    let points: BTreeSet<P> = q.iter().copied().collect();
    let tri: BTreeSet<[P; 3]> = tris
        .iter()
        .map(|t| canonical(t.map(|i| q[i as usize])))
        .collect();
    let used: BTreeSet<P> = tri.iter().flatten().copied().collect();
    let isolated = points.difference(&used).copied().collect();
    (points, tri, isolated)
}

fn round_trip(name: &str, positions: &[[f32; 3]], tris: &[[u32; 3]], params: Params) -> (u64, u64) {
    let mut file = Cursor::new(Vec::new());
    let report = compress(positions, tris, params, &mut file, &|_| true).unwrap();
    let bytes = file.into_inner();
    assert_eq!(report.bytes, bytes.len() as u64);
    let tsc = Tsc::open(&bytes).unwrap();
    let d = tsc.decode(None).unwrap();
    let (points, tri, isolated) = expected(positions, tris, params.bits);
    let got_points: BTreeSet<P> = d.corners.iter().copied().collect();
    assert_eq!(
        got_points.len(),
        d.corners.len(),
        "{name}: a point decoded twice"
    );
    assert_eq!(got_points, points, "{name}: points differ");
    let got_tri: BTreeSet<[P; 3]> = d
        .triangles
        .iter()
        .map(|t| canonical(t.map(|i| d.corners[i as usize])))
        .collect();
    assert_eq!(
        got_tri.len(),
        d.triangles.len(),
        "{name}: a triangle decoded twice"
    );
    assert_eq!(got_tri, tri, "{name}: triangles differ");
    let got_iso: BTreeSet<P> = d.isolated.iter().map(|&i| d.corners[i as usize]).collect();
    assert_eq!(got_iso, isolated, "{name}: isolated points differ");
    assert_eq!(report.vertices, points.len() as u64);
    (bytes.len() as u64, report.nsp_cells)
}

#[test]
fn every_shared_mesh_round_trips_at_12_and_16_bits_in_one_cell_and_in_many() {
    let dir = tessd_testdata::shared("mesh");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    names.sort();
    assert!(
        names.len() >= 10,
        "shared meshes missing in {}",
        dir.display()
    );
    for path in names {
        let mesh = tessd_mesh::io::read_path(&path, &Default::default()).unwrap();
        let tris = mesh.fan_triangles();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        for bits in [12, 16] {
            let one = Params {
                bits,
                min_cell: u64::MAX,
                ..Params::default()
            };
            let (bytes, cells) = round_trip(&name, &mesh.positions, &tris, one);
            assert_eq!(cells, 1);
            let many = Params {
                bits,
                min_cell: 200,
                cell_split: 2,
                root_bits: 3,
                ..Params::default()
            };
            let (_, cells) = round_trip(&name, &mesh.positions, &tris, many);
            if tris.len() > 1000 {
                assert!(cells > 8, "{name}: {cells} cells with N_min 200");
            }
            // geometry ahead of connectivity (§6.4): one bit in one cell, two in many
            let ahead_one = Params { ahead: 1, ..one };
            round_trip(&name, &mesh.positions, &tris, ahead_one);
            let ahead_many = Params { ahead: 2, ..many };
            round_trip(&name, &mesh.positions, &tris, ahead_many);
            println!(
                "{name}: {} vertices, {bits} bits: {:.2} bits/vertex in one cell",
                mesh.positions.len(),
                8.0 * bytes as f64 / mesh.positions.len() as f64
            );
        }
    }
}

#[test]
fn soups_degenerate_and_non_manifold_triangles_round_trip() {
    // a soup: the same corner positions in separate vertices; a triangle with a repeated index;
    // one whose corners quantise onto one point; both orientations of one triangle; a duplicate;
    // an edge shared by four triangles; isolated points
    let positions: Vec<[f32; 3]> = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0], // 0-2
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0], // 3-5 soup copies
        [0.5, 0.5, 0.5],
        [0.5000001, 0.5, 0.5],
        [0.5, 0.5000001, 0.5], // 6-8 collapse at 12 bits
        [1.0, 1.0, 1.0],
        [0.3, 0.9, 0.1],
        [0.9, 0.2, 0.7], // 9-11
        [0.25, 0.25, 0.75],
        [0.75, 0.75, 0.25], // 12-13 isolated
    ];
    let tris = vec![
        [0, 1, 2],
        [3, 4, 5],
        [0, 0, 9],
        [6, 7, 8],
        [1, 2, 9],
        [1, 9, 2],
        [1, 2, 9],
        [0, 1, 10],
        [0, 1, 11],
        [1, 0, 9],
        [4, 3, 11],
    ];
    for bits in [4, 12, 16] {
        round_trip(
            "soup",
            &positions,
            &tris,
            Params {
                bits,
                min_cell: u64::MAX,
                root_bits: 2,
                ..Params::default()
            },
        );
        // many cells, with 0, 1 and 3 bits of geometry ahead of the connectivity (§6.4)
        for ahead in [0, 1, 3] {
            round_trip(
                "soup",
                &positions,
                &tris,
                Params {
                    bits,
                    min_cell: 1,
                    cell_split: 2,
                    root_bits: 1,
                    ahead,
                },
            );
        }
    }
}

#[test]
fn empty_and_point_only_inputs_round_trip() {
    round_trip("empty", &[], &[], Params::default());
    round_trip("one point", &[[1.0, 2.0, 3.0]], &[], Params::default());
    round_trip(
        "points",
        &[[1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [4.0, 0.0, 3.0]],
        &[],
        Params::default(),
    );
}

/// Position triples of `triangles`, rotation-canonical, as f32 bit patterns.
fn float_triangles(
    positions: &[[f32; 3]],
    triangles: impl Iterator<Item = [u32; 3]>,
) -> BTreeSet<[[u32; 3]; 3]> {
    triangles
        .map(|t| {
            let k = t.map(|i| positions[i as usize].map(f32::to_bits));
            *[k, [k[1], k[2], k[0]], [k[2], k[0], k[1]]]
                .iter()
                .min()
                .unwrap()
        })
        .collect()
}

#[test]
fn the_bounded_memory_ply_writer_gives_the_full_decode() {
    let dir = tempfile::tempdir().unwrap();
    for (name, params) in [
        (
            "bun_zipper.ply",
            Params {
                min_cell: 1500,
                ..Params::default()
            },
        ),
        (
            "stanford_bunny.obj",
            Params {
                bits: 16,
                min_cell: 4000,
                cell_split: 2,
                root_bits: 4,
                ahead: 2,
            },
        ),
        (
            "draco_test_nm.obj",
            Params {
                min_cell: 10,
                cell_split: 2,
                root_bits: 2,
                bits: 12,
                ahead: 0,
            },
        ),
    ] {
        let mesh = tessd_mesh::io::read_path(
            &tessd_testdata::shared(&format!("mesh/{name}")),
            &Default::default(),
        )
        .unwrap();
        let tris = mesh.fan_triangles();
        let mut file = Cursor::new(Vec::new());
        compress(&mesh.positions, &tris, params, &mut file, &|_| true).unwrap();
        let tsc_path = dir.path().join("m.tsc");
        std::fs::write(&tsc_path, file.get_ref()).unwrap();
        let tsc = Tsc::open_file(&tsc_path).unwrap();
        assert!(tsc.nodes.len() > 4, "{name}: {} cells", tsc.nodes.len());
        let ply = dir.path().join("m.ply");
        let mut out = std::io::BufWriter::new(std::fs::File::create(&ply).unwrap());
        let report = tsc.write_ply(&mut out, &|_| true).unwrap();
        drop(out);
        let back = tessd_mesh::io::read_path(&ply, &Default::default()).unwrap();
        let whole = tsc.decode(None).unwrap();
        let whole_pos: Vec<[f32; 3]> = whole
            .positions
            .iter()
            .map(|p| p.map(|x| x as f32))
            .collect();
        assert_eq!(back.positions.len() as u64, report.vertices);
        assert_eq!(report.vertices, whole.corners.len() as u64, "{name}");
        let got: BTreeSet<[u32; 3]> = back.positions.iter().map(|p| p.map(f32::to_bits)).collect();
        let want: BTreeSet<[u32; 3]> = whole_pos.iter().map(|p| p.map(f32::to_bits)).collect();
        assert_eq!(got, want, "{name}: vertices");
        assert_eq!(back.face_count(), whole.triangles.len(), "{name}");
        let got = float_triangles(&back.positions, back.faces().map(|f| [f[0], f[1], f[2]]));
        let want = float_triangles(&whole_pos, whole.triangles.iter().copied());
        assert_eq!(got, want, "{name}: triangles");
    }
}

#[test]
fn the_file_is_the_same_at_any_thread_count() {
    let mesh = tessd_mesh::io::read_path(
        &tessd_testdata::shared("mesh/bun_zipper.ply"),
        &Default::default(),
    )
    .unwrap();
    let tris = mesh.fan_triangles();
    let params = Params {
        min_cell: 1000,
        ..Params::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut file = Cursor::new(Vec::new());
            compress(&mesh.positions, &tris, params, &mut file, &|_| true).unwrap();
            file.into_inner()
        })
    };
    let one = run(1);
    assert_eq!(run(2), one);
    assert_eq!(run(5), one);
}
