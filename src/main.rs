//! The `blockstack` command: parses arguments and hands them to [`blockstack::cli`].
//!
//! Ending: on an error, one line on standard error and exit status 2; when standard
//! output is a pipe whose reader has gone (`blockstack eval ... | head -1`), quietly with
//! status 0, as Unix tools do. On Ctrl-C, SIGTERM or SIGHUP, the temporary files of
//! writes in progress are removed first, and the process then dies of the signal (so a
//! shell sees what killed it).

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    remove_temp_files_on_signals();
    let cli = match blockstack::cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => match blockstack::cli::bad_value(&e) {
            Some(line) => {
                let _ = writeln!(std::io::stderr(), "blockstack: {line}");
                return ExitCode::from(2);
            }
            // Help, version, and usage errors as clap prints them.
            None => e.exit(),
        },
    };
    let outcome = blockstack::cli::run(cli).and_then(|()| blockstack::cli::flush_stdout());
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if blockstack::cli::is_closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            // One line naming the problem; the chain of causes joined with ": ". Standard
            // error may be gone too: nothing more can be said then.
            let _ = writeln!(std::io::stderr(), "blockstack: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// Watches for Ctrl-C (SIGINT), SIGTERM and SIGHUP on a thread of its own (signal-hook,
/// already in the build through the terminal UI's crossterm; unlike `ctrlc` it tells which
/// signal came, so the process can die of it).
fn remove_temp_files_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            files::remove_temp_files();
            let _ = signal_hook::low_level::emulate_default_handler(signal);
            std::process::exit(128 + signal);
        }
    });
}
