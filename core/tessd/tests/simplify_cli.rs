//! End-to-end tests of `tessd simplify`, `tessd lod` and `tessd compare` (the binary, job
//! files and the socket): known answers, partition output, errors, LOD stages. usd-core checks
//! of the stages are in `tests/simplify/` (pytest).

mod support;

use support::{Daemon, run_ok, shared_mesh, tessd};

use serde_json::{Value, json};
use std::path::Path;
use std::process::Command;
use tessd_ipc::client::Client;

/// Runs a verb with `--json` and parses its result.
fn run_json(cmd: &mut Command) -> Value {
    serde_json::from_slice(&run_ok(cmd.arg("--json")).stdout).unwrap()
}

/// Runs a command that must fail with exit code 1; returns its stderr.
fn run_err(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(1),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn write_obj(path: &Path, positions: &[[f32; 3]], faces: &[&[u32]]) {
    let mut s = String::new();
    for p in positions {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for f in faces {
        s += "f";
        for i in *f {
            s += &format!(" {}", i + 1);
        }
        s += "\n";
    }
    std::fs::write(path, s).unwrap();
}

fn obj_positions(path: &Path) -> Vec<[f32; 3]> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| {
            let c: Vec<f32> = l[2..]
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            [c[0], c[1], c[2]]
        })
        .collect()
}

/// Corner `i` (bits x, y, z) of the unit cube.
fn cube_corners() -> Vec<[f32; 3]> {
    (0..8)
        .map(|i| std::array::from_fn(|k| (i >> k & 1) as f32))
        .collect()
}

const CUBE_TRIS: [&[u32]; 12] = [
    &[0, 3, 1],
    &[0, 2, 3],
    &[4, 5, 7],
    &[4, 7, 6],
    &[0, 1, 5],
    &[0, 5, 4],
    &[1, 3, 7],
    &[1, 7, 5],
    &[3, 2, 6],
    &[3, 6, 7],
    &[2, 0, 4],
    &[2, 4, 6],
];

fn sorted(mut v: Vec<[f32; 3]>) -> Vec<[f32; 3]> {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v
}

#[test]
fn heaviest_vertex_keeps_exactly_the_cube_corners() {
    let dir = tempfile::tempdir().unwrap();
    let cube = dir.path().join("cube.obj");
    write_obj(&cube, &cube_corners(), &CUBE_TRIS);
    let out = dir.path().join("out.obj");
    // The coarsest tolerance below the edge length: a heaviest vertex never moves a corner
    // onto another, so all 8 stay, exactly.
    let r = run_json(
        tessd()
            .arg("simplify")
            .args([&cube, &out])
            .args(["--method", "quality", "--max-error", "0.99"])
            .args(["--representative", "heaviest"]),
    );
    assert_eq!(
        (&r["output_vertices"], &r["output_faces"], &r["clusters"]),
        (&json!(8), &json!(12), &json!(8))
    );
    assert_eq!(r["max_displacement"], json!(0.0));
    assert_eq!(sorted(obj_positions(&out)), sorted(cube_corners()));
    // The barycentre is within √3/2 of every corner, so the paper's partition keeps one cell
    // and every face collapses onto a point that is no output vertex: the cube's surface
    // would be covered by nothing. The coverage rounds split until it is.
    let r = run_json(tessd().arg("simplify").args([&cube, &out]).args([
        "--method",
        "quality",
        "--max-error",
        "0.99",
    ]));
    assert!(r["refinement_rounds"].as_u64().unwrap() >= 1, "{r}");
    assert_eq!(r["uncovered_faces"], json!(0));
    assert!(r["output_faces"].as_u64().unwrap() > 0, "{r}");
    assert!(r["surface_error"].as_f64().unwrap() <= 0.99, "{r}");
}

#[test]
fn stacked_boxes_report_every_duplicate() {
    const QUADS: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let dir = tempfile::tempdir().unwrap();
    // Two unit boxes stacked along z, each with its own vertices: A's top is B's bottom,
    // reversed.
    let mut positions = cube_corners();
    positions.extend(cube_corners().iter().map(|p| [p[0], p[1], p[2] + 1.0]));
    let mut faces: Vec<Vec<u32>> = QUADS.iter().map(|q| q.to_vec()).collect();
    faces.extend(QUADS.iter().map(|q| q.iter().map(|i| i + 8).collect()));
    // Doubled facets: as is, reversed, and from another start corner.
    faces.extend([vec![0, 1, 5, 4], vec![13, 15, 11, 9], vec![6, 7, 3, 2]]);
    let refs: Vec<&[u32]> = faces.iter().map(Vec::as_slice).collect();
    let mesh = dir.path().join("stacked.obj");
    write_obj(&mesh, &positions, &refs);
    let r = run_json(
        tessd()
            .arg("simplify")
            .arg(&mesh)
            .arg(dir.path().join("out.obj"))
            // Every position its own cell (the adaptive goals triangulate, and a reversed quad
            // split along its other diagonal is no duplicate).
            .args(["--method", "grid", "--cells", "4"]),
    );
    assert_eq!(r["duplicate_faces"], json!(4));
    assert_eq!(r["degenerate_faces"], json!(0));
    assert_eq!(r["output_vertices"], json!(12));
    assert_eq!(r["output_faces"], json!(11));
}

