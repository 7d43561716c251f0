//! What the binary's integration tests share: running the binary, finding the shared data,
//! a daemon process that is killed when the test ends, and one operation run through the
//! registry the daemon and job files share.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

/// The `tessd` binary under test.
pub fn tessd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_tessd"))
}

/// A mesh of the shared test data (`$TESSD_SHARED_DATA`, else `../shared/data`).
pub fn shared_mesh(name: &str) -> PathBuf {
    tessd_testdata::shared(&format!("mesh/{name}"))
}

/// Runs `cmd`, which must succeed.
pub fn run_ok(cmd: &mut Command) -> Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// A fresh daemon endpoint for one test: the socket `name` in `dir`; on Windows, where the
/// daemon listens on named pipes only, a pipe name no other test or test process uses
/// (`\\.\pipe\tessd-test-<pid>-<n>-<name>`).
pub fn endpoint(dir: &Path, name: &str) -> PathBuf {
    if cfg!(windows) {
        use std::sync::atomic::{AtomicU32, Ordering};
        static N: AtomicU32 = AtomicU32::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let _ = dir;
        format!(r"\\.\pipe\tessd-test-{}-{n}-{name}", std::process::id()).into()
    } else {
        dir.join(name)
    }
}

/// A `tessd serve` child process, killed on drop.
pub struct Daemon(pub Child);

impl Daemon {
    /// Starts a daemon on `socket` and waits until it answers.
    pub fn start(socket: &Path) -> Daemon {
        let mut cmd = tessd();
        cmd.arg("serve").arg("--socket").arg(socket);
        // Windows: a process group of its own, so that a test can send it Ctrl-Break
        // (GenerateConsoleCtrlEvent) without reaching itself.
        #[cfg(windows)]
        {
            use std::os::windows::process::CommandExt;
            const CREATE_NEW_PROCESS_GROUP: u32 = 0x0000_0200;
            cmd.creation_flags(CREATE_NEW_PROCESS_GROUP);
        }
        let child = cmd.spawn().unwrap();
        let t = Instant::now();
        while tessd_ipc::socket::connect(socket).is_err() {
            assert!(
                t.elapsed() < Duration::from_secs(10),
                "daemon did not start"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        Daemon(child)
    }

    /// Waits (at most 10 s) for the daemon to exit.
    pub fn wait_exit(&mut self) -> std::process::ExitStatus {
        let t = Instant::now();
        loop {
            if let Some(s) = self.0.try_wait().unwrap() {
                return s;
            }
            assert!(t.elapsed() < Duration::from_secs(10), "daemon did not exit");
            std::thread::sleep(Duration::from_millis(20));
        }
    }
}

impl Drop for Daemon {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Runs `op` with `params` (a JSON object) and `arrays` through the daemon's registry, in
/// process; returns the result's JSON.
pub fn run_op(
    op: &str,
    params: serde_json::Value,
    arrays: &[tessd_ipc::arrays::OwnedArray],
) -> Result<serde_json::Value, tessd_ipc::error::OpError> {
    let serde_json::Value::Object(params) = params else {
        panic!("params must be an object")
    };
    let request = tessd_ipc::registry::Request {
        params,
        arrays: tessd_ipc::arrays::Arrays::from_owned(arrays),
        base_dir: None,
    };
    let sink = |_| {};
    let ctx = tessd_ipc::job::JobContext::new(&sink, tessd_ipc::job::CancelToken::default());
    tessd::ops::registry()
        .run(op, request, &ctx)
        .map(|r| r.result)
}
