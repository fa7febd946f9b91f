//! Writing outputs safely: every command's files go through here.
//!
//! [`OutputPath::check`] classifies a destination *before* any work starts, so that a
//! typo in a folder name fails at once, not after an hour of training:
//!
//! | destination | how it is written |
//! |---|---|
//! | `-` | to standard output |
//! | an existing regular file, or a new path | atomic replace: a hidden temporary file in the same folder, flushed, synced and renamed over the target by [`Output::commit`] |
//! | a character device, FIFO or socket (`/dev/null`, `mkfifo`) | opened and written directly; it stays what it is |
//! | a symbolic link | followed (link after link); its target is classified as above, and the link itself stays a link |
//! | a directory, a missing folder, a folder that is not writable | an error naming the path and what to do |
//!
//! An atomic write that is dropped without [`Output::commit`], or fails on the way,
//! removes its temporary file; one alive when the process is signalled is removed by
//! [`crate::remove_temp_files`]; one that a process killed outright (SIGKILL) left is
//! removed by the next check or write of the same destination. A reader of the target sees the old file or the new one,
//! never half of one.
//!
//! # Appending
//!
//! A file that grows as things happen (a demonstration recording: "a crash loses nothing
//! already recorded") is not written through a temporary file, which a crash would lose
//! whole: [`OutputPath::append`] opens the target itself to append (creating a regular
//! file if missing), after the same checks. Its writer flushes what it is given to the
//! file; whole lines written with one call and flushed are never torn by a kill.
//!
//! # Inputs and outputs
//!
//! [`refuse_same_file`] refuses an output that is one of a command's inputs (the same
//! device and inode when both exist, else the same normalised path): writing it would
//! destroy the input, and reading it while it is replaced gives nonsense.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Component, Path, PathBuf};

use crate::error::{FilesError, Result};
use crate::temp;

/// The name that means standard output.
pub const STDOUT: &str = "-";

/// Symbolic links followed before giving up (Linux's own limit).
const MAX_LINKS: usize = 40;

/// What kind of special file a destination is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Special {
    /// A character device (`/dev/null`, a terminal).
    CharDevice,
    /// A block device.
    BlockDevice,
    /// A named pipe.
    Fifo,
    /// A Unix socket.
    Socket,
}

/// How a destination is written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// Standard output (the path `-`).
    Stdout,
    /// A regular file or a new path (symbolic links resolved): replaced atomically, or
    /// appended to.
    File {
        /// The file to write, links resolved.
        target: PathBuf,
    },
    /// A special file (links resolved), written directly.
    Special {
        /// The file to write, links resolved.
        target: PathBuf,
        /// What it is.
        kind: Special,
    },
}

/// A destination checked and classified; see the module docs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputPath {
    path: PathBuf,
    destination: Destination,
}

impl OutputPath {
    /// Classifies `path` (module docs); an error naming the path and what to do if it
    /// cannot be written. A regular file's folder is checked to be writable by making and
    /// removing a hidden probe file in it.
    pub fn check(path: impl AsRef<Path>) -> Result<OutputPath> {
        let path = path.as_ref();
        let destination = classify(path)?;
        Ok(OutputPath {
            path: path.to_path_buf(),
            destination,
        })
    }

    /// Classifies `path` as [`OutputPath::check`] does, and accepts only a regular file or
    /// a new path (links followed), never standard output or a special file: for a file
    /// that replaces the one before it whole (a plan file), which a pipe or a device would
    /// not hold.
    pub fn check_regular(path: impl AsRef<Path>) -> Result<OutputPath> {
        let out = OutputPath::check(&path)?;
        let kind = match &out.destination {
            Destination::File { .. } => return Ok(out),
            Destination::Stdout => "standard output",
            Destination::Special { kind, .. } => match kind {
                Special::CharDevice => "a character device",
                Special::BlockDevice => "a block device",
                Special::Fifo => "a named pipe",
                Special::Socket => "a socket",
            },
        };
        Err(FilesError::destination(
            path.as_ref(),
            format!("it is {kind}, not a regular file: give a regular file or a new path"),
        ))
    }

