//! Atomic file replacement: write a temporary file next to the target, rename it over the
//! target on success, remove it on any failure (including a panic in the writer).
//!
//! # Where outputs are written (the rule every daemon output follows)
//!
//! The daemon runs as its user and never changes identity or permissions, so it writes only
//! where that user may. Every output file goes through this module:
//!
//! - the temporary file `.<name>.tmp-<pid>-<n>` is created beside the destination with
//!   `O_CREAT | O_EXCL | O_NOFOLLOW`: a file or symbolic link planted at that name is never
//!   opened or written through (another name is tried instead);
//! - it is created with mode `0666` less the process umask, so outputs get the permissions
//!   any file the user creates gets;
//! - it is renamed over the destination only once complete; `rename` replaces a symbolic link
//!   planted at the destination with the file itself and never writes through it, and readers
//!   see the previous file or the complete new one, never a partial one;
//! - a write that fails, is cancelled or panics removes its temporary file. A process killed
//!   outright (SIGKILL, power loss) cannot: its temporary file stays, and the next write into
//!   that folder (by any tessd process, the first one it makes there and again when a minute
//!   has passed) removes it, once no process on this machine has the writer's pid and no one
//!   holds the file's lock (every writer holds an exclusive `flock` on its temporary file).
//!
//! On Windows the same rules hold with Windows' means: the temporary file is created with
//! `CREATE_NEW` (a name that exists is skipped, never opened), locked with `LockFileEx` while it
//! is written, moved over the destination by `MoveFileExW(MOVEFILE_REPLACE_EXISTING |
//! MOVEFILE_WRITE_THROUGH)` while still open and locked, and a writer's liveness is tested by
//! process handle (`OpenProcess` + `GetExitCodeProcess`, [`crate::process::process_alive`]).

use crate::MeshError;
use std::collections::HashMap;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Writes `path` atomically: `write` fills a temporary file `.<name>.tmp-<pid>-<n>` in the
/// same folder (so the rename cannot cross file systems), which is renamed over `path` only when
/// `write` and the final flush succeed; otherwise it is removed and `path` is left untouched.
/// Readers of `path` therefore see either the old file or the complete new one. See the
/// [module documentation](self) for what is and is not followed.
///
/// The writer handed to `write` is buffered. The error type is generic so that callers with
/// their own error type (anything `From<MeshError>`) can use it; I/O failures of the temporary
/// file itself are reported as [`MeshError::Io`] naming `path`. There is no fsync: this
/// protects against failed, cancelled and killed writes, not against power loss.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// let path = dir.path().join("hello.txt");
/// tessd_mesh::io::write_atomic(&path, |w| {
///     w.write_all(b"hello").map_err(|e| tessd_mesh::MeshError::Io { path: "hello.txt".into(), source: e })
/// })
/// .unwrap();
/// assert_eq!(std::fs::read(&path).unwrap(), b"hello");
/// ```
///
/// # Errors
/// Whatever `write` returns, or [`MeshError::Io`] when the temporary file cannot be created,
/// flushed or renamed.
pub fn write_atomic<E, F>(path: &Path, write: F) -> Result<(), E>
where
    F: FnOnce(&mut dyn Write) -> Result<(), E>,
    E: From<MeshError>,
{
    let io_err = |source| MeshError::Io {
        path: path.display().to_string(),
        source,
    };
    let (file, temp) = TempOutput::create(path).map_err(io_err)?;
    let mut w = BufWriter::with_capacity(64 * 1024, file);
    write(&mut w)?;
    w.flush().map_err(io_err)?;
    let file = w.into_inner().map_err(|e| io_err(e.into_error()))?;
    temp.commit(file, false).map_err(io_err)?;
    Ok(())
}

/// A temporary file beside a destination, renamed over it by [`TempOutput::commit`] and
/// removed when dropped uncommitted (a failed, cancelled or panicking write). For writers that
/// need the [`File`] itself (seeking, syncing); [`write_atomic`] wraps it for the others.
///
/// ```
/// # let dir = tempfile::tempdir().unwrap();
/// use std::io::Write;
/// let dest = dir.path().join("out.bin");
/// let (mut file, temp) = tessd_mesh::io::TempOutput::create(&dest).unwrap();
/// file.write_all(b"data").unwrap();
/// temp.commit(file, true).unwrap();
/// assert_eq!(std::fs::read(&dest).unwrap(), b"data");
/// ```
#[derive(Debug)]
pub struct TempOutput {
    temp: PathBuf,
    dest: PathBuf,
    armed: bool,
}

