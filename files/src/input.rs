//! Reading inputs with a size bound.
//!
//! A file given as an input may be anything: `/dev/zero`, a FIFO, a 40 GB log. Every
//! reader of blockstack's files knows how large its files can be, and reads through
//! [`open_bounded`]: a regular file larger than the bound is refused from its metadata,
//! before a byte is read; anything else (a device, a pipe) is read until the bound and
//! refused at the first byte beyond it. Either way the error is one line naming the
//! bound, and memory never grows past it.

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
    let file = File::open(path).map_err(|e| fail(ReadProblem::Io(e.to_string())))?;
    let meta = file.metadata().map_err(|e| fail(ReadProblem::Io(e.to_string())))?;
    if meta.is_dir() {
        return Err(fail(ReadProblem::Io("it is a directory, not a file".into())));
    }
    if meta.is_file() && meta.len() > bound {
        return Err(fail(ReadProblem::TooLarge { bound, what }));
    }
    Ok(BoundedReader::new(file, bound, what))
}