    /// The path as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// How it is written.
    pub fn destination(&self) -> &Destination {
        &self.destination
    }

    /// Whether this is standard output.
    pub fn is_stdout(&self) -> bool {
        self.destination == Destination::Stdout
    }

    /// Starts writing the whole file: atomically for a regular file (module docs). The
    /// destination is classified again first: it may have changed since the check.
    pub fn create(&self) -> Result<Output> {
        let fresh = OutputPath::check(&self.path)?;
        let sink = match &fresh.destination {
            Destination::Stdout => Sink::Stdout(io::stdout()),
            Destination::Special { target, .. } => Sink::Direct(BufWriter::new(open_special(&self.path, target)?)),
            Destination::File { target } => {
                let (dir, name) = folder_and_name(&self.path, target)?;
                let (file, temp) = temp::create(&dir, &name).map_err(|e| FilesError::write(&self.path, &e))?;
                // A replaced file keeps its permissions.
                if let Ok(old) = fs::metadata(target) {
                    let _ = file.set_permissions(old.permissions());
                }
                Sink::Atomic {
                    out: BufWriter::new(file),
                    temp,
                    target: target.clone(),
                }
            }
        };
        Ok(Output {
            path: self.path.clone(),
            sink: Some(sink),
        })
    }

    /// Opens the destination to append to (module docs: recordings): a regular file is
    /// created if missing and written in place, not through a temporary file.
    pub fn append(&self) -> Result<Output> {
        let fresh = OutputPath::check(&self.path)?;
        let sink = match &fresh.destination {
            Destination::Stdout => Sink::Stdout(io::stdout()),
            Destination::Special { target, .. } => Sink::Direct(BufWriter::new(open_special(&self.path, target)?)),
            Destination::File { target } => {
                let file = OpenOptions::new()
                    .create(true)
                    .append(true)
                    .open(target)
                    .map_err(|e| FilesError::write(&self.path, &e))?;
                Sink::Direct(BufWriter::new(file))
            }
        };
        Ok(Output {
            path: self.path.clone(),
            sink: Some(sink),
        })
    }

    /// Writes `contents` as the whole file and commits it.
    pub fn write(&self, contents: &[u8]) -> Result<()> {
        let mut out = self.create()?;
        out.write_all(contents).map_err(|e| FilesError::write(&self.path, &e))?;
        out.commit()
    }
}

/// Checks `path` and writes `contents` as the whole file (atomically for a regular file).
pub fn write(path: impl AsRef<Path>, contents: &[u8]) -> Result<()> {
    OutputPath::check(path)?.write(contents)
}

/// A destination being written; see the module docs. Dropped without [`Output::commit`]
/// (an error on the way), an atomic write removes its temporary file and leaves the
/// target as it was.
#[derive(Debug)]
pub struct Output {
    path: PathBuf,
    /// `None` once committed.
    sink: Option<Sink>,
}

#[derive(Debug)]
enum Sink {
    Stdout(io::Stdout),
    Direct(BufWriter<File>),
    Atomic {
        out: BufWriter<File>,
        temp: PathBuf,
        target: PathBuf,
    },
}

impl Output {
    /// The path as given (`-` for standard output).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The error for a failed write of this output.
    pub fn error(&self, e: &io::Error) -> FilesError {
        FilesError::write(&self.path, e)
    }

