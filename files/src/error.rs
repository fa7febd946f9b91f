//! The errors of reading and writing files: each names the path and says what to do.

use std::fmt;
use std::io;

use thiserror::Error;

/// What can go wrong while checking a destination, writing, or reading a file.
///
/// Every variant displays as one line that names the path. The reasons are kept as text
/// (not as `io::Error`s) so that the error can be cloned and compared, as the errors of
/// the crates above it are.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum FilesError {
    /// A destination that cannot be written, found before any work: a directory, a
    /// missing or unwritable folder, a path that names no file.
    #[error("cannot write {path}: {reason}")]
    Destination {
        /// The path as given.
        path: String,
        /// What is wrong and what to do.
        reason: String,
    },
    /// Writing (or committing) failed.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// The path as given (`-` for standard output).
        path: String,
        /// The system's reason.
        reason: String,
        /// The kind of the underlying I/O error (`BrokenPipe` for a closed pipe).
        kind: io::ErrorKind,
    },
    /// An output that is also one of the command's inputs.
    #[error(
        "{output} is also the input {input}: writing it would destroy the input, so write the output to another file"
    )]
    SameFile {
        /// The output path as given.
        output: String,
        /// The input path as given.
        input: String,
    },
    /// A file that cannot be read, or whose contents are not what was expected.
    #[error("cannot read {path}: {problem}")]
    Read {
        /// The path as given.
        path: String,
        /// What is wrong.
        problem: ReadProblem,
    },
}

impl FilesError {
    /// Whether this is a write to a pipe whose reader has gone (`| head -1`): a command
    /// ends quietly then, as Unix tools do.
    pub fn is_closed_pipe(&self) -> bool {
        matches!(
            self,
            FilesError::Write {
                kind: io::ErrorKind::BrokenPipe,
                ..
            }
        )
    }

    /// The error for a failed write of `path`.
    pub fn write(path: &std::path::Path, e: &io::Error) -> FilesError {
        FilesError::Write {
            path: path.display().to_string(),
            reason: e.to_string(),
            kind: e.kind(),
        }
    }

    /// The error for an unusable destination `path`.
    pub fn destination(path: &std::path::Path, reason: impl Into<String>) -> FilesError {
        FilesError::Destination {
            path: path.display().to_string(),
            reason: reason.into(),
        }
    }

    /// The error for a file `path` that cannot be read.
    pub fn read(path: &str, problem: ReadProblem) -> FilesError {
        FilesError::Read {
            path: path.into(),
            problem,
        }
    }
}

/// Why a file cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ReadProblem {
    /// The system refused (missing file, no permission, a directory, ...).
    #[error("{0}")]
    Io(String),
    /// Larger than anything of its kind can be.
    #[error("it is larger than {}, the most {what} can be", Bytes(*bound))]
    TooLarge {
        /// The bound, in bytes.
        bound: u64,
        /// What the file was read as ("a model file").
        what: &'static str,
    },
    /// Not a safetensors file at all.
    #[error("it is not a safetensors file ({0})")]
    NotSafetensors(String),
    /// A safetensors file of another format (or of none).
    #[error("it is a safetensors file, but {} and not {expected}", found.as_ref().map_or("of no blockstack format".to_string(), |f| format!("a {f} file")))]
    OtherFormat {
        /// The format expected.
        expected: String,
        /// The format the file names, if any.
        found: Option<String>,
    },
    /// A newer version of the format than this build reads.
    #[error(
        "it is {format} version {found}, newer than this blockstack reads (version {supported}): use a newer blockstack"
    )]
    Newer {
        /// The format.
        format: String,
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// An older version of the format than this build reads.
    #[error("it is {format} version {found}, and this blockstack reads version {supported} only")]
    Older {
        /// The format.
        format: String,
        /// The file's version.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// Damaged: a checksum that does not match, an inconsistent header, extra bytes.
    #[error("the file is corrupt: {0}")]
    Corrupt(String),
    /// Cut short: it ends before what its header declares.
    #[error("the file is truncated: {0}")]
    Truncated(String),
}

/// A byte count for people: `1 GiB`, `64 KiB`, `1000 bytes`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Bytes(pub u64);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
        let mut value = self.0;
        let mut unit = None;
        for u in UNITS {
            if value >= 1024 && value.is_multiple_of(1024) {
                value /= 1024;
                unit = Some(u);
            } else {
                break;
            }
        }
        match unit {
            Some(u) => write!(f, "{value} {u}"),
            None => write!(f, "{value} bytes"),
        }
    }
}

/// Shorthand for results whose error is a [`FilesError`].
pub type Result<T, E = FilesError> = std::result::Result<T, E>;
