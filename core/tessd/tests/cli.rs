//! End-to-end tests of the `tessd` binary: CLI verbs, job files versus the socket, the
//! daemon's lifecycle (live-socket refusal, stale sockets, signals, permissions).

mod support;

use support::{Daemon, run_ok, shared_mesh, tessd};

use serde_json::{Value, json};
use tessd_ipc::client::Client;

#[test]
fn stats_json_matches_manifest_counts() {
    let out = run_ok(
        tessd()
            .args(["stats", "--json"])
            .arg(shared_mesh("stanford_bunny.obj")),
    );
    let s: Value = serde_json::from_slice(&out.stdout).unwrap();
    // MANIFEST.md: 35947 vertices of which 1113 unreferenced, 69451 triangles, 223 boundary
    // edges in 5 loops.
    assert_eq!(s["stored_vertices"], 35947);
    assert_eq!(s["vertices"], 35947 - 1113);
    assert_eq!(s["faces"], 69451);
    assert_eq!(s["triangles"], 69451);
    assert_eq!(s["boundary_edges"], 223);
    assert_eq!(s["boundary_loops"], 5);
    assert_eq!(s["non_manifold_edges"], 0);
    let out = run_ok(
        tessd()
            .args(["stats", "--json"])
            .arg(shared_mesh("mpi_polygons.off")),
    );
    let s: Value = serde_json::from_slice(&out.stdout).unwrap();
    // MANIFEST.md: face sizes 3:13, 4:12, 5:2, 6:10, 7:3, 8:6, 9:2, 10:4.
    assert_eq!(
        s["face_sizes"],
        json!({"3": 13, "4": 12, "5": 2, "6": 10, "7": 3, "8": 6, "9": 2, "10": 4})
    );
    let tri: u64 = [
        (3, 13),
        (4, 12),
        (5, 2),
        (6, 10),
        (7, 3),
        (8, 6),
        (9, 2),
        (10, 4),
    ]
    .iter()
    .map(|(n, c)| (n - 2) * c)
    .sum();
    assert_eq!(s["triangles"], tri);
}

#[test]
fn convert_rejects_unknown_format_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("out.xyz");
    let out = tessd()
        .arg("convert")
        .arg(shared_mesh("suzanne.obj"))
        .arg(&out_path)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("xyz"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn truncated_input_fails_naming_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap();
    let out = tessd().arg("stats").arg(&bad).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(":4") && err.contains('7'), "{err}");
}

#[test]
fn job_file_matches_socket_and_writes_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let src = shared_mesh("spot_quadrangulated.obj");
    std::fs::copy(&src, dir.path().join("spot.obj")).unwrap();
    let job = json!({"jobs": [
        {"op": "mesh.stats", "params": {"input": "spot.obj"}},
        {"op": "mesh.convert", "params": {"input": "spot.obj", "output": "spot.ply"}},
    ]});
    let job_path = dir.path().join("job.json");
    std::fs::write(&job_path, job.to_string()).unwrap();
    // Run from another folder: relative paths resolve against the job file's folder.
    let out = run_ok(tessd().args(["job", "run"]).arg(&job_path).current_dir("/"));
    let lines: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2);
    assert!(dir.path().join("spot.ply").exists());

    let socket = support::endpoint(dir.path(), "d.sock");
    let _daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();
    let (over_socket, _) = c
        .call(
            "mesh.stats",
            json!({"input": dir.path().join("spot.obj")}),
            &[],
            |_| {},
        )
        .unwrap();
    assert_eq!(lines[0]["result"], over_socket);
    // The converted file is the same surface again, its vertices split at the UV seams (PLY
    // holds one UV per vertex): 295 more vertices, the same faces and bounds.
    let (ply_stats, _) = c
        .call(
            "mesh.stats",
            json!({"input": dir.path().join("spot.ply")}),
            &[],
            |_| {},
        )
        .unwrap();
    for key in [
        "faces",
        "triangles",
        "face_sizes",
        "bounds",
        "non_manifold_edges",
    ] {
        assert_eq!(ply_stats[key], over_socket[key], "{key}");
    }
    assert_eq!(ply_stats["stored_vertices"], 2930 + 295);
    assert_eq!(lines[1]["result"]["written"]["split_vertices"], 295);
    assert_eq!(lines[1]["result"]["dropped_attributes"], json!([]));
}