    /// Finishes the output: flushes it, and for an atomic write syncs the temporary file,
    /// renames it over the target and syncs the folder.
    pub fn commit(mut self) -> Result<()> {
        let fail = |e: &io::Error| FilesError::write(&self.path, e);
        match self.sink.take().expect("an output is committed once") {
            Sink::Stdout(mut out) => out.flush().map_err(|e| fail(&e)),
            Sink::Direct(mut out) => out.flush().map_err(|e| fail(&e)),
            Sink::Atomic { out, temp, target } => {
                let done = out
                    .into_inner()
                    .map_err(|e| e.into_error())
                    .and_then(|file| file.sync_all())
                    .and_then(|()| temp::rename(&temp, &target));
                if let Err(e) = done {
                    temp::remove(&temp);
                    return Err(fail(&e));
                }
                // The rename is durable once the folder is synced too.
                if let Some(dir) = target.parent() {
                    let dir = if dir.as_os_str().is_empty() {
                        Path::new(".")
                    } else {
                        dir
                    };
                    let _ = File::open(dir).and_then(|d| d.sync_all());
                }
                Ok(())
            }
        }
    }
}

impl Write for Output {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self.sink.as_mut().expect("not committed") {
            Sink::Stdout(out) => out.write(buf),
            Sink::Direct(out) | Sink::Atomic { out, .. } => out.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self.sink.as_mut().expect("not committed") {
            Sink::Stdout(out) => out.flush(),
            Sink::Direct(out) | Sink::Atomic { out, .. } => out.flush(),
        }
    }
}

impl Drop for Output {
    fn drop(&mut self) {
        if let Some(Sink::Atomic { temp, .. }) = &self.sink {
            temp::remove(temp);
        }
    }
}

/// Opens a special file to write.
fn open_special(path: &Path, target: &Path) -> Result<File> {
    OpenOptions::new()
        .write(true)
        .open(target)
        .map_err(|e| FilesError::write(path, &e))
}

/// The folder a regular file `target` lives in (`.` for a bare name) and its file name.
fn folder_and_name(path: &Path, target: &Path) -> Result<(PathBuf, String)> {
    let name = target
        .file_name()
        .ok_or_else(|| FilesError::destination(path, "it names no file: give a file name"))?
        .to_string_lossy()
        .into_owned();
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    Ok((dir, name))
}

/// Classifies `path` (module docs).
fn classify(path: &Path) -> Result<Destination> {
    if path.as_os_str() == STDOUT {
        return Ok(Destination::Stdout);
    }
    if path.as_os_str().is_empty() {
        return Err(FilesError::destination(path, "the path is empty: give a file name"));
    }
    if path.as_os_str().to_string_lossy().ends_with('/') {
        return Err(FilesError::destination(
            path,
            "it names a folder (it ends with '/'): give a file name inside it",
        ));
    }
    let mut target = path.to_path_buf();
    for _ in 0..=MAX_LINKS {
        match fs::symlink_metadata(&target) {
            Ok(meta) => {
                let kind = meta.file_type();
                if kind.is_symlink() {
                    let link = fs::read_link(&target).map_err(|e| FilesError::destination(path, e.to_string()))?;
                    let next = match target.parent() {
                        Some(dir) if link.is_relative() => dir.join(link),
                        _ => link,
                    };
                    // A link whose text names no file but which the system follows, to a
                    // special file: `/dev/fd/N` of a pipe (`>(cat > t)`) reads "pipe:[123]".
                    // The special file is written through the link itself.
                    if fs::symlink_metadata(&next).is_err()
                        && let Some(kind) = fs::metadata(&target).ok().and_then(|m| special_of(m.file_type()))
                    {
                        return Ok(Destination::Special { target, kind });
                    }
                    target = next;
                    continue;
                }
                if kind.is_dir() {
                    return Err(FilesError::destination(
                        path,
                        format!(
                            "it is a directory: give a file name inside it, e.g. {}",
                            path.join("NAME").display()
                        ),
                    ));
                }
                return match special_of(kind) {
                    Some(kind) => Ok(Destination::Special { target, kind }),
                    None => {
                        check_folder(path, &target)?;
                        Ok(Destination::File { target })
                    }
                };
            }
            Err(e) if matches!(e.kind(), io::ErrorKind::NotFound | io::ErrorKind::NotADirectory) => {
                check_folder(path, &target)?;
                return Ok(Destination::File { target });
            }
            Err(e) => return Err(FilesError::destination(path, e.to_string())),
        }
    }
    Err(FilesError::destination(
        path,
        format!("more than {MAX_LINKS} symbolic links to follow: is there a loop?"),
    ))
}

