//! Who is using the daemon: the holders behind `session.hold` / `session.release`.
//!
//! Several host programs (Blender, FreeCAD, a script) may share one daemon. Each one that
//! wants the daemon kept alive *holds* it with its process id; a program that started the
//! daemon stops it on exit only when no holder is left. Holds are keyed by process id rather
//! than by connection because hosts open a connection per request (the Blender add-on does)
//! and because a crashed host cannot release: a holder whose process no longer exists is
//! pruned whenever the holders are counted, so a crash never keeps the daemon alive for ever.
//!
//! A process holds at most once: holding again only refreshes its host name, so a host that
//! reconnects does not need to remember whether it already holds.

use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::sync::Mutex;

/// The processes holding the daemon, shared by every connection of one server.
#[derive(Debug, Default)]
pub struct Holders {
    by_pid: Mutex<BTreeMap<u32, String>>,
}

impl Holders {
    /// No holders.
    pub fn new() -> Holders {
        Holders::default()
    }

    /// Records that process `pid` (a host program called `host`) uses the daemon; returns
    /// the number of live holders, this one included.
    pub fn hold(&self, pid: u32, host: &str) -> usize {
        let mut map = self.lock();
        map.insert(pid, host.to_string());
        prune(&mut map);
        map.len()
    }

    /// Forgets process `pid`'s hold (a no-op when it held nothing); returns the number of live
    /// holders left.
    pub fn release(&self, pid: u32) -> usize {
        let mut map = self.lock();
        map.remove(&pid);
        prune(&mut map);
        map.len()
    }

    /// The number of live holders (dead ones are pruned first).
    pub fn count(&self) -> usize {
        let mut map = self.lock();
        prune(&mut map);
        map.len()
    }

    /// The live holders as `[{"pid": .., "host": ..}]`, by pid, for `hello` and the replies.
    pub fn describe(&self) -> Value {
        let mut map = self.lock();
        prune(&mut map);
        Value::Array(
            map.iter()
                .map(|(pid, host)| json!({"pid": pid, "host": host}))
                .collect(),
        )
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, BTreeMap<u32, String>> {
        // A panic while holding this lock cannot leave the map half-updated (each step is
        // one insert or remove), so a poisoned lock is still usable.
        self.by_pid.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn prune(map: &mut BTreeMap<u32, String>) {
    map.retain(|pid, _| process_alive(*pid));
}

/// Whether process `pid` still exists: the test the stale-temp sweep of atomic writes uses too
/// (`kill(pid, 0)` plus the zombie state on Linux, `OpenProcess` + `GetExitCodeProcess` on
/// Windows; see [`tessd_mesh::process::process_alive`]).
pub use tessd_mesh::process::process_alive;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hold_is_once_per_process_and_release_counts_down() {
        let h = Holders::new();
        let me = std::process::id();
        assert_eq!(h.hold(me, "test"), 1);
        assert_eq!(h.hold(me, "again"), 1);
        assert_eq!(h.describe(), json!([{"pid": me, "host": "again"}]));
        assert_eq!(h.release(me), 0);
        assert_eq!(h.release(me), 0);
    }

    #[cfg(any(unix, windows))]
    #[test]
    fn dead_processes_are_pruned() {
        #[cfg(unix)]
        let mut child = std::process::Command::new("true").spawn().unwrap();
        #[cfg(windows)]
        let mut child = std::process::Command::new("cmd")
            .args(["/C", "exit 0"])
            .spawn()
            .unwrap();
        let pid = child.id();
        child.wait().unwrap();
        let h = Holders::new();
        assert_eq!(h.hold(pid, "gone"), 0);
        assert_eq!(h.count(), 0);
        assert!(process_alive(std::process::id()));
        assert!(!process_alive(0));
    }
}
