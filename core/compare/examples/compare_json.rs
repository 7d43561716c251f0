//! `compare_json A B [--samples N] [--seed S] [--no-vertices] [--edges]`
//!
//! Reads two meshes (OBJ, PLY, STL, OFF), compares them in both directions and prints the
//! [`Comparison`](tessd_compare::Comparison) as one JSON object, with the sample counts and
//! the wall time of each direction (`a_to_b`: index of B + sampling of A and queries, also
//! given separately; file reading excluded). Results are those of `tessd_compare::compare`.
//! Used by `tests/compare/test_vs_meshlab.py`. Threads: `RAYON_NUM_THREADS`.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;
use tessd_compare::{CompareOptions, Comparison, Distance, SurfaceIndex, bbox_diagonal};
use tessd_mesh::Mesh;
use tessd_mesh::io::{ReadOptions, read_path};

const USAGE: &str = "usage: compare_json A B [--samples N] [--seed S] [--no-vertices] [--edges]";

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("compare_json: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let mut args = std::env::args().skip(1);
    let mut paths = Vec::new();
    let mut opts = CompareOptions::default();
    while let Some(a) = args.next() {
        let mut value = |name: &str| {
            args.next()
                .ok_or_else(|| format!("{name} needs a value\n{USAGE}"))
        };
        match a.as_str() {
            "--samples" => {
                let v = value("--samples")?;
                opts = opts.with_samples(v.parse().map_err(|e| format!("--samples {v}: {e}"))?);
            }
            "--seed" => {
                let v = value("--seed")?;
                opts = opts.with_seed(v.parse().map_err(|e| format!("--seed {v}: {e}"))?);
            }
            "--no-vertices" => opts = opts.with_vertices(false),
            "--edges" => opts = opts.with_edges(true),
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            _ if a.starts_with("--") => return Err(format!("unknown option {a}\n{USAGE}")),
            _ => paths.push(a),
        }
    }
    let [pa, pb] = paths.as_slice() else {
        return Err(USAGE.to_string());
    };
    let t = Instant::now();
    let read =
        |p: &str| read_path(Path::new(p), &ReadOptions::default()).map_err(|e| e.to_string());
    let (a, b) = (read(pa)?, read(pb)?);
    let load_s = t.elapsed().as_secs_f64();
    // `one_sided`, split in its two stages to time them.
    let direction = |from: &Mesh, to: &Mesh| -> Result<(Distance, f64, f64), String> {
        let t = Instant::now();
        let index = SurfaceIndex::new(to).map_err(|e| e.to_string())?;
        let build_s = t.elapsed().as_secs_f64();
        let d = index
            .distance_from(from, &opts)
            .map_err(|e| e.to_string())?;
        Ok((d, build_s, t.elapsed().as_secs_f64() - build_s))
    };
    let (ab, ab_build, ab_measure) = direction(&a, &b)?;
    let (ba, ba_build, ba_measure) = direction(&b, &a)?;
    let c = Comparison::from_directions(ab, ba, bbox_diagonal(&a, &b));
    let (ab_s, ba_s) = (ab_build + ab_measure, ba_build + ba_measure);
    println!(
        "{{\"a\": {}, \"b\": {}, \"triangles_a\": {}, \"triangles_b\": {}, \"a_to_b\": {}, \
         \"b_to_a\": {}, \"hausdorff\": {}, \"mean\": {}, \"rms\": {}, \"bbox_diagonal\": {}, \
         \"time_s\": {{\"load\": {load_s}, \"a_to_b\": {ab_s}, \"b_to_a\": {ba_s}, \
         \"a_to_b_index\": {ab_build}, \"a_to_b_sampling\": {ab_measure}, \
         \"b_to_a_index\": {ba_build}, \"b_to_a_sampling\": {ba_measure}}}, \
         \"threads\": {}}}",
        json_str(pa),
        json_str(pb),
        a.triangle_count(),
        b.triangle_count(),
        distance_json(&c.a_to_b),
        distance_json(&c.b_to_a),
        c.hausdorff,
        c.mean,
        c.rms,
        c.bbox_diagonal,
        rayon::current_num_threads(),
    );
    Ok(())
}

fn distance_json(d: &Distance) -> String {
    let p = |v: [f64; 3]| format!("[{}, {}, {}]", v[0], v[1], v[2]);
    format!(
        "{{\"max\": {}, \"mean\": {}, \"rms\": {}, \"samples\": {}, \"area\": {}, \
         \"argmax_point\": {}, \"argmax_closest\": {}}}",
        d.max,
        d.mean,
        d.rms,
        d.samples,
        d.area,
        p(d.argmax_point),
        p(d.argmax_closest)
    )
}

fn json_str(s: &str) -> String {
    let mut o = String::from("\"");
    for ch in s.chars() {
        match ch {
            '"' => o.push_str("\\\""),
            '\\' => o.push_str("\\\\"),
            c if (c as u32) < 0x20 => o.push_str(&format!("\\u{:04x}", c as u32)),
            c => o.push(c),
        }
    }
    o.push('"');
    o
}
