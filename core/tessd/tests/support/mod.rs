//! What the binary's integration tests share: running the binary, finding the shared data,
//! and a daemon process that is killed when the test ends.
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
    let root = std::env::var_os("TESSD_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"));
    root.join("mesh").join(name)
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

/// A `tessd serve` child process, killed on drop.
pub struct Daemon(pub Child);

impl Daemon {
    /// Starts a daemon on `socket` and waits until it answers.
    pub fn start(socket: &Path) -> Daemon {
        let child = tessd()
            .arg("serve")
            .arg("--socket")
            .arg(socket)
            .spawn()
            .unwrap();
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
