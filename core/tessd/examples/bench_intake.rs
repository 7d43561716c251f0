//! Mesh intake benchmark (issue 15, point 0): the phases of taking a large mesh in, each timed
//! with `Instant` on one thread — protocol arrays → `Mesh` (2-D `face_indices` as numpy sends
//! them, and 1-D with `face_sizes` as Blender does), `Mesh::validate`, the mesh back to arrays,
//! and a binary PLY read from memory and from a file in the page cache.
//!
//! Run: `cargo run --release -p tessd --example bench_intake -- [TRIANGLES_M] [RUNS]` (defaults
//! 4 and 7). Prints a Markdown table of medians; `bench/run_intake.sh` stores it with the
//! end-to-end daemon figures in `bench/results/intake.md`.

use std::time::Instant;
use tessd::ops::mesh_arrays::{mesh_from_arrays, mesh_to_arrays};
use tessd_ipc::arrays::{Arrays, OwnedArray};
use tessd_mesh::Mesh;
use tessd_mesh::io::{Format, ReadOptions};

/// A closed torus of `nu × nv` quads split into triangles, vertices in row order (the order a
/// tessellator or scanner gives; the same layout as `bench/intake_daemon.py` sends).
fn torus(triangles: f64) -> Mesh {
    let nv = ((triangles / 5.0).sqrt().round() as u32).max(3);
    let nu = ((triangles / (2.0 * f64::from(nv))).round() as u32).max(3);
    let mut m = Mesh::default();
    let tau = std::f32::consts::TAU;
    m.positions.reserve((nu * nv) as usize);
    for i in 0..nu {
        let u = tau * i as f32 / nu as f32;
        for j in 0..nv {
            let v = tau * j as f32 / nv as f32;
            let ring = 1.0 + 0.4 * v.cos();
            m.positions
                .push([ring * u.cos(), ring * u.sin(), 0.4 * v.sin()]);
        }
    }
    m.face_indices.reserve(6 * (nu * nv) as usize);
    m.face_offsets.reserve(2 * (nu * nv) as usize);
    for i in 0..nu {
        let i1 = (i + 1) % nu;
        for j in 0..nv {
            let j1 = (j + 1) % nv;
            let (a, b, c, d) = (i * nv + j, i1 * nv + j, i1 * nv + j1, i * nv + j1);
            m.push_face(&[a, b, c]);
            m.push_face(&[a, c, d]);
        }
    }
    m
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Times `f` `runs` times (after one warm-up run) and returns the median in seconds.
fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> f64 {
    std::hint::black_box(f());
    median(
        (0..runs)
            .map(|_| {
                let t = Instant::now();
                let out = f();
                let d = t.elapsed().as_secs_f64();
                drop(std::hint::black_box(out));
                d
            })
            .collect(),
    )
}

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a number"))
        .collect();
    let tris_m = args.first().copied().unwrap_or(4.0);
    let runs = args.get(1).copied().unwrap_or(7.0) as usize;
    let mesh = torus(tris_m * 1e6);
    let tris = mesh.triangle_count() as f64;
    let mtps = |s: f64| tris / s / 1e6;

    // The arrays exactly as a request carries them (8-aligned payload, viewed in place).
    let positions = OwnedArray::rows("positions", mesh.positions.clone());
    let faces_2d: Vec<[u32; 3]> = bytemuck::cast_slice(&mesh.face_indices).to_vec();
    let arrays_2d = [positions, OwnedArray::rows("face_indices", faces_2d)];
    let arrays_1d = mesh_to_arrays(mesh.clone());
    // A request's arrays as received (one buffer per array); the mesh takes them over, so each
    // run gets a fresh copy, made outside the timed section.
    let received = |a: &[OwnedArray]| Arrays::from_owned(a);
    let timed_take = |a: &[OwnedArray], validate: bool| {
        median(
            (0..runs)
                .map(|_| {
                    let mut arrays = received(a);
                    let t = Instant::now();
                    let m = mesh_from_arrays(&mut arrays, Vec::new()).unwrap();
                    if validate {
                        m.validate().unwrap();
                    }
                    let d = t.elapsed().as_secs_f64();
                    drop(std::hint::black_box(m));
                    d
                })
                .collect(),
        )
    };

    let mut rows: Vec<(String, f64)> = Vec::new();
    // Floors: one read pass over every array a mesh is (positions, offsets, indices), and one
    // copy of them into fresh memory (what building a `Mesh` from borrowed arrays costs).
    rows.push((
        "floor: max-reduction over positions, offsets and indices (one read pass)".into(),
        time(runs, || {
            let p = bytemuck::cast_slice::<[f32; 3], u32>(&mesh.positions);
            [p, &mesh.face_offsets, &mesh.face_indices]
                .map(|a| a.iter().fold(0u32, |m, &v| m.max(v)))
        }),
    ));
    rows.push((
        "floor: copy of those arrays into fresh allocations".into(),
        time(runs, || {
            (
                mesh.positions.to_vec(),
                mesh.face_offsets.to_vec(),
                mesh.face_indices.to_vec(),
            )
        }),
    ));
    rows.push((
        "arrays → `Mesh` (2-D `face_indices`, no validation)".into(),
        timed_take(&arrays_2d, false),
    ));
    rows.push((
        "arrays → `Mesh` (1-D `face_indices` + `face_sizes`, no validation)".into(),
        timed_take(&arrays_1d, false),
    ));
    rows.push((
        "`Mesh::validate`".into(),
        time(runs, || mesh.validate().unwrap()),
    ));
    rows.push((
        "**arrays → validated `Mesh`** (2-D, what `input_mesh` does)".into(),
        timed_take(&arrays_2d, true),
    ));
    rows.push((
        "`Mesh` → arrays (`mesh_to_arrays`, face sizes)".into(),
        time(runs, || mesh_to_arrays(mesh.clone())) - time(runs, || mesh.clone()),
    ));

    // Binary PLY, as `tessd_mesh::io::write` writes it (float x y z; list uchar uint).
    let mut ply = Vec::new();
    tessd_mesh::io::write(&mesh, &mut ply, Format::Ply).unwrap();
    let options = ReadOptions::default().with_input_len(ply.len() as u64);
    rows.push((
        format!(
            "**binary PLY → validated `Mesh`**, from memory ({:.0} MB)",
            ply.len() as f64 / 1e6
        ),
        time(runs, || {
            tessd_mesh::io::read(&ply[..], Format::Ply, "<memory>", &options).unwrap()
        }),
    ));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("torus.ply");
    std::fs::write(&path, &ply).unwrap();
    rows.push((
        "binary PLY → validated `Mesh`, `read_path` (file in page cache)".into(),
        time(runs, || {
            tessd_mesh::io::read_path(&path, &ReadOptions::default()).unwrap()
        }),
    ));
    rows.push((
        "`std::fs::read` of that file (the floor)".into(),
        time(runs, || std::fs::read(&path).unwrap()),
    ));

    println!(
        "## In-process phases: torus of {} triangles, {} vertices; one thread, median of {runs}\n",
        tris as u64,
        mesh.vertex_count()
    );
    println!("| phase | time (ms) | M triangles/s |\n|---|---|---|");
    for (name, s) in rows {
        println!("| {name} | {:.1} | {:.0} |", s * 1e3, mtps(s));
    }
}
