//! Socket naming, owner-only binding and stale-socket recovery (docs/protocol.md, "Transport").

#[cfg(not(windows))]
use interprocess::local_socket::{ConnectOptions, GenericFilePath, ListenerOptions, ToFsName};
use interprocess::local_socket::{Listener, Stream};
use std::io;
use std::path::{Path, PathBuf};

#[cfg(windows)]
#[path = "socket_windows.rs"]
mod windows;

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
        .unwrap_or_else(|| {
            if cfg!(unix) {
                PathBuf::from("/tmp")
            } else {
                std::env::temp_dir()
            }
        });
    let dir = base.join(format!("tessd-{}", current_uid()));
    if create {
        private_dir(&dir)?;
    }
    Ok(dir)
}

/// The default socket path: `<default dir>/tessd.sock`; on Windows the default pipe
/// `\\.\pipe\tessd-<user>` (see [`resolve`]).
///
/// # Errors
/// As [`default_dir`].
pub fn default_socket(create_dir: bool) -> io::Result<PathBuf> {
    #[cfg(windows)]
    {
        let _ = create_dir;
        resolve(None, false)
    }
    #[cfg(not(windows))]
    Ok(default_dir(create_dir)?.join("tessd.sock"))
}

/// Resolves `--socket NAME_OR_PATH`: a value with a path separator is a path; a bare name `N`
/// is `<default dir>/N.sock`; `None` is the default socket.
///
/// On Windows the daemon listens on a named pipe, never on a file: `None` is the pipe
/// `\\.\pipe\tessd-<user>`, a bare name `N` is `\\.\pipe\tessd-<user>-N`, a value
/// starting with `\\.\pipe\` is used as it is, and any other path-like value (a drive
/// letter, a UNC name, a separator) is refused with an error naming it. `<user>` is
/// `%USERNAME%` with every character outside `[A-Za-z0-9._-]` replaced by `_`.
///
/// # Errors
/// As [`default_dir`]; on Windows, a path-like value that is not a pipe name.
pub fn resolve(name_or_path: Option<&str>, create_dir: bool) -> io::Result<PathBuf> {
    #[cfg(windows)]
    {
        let _ = create_dir;
        pipe_name(
            name_or_path,
            &pipe_user(std::env::var_os("USERNAME").as_deref()),
        )
        .map(PathBuf::from)
    }
    #[cfg(not(windows))]
    match name_or_path {
        None | Some("") => default_socket(create_dir),
        Some(s) if s.contains('/') || s.contains(std::path::MAIN_SEPARATOR) => Ok(PathBuf::from(s)),
        Some(name) => Ok(default_dir(create_dir)?.join(format!("{name}.sock"))),
    }
}

/// The local named-pipe namespace every Windows endpoint lives in.
#[cfg(any(windows, test))]
const PIPE_PREFIX: &str = r"\\.\pipe\";

/// Whether `value` is a local pipe name `\\.\pipe\NAME` (the prefix in any case, a name
/// after it).
#[cfg(any(windows, test))]
fn is_pipe_name(value: &str) -> bool {
    value.len() > PIPE_PREFIX.len()
        && value
            .get(..PIPE_PREFIX.len())
            .is_some_and(|p| p.eq_ignore_ascii_case(PIPE_PREFIX))
}

/// The Windows mapping of `--socket` (see [`resolve`]) for the user name `user` (already made
/// safe by [`pipe_user`]); a pure function, so that its rules are tested on every platform.
#[cfg(any(windows, test))]
fn pipe_name(value: Option<&str>, user: &str) -> io::Result<String> {
    match value {
        None | Some("") => Ok(format!("{PIPE_PREFIX}tessd-{user}")),
        Some(v) if is_pipe_name(v) => Ok(v.to_string()),
        Some(v) if v.contains(['/', '\\', ':']) => Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "--socket {v}: on Windows the daemon listens on a named pipe, not a file; give \
                 a bare name N (the pipe {PIPE_PREFIX}tessd-{user}-N) or a full pipe name \
                 {PIPE_PREFIX}NAME"
            ),
        )),
        Some(name) => Ok(format!("{PIPE_PREFIX}tessd-{user}-{name}")),
    }
}

