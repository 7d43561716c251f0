//! What the CLI tells its user (issue 32): a warning for every attribute a written file drops,
//! what a file really holds (STL's triangles, PLY's seam-split vertices), errors in the CLI's
//! own words (`--cells`, `--out`), lengths with units, and errors that point to the next step.

mod support;

use std::path::Path;
use std::process::Output;

use serde_json::Value;
use support::{run_ok, shared_mesh, tessd};

/// Runs the binary in `dir` with `args`.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    tessd().current_dir(dir).args(args).output().unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs a command that must fail, returning its stderr.
fn fails(dir: &Path, args: &[&str]) -> String {
    let o = run_in(dir, args);
    assert!(!o.status.success(), "should fail: {args:?}\n{}", stdout(&o));
    assert_eq!(o.status.code(), Some(1), "{args:?}");
    stderr(&o)
}

fn mesh(name: &str) -> String {
    shared_mesh(name).display().to_string()
}

/// `tessd stats --json` of a file.
fn stats(dir: &Path, file: &str) -> Value {
    let o = run_ok(tessd().current_dir(dir).args(["stats", "--json", file]));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn convert_says_what_each_file_holds_and_drops() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spot = mesh("spot_triangulated.obj");

    // PLY carries the UVs: 2930 vertices, 295 of them at UV seams split in two.
    let o = run_ok(tessd().current_dir(d).args(["convert", &spot, "s.ply"]));
    println!("{}{}", stdout(&o), stderr(&o));
    assert_eq!(
        stdout(&o).trim(),
        "wrote s.ply (3225 vertices, 5856 faces); 295 vertices added at UV / normal seams \
         (PLY holds one UV and normal per vertex)"
    );
    assert_eq!(stderr(&o), "", "nothing dropped");
    let header = std::fs::read(d.join("s.ply")).unwrap();
    assert!(
        String::from_utf8_lossy(&header[..400]).contains("property float s\nproperty float t\n")
    );
    assert_eq!(stats(d, "s.ply")["stored_vertices"], 3225);

    // STL: the triangles written, and the UVs it cannot hold.
    let o = run_ok(tessd().current_dir(d).args(["convert", &spot, "s.stl"]));
    assert_eq!(stdout(&o).trim(), "wrote s.stl (5856 triangles)");
    assert_eq!(
        stderr(&o),
        "warning: s.stl: dropped uvs (STL cannot carry it)\n"
    );
    let quads = mesh("spot_quadrangulated.obj");
    let o = run_ok(tessd().current_dir(d).args(["convert", &quads, "q.stl"]));
    assert_eq!(
        stdout(&o).trim(),
        "wrote q.stl (5856 triangles: the 2928 faces fan-triangulated, as STL needs)"
    );
    assert_eq!(stats(d, "q.stl")["faces"], 5856);

    // Suzanne has normals (and no UVs): OFF drops them, one line.
    let o = run_ok(
        tessd()
            .current_dir(d)
            .args(["convert", &mesh("suzanne.obj"), "z.off"]),
    );
    let err = stderr(&o);
    assert!(
        err.contains("warning: z.off: dropped normals (OFF cannot carry it)\n"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn every_writing_verb_warns() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spot = mesh("spot_triangulated.obj");
    // simplify
    let o = run_ok(tessd().current_dir(d).args([
        "simplify",
        &spot,
        "a.off",
        "--method",
        "complexity",
        "--target-vertices",
        "50%",
    ]));
    assert_eq!(
        stderr(&o),
        "warning: a.off: dropped uvs (OFF cannot carry it)\n"
    );
    // lod: each per-level file, not the stage (which holds UVs).
    let o = run_ok(tessd().current_dir(d).args([
        "lod",
        &spot,
        "--levels",
        "50%,20%",
        "--out",
        "l.usda",
        "--per-level-dir",
        "lv",
        "--per-level-format",
        "stl",
    ]));
    let err = stderr(&o);
    for i in 0..3 {
        assert!(
            err.contains(&format!(
                "warning: lv{}l_LOD{i}.stl: dropped uvs (STL cannot carry it)\n",
                std::path::MAIN_SEPARATOR
            )),
            "{err}"
        );
    }
    assert!(!err.contains("l.usda"), "{err}");
    // compress: the codec holds positions and triangles only; its result says so.
    let o = run_ok(
        tessd()
            .current_dir(d)
            .args(["compress", &spot, "s.tsc", "--json"]),
    );
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["dropped_attributes"], serde_json::json!(["uvs"]));
    assert_eq!(
        stderr(&o),
        "warning: s.tsc: dropped uvs (the .tsc codec cannot carry it)\n"
    );
    // A streamed PLY input (read in passes) is looked at too.
    run_ok(tessd().current_dir(d).args(["convert", &spot, "s.ply"]));
    let o = run_ok(tessd().current_dir(d).args(["compress", "s.ply", "p.tsc"]));
    assert_eq!(
        stderr(&o),
        "warning: p.tsc: dropped uvs (the .tsc codec cannot carry it)\n"
    );
    // tessellate: B-Rep faces are face groups, which STL cannot hold.
    let crank = tessd_testdata::shared("brep/CrankArm.brep");
    let o = run_ok(tessd().current_dir(d).args([
        "tessellate",
        crank.to_str().unwrap(),
        "c.stl",
        "--tolerance",
        "0.1mm",
    ]));
    assert_eq!(
        stderr(&o),
        "warning: c.stl: dropped face_groups (STL cannot carry it)\n"
    );
}

#[test]
fn errors_name_the_cli_flags() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spot = mesh("spot_triangulated.obj");
    let err = fails(d, &["simplify", &spot, "a.obj", "--method", "grid"]);
    println!("{err}");
    assert!(
        err.contains("method \"grid\" needs `--cells` (cells per axis) or `--cell-size`"),
        "{err}"
    );
    let err = fails(d, &["lod", &spot, "--levels", "50%", "--out", "x.obj"]);
    println!("{err}");
    assert!(
        err.contains("`--out` of `lod` must be a .usda stage"),
        "{err}"
    );
    let err = fails(d, &["compress", &spot, "x.tsc", "--bits", "40"]);
    assert!(err.contains("--bits"), "{err}");
    let err = fails(
        d,
        &[
            "simplify",
            &spot,
            "a.obj",
            "--method",
            "quality",
            "--max-error",
            "-1",
        ],
    );
    assert!(err.contains("`--max-error` must be"), "{err}");
    assert!(!err.contains("`max_error`"), "{err}");
}

