//! The quality goal's surface guarantee as a table: every shared mesh and every adversarial
//! mesh of `tests/adversarial` at 5 %, 1 %, 0.5 % and 0.1 % of its largest side — tolerance,
//! largest vertex displacement, reported surface bound, the measured Hausdorff distance both
//! ways (tessd-compare: every vertex, every edge and 1 M face samples per direction), output
//! vertices and coverage rounds; then the complexity goal at 10 %: its reported bound beside
//! the measured distance.
//!
//! `cargo run --release -p tessd-simplify --example surface_guarantee -- SHARED_MESH_DIR > table.md`
//! (`bash bench/run_simplify_guarantee.sh` writes `bench/results/simplify_guarantee.md`).

#[path = "../tests/adversarial/mod.rs"]
mod adversarial;

use std::path::PathBuf;
use std::time::Instant;
use tessd_compare::{CompareOptions, compare};
use tessd_mesh::Mesh;
use tessd_mesh::io::{ReadOptions, read_path};
use tessd_simplify::{Count, Length, Method, Simplified, SimplifyOptions, simplify};

fn run(mesh: &Mesh, method: Method) -> (Simplified, f64) {
    let t = Instant::now();
    let s = simplify(mesh, &SimplifyOptions::new(method), &mut |_, _| true).expect("simplifies");
    (s, t.elapsed().as_secs_f64() * 1e3)
}

fn main() {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .expect("usage: surface_guarantee MESH_DIR"),
    );
    let mut inputs: Vec<(String, Mesh)> = Vec::new();
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("mesh folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| {
            p.extension()
                .is_some_and(|e| ["obj", "ply", "off"].contains(&e.to_str().unwrap_or("")))
        })
        .collect();
    files.sort();
    for f in files {
        let m = read_path(&f, &ReadOptions::default()).expect("readable mesh");
        inputs.push((f.file_name().unwrap().to_string_lossy().into_owned(), m));
    }
    for (name, m) in adversarial::all() {
        inputs.push((format!("*{name}*"), m));
    }
    let options = CompareOptions::default()
        .with_samples(1_000_000)
        .with_edges(true);
    println!(
        "| input | tolerance | tol (units) | max displacement / tol | surface_error / tol | \
         measured in→out / tol | measured out→in / tol | output vertices | rounds | ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut worst: f64 = 0.0;
    for (name, mesh) in &inputs {
        for fraction in [0.05, 0.01, 0.005, 0.001] {
            let (s, ms) = run(mesh, Method::Quality(Length::Relative(fraction)));
            let r = &s.report;
            let tol = r.tolerance.expect("quality");
            let c = compare(mesh, &s.mesh, &options).expect("measurable");
            worst = worst.max(c.hausdorff / tol);
            println!(
                "| {name} | {} % | {tol:.4e} | {:.3} | {} | {:.3} | {:.3} | {} | {} | {ms:.1} |",
                fraction * 100.0,
                r.max_displacement / tol,
                r.surface_error
                    .map_or("–".to_string(), |e| format!("{:.3}", e / tol)),
                c.a_to_b.max / tol,
                c.b_to_a.max / tol,
                r.output_vertices,
                r.refinement_rounds,
            );
        }
    }
    println!("\nLargest measured symmetric Hausdorff distance: **{worst:.3} × the tolerance**.\n");
    println!("Complexity goal at 10 % of the vertices: the reported bound beside the measure.\n");
    println!(
        "| input | target | output vertices | surface_error | measured Hausdorff | bound / measured | \
         faces off the output |"
    );
    println!("|---|---|---|---|---|---|---|");
    for (name, mesh) in &inputs {
        let (s, _) = run(mesh, Method::Complexity(Count::Relative(0.1)));
        let r = &s.report;
        let Ok(c) = compare(mesh, &s.mesh, &options) else {
            println!(
                "| {name} | {:?} | {} | – | – | – | – |",
                r.target_vertices, r.output_vertices
            );
            continue;
        };
        let e = r.surface_error.unwrap_or(f64::NAN);
        println!(
            "| {name} | {} | {} | {e:.4e} | {:.4e} | {:.2} | {} |",
            r.target_vertices.unwrap_or(0),
            r.output_vertices,
            c.hausdorff,
            e / c.hausdorff,
            r.uncovered_faces,
        );
    }
}
