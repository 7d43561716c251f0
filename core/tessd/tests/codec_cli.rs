//! End-to-end tests of `tessd compress` / `tessd decompress` (the binary and the socket ops
//! `codec.compress` / `codec.decompress`): a round trip re-read by the mesh reader, a coarser
//! prefix, bad parameters and a corrupt file (clear errors, nothing left on disk, daemon up).

mod support;

use serde_json::{Value, json};
use std::process::Command;
use support::{Daemon, run_ok, shared_mesh, tessd};
use tessd_ipc::client::Client;

fn run_json(cmd: &mut Command) -> Value {
    serde_json::from_slice(&run_ok(cmd.arg("--json")).stdout).unwrap()
}

#[test]
fn compress_then_decompress_gives_the_quantised_mesh_back() {
    let dir = tempfile::tempdir().unwrap();
    let tsc = dir.path().join("spot.tsc");
    let out = dir.path().join("spot.ply");
    let spot = shared_mesh("spot_triangulated.obj");
    let c = run_json(tessd().arg("compress").arg(&spot).arg(&tsc).args([
        "--bits",
        "14",
        "--min-cell",
        "1000",
        "--ahead",
        "1",
    ]));
    assert_eq!(c["input_triangles"], json!(5856));
    assert_eq!(
        c["bytes"].as_u64().unwrap(),
        std::fs::metadata(&tsc).unwrap().len()
    );
    assert!(c["nsp_cells"].as_u64().unwrap() > 1, "{c}");
    let d = run_json(tessd().arg("decompress").arg(&tsc).arg(&out));
    assert_eq!(d["triangles"], json!(5856));
    assert_eq!(d["bytes_read"], c["bytes"]);
    // the written file, re-read: every vertex within half a grid step of an input vertex
    let step = c["step"].as_f64().unwrap();
    let input = tessd_mesh::io::read_path(&spot, &Default::default()).unwrap();
    let back = tessd_mesh::io::read_path(&out, &Default::default()).unwrap();
    assert_eq!(back.face_count(), 5856);
    assert_eq!(
        back.positions.len(),
        c["vertices"].as_u64().unwrap() as usize
    );
    for p in &back.positions {
        let near = input
            .positions
            .iter()
            .map(|q| {
                (0..3)
                    .map(|a| (p[a] - q[a]).abs() as f64)
                    .fold(0.0, f64::max)
            })
            .fold(f64::MAX, f64::min);
        assert!(
            near <= 0.5 * step + 1e-6,
            "{p:?} is {near} from the input ({step} step)"
        );
    }
    // a prefix: fewer vertices, fewer bytes than the whole at a shallow precision
    let coarse = run_json(
        tessd()
            .arg("decompress")
            .arg(&tsc)
            .arg(dir.path().join("c.obj"))
            .args(["--max-bits", "5"]),
    );
    assert!(
        coarse["vertices"].as_u64() < d["vertices"].as_u64(),
        "{coarse}"
    );
    assert!(
        coarse["bytes_read"].as_u64() < c["bytes"].as_u64(),
        "{coarse}"
    );
}

#[test]
fn bad_parameters_and_a_corrupt_file_are_clear_errors_and_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let socket = support::endpoint(dir.path(), "d.sock");
    let _daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();
    let spot = shared_mesh("spot_triangulated.obj");
    let tsc = dir.path().join("a.tsc");
    let e = c
        .call(
            "codec.compress",
            json!({"input": spot, "output": tsc, "cell_split": 3}),
            &[],
            |_| {},
        )
        .unwrap_err();
    assert!(e.to_string().contains("--cell-split"), "{e}");
    assert!(!tsc.exists());
    let e = c
        .call(
            "codec.compress",
            json!({"input": spot, "output": tsc, "ahead": 7}),
            &[],
            |_| {},
        )
        .unwrap_err();
    assert!(e.to_string().contains("--ahead"), "{e}");
    assert!(!tsc.exists());
    c.call(
        "codec.compress",
        json!({"input": spot, "output": tsc}),
        &[],
        |_| {},
    )
    .unwrap();
    let mut bytes = std::fs::read(&tsc).unwrap();
    bytes.truncate(bytes.len() / 2);
    let bad = dir.path().join("bad.tsc");
    std::fs::write(&bad, &bytes).unwrap();
    let out = dir.path().join("out.ply");
    let e = c
        .call(
            "codec.decompress",
            json!({"input": bad, "output": out}),
            &[],
            |_| {},
        )
        .unwrap_err();
    assert!(e.to_string().contains("byte offset"), "{e}");
    assert!(!out.exists());
    // without an output the mesh comes back as arrays; the daemon is still up
    let (r, arrays) = c
        .call("codec.decompress", json!({"input": tsc}), &[], |_| {})
        .unwrap();
    assert_eq!(
        arrays.desc("positions").unwrap().shape[0],
        r["vertices"].as_u64().unwrap()
    );
    let mut files: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    // On Windows the daemon's endpoint is a named pipe, not a file here.
    if cfg!(windows) {
        assert_eq!(files, ["a.tsc", "bad.tsc"]);
    } else {
        assert_eq!(files, ["a.tsc", "bad.tsc", "d.sock", "d.sock.lock"]);
    }
}

#[test]
fn a_version_1_file_is_refused_naming_its_version() {
    // suzanne at 10 bits, written by the format-1 tessd (core/codec/tests/data)
    let v1 = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../codec/tests/data/suzanne_v1_p10.tsc");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.ply");
    let r = tessd()
        .arg("decompress")
        .arg(&v1)
        .arg(&out)
        .output()
        .unwrap();
    assert!(!r.status.success());
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("byte offset 4")
            && err.contains("written by format version 1 (an older tessd)")
            && err.contains("compress the mesh again"),
        "{err}"
    );
    assert!(!out.exists());
}
