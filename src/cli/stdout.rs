//! Standard output through a fallible writer.
//!
//! `println!` panics when standard output fails (a closed pipe, a full disk); every
//! command prints through [`line`](fn@line) and [`text`] instead, whose errors travel back to
//! `main` like any other: a closed pipe ends the command quietly with status 0
//! ([`is_closed_pipe`]), any other failure with one line and status 2. Commands print
//! after their files are written, so a closed pipe never costs a model.
//!
//! A command whose output file is `-` (standard output: `run --trajectory -`) keeps
//! standard output for that data and prints its own report on standard error
//! ([`claim_for_data`]); at most one of its outputs may be `-`.

use std::fmt::Display;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result};
use files::OutputPath;

const CONTEXT: &str = "cannot write to standard output";

/// Whether standard output carries a command's data, so reports go to standard error.
static CARRIES_DATA: AtomicBool = AtomicBool::new(false);

/// Checks a command's outputs before its work: if one of them is standard output, the
/// command's report goes to standard error from now on; two of them cannot both be.
pub fn claim_for_data(outputs: &[Option<&OutputPath>]) -> Result<()> {
    let on_stdout = outputs.iter().flatten().filter(|o| o.is_stdout()).count();
    anyhow::ensure!(
        on_stdout <= 1,
        "only one output can be standard output (-): give the others file names"
    );
    if on_stdout == 1 {
        CARRIES_DATA.store(true, Ordering::Relaxed);
    }
    Ok(())
}

/// Where reports go, and what a failure to write them is called.
fn report() -> (Box<dyn Write>, &'static str) {
    if CARRIES_DATA.load(Ordering::Relaxed) {
        (Box::new(io::stderr()), "cannot write to standard error")
    } else {
        (Box::new(io::stdout()), CONTEXT)
    }
}

/// Prints `text` and a newline.
pub fn line(text: impl Display) -> Result<()> {
    let (mut out, context) = report();
    writeln!(out, "{text}").context(context)
}

/// Prints `text` as it is.
pub fn text(text: &str) -> Result<()> {
    let (mut out, context) = report();
    out.write_all(text.as_bytes()).context(context)
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