#[test]
fn partition_wire_boxes_match_the_clusters() {
    let dir = tempfile::tempdir().unwrap();
    let boxes = dir.path().join("boxes.obj");
    let r = run_json(
        tessd()
            .arg("simplify")
            .arg(shared_mesh("spot_triangulated.obj"))
            .arg(dir.path().join("out.ply"))
            .args(["--method", "complexity", "--target-vertices", "5%"])
            .arg("--partition")
            .arg(&boxes),
    );
    assert_eq!(r["output_vertices"], json!(147));
    let c = r["clusters"].as_u64().unwrap() as usize;
    assert_eq!(r["cells"], json!(c));
    let text = std::fs::read_to_string(&boxes).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 8 * c);
    assert_eq!(text.lines().filter(|l| l.starts_with("l ")).count(), 12 * c);
}

#[test]
fn bad_options_fail_clearly_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let spot = shared_mesh("spot_triangulated.obj");
    let out = dir.path().join("out.obj");
    let simplify = |args: &[&str]| {
        let mut c = tessd();
        c.arg("simplify").args([&spot, &out]).args(args);
        c
    };
    // The CLI's messages name its flags (the daemon's name the parameters).
    for (args, message) in [
        (
            &["--method", "quality", "--max-error", "-1"][..],
            "invalid_request: `--max-error` must be positive, got -1",
        ),
        (
            &["--method", "quality", "--max-error", "abc%"],
            "`--max-error` must be a positive number or a percentage",
        ),
        (
            &["--method", "quality", "--max-error", "NaN%"],
            "`--max-error` must be a positive number or a percentage",
        ),
        (
            &["--method", "quality"],
            "method \"quality\" needs `--max-error`",
        ),
        (
            &["--method", "complexity", "--target-vertices", "2930"],
            "`--target-vertices`: the target of 2930 vertices must be between 1 and the input's 2930",
        ),
        (
            &["--method", "complexity", "--target-vertices", "0%"],
            "`--target-vertices` must be positive, got 0%",
        ),
        (
            &["--method", "grid", "--cells", "0"],
            "`--cells` must be a positive integer",
        ),
        (
            &["--method", "grid", "--cell-size", "-2"],
            "`--cell-size` must be a positive number",
        ),
    ] {
        let stderr = run_err(&mut simplify(args));
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    }
    // A mesh without faces.
    let empty = dir.path().join("empty.obj");
    std::fs::write(&empty, "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    let stderr = run_err(
        tessd()
            .arg("simplify")
            .args([&empty, &out])
            .args(["--method", "grid", "--cells", "2"]),
    );
    assert!(
        stderr.contains("invalid_mesh: the mesh has no faces"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn job_file_runs_the_same_simplify_as_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(shared_mesh("suzanne.obj"), dir.path().join("suzanne.obj")).unwrap();
    let job = json!({"op": "simplify", "params": {
        "input": "suzanne.obj", "output": "job.obj", "method": "quality", "max_error": "2%",
        "representative": "quadric", "preserve_boundaries": true}});
    let job_path = dir.path().join("job.json");
    std::fs::write(&job_path, job.to_string()).unwrap();
    let out = run_ok(tessd().args(["job", "run"]).arg(&job_path).current_dir("/"));
    let line: Value = serde_json::from_slice(&out.stdout).unwrap();
    let cli = run_json(
        tessd()
            .args(["simplify", "suzanne.obj", "cli.obj"])
            .args(["--method", "quality", "--max-error", "2%"])
            .args(["--representative", "quadric", "--preserve-boundaries"])
            .current_dir(dir.path()),
    );
    let mut from_job = line["result"].clone();
    from_job["output"] = Value::Null;
    let mut from_cli = cli.clone();
    from_cli["output"] = Value::Null;
    assert_eq!(from_job, from_cli);
    assert_eq!(
        std::fs::read(dir.path().join("job.obj")).unwrap(),
        std::fs::read(dir.path().join("cli.obj")).unwrap()
    );
}

#[test]
fn compare_measures_a_translation() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.obj");
    let b = dir.path().join("b.obj");
    write_obj(&a, &cube_corners(), &CUBE_TRIS);
    let moved: Vec<[f32; 3]> = cube_corners()
        .iter()
        .map(|p| [p[0] + 0.25, p[1], p[2]])
        .collect();
    write_obj(&b, &moved, &CUBE_TRIS);
    let c = run_json(
        tessd()
            .arg("compare")
            .args([&a, &b])
            .args(["--samples", "20000"]),
    );
    // Exact up to the rounding of the closest-point arithmetic.
    for d in [&c["hausdorff"], &c["a_to_b"]["max"], &c["b_to_a"]["max"]] {
        assert!((d.as_f64().unwrap() - 0.25).abs() < 1e-12, "{c}");
    }
    let rms = c["rms"].as_f64().unwrap();
    assert!(rms > 0.0 && rms <= 0.25, "{c}");
    let diagonal = c["bbox_diagonal"].as_f64().unwrap();
    assert!((diagonal - (1.25f64.powi(2) + 2.0).sqrt()).abs() < 1e-12);
    assert!((c["hausdorff_relative"].as_f64().unwrap() - 0.25 / diagonal).abs() < 1e-12);
    let same = run_json(tessd().arg("compare").args([&a, &a]));
    assert!(same["hausdorff"].as_f64().unwrap() < 1e-12, "{same}");
    let text = run_ok(
        tessd()
            .arg("compare")
            .args([&a, &b])
            .args(["--samples", "1000"]),
    );
    let text = String::from_utf8(text.stdout).unwrap();
    assert!(text.contains("\nHausdorff 0.25"), "{text}");
}

