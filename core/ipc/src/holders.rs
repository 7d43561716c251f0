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

/// Whether process `pid` still exists.
///
/// On Unix, `kill(pid, 0)` asks the kernel without sending anything: success or `EPERM`
/// (the process exists but belongs to someone else) mean alive. A zombie (exited, not yet
/// reaped by its parent) still passes that test, so on Linux its `/proc/<pid>/stat` state
/// is read too: a zombie no longer uses the daemon. On Windows the process is opened by its
/// pid: no such process means gone, one that cannot be opened (another account's, access
/// denied) means alive, and an open one is alive while its exit code is `STILL_ACTIVE` (an
/// exited process whose handle someone still holds is Windows' zombie). Elsewhere there is no
/// cheap portable test, so holders are kept until they release.
pub fn process_alive(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(raw) = libc::pid_t::try_from(pid) else {
            return false;
        };
        if raw <= 0 {
            return false;
        }
        // SAFETY: signal 0 performs only the existence and permission checks.
        let rc = unsafe { libc::kill(raw, 0) };
        if rc != 0 && std::io::Error::last_os_error().raw_os_error() != Some(libc::EPERM) {
            return false;
        }
        #[cfg(target_os = "linux")]
        if is_zombie(pid) {
            return false;
        }
        true
    }
    #[cfg(windows)]
    {
        use windows_sys::Win32::Foundation::{
            CloseHandle, ERROR_INVALID_PARAMETER, GetLastError, STILL_ACTIVE,
        };
        use windows_sys::Win32::System::Threading::{
            GetExitCodeProcess, OpenProcess, PROCESS_QUERY_LIMITED_INFORMATION,
        };
        // SAFETY: OpenProcess has no preconditions; it returns null or a handle we own.
        let handle = unsafe { OpenProcess(PROCESS_QUERY_LIMITED_INFORMATION, 0, pid) };
        if handle.is_null() {
            // SAFETY: reads this thread's last error, set by the failed OpenProcess.
            return unsafe { GetLastError() } != ERROR_INVALID_PARAMETER;
        }
        let mut code = 0u32;
        // SAFETY: `handle` is a valid process handle with query rights; `code` is writable.
        let ok = unsafe { GetExitCodeProcess(handle, &mut code) } != 0;
        // SAFETY: `handle` is ours and closed once.
        unsafe { CloseHandle(handle) };
        !ok || code == STILL_ACTIVE as u32
    }
    #[cfg(not(any(unix, windows)))]
    {
        let _ = pid;
        true
    }
}

/// Whether `/proc/<pid>/stat` shows the zombie state `Z` (false when it cannot be read).
#[cfg(target_os = "linux")]
fn is_zombie(pid: u32) -> bool {
    let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
        return false;
    };
    // The command name (field 2) is in parentheses and may itself hold spaces or ')': the
    // state is the first field after the last ')'.
    stat.rsplit_once(')')
        .and_then(|(_, rest)| rest.split_whitespace().next())
        .is_some_and(|state| state == "Z")
}

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

    #[cfg(target_os = "linux")]
    #[test]
    fn zombies_are_not_alive() {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        // Not reaped yet: wait until it has exited, then it is a zombie.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(5);
        while !is_zombie(pid) && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(!process_alive(pid));
        child.wait().unwrap();
    }
}
