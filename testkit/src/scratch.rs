//! Scratch folders for the workspace's tests, removed when a test ends so that test runs do
//! not fill the disk.

use std::path::Path;

/// A fresh, empty scratch folder, removed with everything in it when the test ends (passed
/// or failed), so that test runs do not fill the disk.
pub struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;

    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A fresh scratch folder in the system's temporary directory, its name starting with `name`.
pub fn scratch(name: &str) -> Scratch {
    let dir = tempfile::Builder::new()
        .prefix(&format!("blockstack-test-{name}-"))
        .tempdir()
        .expect("a scratch folder");
    Scratch(dir)
}
