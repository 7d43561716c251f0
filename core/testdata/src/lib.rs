//! Where tessd's tests find their data, in one place for every crate (a dev-dependency only):
//!
//! - the **shared test data** (real meshes and CAD parts, `shared/data/MANIFEST.md` says where
//!   each comes from): `$TESSD_SHARED_DATA`, else `shared/data` beside the repository;
//! - the **B-Rep fixtures**, `tessd-brep` documents of `core/tessellate/tests/data/`.
//!
//! A missing file fails the test that asked for it, naming the path and the variable to set:
//! a test never skips for want of data.

#![warn(missing_docs)]

use std::path::{Path, PathBuf};

/// The repository's root (this crate lives in `core/testdata`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The shared test-data folder: `$TESSD_SHARED_DATA`, else `../shared/data` beside the
/// repository. Not checked: see [`shared`].
pub fn shared_dir() -> PathBuf {
    let dir = std::env::var_os("TESSD_SHARED_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo_root().join("../shared/data"));
    // Absolute, so that a child process run in another folder finds it too (under Wine a Unix
    // path such as /work/shared/data is relative to the current drive: Z: here, C: in a
    // temporary folder).
    std::path::absolute(&dir).unwrap_or(dir)
}

/// `rel` (such as `"mesh/spot_triangulated.obj"`) in the shared test data.
///
/// # Panics
/// When it does not exist, naming the path and `TESSD_SHARED_DATA`.
pub fn shared(rel: &str) -> PathBuf {
    existing(shared_dir().join(rel), "set TESSD_SHARED_DATA")
}

/// The B-Rep fixture `name` (such as `"bottle.json"`) of `core/tessellate/tests/data/`.
///
/// # Panics
/// When it does not exist.
pub fn brep_fixture(name: &str) -> PathBuf {
    existing(
        repo_root().join("core/tessellate/tests/data").join(name),
        "a fixture of core/tessellate/tests/data",
    )
}

/// The text of the B-Rep fixture `name`.
///
/// # Panics
/// When it cannot be read.
pub fn brep_fixture_text(name: &str) -> String {
    let path = brep_fixture(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {}: {e}", path.display()))
}

fn existing(path: PathBuf, hint: &str) -> PathBuf {
    assert!(
        path.exists(),
        "test data not found at {} ({hint})",
        path.display()
    );
    path
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_fixtures_and_the_shared_data_are_found() {
        assert!(super::brep_fixture_text("bottle.json").contains("tessd-brep"));
        assert!(super::shared("MANIFEST.md").is_file());
    }

    #[test]
    #[should_panic(expected = "test data not found")]
    fn a_missing_file_fails_loudly() {
        super::shared("mesh/no_such_mesh.obj");
    }
}