#[test]
fn lengths_take_units_with_the_mesh_unit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let spot = mesh("spot_triangulated.obj");
    let simplify = |out: &str, extra: &[&str]| {
        let mut args = vec!["simplify", spot.as_str(), out, "--method", "quality"];
        args.extend_from_slice(extra);
        run_in(d, &args)
    };
    // Without the mesh's unit, a length with one is refused, saying what to add.
    let o = simplify("a.obj", &["--max-error", "5mm"]);
    let err = stderr(&o);
    println!("{err}");
    assert!(!o.status.success());
    assert!(err.contains("`--max-error` \"5mm\" has a unit"), "{err}");
    assert!(err.contains("give `--units`"), "{err}");
    // 5 cm of a mesh in metres is 0.05 model units: the same file as --max-error 0.05.
    run_ok(tessd().current_dir(d).args([
        "simplify",
        &spot,
        "cm.obj",
        "--method",
        "quality",
        "--max-error",
        "5cm",
        "--units",
        "m",
    ]));
    run_ok(tessd().current_dir(d).args([
        "simplify",
        &spot,
        "plain.obj",
        "--method",
        "quality",
        "--max-error",
        "0.05",
    ]));
    let (a, b) = (
        std::fs::read(d.join("cm.obj")).unwrap(),
        std::fs::read(d.join("plain.obj")).unwrap(),
    );
    assert!(a == b, "5cm with --units m and 0.05 differ");
    // 50 mm of a mesh in millimetres is 50 model units: a different (coarser) result.
    run_ok(tessd().current_dir(d).args([
        "simplify",
        &spot,
        "mm.obj",
        "--method",
        "quality",
        "--max-error",
        "5cm",
        "--units",
        "mm",
    ]));
    assert!(std::fs::read(d.join("mm.obj")).unwrap() != a);
    // Grid cells and lod's quality levels take lengths too.
    for (out, size, units) in [("g1.obj", "10cm", Some("m")), ("g2.obj", "0.1", None)] {
        let mut args = vec![
            "simplify",
            spot.as_str(),
            out,
            "--method",
            "grid",
            "--cell-size",
            size,
        ];
        if let Some(u) = units {
            args.extend(["--units", u]);
        }
        run_ok(tessd().current_dir(d).args(&args));
    }
    assert_eq!(
        std::fs::read(d.join("g1.obj")).unwrap(),
        std::fs::read(d.join("g2.obj")).unwrap()
    );
    let o = run_ok(tessd().current_dir(d).args([
        "lod", &spot, "--method", "quality", "--levels", "2cm,10cm", "--units", "m", "--out",
        "l.usda", "--json",
    ]));
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    let tol: Vec<f64> = r["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["tolerance"].as_f64().unwrap())
        .collect();
    assert!(
        (tol[0] - 0.02).abs() < 1e-12 && (tol[1] - 0.1).abs() < 1e-12,
        "{tol:?}"
    );
}

#[test]
fn errors_point_to_the_next_step() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let screw = tessd_testdata::shared("brep/screw.step");
    let err = fails(
        d,
        &[
            "tessellate",
            screw.to_str().unwrap(),
            "out.usda",
            "--tolerance",
            "0.1mm",
        ],
    );
    println!("{err}");
    assert!(
        err.contains("export it first with `python -m tessd.brep export screw.step screw.json`"),
        "{err}"
    );
    assert!(err.contains("OCP"), "{err}");

    let spot = mesh("spot_triangulated.obj");
    let err = fails(d, &["convert", &spot, "x.usdc"]);
    println!("{err}");
    assert!(
        err.contains("expected .obj, .ply, .stl, .off or .usda (a USD stage)"),
        "{err}"
    );
    assert!(
        err.contains("binary USD (.usdc, .usdz, .usd) is not supported: use .usda"),
        "{err}"
    );

    for out in ["out/x.ply", "out/x.usda", "out/x.tsc"] {
        let verb = if out.ends_with(".tsc") {
            "compress"
        } else {
            "convert"
        };
        let err = fails(d, &[verb, &spot, out]);
        println!("{err}");
        assert!(err.contains("the folder"), "{err}");
        let sep = std::path::MAIN_SEPARATOR;
        assert!(
            err.contains(&format!("{sep}out{sep} does not exist")),
            "{err}"
        );
    }
}
