//! Atomic file replacement: write a temporary file next to the target, rename it over the
//! target on success, remove it on any failure (including a panic in the writer).

use crate::MeshError;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, ErrorKind, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `path` atomically: `write` fills a temporary file `.<name>.tmp-<pid>-<n>` in the same
/// folder (so the rename cannot cross file systems), which is renamed over `path` only when
/// `write` and the final flush succeed; otherwise it is removed and `path` is left untouched.
/// Readers of `path` therefore see either the old file or the complete new one.
///
/// The writer handed to `write` is buffered. The error type is generic so that callers with
/// their own error type (anything `From<MeshError>`) can use it; I/O failures of the temporary
/// file itself are reported as [`MeshError::Io`] naming `path`. There is no fsync: this
/// protects against failed and cancelled writes, not against power loss.
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
    let Some(file_name) = path.file_name() else {
        return Err(MeshError::Io {
            path: path.display().to_string(),
            source: std::io::Error::new(ErrorKind::InvalidInput, "not a file path"),
        }
        .into());
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let (file, temp) = create_temp(dir, &file_name.to_string_lossy()).map_err(io_err)?;
    let mut guard = TempGuard {
        path: temp,
        armed: true,
    };
    let mut w = BufWriter::with_capacity(64 * 1024, file);
    write(&mut w)?;
    w.flush().map_err(io_err)?;
    drop(w);
    std::fs::rename(&guard.path, path).map_err(io_err)?;
    guard.armed = false;
    Ok(())
}

/// Creates a fresh temporary file in `dir`, retrying on name collisions.
fn create_temp(dir: &Path, name: &str) -> std::io::Result<(File, PathBuf)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let pid = std::process::id();
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let temp = dir.join(format!(".{name}.tmp-{pid}-{n}"));
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(f) => return Ok((f, temp)),
            Err(e) if e.kind() == ErrorKind::AlreadyExists && n < u64::MAX => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Removes the temporary file on drop unless it was renamed (disarmed).
struct TempGuard {
    path: PathBuf,
    armed: bool,
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        if self.armed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

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

        write_atomic::<MeshError, _>(&path, |w| {
            w.write_all(b"new").map_err(|e| MeshError::Io {
                path: "x".into(),
                source: e,
            })
        })
        .unwrap();
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
}