/// What kind of special file `kind` is, if it is one.
fn special_of(kind: fs::FileType) -> Option<Special> {
    if kind.is_char_device() {
        Some(Special::CharDevice)
    } else if kind.is_block_device() {
        Some(Special::BlockDevice)
    } else if kind.is_fifo() {
        Some(Special::Fifo)
    } else if kind.is_socket() {
        Some(Special::Socket)
    } else {
        None
    }
}

/// Checks that the folder of the regular file `target` (given as `path`) exists and that
/// a file can be made in it.
fn check_folder(path: &Path, target: &Path) -> Result<()> {
    let (dir, name) = folder_and_name(path, target)?;
    match fs::metadata(&dir) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => {
            return Err(FilesError::destination(
                path,
                format!("{} is not a folder", dir.display()),
            ));
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => {
            return Err(FilesError::destination(
                path,
                format!(
                    "the folder {} does not exist: create it first (mkdir -p {})",
                    dir.display(),
                    dir.display()
                ),
            ));
        }
        Err(e) => {
            return Err(FilesError::destination(
                path,
                format!("cannot use the folder {}: {e}", dir.display()),
            ));
        }
    }
    probe(path, &dir, &name)
}

/// Makes and removes a hidden file in `dir`: the one test of writability that holds for
/// root, read-only file systems and access lists alike.
fn probe(path: &Path, dir: &Path, name: &str) -> Result<()> {
    match temp::create(dir, name) {
        Ok((_, probe)) => {
            temp::remove(&probe);
            Ok(())
        }
        Err(e) => Err(FilesError::destination(
            path,
            format!(
                "the folder {} is not writable ({e}): choose another folder or make it writable",
                dir.display()
            ),
        )),
    }
}

/// Makes the folder `path` (and its parents) if missing, and checks that it is a folder
/// and writable: for commands whose output is a folder of files.
pub fn prepare_folder(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    match fs::metadata(path) {
        Ok(meta) if !meta.is_dir() => {
            return Err(FilesError::destination(
                path,
                "it exists and is not a folder: give a folder (it is made if missing)",
            ));
        }
        Ok(_) => {}
        Err(_) => fs::create_dir_all(path)
            .map_err(|e| FilesError::destination(path, format!("cannot make the folder: {e}")))?,
    }
    probe(path, path, "probe")
}

/// An error if the output `output` is the input `input`: the same device and inode when
/// both exist (links, hard links and other spellings included), else the same path once
/// made absolute and normalised. Standard output is never an input.
pub fn refuse_same_file(output: impl AsRef<Path>, input: impl AsRef<Path>) -> Result<()> {
    let (output, input) = (output.as_ref(), input.as_ref());
    if output.as_os_str() == STDOUT {
        return Ok(());
    }
    let same = match (fs::metadata(output), fs::metadata(input)) {
        (Ok(o), Ok(i)) => (o.dev(), o.ino()) == (i.dev(), i.ino()),
        _ => normalised(output) == normalised(input),
    };
    if same {
        Err(FilesError::SameFile {
            output: output.display().to_string(),
            input: input.display().to_string(),
        })
    } else {
        Ok(())
    }
}

/// `path` made absolute with its existing folder's links resolved, `.` and `..` removed.
fn normalised(path: &Path) -> PathBuf {
    let absolute = std::env::current_dir().map_or_else(|_| path.to_path_buf(), |cwd| cwd.join(path));
    // Resolve the folder when it exists, so that `a/../b` and links to folders compare.
    if let (Some(dir), Some(name)) = (absolute.parent(), absolute.file_name())
        && let Ok(dir) = fs::canonicalize(dir)
    {
        return dir.join(name);
    }
    let mut out = PathBuf::new();
    for part in absolute.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}