#[test]
fn lod_writes_variants_usdlod_and_per_level_files() {
    let dir = tempfile::tempdir().unwrap();
    let spot = shared_mesh("spot_triangulated.obj");
    let variants = dir.path().join("v.usda");
    let r = run_json(
        tessd()
            .arg("lod")
            .arg(&spot)
            .args(["--levels", "50%,20%,5%", "--out"])
            .arg(&variants)
            .arg("--per-level-dir")
            .arg(dir.path().join("levels")),
    );
    let counts: Vec<u64> = r["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["output_vertices"].as_u64().unwrap())
        .collect();
    assert_eq!(counts, [1465, 586, 147]);
    let text = std::fs::read_to_string(&variants).unwrap();
    assert!(text.contains("prepend variantSets = \"LOD\""));
    for i in 0..4 {
        assert!(text.contains(&format!("        \"LOD{i}\" {{\n")), "LOD{i}");
        let level = dir.path().join(format!("levels/v_LOD{i}.obj"));
        assert!(level.exists(), "{}", level.display());
    }
    assert!(!text.contains("LOD4"));

    let usdlod = dir.path().join("u.usda");
    run_json(
        tessd()
            .arg("lod")
            .arg(&spot)
            .args(["--levels", "50%,20%,5%", "--lod-schema", "usdlod", "--out"])
            .arg(&usdlod),
    );
    let text = std::fs::read_to_string(&usdlod).unwrap();
    assert!(text.contains("prepend apiSchemas = [\"LODRootAPI\"]"));
    assert!(text.contains("rel lod:heuristics = </Root/spot_triangulated_lodHeuristic>"));
    assert!(text.contains("def LODScreenSizeHeuristic \"spot_triangulated_lodHeuristic\""));
    assert_eq!(text.matches("token visibility = \"invisible\"").count(), 3);
    assert_eq!(text.matches("token visibility = \"inherited\"").count(), 1);
}

#[test]
fn socket_returns_the_partition_as_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let socket = support::endpoint(dir.path(), "d.sock");
    let _daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();
    let spot = shared_mesh("spot_triangulated.obj");
    let (r, arrays) = c
        .call(
            "simplify",
            json!({"input": spot, "method": "grid", "cells": 8, "partition": true}),
            &[],
            |_| {},
        )
        .unwrap();
    let n = r["clusters"].as_u64().unwrap();
    for name in ["cells_min", "cells_max"] {
        let d = arrays.desc(name).unwrap();
        assert_eq!((d.dtype.name(), d.shape.as_slice()), ("f32", &[n, 3][..]));
    }
    let d = arrays.desc("positions").unwrap();
    assert_eq!(d.shape, [r["output_vertices"].as_u64().unwrap(), 3]);
    // An error keeps the connection usable.
    let e = c
        .call(
            "simplify",
            json!({"input": spot, "method": "grid", "cells": 8, "cell_size": 1.0}),
            &[],
            |_| {},
        )
        .unwrap_err();
    assert!(e.to_string().contains("not both"), "{e}");
    let (pong, _) = c.call("ping", json!({"echo": 1}), &[], |_| {}).unwrap();
    assert_eq!(pong["echo"], json!(1));
}
