//! Writing files so that a crash never leaves a half-written one in place.
//!
//! Everything blockstack writes (trajectories, pictures, models, reports) goes to a
//! temporary file beside the target, which is renamed over the target only once complete.

use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{Result, SimError};

/// Writes `contents` to `path` atomically: a temporary file, then a rename.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<()> {
    let mut w = AtomicWriter::create(path)?;
    w.write_all(contents).map_err(|e| write_error(path, &e))?;
    w.commit()
}

/// A file being written: a temporary beside the target until [`AtomicWriter::commit`]
/// renames it into place. Dropped without a commit, it leaves the target untouched (and
/// the temporary, with whatever was written, for inspection).
pub struct AtomicWriter {
    path: PathBuf,
    temp: PathBuf,
    out: BufWriter<File>,
}

impl AtomicWriter {
    /// Starts writing `path`; an error naming the path if its folder is missing or not
    /// writable.
    pub fn create(path: &Path) -> Result<Self> {
        let mut name = path
            .file_name()
            .ok_or_else(|| write_error(path, &"it names no file"))?
            .to_os_string();
        name.push(format!(".tmp{}", std::process::id()));
        let temp = path.with_file_name(name);
        let file = File::create(&temp).map_err(|e| write_error(path, &e))?;
        Ok(Self {
            path: path.to_path_buf(),
            temp,
            out: BufWriter::new(file),
        })
    }

    /// Finishes the file: flushes, syncs, and renames it over the target.
    pub fn commit(self) -> Result<()> {
        let path = self.path.clone();
        let file = self.out.into_inner().map_err(|e| write_error(&path, &e.error()))?;
        file.sync_all().map_err(|e| write_error(&path, &e))?;
        fs::rename(&self.temp, &self.path).map_err(|e| write_error(&path, &e))
    }

    /// The path being written.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Write for AtomicWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.out.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

/// The error for a failed write of `path`.
pub fn write_error(path: &Path, reason: &dyn std::fmt::Display) -> SimError {
    SimError::Write {
        path: path.display().to_string(),
        reason: reason.to_string(),
    }
}
