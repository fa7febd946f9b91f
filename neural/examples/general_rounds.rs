//! Trains the general policy (`dqn --preset general`) with another number of message-passing
//! rounds, everything else the preset's, and saves it: what scripts/policy-scale.sh times
//! beside the preset's own network (the command line does not set the rounds).
//!
//! `cargo run --release -p neural --example general_rounds -- ROUNDS SEED OUT`

use std::path::PathBuf;
use std::process::ExitCode;

use neural::relational::{RelationalConfig, RelationalModel};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [rounds, seed, out] = args.as_slice() else {
        eprintln!("usage: general_rounds ROUNDS SEED OUT");
        return ExitCode::FAILURE;
    };
    let (Ok(rounds), Ok(seed)) = (rounds.parse::<usize>(), seed.parse::<u64>()) else {
        eprintln!("general_rounds: ROUNDS and SEED are whole numbers");
        return ExitCode::FAILURE;
    };
    let mut config = RelationalConfig::general();
    config.shape.rounds = rounds;
    config.seed = seed;
    let trained = config
        .validate()
        .and_then(|()| RelationalModel::train(&config, &mut |_| {}))
        .and_then(|model| model.save(&PathBuf::from(out)));
    match trained {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("general_rounds: {e}");
            ExitCode::FAILURE
        }
    }
}
