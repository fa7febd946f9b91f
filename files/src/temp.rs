//! The process-wide registry of live temporary files.
//!
//! Every temporary file this crate makes (the hidden file an atomic replace writes, the
//! probe that checks a folder is writable) is created, renamed and removed while holding
//! the registry's lock, and is listed in it for exactly as long as it exists. So
//! [`remove_temp_files`], called from a Ctrl-C / SIGTERM handler, finds every one: a file
//! is either listed (and removed) or already renamed into place or gone. After that call
//! the registry is closed: no new temporary file can be made, so none can appear between
//! the clean-up and the process's exit.

use std::collections::BTreeSet;
use std::fs::{self, File, OpenOptions};
use std::io;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// The live temporary files, and whether the registry is closed.
struct Registry {
    live: BTreeSet<PathBuf>,
    closed: bool,
    /// Numbers the temporary files of this process, so two writers never collide.
    next: u64,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    live: BTreeSet::new(),
    closed: false,
    next: 0,
});

/// The registry, even after a panic elsewhere poisoned its lock (its state is a set of
/// paths and stays consistent).
fn registry() -> MutexGuard<'static, Registry> {
    REGISTRY.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

fn closed_error() -> io::Error {
    io::Error::new(io::ErrorKind::Interrupted, "the process is ending")
}

/// Creates a new hidden temporary file in `dir` for `name`: `.NAME.PID-N.tmp`, opened for
/// writing, and lists it. First removes the stale temporary files of the same destination
/// ([`remove_stale`]).
pub(crate) fn create(dir: &Path, name: &str) -> io::Result<(File, PathBuf)> {
    let mut reg = registry();
    if reg.closed {
        return Err(closed_error());
    }
    remove_stale(dir, name);
    loop {
        let n = reg.next;
        reg.next += 1;
        let path = dir.join(format!(".{name}.{}-{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(file) => {
                reg.live.insert(path.clone());
                return Ok((file, path));
            }
            // Left by another process with the same id: take the next number.
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Removes the temporary files that processes no longer running left for `dir/name` (a
/// process killed with SIGKILL cannot clean up, and a checkpoint's temporary file can be
/// large). Only this crate's own names for that exact destination, `.NAME.PID-N.tmp`, whose
/// process `PID` is gone; nothing where running processes cannot be told (no `/proc`).
/// Best effort: a file that cannot be listed or removed is left as it is.
fn remove_stale(dir: &Path, name: &str) {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return;
    }
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{name}.");
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(|n| n.strip_suffix(".tmp"))
            .and_then(stale_pid)
        else {
            continue;
        };
        if pid != std::process::id() && !proc.join(pid.to_string()).exists() {
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// The `PID` of a temporary file's `PID-N` part, if it is exactly that.
fn stale_pid(part: &str) -> Option<u32> {
    let (pid, n) = part.split_once('-')?;
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    (digits(pid) && digits(n)).then(|| pid.parse().ok()).flatten()
}

/// Renames the listed temporary file `temp` over `target` and unlists it.
pub(crate) fn rename(temp: &Path, target: &Path) -> io::Result<()> {
    let mut reg = registry();
    if reg.closed {
        return Err(closed_error());
    }
    fs::rename(temp, target)?;
    reg.live.remove(temp);
    Ok(())
}

/// Removes the listed temporary file `temp` (if it still exists) and unlists it.
pub(crate) fn remove(temp: &Path) {
    let mut reg = registry();
    let _ = fs::remove_file(temp);
    reg.live.remove(temp);
}

/// The temporary files alive now.
pub fn live_temp_files() -> Vec<PathBuf> {
    registry().live.iter().cloned().collect()
}

/// Removes every live temporary file and closes the registry: from now on, making a
/// temporary file (and so an atomic write) fails. Call it when the process is about to
/// end on a signal. Returns how many files it removed.
pub fn remove_temp_files() -> usize {
    let mut reg = registry();
    reg.closed = true;
    let mut removed = 0;
    for path in std::mem::take(&mut reg.live) {
        if fs::remove_file(&path).is_ok() {
            removed += 1;
        }
    }
    removed
}
