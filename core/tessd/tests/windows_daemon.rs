//! The daemon as a Windows user meets it (issue 37), on every platform: the real binary on a
//! fresh endpoint (a named pipe on Windows, run under Wine in CI; a socket elsewhere), driven by
//! the Rust client: `mesh.stats`, `simplify`, `tessellate` of a small B-Rep, a long job
//! cancelled (answered `cancelled`), and a daemon killed outright (`TerminateProcess` on
//! Windows, SIGKILL elsewhere) while it writes a big output: no file at the destination, only
//! the killed writer's temporary file, which the next write into that folder removes.

mod support;

use serde_json::json;
use std::path::Path;
use std::time::{Duration, Instant};
use support::{Daemon, shared_mesh};
use tessd_ipc::arrays::OwnedArray;
use tessd_ipc::client::{Client, ClientError};
use tessd_ipc::error::ErrorCode;

/// The names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A grid of `n` × `n` vertices, two triangles per cell, as mesh arrays.
fn grid(n: u32) -> Vec<OwnedArray> {
    let mut positions = Vec::with_capacity((n * n * 3) as usize);
    for y in 0..n {
        for x in 0..n {
            positions.extend([x as f32 * 0.001, y as f32 * 0.001, ((x ^ y) % 7) as f32]);
        }
    }
    let mut faces = Vec::with_capacity(((n - 1) * (n - 1) * 6) as usize);
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let v = y * n + x;
            faces.extend([v, v + 1, v + n + 1, v, v + n + 1, v + n]);
        }
    }
    let f = faces.len() as u64 / 3;
    vec![
        OwnedArray::new("positions", vec![u64::from(n * n), 3], positions),
        OwnedArray::new("face_indices", vec![f, 3], faces),
    ]
}

#[test]
fn a_client_session_then_a_kill_mid_write_leaves_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    let socket = support::endpoint(dir.path(), "w.sock");
    println!("endpoint {}", socket.display());
    let mut daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();

    // mesh.stats of a file given by its absolute path (C:\... under Wine).
    let spot = shared_mesh("spot_triangulated.obj");
    let (stats, _) = c
        .call("mesh.stats", json!({"input": spot}), &[], |_| {})
        .unwrap();
    println!(
        "mesh.stats: {} vertices, {} triangles",
        stats["vertices"], stats["triangles"]
    );
    assert_eq!(stats["non_manifold_edges"], 0);
    let triangles = stats["triangles"].as_u64().unwrap();
    assert!(triangles > 5000, "{stats}");

    // simplify to half, written beside the test's other files.
    let half = dir.path().join("half.ply");
    let (simplified, _) = c
        .call(
            "simplify",
            json!({
                "input": spot, "method": "complexity", "target_vertices": "50%", "output": half
            }),
            &[],
            |_| {},
        )
        .unwrap();
    let (reread, _) = c
        .call("mesh.stats", json!({"input": half}), &[], |_| {})
        .unwrap();
    let vertices = stats["vertices"].as_u64().unwrap();
    let kept = reread["vertices"].as_u64().unwrap();
    println!(
        "simplify: {vertices} -> {kept} vertices (re-read from {}), target {}",
        half.display(),
        simplified["target_vertices"]
    );
    assert!(kept <= vertices / 2 && kept > vertices / 4, "{simplified}");

    // Windows spellings of paths: a drive with forward slashes, and the verbatim `\\?\`
    // prefix (UNC names need a server: core/ipc/tests/paths.rs checks how they resolve).
    if cfg!(windows) {
        let fwd = std::path::absolute(&spot)
            .unwrap()
            .display()
            .to_string()
            .replace('\\', "/");
        let (again, _) = c
            .call("mesh.stats", json!({"input": fwd}), &[], |_| {})
            .unwrap();
        assert_eq!(again["vertices"], stats["vertices"], "{fwd}");
        let dest = std::path::absolute(dir.path().join("verbatim.ply")).unwrap();
        let verbatim = format!(r"\\?\{}", dest.display());
        c.call(
            "mesh.convert",
            json!({"input": fwd, "output": verbatim}),
            &[],
            |_| {},
        )
        .unwrap();
        println!("paths: read {fwd}, wrote {verbatim}");
        assert!(dest.is_file());
    }

    // tessellate a B-Rep document from the tessellator's fixtures.
    let cube = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tessellate/tests/data/cube.json");
    let brep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(cube).unwrap()).unwrap();
    let (tess, arrays) = c
        .call(
            "tessellate",
            json!({"brep": brep, "tolerance": "0.1%"}),
            &[],
            |_| {},
        )
        .unwrap();
    let (idx, _) = arrays.get::<u32>("face_indices").unwrap().unwrap();
    println!("tessellate: {} triangles", idx.len() / 3);
    assert!(idx.len() / 3 >= 12, "{tess}");

    // A long job, cancelled from its own progress: answered `cancelled`, in well under its 30 s.
    let canceller = c.canceller();
    let t = Instant::now();
    let mut sent = false;
    let e = c
        .call(
            "debug.sleep",
            json!({"seconds": 30, "steps": 300}),
            &[],
            |_| {
                if !sent {
                    sent = canceller.cancel().unwrap();
                }
            },
        )
        .unwrap_err();
    println!(
        "cancel: {e} after {:.0} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    assert!(
        matches!(&e, ClientError::Op(op) if op.code == ErrorCode::Cancelled),
        "{e}"
    );
    assert!(t.elapsed() < Duration::from_secs(10));
    assert!(!canceller.cancel().unwrap(), "nothing runs any more");
    // The connection still serves.
    let (pong, _) = c.call("ping", json!({"echo": 7}), &[], |_| {}).unwrap();
    assert_eq!(pong["echo"], 7);

    // A big output, and the daemon killed as soon as its temporary file appears.
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let big = out_dir.join("big.obj");
    let mesh = grid(1500);
    let writer = std::thread::spawn({
        let (socket, big) = (socket.clone(), big.clone());
        move || {
            let mut c = Client::connect(&socket).unwrap();
            c.call("mesh.convert", json!({"output": big}), &mesh, |_| {})
                .map(|(r, _)| r)
        }
    });
    let t = Instant::now();
    let temp = loop {
        if let Some(name) = names(&out_dir)
            .into_iter()
            .find(|n| n.starts_with(".big.obj.tmp-"))
        {
            break name;
        }
        assert!(!writer.is_finished(), "the write ended before it was seen");
        assert!(t.elapsed() < Duration::from_secs(60), "no temporary file");
        std::thread::sleep(Duration::from_millis(1));
    };
    daemon.0.kill().unwrap();
    daemon.0.wait().unwrap();
    let answer = writer.join().unwrap();
    println!(
        "killed mid-write after {:.0} ms; the client got {answer:?}; left: {:?}",
        t.elapsed().as_secs_f64() * 1e3,
        names(&out_dir)
    );
    assert!(answer.is_err(), "the write completed before the kill");
    // No partial file at the destination: only the killed writer's temporary file.
    assert!(!big.exists());
    assert_eq!(names(&out_dir), [temp]);

    // The next write into that folder (a new process) removes it.
    let next = out_dir.join("next.ply");
    support::run_ok(support::tessd().args(["convert"]).arg(&spot).arg(&next));
    println!("after the next write: {:?}", names(&out_dir));
    assert_eq!(names(&out_dir), ["next.ply"]);
}