#[test]
fn daemon_lifecycle() {
    let dir = tempfile::tempdir().unwrap();
    let socket = support::endpoint(dir.path(), "life.sock");
    // Windows: console events reach only processes attached to a console; a test run without
    // one (Wine without a terminal, CI) gets its own, which the daemon inherits.
    #[cfg(windows)]
    {
        #[link(name = "kernel32")]
        unsafe extern "system" {
            fn AllocConsole() -> i32;
        }
        // SAFETY: a plain call; it fails harmlessly when a console is already attached.
        unsafe { AllocConsole() };
    }
    let mut daemon = Daemon::start(&socket);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&socket).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
    }
    // A second daemon on a live socket refuses, and the first keeps serving.
    let second = tessd()
        .arg("serve")
        .arg("--socket")
        .arg(&socket)
        .output()
        .unwrap();
    assert_eq!(second.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&second.stderr).contains("already serving"));
    let mut c = Client::connect(&socket).unwrap();
    assert_eq!(
        c.call("ping", json!({"echo": 5}), &[], |_| {}).unwrap().0["echo"],
        5
    );
    // `elapsed_ms` is on operations' replies only (not `ping`'s).
    assert_eq!(c.last_elapsed_ms(), None);
    c.call("debug.sleep", json!({"seconds": 0.01}), &[], |_| {})
        .unwrap();
    assert!(c.last_elapsed_ms().is_some_and(|ms| ms >= 10.0));
    // SIGTERM (Ctrl-Break on Windows): clean exit, socket removed.
    #[cfg(unix)]
    {
        // SAFETY: kill() with a valid pid and signal number.
        unsafe { libc::kill(daemon.0.id() as i32, libc::SIGTERM) };
    }
    // Windows: Ctrl-Break to the daemon's process group, which its console handler takes as
    // SIGTERM. Wine 8 cannot send a console event to a process group (GenerateConsoleCtrlEvent
    // fails with or without a console; its handler does run for a Ctrl-C typed on a terminal),
    // so there the shutdown request stands in.
    #[cfg(windows)]
    {
        #[link(name = "kernel32")]
        unsafe extern "system" {
            fn GenerateConsoleCtrlEvent(event: u32, group: u32) -> i32;
            fn GetModuleHandleA(name: *const u8) -> *mut std::ffi::c_void;
            fn GetProcAddress(
                module: *mut std::ffi::c_void,
                name: *const u8,
            ) -> *mut std::ffi::c_void;
        }
        const CTRL_BREAK_EVENT: u32 = 1;
        // SAFETY: NUL-terminated names; ntdll is always loaded; Wine's exports `wine_get_version`.
        let wine = unsafe {
            !GetProcAddress(
                GetModuleHandleA(c"ntdll.dll".as_ptr().cast()),
                c"wine_get_version".as_ptr().cast(),
            )
            .is_null()
        };
        if wine {
            c.call("shutdown", json!({}), &[], |_| {}).unwrap();
        } else {
            // SAFETY: a plain call; the group is the daemon's own (Daemon::start made it one).
            let sent = unsafe { GenerateConsoleCtrlEvent(CTRL_BREAK_EVENT, daemon.0.id()) };
            assert_ne!(sent, 0, "{}", std::io::Error::last_os_error());
        }
    }
    assert!(daemon.wait_exit().success());
    assert!(!socket.exists());
    drop(daemon);

    // A stale socket file (nobody listening) is replaced. Unix only: a named pipe leaves no
    // file behind.
    #[cfg(unix)]
    {
        let stale = std::os::unix::net::UnixListener::bind(&socket).unwrap();
        drop(stale);
        assert!(socket.exists());
    }
    let mut daemon = Daemon::start(&socket);
    let mut c = Client::connect(&socket).unwrap();
    assert_eq!(
        c.call("hello", json!({}), &[], |_| {}).unwrap().0["server"],
        "tessd"
    );
    c.call("shutdown", json!({}), &[], |_| {}).unwrap();
    assert!(daemon.wait_exit().success());
}
