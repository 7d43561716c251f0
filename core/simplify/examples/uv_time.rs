//! Times carrying per-corner UVs through a simplification (issue 33, "What the user waits
//! for"): a 1.31 M-triangle ico sphere with spherical UVs (a seam where u wraps), complexity
//! 10 %, barycentre, one thread; the call with and without UVs interleaved in one process,
//! stage by stage (the progress callback's names), medians of `runs` (default 5).
//!
//! `cargo run --release -p tessd-simplify --example uv_time [runs] [level] [threads] [shuffle] [groups]`
//! (`shuffle`: vertices renumbered at random, as a mesh whose vertex order has no locality;
//! `groups`: four face groups in bands of z, as materials).
use std::collections::HashMap;
use std::time::Instant;
use tessd_mesh::{FaceVarying, Mesh};
use tessd_simplify::{Count, Method, Representative, SimplifyOptions, simplify};

/// An ico sphere subdivided `level` times (20·4^level triangles).
fn ico_sphere(level: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<[f32; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .to_vec();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(f.len() * 4);
        let mut m = |a: u32, b: u32, p: &mut Vec<[f32; 3]>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (x, y) = (p[a as usize], p[b as usize]);
                p.push(std::array::from_fn(|k| (x[k] + y[k]) / 2.0));
                p.len() as u32 - 1
            })
        };
        for &[a, b, c] in &f {
            let (ab, bc, ca) = (m(a, b, &mut p), m(b, c, &mut p), m(c, a, &mut p));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        f = next;
    }
    for v in &mut p {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.iter_mut().for_each(|x| *x /= l);
    }
    Mesh {
        positions: p,
        face_offsets: (0..=f.len() as u32).map(|i| i * 3).collect(),
        face_indices: f.into_iter().flatten().collect(),
        ..Mesh::default()
    }
}

/// Spherical UVs per corner (Blender's layout: one value per corner, identity indices); a
/// face crossing u = 0/1 takes u + 1 on its low corners, so the seam splits values.
fn corner_uvs(mesh: &Mesh) -> FaceVarying<[f32; 2]> {
    let uv = |p: [f32; 3]| {
        let u = 0.5 + p[1].atan2(p[0]) / std::f32::consts::TAU;
        let v = 0.5 + p[2].clamp(-1.0, 1.0).asin() / std::f32::consts::PI;
        [u, v]
    };
    let mut values = Vec::with_capacity(mesh.face_indices.len());
    for tri in mesh.face_indices.chunks_exact(3) {
        let mut t: Vec<[f32; 2]> = tri
            .iter()
            .map(|&v| uv(mesh.positions[v as usize]))
            .collect();
        let (lo, hi) = t
            .iter()
            .fold((1f32, 0f32), |(l, h), x| (l.min(x[0]), h.max(x[0])));
        if hi - lo > 0.5 {
            t.iter_mut()
                .filter(|x| x[0] < 0.5)
                .for_each(|x| x[0] += 1.0);
        }
        values.extend(t);
    }
    FaceVarying {
        indices: (0..values.len() as u32).collect(),
        values,
    }
}

/// Renumbers the vertices in a fixed pseudo-random order (Fisher–Yates with an LCG).
fn shuffle_vertices(mesh: &mut Mesh) {
    let n = mesh.positions.len();
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for i in (1..n).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        order.swap(i, ((state >> 33) % (i as u64 + 1)) as usize);
    }
    // order[new] = old
    let mut new_of = vec![0u32; n];
    for (new, &old) in order.iter().enumerate() {
        new_of[old as usize] = new as u32;
    }
    mesh.positions = order.iter().map(|&o| mesh.positions[o as usize]).collect();
    mesh.face_indices
        .iter_mut()
        .for_each(|v| *v = new_of[*v as usize]);
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The daemon's allocator (huge pages for mesh-sized buffers), so the times are the daemon's.
#[global_allocator]
static ALLOCATOR: tessd_mesh::allocation::LargePages = tessd_mesh::allocation::LargePages;

fn main() {
    tessd_mesh::allocation::return_large_buffers_to_system();
    let a: Vec<String> = std::env::args().collect();
    let runs: usize = a.get(1).map_or(5, |s| s.parse().unwrap());
    let level: u32 = a.get(2).map_or(8, |s| s.parse().unwrap());
    let threads: usize = a.get(3).map_or(1, |s| s.parse().unwrap());
    let mut plain = ico_sphere(level);
    if a.iter().skip(4).any(|s| s == "shuffle") {
        shuffle_vertices(&mut plain);
    }
    if a.iter().skip(4).any(|s| s == "groups") {
        // Four materials in bands of z, as Blender's material indices.
        let z = |f: usize| plain.positions[plain.face_indices[3 * f] as usize][2];
        plain.face_groups = (0..plain.face_count())
            .map(|f| ((z(f) + 1.0) * 2.0).min(3.0) as u32)
            .collect();
        plain.group_names = (0..4).map(|g| format!("m{g}")).collect();
    }
    let mut with_uvs = plain.clone();
    with_uvs.uvs = Some(corner_uvs(&plain));
    println!(
        "ico sphere: {} triangles, {} corners, {} threads",
        plain.face_count(),
        plain.face_indices.len(),
        threads
    );
    let opts = SimplifyOptions::new(Method::Complexity(Count::Relative(0.1)))
        .with_representative(Representative::Barycenter);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    // stage name -> times, per variant
    let mut times: [Vec<(String, Vec<f64>)>; 2] = [Vec::new(), Vec::new()];
    let (mut uv_values, mut uv_hash) = (0, 0u64);
    for _ in 0..runs {
        for (k, mesh) in [&plain, &with_uvs].into_iter().enumerate() {
            let mut stages = vec![("start".to_string(), Instant::now())];
            let s = pool.install(|| {
                simplify(mesh, &opts, &mut |_, st| {
                    stages.push((st.to_string(), Instant::now()));
                    true
                })
                .unwrap()
            });
            stages.push(("end".into(), Instant::now()));
            if let Some(t) = &s.mesh.uvs {
                uv_values = t.values.len();
                // FNV-1a over the values' bits and the indices: old and new builds compare.
                let words = t.values.iter().flat_map(|v| v.map(f32::to_bits));
                uv_hash = words
                    .chain(t.indices.iter().copied())
                    .fold(0xcbf2_9ce4_8422_2325u64, |h, w| {
                        (h ^ u64::from(w)).wrapping_mul(0x100_0000_01b3)
                    });
            }
            let total = (stages.last().unwrap().1 - stages[0].1).as_secs_f64() * 1e3;
            let mut row: Vec<(String, f64)> = stages
                .windows(2)
                .map(|w| (w[0].0.clone(), (w[1].1 - w[0].1).as_secs_f64() * 1e3))
                .collect();
            row.push(("TOTAL".into(), total));
            for (i, (name, t)) in row.into_iter().enumerate() {
                if times[k].len() <= i {
                    times[k].push((name, Vec::new()));
                }
                times[k][i].1.push(t);
            }
        }
    }
    println!("output uv values: {uv_values}, hash {uv_hash:016x}");
    for (k, label) in ["without uvs", "with uvs"].into_iter().enumerate() {
        let line: Vec<String> = times[k]
            .iter()
            .map(|(n, t)| format!("{n} {:.1}", median(t.clone())))
            .collect();
        println!("{label}: {}", line.join(", "));
    }
}
