//! Times one simplification of a mesh file (or a generated wavy grid) and prints the report.
//!
//! `cargo run --release -p tessd-simplify --example simplify_file -- IN|grid:TRIANGLES_M
//!  grid:CELLS | quality:TOL | complexity:FRACTION [barycenter|heaviest|quadric]`

use std::time::Instant;
use tessd_mesh::Mesh;
use tessd_simplify::{Count, GridSize, Length, Method, Representative, SimplifyOptions, simplify};

fn wavy_grid(triangles: f64) -> Mesh {
    let n = (triangles / 2.0).sqrt() as u32;
    let mut m = Mesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions
                .push([x, y, 0.05 * (7.0 * x).sin() * (5.0 * y).cos()]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            m.push_face(&[v, v + 1, v + n + 2]);
            m.push_face(&[v, v + n + 2, v + n + 1]);
        }
    }
    m
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mesh = match args[0].strip_prefix("grid:") {
        Some(m) => wavy_grid(m.parse::<f64>().unwrap() * 1e6),
        None => tessd_mesh::io::read_path(args[0].as_ref(), &Default::default()).unwrap(),
    };
    let (kind, value) = args[1].split_once(':').unwrap();
    let v: f64 = value.parse().unwrap();
    let method = match kind {
        "grid" => Method::Grid(GridSize::CellsPerAxis(v as u32)),
        "quality" => Method::Quality(Length::Relative(v)),
        _ => Method::Complexity(Count::Relative(v)),
    };
    let rep = match args.get(2).map(String::as_str) {
        Some("heaviest") => Representative::Heaviest,
        Some("quadric") => Representative::Quadric,
        _ => Representative::Barycenter,
    };
    let options = SimplifyOptions::new(method).with_representative(rep);
    let t = Instant::now();
    let mut last = Instant::now();
    let out = simplify(&mesh, &options, &mut |_, stage| {
        eprintln!("  {:>7.3} s -> {stage}", last.elapsed().as_secs_f64());
        last = Instant::now();
        true
    })
    .unwrap();
    let dt = t.elapsed().as_secs_f64();
    println!(
        "{} triangles in, {:?}: {:.3} s ({:.1} M triangles/s)\n{:#?}",
        mesh.triangle_count(),
        method,
        dt,
        mesh.triangle_count() as f64 / dt / 1e6,
        out.report
    );
}
