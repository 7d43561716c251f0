//! `tessd render` through the real binary: PNG files that decode, the face-id PNG agreeing with
//! the reported coverage, turntables, B-Rep input, and refusals (missing input, sizes out of
//! range, step-2 options) that exit non-zero, name the value and write nothing.

mod support;

use serde_json::Value;
use std::path::{Path, PathBuf};
use support::{run_ok, shared_mesh, tessd};

fn brep(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tessellate/tests/data")
        .join(name)
}

fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    tessd_render::image::decode_png(&bytes).unwrap()
}

/// Files in `dir`, sorted.
fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn renders_the_bunny_with_face_ids_and_timings() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bunny.png");
    let ids = dir.path().join("ids.png");
    let o = run_ok(
        tessd()
            .arg("render")
            .arg(shared_mesh("stanford_bunny.obj"))
            .arg(&out)
            .args(["--size", "320x240", "--view", "front", "--edges", "--json"])
            .arg("--face-ids")
            .arg(&ids),
    );
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (r["width"].as_u64(), r["height"].as_u64()),
        (Some(320), Some(240))
    );
    assert_eq!(r["triangles"], 69451);
    assert_eq!(r["pixels"], 320 * 240);
    for step in ["tessellate", "upload", "draw", "readback", "encode"] {
        assert!(r["timings_ms"][step].as_f64().is_some(), "{step}: {r}");
    }
    assert!(r["adapter"]["name"].as_str().is_some_and(|s| !s.is_empty()));
    let (w, h, color) = decode(&out);
    assert_eq!((w, h), (320, 240));
    // Background grey in the corner, something else where the bunny is.
    assert_eq!(&color[..4], &[224, 224, 224, 255]);
    let (_, _, id_rgba) = decode(&ids);
    let id_values = tessd_render::image::rgba_to_face_ids(&id_rgba);
    let covered = id_values.iter().filter(|&&i| i != 0).count();
    assert_eq!(covered as u64, r["covered"].as_u64().unwrap());
    assert!(covered > 1000);
    // No groups: every covered pixel is face index 0, id 1.
    assert!(id_values.iter().all(|&i| i <= 1));
    assert!(id_rgba.chunks_exact(4).all(|p| p[3] == 255));
    assert_eq!(files(dir.path()), ["bunny.png", "ids.png"]);
}

#[test]
fn renders_a_brep_part_with_one_id_per_face() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("crank.png");
    let ids = dir.path().join("ids.png");
    let o = run_ok(
        tessd()
            .arg("render")
            .arg(brep("CrankArm.json"))
            .arg(&out)
            .args(["--size", "400x300", "--shading", "face-ids", "--json"])
            .arg("--face-ids")
            .arg(&ids),
    );
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    let faces = r["faces"].as_u64().unwrap() as u32;
    assert!(r["tolerance"].as_f64().unwrap() > 0.0);
    let (_, _, rgba) = decode(&ids);
    let mut seen = tessd_render::image::rgba_to_face_ids(&rgba);
    seen.sort_unstable();
    seen.dedup();
    assert!(seen.len() > 10, "{seen:?}");
    assert!(*seen.last().unwrap() <= faces);
}

#[test]
fn turntable_writes_n_frames() {
    let dir = tempfile::tempdir().unwrap();
    let o = run_ok(
        tessd()
            .arg("render")
            .arg(brep("CrankArm.json"))
            .arg(dir.path().join("spin.png"))
            .args(["--size", "64x48", "--turntable", "5", "--json"])
            .arg("--face-ids")
            .arg(dir.path().join("ids.png")),
    );
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["frames"], 5);
    let mut expected: Vec<String> = (0..5).map(|i| format!("spin_{i:03}.png")).collect();
    expected.extend((0..5).map(|i| format!("ids_{i:03}.png")));
    expected.sort();
    assert_eq!(files(dir.path()), expected);
    // The frames differ: the part turns.
    let a = decode(&dir.path().join("spin_000.png")).2;
    let b = decode(&dir.path().join("spin_001.png")).2;
    assert_ne!(a, b);
}

/// Runs a render that must fail; returns its stderr and checks that `dir` stays empty.
fn refused(dir: &Path, args: &[&str], input: &Path) -> String {
    let o = tessd()
        .arg("render")
        .arg(input)
        .arg(dir.join("out.png"))
        .args(args)
        .arg("--face-ids")
        .arg(dir.join("ids.png"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(!o.status.success(), "{args:?} succeeded");
    assert_eq!(files(dir), Vec::<String>::new(), "{args:?} wrote files");
    err
}

#[test]
fn bad_requests_fail_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = shared_mesh("stanford_bunny.obj");
    let err = refused(dir.path(), &[], &dir.path().join("missing.obj"));
    assert!(err.contains("missing.obj"), "{err}");
    for size in ["0x0", "100000x100000", "12"] {
        let err = refused(dir.path(), &["--size", size], &bunny);
        assert!(err.contains(size), "{err}");
    }
    // Ray casting needs exact surfaces: a mesh is refused; a bad crack mode is refused by
    // the argument parser, naming it.
    let err = refused(dir.path(), &["--raycast"], &bunny);
    assert!(err.contains("B-Rep"), "{err}");
    let err = refused(dir.path(), &["--cracks", "sideways"], &bunny);
    assert!(err.contains("sideways"), "{err}");
    let err = refused(dir.path(), &["--fov", "0"], &bunny);
    assert!(err.contains("fov"), "{err}");
    let err = refused(dir.path(), &["--eye", "0,0,0", "--target", "0,0,0"], &bunny);
    assert!(err.contains("same point"), "{err}");
}

#[test]
fn an_explicit_eye_gives_the_same_picture_as_the_equivalent_view() {
    // `--view front` is the eye straight in front of the box centre along −Y: the explicit
    // camera the op reports for it must render the same pixels.
    let dir = tempfile::tempdir().unwrap();
    let bunny = shared_mesh("stanford_bunny.obj");
    let a = dir.path().join("a.png");
    let o = run_ok(
        tessd()
            .arg("render")
            .arg(&bunny)
            .arg(&a)
            .args(["--size", "96x64", "--view", "front", "--json"]),
    );
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    let v = |k: &str| {
        let p = r["camera"][k].as_array().unwrap();
        format!("{},{},{}", p[0], p[1], p[2])
    };
    let b = dir.path().join("b.png");
    run_ok(
        tessd()
            .arg("render")
            .arg(&bunny)
            .arg(&b)
            .args([
                "--size",
                "96x64",
                "--eye",
                &v("eye"),
                "--target",
                &v("target"),
            ])
            .args(["--up", &v("up")]),
    );
    assert_eq!(decode(&a), decode(&b));
}
