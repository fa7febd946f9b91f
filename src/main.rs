//! The `blockstack` command: parses arguments and hands them to [`blockstack::cli`].

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = blockstack::cli::Cli::parse();
    match blockstack::cli::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line naming the problem; the chain of causes joined with ": ".
            eprintln!("blockstack: {e:#}");
            ExitCode::from(2)
        }
    }
}
