//! Plans from a seeded start with both planners and prints them.
//!
//! Run: `cargo run --release -p oracle --example plan -- [SEED] [GOAL]`, e.g. `-- 7 1,0,2`.

use oracle::{ExactSolver, Oracle};
use sim::render::{Colour, ascii};
use sim::{Backend, Env, EnvConfig, Goal};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let seed: u64 = args.next().map_or(Ok(7), |s| s.parse())?;
    let goal: Goal = args.next().as_deref().unwrap_or("1,0,2").parse()?;
    let config = EnvConfig {
        backend: Backend::Grid,
        ..EnvConfig::with_goal(goal.clone())
    };
    let obs = Env::new(config.clone())?.reset(seed);
    print!("{}", ascii(&obs, Colour::Never));
    let oracle = Oracle::new(config.grid).plan(&obs.state, &goal)?;
    let exact = ExactSolver::new(config.grid).solve(&obs.state, &goal)?;
    println!("goal {goal}, start {:?}", obs.state.cells());
    println!("oracle ({} actions): {oracle}", oracle.len());
    println!("exact  ({} actions): {exact}", exact.len());
    Ok(())
}
