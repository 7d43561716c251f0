//! Atomic file output.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use crate::UsdError;
use crate::error::STREAM;

/// Writes a `.usda` file atomically: `write` streams the stage into a temporary file in the
/// same folder, which is renamed over `path` only when everything succeeded, so readers never
/// see a partial stage and a failure leaves no file behind (and an existing `path` untouched).
///
/// ```no_run
/// # fn main() -> Result<(), tessd_usd::UsdError> {
/// use tessd_usd::{write_mesh_stage, write_usda_file, MeshPrimOptions, StageOptions};
/// let mesh = tessd_mesh::Mesh::default();
/// let (stage, prim) = (StageOptions::default(), MeshPrimOptions::default());
/// write_usda_file("out.usda".as_ref(), |w| write_mesh_stage(w, &mesh, &stage, &prim))?;
/// # Ok(()) }
/// ```
///
/// # Errors
/// Whatever `write` returns, and [`UsdError::Io`] (naming `path`) when the temporary file cannot
/// be created, written, synced or renamed.
pub fn write_usda_file<F>(path: &Path, write: F) -> Result<(), UsdError>
where
    F: FnOnce(&mut dyn Write) -> Result<(), UsdError>,
{
    write_atomic(path, write)
}

/// Temp file + rename in the target folder. Kept in one function so it can be swapped for
/// `tessd_mesh::io::write_atomic` once that lands.
fn write_atomic<F>(path: &Path, write: F) -> Result<(), UsdError>
where
    F: FnOnce(&mut dyn Write) -> Result<(), UsdError>,
{
    let io_err = |source: io::Error| UsdError::Io {
        path: path.display().to_string(),
        source,
    };
    let (tmp_path, file) = create_temp(path).map_err(io_err)?;
    let result = (|| {
        let mut w = BufWriter::with_capacity(1 << 16, file);
        write(&mut w).map_err(|e| match e {
            UsdError::Io { path: p, source } if p == STREAM => io_err(source),
            e => e,
        })?;
        let file = w.into_inner().map_err(|e| io_err(e.into_error()))?;
        file.sync_all().map_err(io_err)?;
        drop(file);
        fs::rename(&tmp_path, path).map_err(io_err)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp_path);
    }
    result
}

/// Creates `.<name>.<pid>.<n>.tmp` next to `path`.
fn create_temp(path: &Path) -> io::Result<(PathBuf, File)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(io::ErrorKind::InvalidInput, "the path does not name a file")
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let mut tmp_name = std::ffi::OsString::from(".");
        tmp_name.push(name);
        tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
        let tmp = dir.join(tmp_name);
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.usda");
        write_usda_file(&p, |w| {
            w.write_all(b"#usda 1.0\n").map_err(UsdError::stream)
        })
        .unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "#usda 1.0\n");
        assert_eq!(entries(dir.path()), ["a.usda"]);
    }

    #[test]
    fn failure_keeps_the_old_file_and_names_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.usda");
        fs::write(&p, "old").unwrap();
        let e = write_usda_file(&p, |w| {
            w.write_all(b"partial").map_err(UsdError::stream)?;
            Err(UsdError::stream(io::Error::other("disk full")))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), format!("{}: disk full", p.display()));
        assert_eq!(fs::read_to_string(&p).unwrap(), "old");
        assert_eq!(entries(dir.path()), ["a.usda"]);
    }

    #[test]
    fn missing_folder_is_an_io_error() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("no/such/a.usda");
        let e = write_usda_file(&p, |_| Ok(())).unwrap_err();
        assert_eq!(e.code(), "io");
    }
}