impl TempOutput {
    /// Creates a fresh temporary file beside `dest` (mode `0666` less the umask, never through
    /// a symbolic link, locked with `flock`, `LockFileEx` on Windows, while it is written),
    /// after removing the stale temporary files that killed writers left in that folder.
    ///
    /// # Errors
    /// When `dest` has no file name or the file cannot be created (a missing or read-only
    /// folder, a full disk).
    pub fn create(dest: &Path) -> std::io::Result<(File, TempOutput)> {
        let Some(name) = dest.file_name() else {
            return Err(std::io::Error::new(
                ErrorKind::InvalidInput,
                "not a file path",
            ));
        };
        let dir = match dest.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        // Say what is missing, not only "No such file or directory".
        if !dir.exists() {
            return Err(std::io::Error::new(
                ErrorKind::NotFound,
                format!(
                    "the folder {}{} does not exist",
                    dir.display(),
                    std::path::MAIN_SEPARATOR
                ),
            ));
        }
        sweep_stale_temps(dir);
        static COUNTER: AtomicU64 = AtomicU64::new(0);
        let (file, temp) = create_temp(dir, &name.to_string_lossy(), &COUNTER)?;
        let guard = TempOutput {
            temp,
            dest: dest.to_path_buf(),
            armed: true,
        };
        Ok((file, guard))
    }

    /// The temporary file's path.
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// Renames the temporary file over the destination (its contents synced to disk first when
    /// `sync` is set) and closes `file`. The file stays open, and so locked, until it has its
    /// final name, so that no sweeper can take it for a dead writer's in between (on Windows
    /// the move is `MoveFileExW` with write-through).
    ///
    /// # Errors
    /// When syncing or renaming fails; the temporary file is then removed.
    pub fn commit(mut self, file: File, sync: bool) -> std::io::Result<()> {
        if sync {
            file.sync_all()?;
        }
        replace(&self.temp, &self.dest)?;
        self.armed = false;
        drop(file);
        Ok(())
    }
}

/// Renames `temp` over `dest` (replacing it): `rename(2)` on Unix.
#[cfg(not(windows))]
fn replace(temp: &Path, dest: &Path) -> std::io::Result<()> {
    std::fs::rename(temp, dest)
}

/// Moves `temp` over `dest` with `MoveFileExW(MOVEFILE_REPLACE_EXISTING |
/// MOVEFILE_WRITE_THROUGH)`: the call returns once the move is on disk (std's `rename` passes
/// no write-through). The temporary file may stay open: every file std opens shares deletion,
/// which a move needs. A destination another program holds open without sharing deletion
/// cannot be replaced (Windows' rule); that is an error naming it.
#[cfg(windows)]
fn replace(temp: &Path, dest: &Path) -> std::io::Result<()> {
    use windows_sys::Win32::Storage::FileSystem::{
        MOVEFILE_REPLACE_EXISTING, MOVEFILE_WRITE_THROUGH, MoveFileExW,
    };
    let (from, to) = (wide_path(temp)?, wide_path(dest)?);
    // SAFETY: two NUL-terminated wide paths that live across the call.
    let ok = unsafe {
        MoveFileExW(
            from.as_ptr(),
            to.as_ptr(),
            MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH,
        )
    };
    if ok == 0 {
        let e = std::io::Error::last_os_error();
        return Err(std::io::Error::new(
            e.kind(),
            format!(
                "cannot move {} over {}: {e}",
                temp.display(),
                dest.display()
            ),
        ));
    }
    Ok(())
}