/// `%USERNAME%` as it goes into a pipe name: every character outside `[A-Za-z0-9._-]` becomes
/// `_` (one per character, so that `José` is `Jos_`); `user` when it is unset or empty.
#[cfg(any(windows, test))]
fn pipe_user(raw: Option<&std::ffi::OsStr>) -> String {
    let raw = raw.map(|r| r.to_string_lossy()).unwrap_or_default();
    if raw.is_empty() {
        return "user".into();
    }
    raw.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .collect()
}

#[cfg(unix)]
fn current_uid() -> u32 {
    // SAFETY: getuid has no preconditions and cannot fail.
    unsafe { libc::getuid() }
}

#[cfg(windows)]
fn current_uid() -> String {
    pipe_user(std::env::var_os("USERNAME").as_deref())
}

#[cfg(not(any(unix, windows)))]
fn current_uid() -> String {
    std::env::var("USERNAME").unwrap_or_else(|_| "user".into())
}

/// Creates the per-user socket folder with mode 0700, or checks the one that exists: it must be
/// a real folder (a symbolic link there is refused, never followed: it could lead to a folder
/// someone else controls) owned by this user; one open to others is closed to mode 0700.
#[cfg(unix)]
fn private_dir(dir: &Path) -> io::Result<()> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    match std::fs::DirBuilder::new().mode(0o700).create(dir) {
        Ok(()) => return Ok(()),
        Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {}
        Err(e) => return Err(e),
    }
    let meta = std::fs::symlink_metadata(dir)?;
    if meta.file_type().is_symlink() {
        return Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!(
                "the socket folder {} is a symbolic link{}; refusing to follow it (remove it, \
                 tessd creates the folder itself)",
                dir.display(),
                link_target(dir)
            ),
        ));
    }
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

/// ` (to TARGET)` for a symbolic link whose target can be read, else nothing.
#[cfg(unix)]
fn link_target(path: &Path) -> String {
    std::fs::read_link(path)
        .map(|t| format!(" (to {})", t.display()))
        .unwrap_or_default()
}

#[cfg(not(unix))]
fn private_dir(dir: &Path) -> io::Result<()> {
    std::fs::create_dir_all(dir)
}

