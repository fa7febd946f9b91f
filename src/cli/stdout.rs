//! Standard output through a fallible writer.
//!
//! `println!` panics when standard output fails (a closed pipe, a full disk); every
//! command prints through [`line`] and [`text`] instead, whose errors travel back to
//! `main` like any other: a closed pipe ends the command quietly with status 0
//! ([`is_closed_pipe`]), any other failure with one line and status 2. Commands print
//! after their files are written, so a closed pipe never costs a model.

use std::fmt::Display;
use std::io::{self, Write};

use anyhow::{Context, Result};

const CONTEXT: &str = "cannot write to standard output";

/// Prints `text` and a newline.
pub fn line(text: impl Display) -> Result<()> {
    writeln!(io::stdout(), "{text}").context(CONTEXT)
}

/// Prints `text` as it is.
pub fn text(text: &str) -> Result<()> {
    io::stdout().write_all(text.as_bytes()).context(CONTEXT)
}

/// Flushes standard output: its last bytes may still be buffered when a command ends.
pub fn flush_stdout() -> Result<()> {
    io::stdout().flush().context(CONTEXT)
}

/// Whether `e` comes from writing to a pipe whose reader has gone.
pub fn is_closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        let files_error = |f: &files::FilesError| f.is_closed_pipe();
        cause
            .downcast_ref::<io::Error>()
            .is_some_and(|e| e.kind() == io::ErrorKind::BrokenPipe)
            || cause.downcast_ref::<files::FilesError>().is_some_and(files_error)
            || matches!(cause.downcast_ref::<sim::SimError>(), Some(sim::SimError::Files(f)) if files_error(f))
            || matches!(
                cause.downcast_ref::<agent::AgentError>(),
                Some(agent::AgentError::Files(f) | agent::AgentError::Sim(sim::SimError::Files(f))) if files_error(f)
            )
    })
}
