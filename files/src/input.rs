//! Reading inputs with a size bound.
//!
//! A file given as an input may be anything: `/dev/zero`, a FIFO, a 40 GB log. Every
//! reader of blockstack's files knows how large its files can be, and reads through
//! [`open_bounded`]: anything but a regular file (a folder, a pipe, a device, a socket) is
//! refused from its metadata before it is opened (opening a FIFO with no writer blocks,
//! and a device may never end); a regular file larger than the bound is refused from its
//! metadata, before a byte is read; and a file that grows while it is read is refused at
//! the first byte beyond the bound. Either way the error is one line, and memory never
//! grows past the bound.

use std::fs::File;
use std::io::{self, Read};
use std::path::Path;

use crate::error::{Bytes, FilesError, ReadProblem, Result};

/// A reader that fails (with [`io::ErrorKind::FileTooLarge`]) once more than its bound
/// has been read.
#[derive(Debug)]
pub struct BoundedReader<R> {
    inner: R,
    bound: u64,
    read: u64,
    what: &'static str,
}

impl<R: Read> BoundedReader<R> {
    /// Reads `inner`, allowing at most `bound` bytes; `what` names the kind of file in
    /// the error ("a model file").
    pub fn new(inner: R, bound: u64, what: &'static str) -> Self {
        BoundedReader {
            inner,
            bound,
            read: 0,
            what,
        }
    }

    /// The bound, in bytes.
    pub fn bound(&self) -> u64 {
        self.bound
    }

    /// The problem this reader reports when the bound is passed.
    pub fn too_large(&self) -> ReadProblem {
        ReadProblem::TooLarge {
            bound: self.bound,
            what: self.what,
        }
    }
}

impl<R: Read> Read for BoundedReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        // Ask for at most one byte beyond the bound: enough to tell that it was passed.
        let room = (self.bound - self.read.min(self.bound)).saturating_add(1);
        let want = buf.len().min(usize::try_from(room).unwrap_or(usize::MAX));
        let n = self.inner.read(&mut buf[..want])?;
        self.read += n as u64;
        if self.read > self.bound {
            return Err(io::Error::new(
                io::ErrorKind::FileTooLarge,
                format!("larger than {}, the most {} can be", Bytes(self.bound), self.what),
            ));
        }
        Ok(n)
    }
}

/// Opens `path` to read at most `bound` bytes (module docs); `what` names the kind of file
/// in the errors ("a model file", "a recording").
pub fn open_bounded(path: &Path, bound: u64, what: &'static str) -> Result<BoundedReader<File>> {
    let shown = path.display().to_string();
    let fail = |problem| FilesError::read(&shown, problem);
    // Looked at before it is opened: opening a FIFO with no writer blocks until one comes.
    let before = std::fs::metadata(path).map_err(|e| fail(ReadProblem::Io(e.to_string())))?;
    check_regular(&before, bound, what).map_err(fail)?;
    let file = File::open(path).map_err(|e| fail(ReadProblem::Io(e.to_string())))?;
    // And again once open, in case the path was swapped for something else in between.
    let meta = file.metadata().map_err(|e| fail(ReadProblem::Io(e.to_string())))?;
    check_regular(&meta, bound, what).map_err(fail)?;
    Ok(BoundedReader::new(file, bound, what))
}

/// `Ok` for a regular file of at most `bound` bytes; otherwise the problem, in words.
fn check_regular(meta: &std::fs::Metadata, bound: u64, what: &'static str) -> std::result::Result<(), ReadProblem> {
    if meta.is_dir() {
        return Err(ReadProblem::Io("it is a directory, not a file".into()));
    }
    if !meta.is_file() {
        return Err(ReadProblem::Io(format!(
            "it is a pipe or a device, not a regular file: {what} is read from a file (save it to one first)"
        )));
    }
    if meta.len() > bound {
        return Err(ReadProblem::TooLarge { bound, what });
    }
    Ok(())
}

/// The SHA-256 of the file at `path`, as 64 hex digits, read through [`open_bounded`] (so a
/// pipe, a device or a file over `bound` is refused, naming `what`): what a run that reads
/// the file is keyed by, so that a changed file is a new run.
pub fn digest_file(path: &Path, bound: u64, what: &'static str) -> Result<String> {
    use sha2::{Digest, Sha256};
    let shown = path.display().to_string();
    let mut reader = open_bounded(path, bound, what)?;
    let mut hash = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = reader
            .read(&mut buf)
            .map_err(|e| FilesError::read(&shown, ReadProblem::Io(e.to_string())))?;
        if n == 0 {
            break;
        }
        hash.update(&buf[..n]);
    }
    Ok(hash.finalize().iter().map(|b| format!("{b:02x}")).collect())
}
