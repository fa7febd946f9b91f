//! The `blockstack` command: parses arguments and hands them to [`blockstack::cli`].

use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    threads::configure();
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

/// Thread settings of candle, the neural learner's tensor library, made before any thread
/// starts (changing the environment is only sound then).
mod threads {
    /// candle sizes its element-wise thread pool from `CANDLE_NUM_THREADS` and its matrix
    /// products from `RAYON_NUM_THREADS`. Its element-wise pool spins while it waits for
    /// work: on this project's shared 2-core machines the small networks trained about 3x
    /// faster with one such thread than with two. Without `RAYON_NUM_THREADS` candle reads
    /// the CPU list again for every matrix product. A user's own settings win.
    pub fn configure() {
        let cores = std::thread::available_parallelism().map_or(1, usize::from);
        for (name, value) in [("CANDLE_NUM_THREADS", 1), ("RAYON_NUM_THREADS", cores)] {
            if std::env::var_os(name).is_none() {
                // SAFETY: called first thing in main, before any other thread exists.
                unsafe { std::env::set_var(name, value.to_string()) };
            }
        }
    }
}
