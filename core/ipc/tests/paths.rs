//! Path parameters with drive letters and UNC names (issue 37): a request's path is used as
//! given when it is absolute on the platform the daemon runs on, and joined to the job file's
//! folder otherwise. On Windows `C:\a\b.ply`, `C:/a/b.ply` and `\\server\share\b.ply` are
//! absolute; on Unix they are file names like any other (a Unix file may be called `C:\a`).

use std::path::{Path, PathBuf};
use tessd_ipc::arrays::Arrays;
use tessd_ipc::registry::Request;

fn request(base: Option<&str>) -> Request {
    Request {
        params: serde_json::Map::new(),
        arrays: Arrays::from_owned(&[]),
        base_dir: base.map(PathBuf::from),
    }
}

#[test]
fn over_the_socket_paths_are_used_as_given() {
    let r = request(None);
    for p in [
        r"C:\a\b.ply",
        "C:/a/b.ply",
        r"\\server\share\b.ply",
        "//server/share/b.ply",
        "/a/b.ply",
        "b.ply",
    ] {
        assert_eq!(r.resolve(p), Path::new(p), "{p}");
    }
}

#[cfg(windows)]
#[test]
fn windows_drive_and_unc_paths_are_absolute_in_a_job_file() {
    let r = request(Some(r"D:\jobs"));
    for p in [
        r"C:\a\b.ply",
        "C:/a/b.ply",
        r"\\server\share\b.ply",
        "//server/share/b.ply",
        r"\\?\C:\a\b.ply",
    ] {
        assert_eq!(r.resolve(p), Path::new(p), "{p}");
    }
    assert_eq!(r.resolve(r"sub\b.ply"), Path::new(r"D:\jobs\sub\b.ply"));
    assert_eq!(r.resolve("sub/b.ply"), Path::new(r"D:\jobs\sub/b.ply"));
    // Rooted without a drive: on the job folder's drive.
    assert_eq!(r.resolve(r"\a\b.ply"), Path::new(r"D:\a\b.ply"));
    let unc = request(Some(r"\\server\share\jobs"));
    assert_eq!(
        unc.resolve("b.ply"),
        Path::new(r"\\server\share\jobs\b.ply")
    );
}

#[cfg(unix)]
#[test]
fn unix_drive_like_names_are_file_names_in_a_job_file() {
    let r = request(Some("/jobs"));
    assert_eq!(r.resolve(r"C:\a\b.ply"), Path::new(r"/jobs/C:\a\b.ply"));
    assert_eq!(r.resolve("C:/a/b.ply"), Path::new("/jobs/C:/a/b.ply"));
    assert_eq!(r.resolve("/a/b.ply"), Path::new("/a/b.ply"));
    assert_eq!(
        r.resolve("//server/share/b.ply"),
        Path::new("//server/share/b.ply")
    );
}
