//! Geometry ahead of the connectivity (§6.4, `--ahead m`): a partial decode has the same
//! connectivity as without it, its vertices move to the barycentres of the points they will split
//! into, and those lie closer to the input's points; the whole file still decodes losslessly (the
//! `lossless` tests) and costs a few bits per vertex more.

use std::io::Cursor;

use tessd_codec::{Decoded, Params, Tsc, compress};

fn bunny() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    let path = tessd_testdata::shared("mesh/bun_zipper.ply");
    let mesh = tessd_mesh::io::read_path(&path, &Default::default()).unwrap();
    let tris = mesh.fan_triangles();
    (mesh.positions, tris)
}

fn encode(positions: &[[f32; 3]], tris: &[[u32; 3]], ahead: u32) -> Vec<u8> {
    let params = Params {
        min_cell: 5000,
        ahead,
        ..Params::default()
    };
    let mut file = Cursor::new(Vec::new());
    compress(positions, tris, params, &mut file, &|_| true).unwrap();
    file.into_inner()
}

/// Root mean square of each decoded vertex's distance to the nearest input point (brute force
/// over every 7th decoded vertex).
fn rms_to_input(d: &Decoded, input: &[[f32; 3]]) -> f64 {
    let mut sum = 0.0;
    let mut n = 0;
    for p in d.positions.iter().step_by(7) {
        let best = input
            .iter()
            .map(|q| (0..3).map(|a| (p[a] - q[a] as f64).powi(2)).sum::<f64>())
            .fold(f64::INFINITY, f64::min);
        sum += best;
        n += 1;
    }
    (sum / n as f64).sqrt()
}

#[test]
fn partial_decodes_keep_their_connectivity_and_move_closer_to_the_input() {
    let (positions, tris) = bunny();
    let plain = Tsc::open(&encode(&positions, &tris, 0)).unwrap();
    let ahead = Tsc::open(&encode(&positions, &tris, 2)).unwrap();
    let (a, b) = (plain.bytes_len() as f64, ahead.bytes_len() as f64);
    println!(
        "bits/vertex: {:.2} plain, {:.2} with --ahead 2",
        8.0 * a / positions.len() as f64,
        8.0 * b / positions.len() as f64
    );
    assert!(b > a && b < 1.3 * a, "plain {a} bytes, ahead {b}");
    for bits in [5, 6, 7] {
        let p = plain.decode(Some(bits)).unwrap();
        let q = ahead.decode(Some(bits)).unwrap();
        // the same kd-cells and triangles: only where the vertices are drawn differs
        assert_eq!(p.corners, q.corners, "{bits} bits");
        assert_eq!(p.triangles, q.triangles, "{bits} bits");
        assert_ne!(p.positions, q.positions, "{bits} bits");
        let (dp, dq) = (rms_to_input(&p, &positions), rms_to_input(&q, &positions));
        println!("{bits} bits: vertices to input points, RMS {dp:.3e} plain, {dq:.3e} ahead");
        assert!(dq < 0.7 * dp, "{bits} bits: {dq} ahead, {dp} plain");
    }
    // the whole file: both give the input's grid points
    assert_eq!(
        plain.decode(None).unwrap(),
        Decoded {
            bytes_read: plain.bytes_len(),
            ..ahead.decode(None).unwrap()
        }
    );
}
