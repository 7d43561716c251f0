//! Whether the socket path still names the socket this daemon bound (issue 38).
//!
//! A daemon whose socket file was removed (its folder deleted at logout, a tmp cleaner, a
//! script) or replaced (another daemon took the path) can no longer be reached by any client.
//! The server checks every few seconds, at the cost of one `stat`, that the path is still the
//! file it bound — same device and inode, recorded right after the bind — and leaves when it
//! is not. On the way out it removes the socket file only while it is still its own, so that a
//! daemon that took the path over keeps its socket.
//!
//! Windows: a named pipe cannot be removed from under the daemon that serves it (its name lives
//! as long as one of its instances is open), so there is nothing to watch and nothing to remove.

use std::path::Path;
#[cfg(unix)]
use std::path::PathBuf;

/// The socket file a server bound, and the means to tell whether its path still names it.
pub(crate) struct SocketWatch {
    #[cfg(unix)]
    path: PathBuf,
    /// Device and inode of the socket file right after the bind; `None` when it could not be
    /// read (then the first check reports the loss).
    #[cfg(unix)]
    bound: Option<FileId>,
    /// The last error that left the check undecided, logged once rather than every check.
    #[cfg(unix)]
    undecided: Option<String>,
}

/// A file's identity: its device and inode.
#[cfg(unix)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct FileId {
    dev: u64,
    ino: u64,
}

#[cfg(unix)]
impl FileId {
    /// The identity of the file at `path` itself (a symbolic link there is not followed).
    fn of(path: &Path) -> std::io::Result<FileId> {
        use std::os::unix::fs::MetadataExt;
        let meta = std::fs::symlink_metadata(path)?;
        Ok(FileId {
            dev: meta.dev(),
            ino: meta.ino(),
        })
    }
}

impl SocketWatch {
    /// Records the identity of the socket file at `path`; call it right after the bind.
    pub(crate) fn new(path: &Path) -> SocketWatch {
        #[cfg(unix)]
        {
            let bound = match FileId::of(path) {
                Ok(id) => Some(id),
                Err(e) => {
                    log::warn!(
                        "cannot read the socket file {} just bound: {e}",
                        path.display()
                    );
                    None
                }
            };
            SocketWatch {
                path: path.to_path_buf(),
                bound,
                undecided: None,
            }
        }
        #[cfg(not(unix))]
        {
            let _ = path;
            SocketWatch {}
        }
    }

    /// Why the path no longer names the bound socket (removed, or replaced by another file),
    /// or `None` while it still does. An error other than "not there" (a folder made
    /// unreadable, say) decides nothing: it is logged once and the daemon keeps serving.
    #[cfg(unix)]
    pub(crate) fn lost(&mut self) -> Option<String> {
        use std::io::ErrorKind;
        let path = self.path.display();
        match FileId::of(&self.path) {
            Ok(now) if Some(now) == self.bound => {
                self.undecided = None;
                None
            }
            Ok(now) => Some(match self.bound {
                Some(was) => format!(
                    "the socket {path} was replaced by another file (device {}, inode {}; this \
                     daemon bound device {}, inode {})",
                    now.dev, now.ino, was.dev, was.ino
                ),
                None => format!("the socket {path} was replaced by another file"),
            }),
            Err(e) if matches!(e.kind(), ErrorKind::NotFound | ErrorKind::NotADirectory) => {
                let folder = self
                    .path
                    .parent()
                    .filter(|p| !p.as_os_str().is_empty() && std::fs::symlink_metadata(p).is_err());
                Some(match folder {
                    Some(dir) => format!(
                        "the socket {path} was removed (its folder {} is gone)",
                        dir.display()
                    ),
                    None => format!("the socket {path} was removed"),
                })
            }
            Err(e) => {
                let message = e.to_string();
                if self.undecided.as_ref() != Some(&message) {
                    log::warn!(
                        "cannot check the socket {path}: {message}; still serving, checking again"
                    );
                    self.undecided = Some(message);
                }
                None
            }
        }
    }

    /// Removes the socket file if the path still names the one this daemon bound, deciding
    /// under the start lock (`<socket>.lock`, see `socket::bind`) so that no daemon binds the
    /// path between the check and the removal. Another daemon's socket is left alone; so is the
    /// lock file, which stays for the next daemon (removing a file others may hold locked
    /// would let two daemons each lock their own copy).
    #[cfg(unix)]
    pub(crate) fn remove_if_ours(&self) {
        let Some(bound) = self.bound else { return };
        let _turn = start_lock(&self.path);
        match FileId::of(&self.path) {
            Ok(now) if now == bound => {
                if let Err(e) = std::fs::remove_file(&self.path) {
                    log::warn!("cannot remove the socket {}: {e}", self.path.display());
                }
            }
            Ok(_) => log::info!(
                "leaving {} alone: it is another daemon's socket now",
                self.path.display()
            ),
            Err(_) => {}
        }
    }

    /// Windows: a named pipe goes with its last handle; nothing to remove.
    #[cfg(not(unix))]
    pub(crate) fn remove_if_ours(&self) {}
}

/// Takes the exclusive `flock` on `<socket>.lock` that `socket::bind` holds while it binds,
/// trying for up to a second (the exit path must not hang on it): `None` when the lock file
/// cannot be opened (its folder is gone, then so is the socket) or stays locked.
#[cfg(unix)]
fn start_lock(socket: &Path) -> Option<std::fs::File> {
    use std::os::unix::io::AsRawFd;
    let file = crate::socket::open_start_lock(socket).ok()?;
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(1);
    loop {
        // SAFETY: flock on a descriptor this function owns; LOCK_NB never blocks.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } == 0 {
            return Some(file);
        }
        if std::time::Instant::now() >= deadline {
            log::debug!("the start lock of {} stays taken", socket.display());
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::unix::net::UnixListener;

    #[test]
    fn a_removed_or_replaced_socket_is_lost_and_only_our_own_is_removed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("w.sock");
        let first = UnixListener::bind(&path).unwrap();
        let mut watch = SocketWatch::new(&path);
        assert_eq!(watch.lost(), None);

        // replaced: another socket at the same path
        std::fs::remove_file(&path).unwrap();
        let second = UnixListener::bind(&path).unwrap();
        let why = watch.lost().expect("a replaced socket is lost");
        assert!(why.contains("replaced by another file"), "{why}");
        watch.remove_if_ours();
        assert!(path.exists(), "the other daemon's socket was removed");
        assert!(dir.path().join("w.sock.lock").exists());

        // ours again: removed on the way out
        drop(second);
        std::fs::remove_file(&path).unwrap();
        let _again = UnixListener::bind(&path).unwrap();
        let watch = SocketWatch::new(&path);
        watch.remove_if_ours();
        assert!(!path.exists());
        drop(first);

        // removed, then its folder too
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let path = sub.join("x.sock");
        let _l = UnixListener::bind(&path).unwrap();
        let mut watch = SocketWatch::new(&path);
        std::fs::remove_file(&path).unwrap();
        let why = watch.lost().unwrap();
        assert!(why.ends_with("x.sock was removed"), "{why}");
        std::fs::remove_dir(&sub).unwrap();
        let why = watch.lost().unwrap();
        assert!(
            why.contains("was removed (its folder") && why.contains("is gone"),
            "{why}"
        );
        watch.remove_if_ours();
        assert!(!sub.exists(), "nothing is recreated on the way out");
    }
}
