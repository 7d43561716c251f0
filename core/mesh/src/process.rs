//! Whether a process still exists, by pid: what the stale-temp sweep of atomic writes
//! ([`crate::io::TempOutput`]) and the daemon's holders (`tessd_ipc::holders`) both ask.

/// Whether process `pid` still exists on this machine.
///
/// On Unix, `kill(pid, 0)` asks the kernel without sending anything: success or `EPERM`
/// (the process exists but belongs to someone else) mean alive. A zombie (exited, not yet
/// reaped by its parent) still passes that test, so on Linux its `/proc/<pid>/stat` state
/// is read too: a zombie counts as gone. On Windows the process is opened by its pid: no such
/// process means gone, one that cannot be opened (another account's, access denied) means
/// alive, and an open one is alive while its exit code is `STILL_ACTIVE` (an exited process
/// whose handle someone still holds is Windows' zombie). Elsewhere there is no cheap portable
/// test, and every pid counts as alive.
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
        if pid == 0 {
            // The System Idle Process: never a writer or a holder.
            return false;
        }
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
    fn this_process_is_alive_an_exited_one_is_not() {
        assert!(process_alive(std::process::id()));
        assert!(!process_alive(0));
        #[cfg(unix)]
        let mut child = std::process::Command::new("true").spawn().unwrap();
        #[cfg(windows)]
        let mut child = std::process::Command::new("cmd")
            .args(["/C", "exit 0"])
            .spawn()
            .unwrap();
        let pid = child.id();
        child.wait().unwrap();
        assert!(!process_alive(pid));
    }

    // windows: compiled out — Linux zombies, read from /proc (Windows' kind, an exited process
    // whose handle is held, is in this_process_is_alive_an_exited_one_is_not).
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