/// `path` as a NUL-terminated wide string for the `W` functions; a path of 248 characters or
/// more gets the `\\?\` prefix (made absolute, `/` turned to `\`, a UNC name as
/// `\\?\UNC\server\share\...`) so that it is not cut at `MAX_PATH`.
#[cfg(windows)]
fn wide_path(path: &Path) -> std::io::Result<Vec<u16>> {
    use std::os::windows::ffi::OsStrExt;
    let raw: Vec<u16> = path.as_os_str().encode_wide().collect();
    let verbatim: Vec<u16> = r"\\?\".encode_utf16().collect();
    let mut wide = if raw.len() < 248 || raw.starts_with(&verbatim) {
        raw
    } else {
        let abs: Vec<u16> = std::path::absolute(path)?
            .as_os_str()
            .encode_wide()
            .map(|c| {
                if c == u16::from(b'/') {
                    u16::from(b'\\')
                } else {
                    c
                }
            })
            .collect();
        let unc: Vec<u16> = r"\\".encode_utf16().collect();
        let mut out = verbatim;
        if abs.starts_with(&unc) {
            out.extend(r"UNC\".encode_utf16());
            out.extend_from_slice(&abs[2..]);
        } else {
            out.extend_from_slice(&abs);
        }
        out
    };
    if wide.contains(&0) {
        return Err(std::io::Error::new(
            ErrorKind::InvalidInput,
            format!("{} holds a NUL character", path.display()),
        ));
    }
    wide.push(0);
    Ok(wide)
}

impl Drop for TempOutput {
    fn drop(&mut self) {
        if self.armed {
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

/// The marker between a temporary file's destination name and its pid (`tessd.batch` sweeps
/// the same pattern: python/tessd/batch/layout.py, `TEMP_RE`).
const TEMP_MARK: &str = ".tmp-";

/// Longest destination-name prefix kept in a temporary file's name, so that the name stays
/// within the usual 255-byte limit whatever the destination's name.
const TEMP_NAME_PREFIX: usize = 200;

/// Creates a fresh temporary file in `dir`, numbered from `counter`, retrying on name
/// collisions (a name that exists, as a file or as a symbolic link, is skipped, never opened).
fn create_temp(dir: &Path, name: &str, counter: &AtomicU64) -> std::io::Result<(File, PathBuf)> {
    let pid = std::process::id();
    let mut cut = name.len().min(TEMP_NAME_PREFIX);
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    let name = &name[..cut];
    loop {
        let n = counter.fetch_add(1, Ordering::Relaxed);
        let temp = dir.join(format!(".{name}{TEMP_MARK}{pid}-{n}"));
        let mut options = OpenOptions::new();
        options.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            options
                .mode(0o666)
                .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC);
        }
        match options.open(&temp) {
            Ok(f) => {
                lock_exclusive(&f);
                return Ok((f, temp));
            }
            Err(e) if e.kind() == ErrorKind::AlreadyExists && n < u64::MAX => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Takes an exclusive `flock` on `file` without waiting, so that a sweeper on another machine
/// sharing the folder (where this pid means nothing) sees it in use; a file system without
/// `flock` simply goes without.
#[cfg(unix)]
fn lock_exclusive(file: &File) -> bool {
    use std::os::unix::io::AsRawFd;
    // SAFETY: flock on a descriptor `file` owns; LOCK_NB never blocks.
    unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) == 0 }
}

/// Takes an exclusive `LockFileEx` lock on the whole of `file` without waiting (Windows' locks
/// are mandatory: other handles cannot read or write the file while it is held; the writer's
/// own handle can). `false` when another handle holds it.
#[cfg(windows)]
fn lock_exclusive(file: &File) -> bool {
    use std::os::windows::io::AsRawHandle;
    use windows_sys::Win32::Storage::FileSystem::{
        LOCKFILE_EXCLUSIVE_LOCK, LOCKFILE_FAIL_IMMEDIATELY, LockFileEx,
    };
    use windows_sys::Win32::System::IO::OVERLAPPED;
    // SAFETY: OVERLAPPED is plain data; all zero is offset 0 with no event.
    let mut overlapped: OVERLAPPED = unsafe { std::mem::zeroed() };
    // SAFETY: a handle `file` owns; the range is the whole file (and beyond); FAIL_IMMEDIATELY
    // never blocks, and the lock goes with the handle when it is closed.
    unsafe {
        LockFileEx(
            file.as_raw_handle(),
            LOCKFILE_EXCLUSIVE_LOCK | LOCKFILE_FAIL_IMMEDIATELY,
            0,
            u32::MAX,
            u32::MAX,
            &mut overlapped,
        ) != 0
    }
}

/// Where there is neither `flock` nor `LockFileEx`: nothing is locked, and `false` says so, so
/// that [`remove_if_unlocked`] there never takes a file for unheld.
#[cfg(not(any(unix, windows)))]
fn lock_exclusive(_file: &File) -> bool {
    false
}

/// How long a folder's sweep holds before the next write into it sweeps again.
const SWEEP_INTERVAL: Duration = Duration::from_secs(60);

/// Most folders whose last sweep is remembered (beyond, the memory starts afresh).
const SWEEP_MEMORY: usize = 4096;

/// Removes the temporary files that writers killed before they could clean up left in `dir`:
/// regular files named `.<name>.tmp-<pid>-<n>` whose pid no process on this machine has
/// and that no one holds locked. Done at the first write into a folder and again when
/// [`SWEEP_INTERVAL`] has passed since its last sweep; failures are ignored (a sweep only
/// tidies).
fn sweep_stale_temps(dir: &Path) {
    static SWEPT: OnceLock<Mutex<HashMap<PathBuf, Instant>>> = OnceLock::new();
    let now = Instant::now();
    {
        let mut swept = SWEPT
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        if swept
            .get(dir)
            .is_some_and(|t| now.duration_since(*t) < SWEEP_INTERVAL)
        {
            return;
        }
        if swept.len() >= SWEEP_MEMORY {
            swept.clear();
        }
        swept.insert(dir.to_path_buf(), now);
    }
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_pid) else {
            continue;
        };
        // Only regular files: a symbolic link or anything else with that name is left alone.
        if !entry.file_type().is_ok_and(|t| t.is_file()) || pid == std::process::id() {
            continue;
        }
        if crate::process::process_alive(pid) {
            continue;
        }
        remove_if_unlocked(&entry.path());
    }
}

/// The writer's pid in a temporary file name `.<name>.tmp-<pid>-<n>`, or `None` for any
/// other name.
fn temp_pid(name: &str) -> Option<u32> {
    let (_, tail) = name.strip_prefix('.')?.rsplit_once(TEMP_MARK)?;
    let (pid, n) = tail.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(pid) || !digits(n) {
        return None;
    }
    pid.parse().ok()
}

/// Removes `path` when nobody holds a lock on it (opened without following a symbolic link).
#[cfg(unix)]
fn remove_if_unlocked(path: &Path) {
    use std::os::unix::fs::OpenOptionsExt;
    let Ok(f) = OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
        .open(path)
    else {
        return;
    };
    if lock_exclusive(&f) {
        let _ = std::fs::remove_file(path);
    }
}

/// Removes `path` when nobody holds a lock on it (opened without following a reparse point;
/// the removal happens while the lock is held, the file goes when the handle closes).
#[cfg(windows)]
fn remove_if_unlocked(path: &Path) {
    use std::os::windows::fs::OpenOptionsExt;
    use windows_sys::Win32::Storage::FileSystem::FILE_FLAG_OPEN_REPARSE_POINT;
    let Ok(f) = OpenOptions::new()
        .read(true)
        .custom_flags(FILE_FLAG_OPEN_REPARSE_POINT)
        .open(path)
    else {
        return;
    };
    if lock_exclusive(&f) {
        let _ = std::fs::remove_file(path);
    }
}

/// Where no lock can be seen, nothing is removed.
#[cfg(not(any(unix, windows)))]
fn remove_if_unlocked(_path: &Path) {}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), MeshError> {
        write_atomic::<MeshError, _>(path, |w| {
            w.write_all(bytes).map_err(|e| MeshError::Io {
                path: "x".into(),
                source: e,
            })
        })
    }

    /// The pid of a process that has exited and been reaped.
    #[cfg(target_os = "linux")]
    fn dead_pid() -> u32 {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        pid
    }

    #[test]
    fn replaces_on_success_and_cleans_up_on_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        std::fs::write(&path, b"old").unwrap();
        let r: Result<(), MeshError> = write_atomic(&path, |w| {
            w.write_all(b"partial").unwrap();
            Err(MeshError::Invalid("boom".into()))
        });
        assert_eq!(r.unwrap_err().to_string(), "boom");
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(dir.path()), ["out.txt"]);

        write_bytes(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(entries(dir.path()), ["out.txt"]);
    }

    #[test]
    fn panicking_writer_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.bin");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomic::<MeshError, _>(&path, |_| panic!("writer panics"));
        });
        assert!(r.is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn missing_folder_is_an_io_error_naming_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nope").join("x.obj");
        let e = write_atomic::<MeshError, _>(&path, |_| Ok(())).unwrap_err();
        assert!(
            matches!(&e, MeshError::Io { path: p, .. } if p.ends_with("x.obj")),
            "{e}"
        );
    }

    #[test]
    fn temp_names_parse_back_to_their_pid() {
        assert_eq!(temp_pid(".out.ply.tmp-123-7"), Some(123));
        assert_eq!(temp_pid("..tmp-1-0"), Some(1));
        assert_eq!(temp_pid(".a.tmp-b.tmp-42-0"), Some(42));
        for other in [
            "out.ply",
            "out.ply.tmp-123-7",
            ".out.ply.tmp--7",
            ".out.ply.tmp-12x-7",
            ".out.ply.tmp-123-",
            ".out.ply.tmp-123-ab12",
            ".out.ply.tmp-123",
            ".out.ply.tessd-123-7.tmp",
        ] {
            assert_eq!(temp_pid(other), None, "{other}");
        }
    }

    #[test]
    fn a_long_name_gets_a_temp_name_within_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let name = format!("{}.obj", "é".repeat(120)); // 244 bytes
        let path = dir.path().join(&name);
        write_bytes(&path, b"x").unwrap();
        assert_eq!(entries(dir.path()), [name]);
    }

    // windows: compiled out — creating a symbolic link needs a privilege on Windows
    #[cfg(unix)]
    #[test]
    fn a_symlink_at_the_destination_is_replaced_not_written_through() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, b"victim").unwrap();
        let path = dir.path().join("out.txt");
        std::os::unix::fs::symlink(&victim, &path).unwrap();
        write_bytes(&path, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&path).unwrap().is_file());
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(std::fs::read(&victim).unwrap(), b"victim");
    }

    // windows: compiled out — creating a symbolic link needs a privilege on Windows
    #[cfg(unix)]
    #[test]
    fn files_and_symlinks_planted_at_temp_names_are_skipped_not_followed() {
        let dir = tempfile::tempdir().unwrap();
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, b"victim").unwrap();
        let pid = std::process::id();
        let name = |n: u64| dir.path().join(format!(".out.txt{TEMP_MARK}{pid}-{n}"));
        for n in 0..3 {
            std::os::unix::fs::symlink(&victim, name(n)).unwrap();
        }
        std::os::unix::fs::symlink(dir.path().join("dangling"), name(3)).unwrap();
        std::fs::write(name(4), b"planted").unwrap();
        let counter = AtomicU64::new(0);
        let (mut file, temp) = create_temp(dir.path(), "out.txt", &counter).unwrap();
        assert_eq!(temp, name(5));
        file.write_all(b"new").unwrap();
        drop(file);
        assert_eq!(std::fs::read(&temp).unwrap(), b"new");
        assert_eq!(std::fs::read(&victim).unwrap(), b"victim");
        assert_eq!(std::fs::read(name(4)).unwrap(), b"planted");
        assert!(!dir.path().join("dangling").exists());
    }

    // windows: compiled out — the umask, read from /proc; Windows files have no mode bits
    #[cfg(target_os = "linux")]
    #[test]
    fn outputs_get_the_umask_mode() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        write_bytes(&path, b"x").unwrap();
        // The mask as the kernel reports it (reading it with umask(2) would change it).
        let status = std::fs::read_to_string("/proc/self/status").unwrap();
        let mask = status
            .lines()
            .find_map(|l| l.strip_prefix("Umask:"))
            .map(|m| u32::from_str_radix(m.trim(), 8).unwrap())
            .unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o666 & !mask);
    }

    // windows: compiled out — /proc, init's pid 1 and symbolic links; its Windows form is
    // windows_stale_temps_of_dead_writers_are_swept_live_and_locked_ones_kept.
    #[cfg(target_os = "linux")]
    #[test]
    fn stale_temps_of_dead_writers_are_swept_live_and_locked_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let dead = dead_pid();
        let stale = dir.path().join(format!(".a.usda{TEMP_MARK}{dead}-3"));
        std::fs::write(&stale, b"half").unwrap();
        // A dead pid, but the file is locked: a writer on another machine.
        let remote = dir.path().join(format!(".b.usda{TEMP_MARK}{dead}-4"));
        std::fs::write(&remote, b"half").unwrap();
        let held = File::open(&remote).unwrap();
        assert!(lock_exclusive(&held));
        // A live pid (init's): kept.
        let live = dir.path().join(format!(".c.usda{TEMP_MARK}1-5"));
        std::fs::write(&live, b"half").unwrap();
        // A symbolic link with a temp name: never touched.
        let link = dir.path().join(format!(".d.usda{TEMP_MARK}{dead}-6"));
        std::os::unix::fs::symlink("/nonexistent", &link).unwrap();
        // Someone else's file.
        let user = dir.path().join(".e.usda.tmp");
        std::fs::write(&user, b"mine").unwrap();

        write_bytes(&dir.path().join("a.usda"), b"whole").unwrap();
        let mut expected: Vec<String> = [&remote, &live, &link, &user]
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        expected.push("a.usda".into());
        expected.sort();
        assert_eq!(entries(dir.path()), expected);
        drop(held);
    }

    /// A process that runs until it is killed: `cmd` waiting on its open stdin.
    #[cfg(windows)]
    fn live_child() -> std::process::Child {
        std::process::Command::new("cmd")
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap()
    }

    #[cfg(windows)]
    #[test]
    fn windows_stale_temps_of_dead_writers_are_swept_live_and_locked_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let mut gone = std::process::Command::new("cmd")
            .args(["/C", "exit 0"])
            .spawn()
            .unwrap();
        let dead = gone.id();
        gone.wait().unwrap();
        drop(gone);
        let stale = dir.path().join(format!(".a.usda{TEMP_MARK}{dead}-3"));
        std::fs::write(&stale, b"half").unwrap();
        // A dead pid, but the file is locked (LockFileEx): a writer on another machine.
        let remote = dir.path().join(format!(".b.usda{TEMP_MARK}{dead}-4"));
        std::fs::write(&remote, b"half").unwrap();
        let held = File::open(&remote).unwrap();
        assert!(lock_exclusive(&held));
        // A second handle cannot take the lock while it is held.
        assert!(!lock_exclusive(&File::open(&remote).unwrap()));
        // A live writer: kept.
        let mut writer = live_child();
        let live = dir
            .path()
            .join(format!(".c.usda{TEMP_MARK}{}-5", writer.id()));
        std::fs::write(&live, b"half").unwrap();
        // Someone else's file.
        let user = dir.path().join(".e.usda.tmp");
        std::fs::write(&user, b"mine").unwrap();

        write_bytes(&dir.path().join("a.usda"), b"whole").unwrap();
        let mut expected: Vec<String> = [&remote, &live, &user]
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        expected.push("a.usda".into());
        expected.sort();
        assert_eq!(entries(dir.path()), expected);
        assert_eq!(std::fs::read(dir.path().join("a.usda")).unwrap(), b"whole");
        drop(held);
        writer.kill().unwrap();
        writer.wait().unwrap();
    }

    #[cfg(windows)]
    #[test]
    fn windows_replaces_over_a_long_path_and_forward_slashes() {
        let dir = tempfile::tempdir().unwrap();
        let mut deep = dir.path().to_path_buf();
        while deep.as_os_str().len() < 300 {
            deep.push("a-rather-long-folder-name");
        }
        std::fs::create_dir_all(&deep).unwrap();
        let path = deep.join("out.ply");
        std::fs::write(&path, b"old").unwrap();
        write_bytes(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(entries(&deep), ["out.ply"]);
        // The same destination spelt with forward slashes.
        let slashed = PathBuf::from(
            dir.path()
                .join("fwd.ply")
                .display()
                .to_string()
                .replace('\\', "/"),
        );
        write_bytes(&slashed, b"fwd").unwrap();
        assert_eq!(std::fs::read(dir.path().join("fwd.ply")).unwrap(), b"fwd");
    }
}