/// Connects to the socket at `path`. On Windows `path` is a pipe name (see [`resolve`]), and a
/// pipe that another account owns is refused (it could be squatting on the daemon's name).
///
/// # Errors
/// When nothing listens there; on Windows, also when the pipe is not this user's.
pub fn connect(path: &Path) -> io::Result<Stream> {
    #[cfg(windows)]
    return windows::connect(path);
    #[cfg(not(windows))]
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
    /// The socket path or its folder is not safe to use: a symbolic link, something other than
    /// a socket, or a folder another user owns. Nothing there is followed, removed or changed.
    #[error("refusing to listen on {path}: {reason}")]
    Unsafe {
        /// The socket path.
        path: PathBuf,
        /// What is wrong, naming the offending file or folder.
        reason: String,
    },
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
/// On Windows `path` is a named pipe `\\.\pipe\NAME` (see [`resolve`]), created as its first
/// instance with a security descriptor that admits only the current user (owner and the one
/// ACE of the DACL): a name a daemon of this user holds is [`BindError::InUse`], one another
/// account holds is [`BindError::Unsafe`], and a file path is refused.
///
/// Nothing planted at the path is followed or destroyed: a symbolic link at `path` or at its
/// folder, a file there that is not a socket, or a folder owned by another user (who could
/// swap the socket) is refused with [`BindError::Unsafe`]. A missing folder is created with
/// mode 0700.
///
/// # Errors
/// [`BindError::InUse`] when a daemon answers there; [`BindError::Unsafe`] as above;
/// [`BindError::Io`] otherwise.
pub fn bind(path: &Path) -> Result<Listener, BindError> {
    #[cfg(windows)]
    return windows::bind(path);
    #[cfg(not(windows))]
    bind_file(path)
}

/// [`bind`] for a socket file (everywhere but Windows).
#[cfg(not(windows))]
fn bind_file(path: &Path) -> Result<Listener, BindError> {
    let io_err = |source| BindError::Io {
        path: path.to_path_buf(),
        source,
    };
    let unsafe_path = |reason: String| BindError::Unsafe {
        path: path.to_path_buf(),
        reason,
    };
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        create_folder(parent).map_err(io_err)?;
        check_folder(parent).map_err(unsafe_path)?;
    }
    // Refused before the start lock is taken, so that a refusal leaves nothing beside the path
    // (and checked again under the lock, where the decision is made).
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        check_socket_file(path, &meta).map_err(unsafe_path)?;
    }
    // Daemons started at the same moment (the workers of one node) take turns: between a
    // socket file's creation and its `listen` a connect is refused, and without the lock a
    // second daemon would take that fresh file for stale, delete it and leave the first one
    // listening where nobody can reach it.
    let _turn = StartLock::take(path).map_err(|e| {
        #[cfg(unix)]
        if e.raw_os_error() == Some(libc::ELOOP) {
            return unsafe_path(format!(
                "its lock file {}.lock is a symbolic link; it is not followed (remove it if it \
                 is yours)",
                path.display()
            ));
        }
        io_err(e)
    })?;
    if let Ok(meta) = std::fs::symlink_metadata(path) {
        check_socket_file(path, &meta).map_err(unsafe_path)?;
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

/// Creates `dir` and its missing parents with mode 0700 (nothing is changed when it exists).
#[cfg(not(windows))]
fn create_folder(dir: &Path) -> io::Result<()> {
    let mut builder = std::fs::DirBuilder::new();
    builder.recursive(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::DirBuilderExt;
        builder.mode(0o700);
    }
    builder.create(dir)
}

/// Why the socket's folder `dir` is unsafe: a symbolic link, or a folder owned by a user other
/// than this one and root (who could replace the socket with their own).
#[cfg(unix)]
fn check_folder(dir: &Path) -> Result<(), String> {
    use std::os::unix::fs::MetadataExt;
    let meta = std::fs::symlink_metadata(dir)
        .map_err(|e| format!("cannot inspect its folder {}: {e}", dir.display()))?;
    if meta.file_type().is_symlink() {
        return Err(format!(
            "its folder {} is a symbolic link{}; give the real folder instead",
            dir.display(),
            link_target(dir)
        ));
    }
    if !meta.is_dir() {
        return Err(format!("{} is not a folder", dir.display()));
    }
    let uid = current_uid();
    if meta.uid() != uid && meta.uid() != 0 {
        return Err(format!(
            "its folder {} belongs to another user (uid {}), who could replace the socket",
            dir.display(),
            meta.uid()
        ));
    }
    Ok(())
}

#[cfg(not(any(unix, windows)))]
fn check_folder(_dir: &Path) -> Result<(), String> {
    Ok(())
}

/// Why the existing file at the socket path must not be replaced: a symbolic link (it is not
/// followed, whatever it points to) or anything but a socket (a user's file is never deleted).
#[cfg(unix)]
fn check_socket_file(path: &Path, meta: &std::fs::Metadata) -> Result<(), String> {
    use std::os::unix::fs::FileTypeExt;
    let kind = meta.file_type();
    if kind.is_symlink() {
        return Err(format!(
            "{} is a symbolic link{}, not a socket; it is not followed (remove it if it is yours)",
            path.display(),
            link_target(path)
        ));
    }
    if !kind.is_socket() {
        return Err(format!(
            "{} exists and is not a socket; it is left alone (choose another --socket)",
            path.display()
        ));
    }
    Ok(())
}

#[cfg(not(any(unix, windows)))]
fn check_socket_file(_path: &Path, _meta: &std::fs::Metadata) -> Result<(), String> {
    Ok(())
}

/// An exclusive `flock` on `<socket>.lock`, held while [`bind`] decides whether the socket file
/// is stale and binds (released on drop). The lock file stays, empty, in the socket's private
/// folder; where there is no `flock`, nothing is locked. (Windows' named pipes have no stale
/// files: the first-instance flag decides there.)
#[cfg(not(windows))]
struct StartLock(#[allow(dead_code)] Option<std::fs::File>);

#[cfg(not(windows))]
impl StartLock {
    fn take(socket: &Path) -> io::Result<StartLock> {
        #[cfg(unix)]
        {
            use std::os::unix::io::AsRawFd;
            let file = open_start_lock(socket)?;
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

/// Opens (creating it, mode 0600) `<socket>.lock`, the file whose `flock` orders the daemons
/// binding one socket path ([`bind`]) and the removal of a socket on exit
/// (`socket_watch`); a symbolic link there is refused (`ELOOP`), never followed.
#[cfg(unix)]
pub(crate) fn open_start_lock(socket: &Path) -> io::Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    let mut name = socket.as_os_str().to_owned();
    name.push(".lock");
    std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .mode(0o600)
        .custom_flags(libc::O_NOFOLLOW)
        .open(PathBuf::from(name))
}

#[cfg(test)]
mod pipe_name_tests {
    use super::*;

    #[test]
    fn windows_names_map_to_the_users_pipes() {
        assert_eq!(pipe_name(None, "ann").unwrap(), r"\\.\pipe\tessd-ann");
        assert_eq!(pipe_name(Some(""), "ann").unwrap(), r"\\.\pipe\tessd-ann");
        assert_eq!(
            pipe_name(Some("w1"), "ann").unwrap(),
            r"\\.\pipe\tessd-ann-w1"
        );
        assert_eq!(
            pipe_name(Some(r"\\.\pipe\other"), "ann").unwrap(),
            r"\\.\pipe\other"
        );
        assert_eq!(
            pipe_name(Some(r"\\.\PIPE\Other"), "ann").unwrap(),
            r"\\.\PIPE\Other"
        );
        for bad in [
            r"C:\x\t.sock",
            "C:/x/t.sock",
            "C:t.sock",
            r"\\server\share\t.sock",
            r"\\server\pipe\t",
            r"\\.\pipe\",
            "sub/t",
            r"sub\t",
        ] {
            let e = pipe_name(Some(bad), "ann").unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "{bad}");
            let text = e.to_string();
            assert!(text.starts_with(&format!("--socket {bad}:")), "{text}");
            assert!(text.contains(r"\\.\pipe\tessd-ann-N"), "{text}");
        }
    }

    #[test]
    fn user_names_are_made_safe_for_pipe_names() {
        let u = |s: &str| pipe_user(Some(std::ffi::OsStr::new(s)));
        assert_eq!(u("Ann.B_c-1"), "Ann.B_c-1");
        assert_eq!(u("José Ruiz"), "Jos__Ruiz");
        assert_eq!(u(r"DOM\ann"), "DOM_ann");
        assert_eq!(u(""), "user");
        assert_eq!(pipe_user(None), "user");
    }
}

// windows: compiled out — socket files' modes and planted symbolic links; a pipe has neither
// (socket_windows.rs tests the pipe's DACL and squatters instead).
#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn unsafe_reason(path: &Path) -> String {
        match bind(path) {
            Err(BindError::Unsafe { reason, .. }) => reason,
            Err(e) => panic!("expected a refusal, got {e}"),
            Ok(_) => panic!("bound at {}", path.display()),
        }
    }

    #[test]
    fn a_symlink_or_a_file_at_the_path_is_refused_and_left_alone() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.txt");
        std::fs::write(&target, b"keep").unwrap();
        let path = dir.path().join("t.sock");
        std::os::unix::fs::symlink(&target, &path).unwrap();
        let reason = unsafe_reason(&path);
        assert!(reason.contains("is a symbolic link"), "{reason}");
        assert!(reason.contains("target.txt"), "{reason}");
        assert!(std::fs::symlink_metadata(&path).unwrap().is_symlink());
        std::fs::remove_file(&path).unwrap();

        std::fs::write(&path, b"mine").unwrap();
        let reason = unsafe_reason(&path);
        assert!(reason.contains("is not a socket"), "{reason}");
        assert_eq!(std::fs::read(&path).unwrap(), b"mine");
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        assert!(!dir.path().join("t.sock.lock").exists());
    }

    #[test]
    fn a_symlinked_folder_is_refused_a_missing_one_made_private() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real");
        std::fs::create_dir(&real).unwrap();
        let link = dir.path().join("link");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        let reason = unsafe_reason(&link.join("t.sock"));
        assert!(
            reason.contains("its folder") && reason.contains("symbolic link"),
            "{reason}"
        );
        assert_eq!(std::fs::read_dir(&real).unwrap().count(), 0);

        let fresh = dir.path().join("a").join("b");
        let path = fresh.join("t.sock");
        let listener = bind(&path).unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&fresh), 0o700);
        assert_eq!(mode(&path), 0o600);
        drop(listener);
    }
}
