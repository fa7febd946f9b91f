//! What the `agent` integration tests share.

use std::path::{Path, PathBuf};

/// A file path in a fresh folder of the system's temporary directory; the folder, and the
/// file in it, go when this is dropped.
pub struct TempPath {
    _dir: tempfile::TempDir,
    path: PathBuf,
}

impl std::ops::Deref for TempPath {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.path
    }
}

impl AsRef<Path> for TempPath {
    fn as_ref(&self) -> &Path {
        &self.path
    }
}

/// A path named `name` in a fresh scratch folder.
pub fn temp_path(name: &str) -> TempPath {
    let dir = tempfile::tempdir().expect("a scratch folder");
    let path = dir.path().join(name);
    TempPath { _dir: dir, path }
}
