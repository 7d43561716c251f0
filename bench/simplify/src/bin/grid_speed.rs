//! tessd's grid goal against meshoptimizer's simplifySloppy at equal output size, in one
//! process, interleaved, medians (issue 33's grid goals): `grid_speed [triangles] [runs]`.
//! For each fraction of the input's vertices, the grid's cells per axis are searched until
//! its output lands near that count, and simplifySloppy's index target until its output has
//! as many vertices; then both are timed in turns. Set `RAYON_NUM_THREADS` for the threads.

#[path = "../generate.rs"]
mod generate;
#[path = "../mem.rs"]
#[allow(dead_code)]
mod mem;

use meshopt::VertexDataAdapter;
use std::time::Instant;
use tessd_simplify::{GridSize, Method, Representative, SimplifyOptions, simplify};

/// The daemon's allocator (`tessd_mesh::allocation`), so that the figures are the daemon's.
#[global_allocator]
static ALLOCATOR: tessd_mesh::allocation::LargePages = tessd_mesh::allocation::LargePages;

fn main() {
    tessd_mesh::allocation::return_large_buffers_to_system();
    let args: Vec<String> = std::env::args().collect();
    let triangles: u64 = args.get(1).map_or(1_000_000, |a| a.parse().unwrap());
    let runs: usize = args.get(2).map_or(5, |a| a.parse().unwrap());
    let fractions: Vec<f64> = args
        .get(3)
        .map_or("0.5,0.1,0.01".into(), |a: &String| a.clone())
        .split(',')
        .map(|f| f.parse().unwrap())
        .collect();
    let mesh = generate::bumpy_torus(triangles);
    let indices = mesh.face_indices.clone();
    let adapter = VertexDataAdapter::new(bytemuck::cast_slice(&mesh.positions), 12, 0).unwrap();
    let sloppy =
        |target: usize| meshopt::simplify_sloppy(&indices, &adapter, target, f32::MAX, None);
    let distinct = |ix: &[u32]| {
        let mut seen = vec![false; mesh.positions.len()];
        ix.iter()
            .filter(|&&i| !std::mem::replace(&mut seen[i as usize], true))
            .count()
    };
    let grid = |cells: u32, rep: Representative| {
        let o = SimplifyOptions::new(Method::Grid(GridSize::CellsPerAxis(cells)))
            .with_representative(rep);
        simplify(&mesh, &o, &mut |_, _| true).unwrap()
    };
    let nv = mesh.positions.len();
    if fractions.is_empty() || args.get(4).is_some_and(|m| m == "prep") {
        // The preparation's passes one by one (medians of `runs`).
        let med = |f: &mut dyn FnMut()| {
            let mut v: Vec<f64> = (0..runs)
                .map(|_| {
                    let s = Instant::now();
                    f();
                    s.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        if args.get(5).is_some_and(|m| m == "weights") {
            // Only the weights pass, for `perf record`.
            for _ in 0..runs {
                drop(tessd_simplify::weights::vertex_weights(
                    &mesh,
                    tessd_simplify::Weighting::LongestEdge,
                ));
            }
            return;
        }
        let validate = med(&mut || mesh.validate().unwrap());
        let polygons = med(&mut || assert!(!mesh.faces().any(|f| f.len() > 3)));
        let weights = med(&mut || {
            drop(tessd_simplify::weights::vertex_weights(
                &mesh,
                tessd_simplify::Weighting::LongestEdge,
            ))
        });
        println!(
            "prep: validate {validate:.2} ms, polygons {polygons:.2} ms, weights {weights:.2} ms"
        );
        // The preparation stage (until the first progress call) of a mesh of triangles alone,
        // checked inside its passes, against the same mesh with one crease, which takes
        // `Mesh::validate` and the separate passes; interleaved, medians.
        let mut creased = mesh.clone();
        creased.creases.push(tessd_mesh::Crease {
            a: mesh.face_indices[0],
            b: mesh.face_indices[1],
            value: 1.0,
        });
        let o = SimplifyOptions::new(Method::Grid(GridSize::CellsPerAxis(40)));
        let prepare = |m: &tessd_mesh::Mesh| {
            let s = Instant::now();
            let mut t = None;
            simplify(m, &o, &mut |_, _| {
                t.get_or_insert(s.elapsed().as_secs_f64() * 1e3);
                true
            })
            .unwrap();
            t.unwrap()
        };
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for _ in 0..runs {
            a.push(prepare(&mesh));
            b.push(prepare(&creased));
        }
        a.sort_by(f64::total_cmp);
        b.sort_by(f64::total_cmp);
        let (a, b) = (a[runs / 2], b[runs / 2]);
        println!(
            "prepare stage: plain triangles {a:.2} ms, validated {b:.2} ms ({:.2}x)",
            b / a
        );
        return;
    }
    println!(
        "torus {} triangles, {} vertices, RAYON_NUM_THREADS={:?}",
        mesh.face_count(),
        nv,
        std::env::var("RAYON_NUM_THREADS").ok()
    );
    for f in fractions {
        let want = (f * nv as f64) as usize;
        // Cells per axis landing nearest `want` output vertices (counts grow with cells).
        let (mut lo, mut hi) = (1u32, 4096u32);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            if (grid(mid, Representative::Barycenter).report.output_vertices as usize) < want {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let cells = hi;
        let got = grid(cells, Representative::Barycenter)
            .report
            .output_vertices as usize;
        // Sloppy's index target giving as many vertices.
        let (mut a, mut b) = (3usize, indices.len());
        while b - a > 3 {
            let mid = (a + b) / 2;
            if distinct(&sloppy(mid)) < got {
                a = mid;
            } else {
                b = mid;
            }
        }
        let sv = distinct(&sloppy(b));
        // `grid_speed N runs fraction MODE`: only MODE (sloppy, bary, quadric), `runs` times, for `perf stat`.
        if let Some(mode) = args.get(4) {
            if mode == "mem" {
                // Extra peak memory of one call over the input's bytes.
                let input = 12 * mesh.positions.len() + 4 * indices.len();
                for rep in [Representative::Barycenter, Representative::Quadric] {
                    mem::reset_peak();
                    let before = mem::status_kib("VmRSS");
                    let out = grid(cells, rep);
                    let peak = mem::status_kib("VmHWM");
                    let extra = (peak - before) as f64 * 1024.0 / input as f64;
                    println!(
                        "   {rep:?}: extra peak {extra:.2}x the input ({} output vertices)",
                        out.report.output_vertices
                    );
                }
                continue;
            }
            for _ in 0..runs {
                match mode.as_str() {
                    "sloppy" => drop(sloppy(b)),
                    "bary" => drop(grid(cells, Representative::Barycenter)),
                    _ => drop(grid(cells, Representative::Quadric)),
                }
            }
            continue;
        }
        let mut t: [Vec<f64>; 3] = Default::default();
        let time = |f: &mut dyn FnMut()| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        };
        for _ in 0..runs {
            t[0].push(time(&mut || drop(sloppy(b))));
            t[1].push(time(&mut || drop(grid(cells, Representative::Barycenter))));
            t[2].push(time(&mut || drop(grid(cells, Representative::Quadric))));
        }
        // Stage times (between progress callbacks, each named after the stage it starts),
        // averaged over the runs.
        for rep in [Representative::Barycenter, Representative::Quadric] {
            let mut stages: Vec<(String, f64)> = Vec::new();
            for _ in 0..runs {
                let o = SimplifyOptions::new(Method::Grid(GridSize::CellsPerAxis(cells)))
                    .with_representative(rep);
                let mut last = Instant::now();
                let mut prev = String::from("prepare");
                let mut k = 0;
                simplify(&mesh, &o, &mut |_, stage| {
                    let now = Instant::now();
                    let ms = (now - last).as_secs_f64() * 1e3 / runs as f64;
                    if stages.len() <= k {
                        stages.push((prev.clone(), 0.0));
                    }
                    stages[k].1 += ms;
                    k += 1;
                    prev = stage.to_string();
                    last = now;
                    true
                })
                .unwrap();
            }
            let line: Vec<String> = stages.iter().map(|(s, t)| format!("{s} {t:.1}")).collect();
            println!("   {rep:?}: {}", line.join(", "));
        }
        let med = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let m: Vec<f64> = t.iter_mut().map(med).collect();
        println!(
            "{:>5.1}% cells {cells:>4}: tessd {got} v, sloppy {sv} v | sloppy {:.1} ms | \
             grid bary {:.1} ms ({:.2}x) quadric {:.1} ms ({:.2}x)",
            f * 100.0,
            m[0],
            m[1],
            m[0] / m[1],
            m[2],
            m[0] / m[2],
        );
    }
}
