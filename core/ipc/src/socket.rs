//! Socket naming, owner-only binding and stale-socket recovery (docs/protocol.md, "Transport").

use interprocess::local_socket::{
    ConnectOptions, GenericFilePath, Listener, ListenerOptions, Stream, ToFsName,
};
use std::io;
use std::path::{Path, PathBuf};

/// The per-user folder for sockets: `$XDG_RUNTIME_DIR` when it is a directory, else
/// `<tmp>/tessd-<uid>` (created with mode 0700 when `create` is set).
///
/// # Errors
/// When the private folder cannot be created, or exists but belongs to someone else or is
/// open to others (a socket there could be hijacked).
pub fn default_dir(create: bool) -> io::Result<PathBuf> {
    if let Some(x) = std::env::var_os("XDG_RUNTIME_DIR").map(PathBuf::from)
        && x.is_dir()
    {
        return Ok(x);
    }
    // An empty TMPDIR counts as unset (as Python's tempfile and the tessd client read it).
    let base = std::env::var_os("TMPDIR")
        .filter(|t| !t.is_empty())
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/tmp"));
    let dir = base.join(format!("tessd-{}", current_uid()));
    if create {
        private_dir(&dir)?;
    }
    Ok(dir)
}

/// The default socket path: `<default dir>/tessd.sock`.
///
/// # Errors
/// As [`default_dir`].
pub fn default_socket(create_dir: bool) -> io::Result<PathBuf> {
    Ok(default_dir(create_dir)?.join("tessd.sock"))
}

/// Resolves `--socket NAME_OR_PATH`: a value with a path separator is a path; a bare name `N`
/// is `<default dir>/N.sock`; `None` is the default socket.
///
/// # Errors
/// As [`default_dir`].
pub fn resolve(name_or_path: Option<&str>, create_dir: bool) -> io::Result<PathBuf> {
    match name_or_path {
        None | Some("") => default_socket(create_dir),
        Some(s) if s.contains('/') || s.contains(std::path::MAIN_SEPARATOR) => Ok(PathBuf::from(s)),
        Some(name) => Ok(default_dir(create_dir)?.join(format!("{name}.sock"))),
    }
}

#[cfg(unix)]
fn current_uid() -> u32 {
    // SAFETY: getuid has no preconditions and cannot fail.
    unsafe { libc::getuid() }
}

#[cfg(not(unix))]
fn current_uid() -> String {
    std::env::var("USERNAME").unwrap_or_else(|_| "user".into())
}

#[cfg(unix)]
fn private_dir(dir: &Path) -> io::Result<()> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    match std::fs::DirBuilder::new().mode(0o700).create(dir) {
        Ok(()) => return Ok(()),
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(e),
    }
    let meta = std::fs::symlink_metadata(dir)?;
    if !meta.is_dir() || meta.uid() != current_uid() {
        return Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!(
                "{} exists but is not a folder owned by this user",
                dir.display()
            ),
        ));
    }
    if meta.mode() & 0o077 != 0 {
        std::fs::set_permissions(dir, std::fs::Permissions::from_mode(0o700))?;
    }
    Ok(())
}

#[cfg(not(unix))]
fn private_dir(dir: &Path) -> io::Result<()> {
    std::fs::create_dir_all(dir)
}

/// Connects to the socket at `path`.
///
/// # Errors
/// When nothing listens there.
pub fn connect(path: &Path) -> io::Result<Stream> {
    ConnectOptions::new()
        .name(path.to_fs_name::<GenericFilePath>()?)
        .connect_sync()
}

/// Why [`bind`] failed.
#[derive(Debug, thiserror::Error)]
pub enum BindError {
    /// A daemon already answers on the socket; it is left alone.
    #[error("a tessd daemon is already serving on {0}")]
    InUse(PathBuf),
    /// Any other failure.
    #[error("cannot listen on {path}: {source}")]
    Io {
        /// The socket path.
        path: PathBuf,
        /// The cause.
        #[source]
        source: io::Error,
    },
}

/// Binds a listener at `path` with owner-only permissions (mode 0600). A socket file that no
/// process answers on is stale and is replaced; a live one is never taken over.
///
/// # Errors
/// [`BindError::InUse`] when a daemon answers there; [`BindError::Io`] otherwise.
pub fn bind(path: &Path) -> Result<Listener, BindError> {
    let io_err = |source| BindError::Io {
        path: path.to_path_buf(),
        source,
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(io_err)?;
    }
    // Daemons started at the same moment (the workers of one node) take turns: between a
    // socket file's creation and its `listen` a connect is refused, and without the lock a
    // second daemon would take that fresh file for stale, delete it and leave the first one
    // listening where nobody can reach it.
    let _turn = StartLock::take(path).map_err(io_err)?;
    if std::fs::symlink_metadata(path).is_ok() {
        if connect(path).is_ok() {
            return Err(BindError::InUse(path.to_path_buf()));
        }
        log::info!("removing stale socket {}", path.display());
        std::fs::remove_file(path).map_err(io_err)?;
    }
    let name = path.to_fs_name::<GenericFilePath>().map_err(io_err)?;
    let opts = ListenerOptions::new().name(name).try_overwrite(false);
    #[cfg(unix)]
    let opts = {
        use interprocess::os::unix::local_socket::ListenerOptionsExt;
        opts.mode(0o600)
    };
    opts.create_sync().map_err(|e| {
        if e.kind() == io::ErrorKind::AddrInUse {
            BindError::InUse(path.to_path_buf())
        } else {
            io_err(e)
        }
    })
}

/// An exclusive `flock` on `<socket>.lock`, held while [`bind`] decides whether the socket file
/// is stale and binds (released on drop). The lock file stays, empty, in the socket's private
/// folder; on Windows, whose named pipes have no stale files, nothing is locked.
struct StartLock(#[allow(dead_code)] Option<std::fs::File>);

impl StartLock {
    fn take(socket: &Path) -> io::Result<StartLock> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            use std::os::unix::io::AsRawFd;
            let mut name = socket.as_os_str().to_owned();
            name.push(".lock");
            let file = std::fs::OpenOptions::new()
                .create(true)
                .truncate(false)
                .write(true)
                .mode(0o600)
                .custom_flags(libc::O_NOFOLLOW)
                .open(PathBuf::from(name))?;
            // SAFETY: flock on a descriptor this function owns; it blocks until the lock is ours.
            while unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } != 0 {
                let e = io::Error::last_os_error();
                if e.kind() != io::ErrorKind::Interrupted {
                    return Err(e);
                }
            }
            Ok(StartLock(Some(file)))
        }
        #[cfg(not(unix))]
        {
            let _ = socket;
            Ok(StartLock(None))
        }
    }
}
