//! View-dependent decoding (§6.2–6.3): a camera that needs every bit gives the whole mesh, each
//! triangle once; a far camera reads less of the file and shows fewer triangles; a camera looking
//! away shows nothing; and a session that moves between cameras shows what a fresh decode of each
//! camera shows — with geometry ahead of the connectivity (§6.4) too.

use std::collections::BTreeSet;
use std::io::Cursor;
use std::sync::Arc;

use tessd_codec::{Camera, Params, Tsc, ViewSession, compress};

fn bunny(params: Params) -> (Arc<Tsc>, [f64; 3], f64) {
    let path = tessd_testdata::shared("mesh/bun_zipper.ply");
    let mesh = tessd_mesh::io::read_path(&path, &Default::default()).unwrap();
    let tris: Vec<[u32; 3]> = mesh.faces().map(|f| [f[0], f[1], f[2]]).collect();
    let mut file = Cursor::new(Vec::new());
    compress(&mesh.positions, &tris, params, &mut file, &|_| true).unwrap();
    let (min, max) = mesh.bounds().unwrap();
    let centre = std::array::from_fn(|a| (min[a] as f64 + max[a] as f64) / 2.0);
    let radius = (0..3).map(|a| (max[a] - min[a]) as f64).fold(0.0, f64::max);
    (
        Arc::new(Tsc::open(&file.into_inner()).unwrap()),
        centre,
        radius,
    )
}

fn camera(centre: [f64; 3], distance: f64, toward: [f64; 3]) -> Camera {
    Camera {
        eye: [centre[0], centre[1], centre[2] + distance],
        target: toward,
        up: [0.0, 1.0, 0.0],
        fov: 40.0,
        width: 800,
        height: 600,
    }
}

type Tri = [[i64; 3]; 3];

/// Triangles as position triples on a fine integer lattice, rotation-canonical.
fn triangle_set(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> BTreeSet<Tri> {
    let key = |p: [f64; 3]| p.map(|x| (x * 1e7).round() as i64);
    triangles
        .iter()
        .map(|t| {
            let k = t.map(|i| key(positions[i as usize]));
            *[k, [k[1], k[2], k[0]], [k[2], k[0], k[1]]]
                .iter()
                .min()
                .unwrap()
        })
        .collect()
}

#[test]
fn a_camera_needing_every_bit_sees_the_whole_mesh_once() {
    for ahead in [0, 2] {
        a_camera_needing_every_bit_sees_the_whole_mesh_once_with(ahead);
    }
}

fn a_camera_needing_every_bit_sees_the_whole_mesh_once_with(ahead: u32) {
    let params = Params {
        min_cell: 3000,
        ahead,
        ..Params::default()
    };
    let (tsc, centre, radius) = bunny(params);
    assert!(tsc.nodes.len() > 8);
    let full = tsc.decode(None).unwrap();
    let mut session = ViewSession::new(tsc.clone());
    let view = session
        .view(&camera(centre, 3.0 * radius, centre), 1e-9)
        .unwrap();
    assert!(view.cells.iter().all(|&(_, b)| b == 12), "{:?}", view.cells);
    let want = triangle_set(&full.positions, &full.triangles);
    let got = triangle_set(&view.positions, &view.triangles);
    assert_eq!(
        view.triangles.len(),
        got.len(),
        "a border triangle shown twice"
    );
    assert_eq!(got, want);
}

#[test]
fn a_far_camera_reads_less_and_shows_less_and_looking_away_shows_nothing() {
    let (tsc, centre, radius) = bunny(Params {
        min_cell: 3000,
        ..Params::default()
    });
    let file_chunks: u64 = tsc.nodes.iter().map(|n| n.len).sum();
    let near = ViewSession::new(tsc.clone())
        .view(&camera(centre, 1.5 * radius, centre), 1.0)
        .unwrap();
    let far = ViewSession::new(tsc.clone())
        .view(&camera(centre, 40.0 * radius, centre), 1.0)
        .unwrap();
    assert!(
        far.triangles.len() * 4 < near.triangles.len(),
        "far {} near {}",
        far.triangles.len(),
        near.triangles.len()
    );
    assert!(
        far.bytes_read < file_chunks / 2,
        "far read {} of {file_chunks}",
        far.bytes_read
    );
    assert!(far.cells.iter().all(|&(_, b)| b < 12));
    let away = [centre[0], centre[1], centre[2] + 10.0 * radius];
    let none = ViewSession::new(tsc)
        .view(&camera(centre, 2.0 * radius, away), 1.0)
        .unwrap();
    assert_eq!(none.triangles.len(), 0);
}

#[test]
fn a_moving_session_shows_what_a_fresh_decode_shows() {
    for ahead in [0, 1] {
        a_moving_session_shows_what_a_fresh_decode_shows_with(ahead);
    }
}

fn a_moving_session_shows_what_a_fresh_decode_shows_with(ahead: u32) {
    let (tsc, centre, radius) = bunny(Params {
        min_cell: 2000,
        ahead,
        ..Params::default()
    });
    let side = [centre[0] + radius, centre[1], centre[2]];
    let cameras = [
        camera(centre, 30.0 * radius, centre),
        camera(centre, 1.2 * radius, side),
        camera(centre, 0.8 * radius, centre),
        camera(centre, 30.0 * radius, centre),
        camera(centre, 1.2 * radius, side),
    ];
    let mut session = ViewSession::new(tsc.clone());
    for (k, cam) in cameras.iter().enumerate() {
        let moved = session.view(cam, 1.0).unwrap();
        let fresh = ViewSession::new(tsc.clone()).view(cam, 1.0).unwrap();
        assert_eq!(moved.cells, fresh.cells, "ahead {ahead}, camera {k}");
        assert_eq!(
            triangle_set(&moved.positions, &moved.triangles),
            triangle_set(&fresh.positions, &fresh.triangles),
            "ahead {ahead}, camera {k}"
        );
    }
}
