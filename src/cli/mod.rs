//! The command line: one module per subcommand. Errors come back as `anyhow` errors; the
//! binary prints them as one line and exits with status 2.
//!
//! Every command that writes a file checks its destination (`files::OutputPath`) and
//! refuses an output that is one of its inputs before any work starts, and prints through
//! [`stdout`], never `println!`.

use clap::{Parser, Subcommand};
use experiments::reproduce::Report;

mod checkpoint;
mod correct;
mod demo;
mod dqn;
mod eval;
mod generate;
mod learn_from_demos;
mod pilot;
mod profile;
mod progress;
mod render;
mod reproduce;
mod run;
mod serve;
mod solve;
mod solve_all;
mod solver_budget;
pub mod stdout;
mod train;
mod world;

pub use stdout::{flush_stdout, is_closed_pipe};

/// blockstack: teach an agent to stack blocks in a physics-backed 2D world.
#[derive(Debug, Parser)]
#[command(name = "blockstack", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Reproduce the paper: run experiments E1-E8 and write the report (README.md, results.json, pictures).
    Reproduce(reproduce::ReproduceArgs),
    /// The classic Blocks World benchmark, ours: run E9 and E10 and write their report (as `reproduce` does).
    Benchmark(reproduce::ReproduceArgs),
    /// Play episodes with an agent and report failures and steps to goal.
    Run(run::RunArgs),
    /// Draw a start state as a PNG picture or as text.
    Render(render::RenderArgs),
    /// Plan from a given state with the exact solver or the oracle, or a PDDL problem's block moves, and print the plan.
    Solve(solve::SolveArgs),
    /// Plan every PDDL problem of a folder and compare the costs with the best known ones.
    SolveAll(solve_all::SolveAllArgs),
    /// Write seeded random Blocks World problems as PDDL files.
    Generate(generate::GenerateArgs),
    /// Train a tabular Q-learner and save it as a model file.
    Train(train::TrainArgs),
    /// Evaluate a model on seeded starts, per goal and overall.
    Eval(eval::EvalArgs),
    /// Watch a trained agent play in the terminal and correct it; it learns from each correction.
    Demo(demo::DemoArgs),
    /// Let a simulated demonstrator (1, 2 or 3) correct a trained agent, headless.
    Correct(correct::CorrectArgs),
    /// Apply a recorded demonstration session to a model, headless.
    LearnFromDemos(learn_from_demos::LearnFromDemosArgs),
    /// Train a deep Q-network (DQN, or DQfD from demonstrations) and save it as a network file.
    Dqn(Box<dqn::DqnArgs>),
    /// Serve a page where people play, watch and correct the agent in a browser; studies.
    Serve(serve::ServeArgs),
    /// Pilot a study: simulated participants through the real server, before a launch.
    Pilot(pilot::PilotArgs),
}

/// A flag's value that clap refused (`--view front`), as one line naming the flag, the value
/// and why: `--view front: cannot read view from "front": choose one of top, side`, as every
/// other bad input is reported. `None` for other errors (help, version, usage).
pub fn bad_value(e: &clap::Error) -> Option<String> {
    use clap::error::{ContextKind, ContextValue, ErrorKind};
    if !matches!(e.kind(), ErrorKind::ValueValidation | ErrorKind::InvalidValue) {
        return None;
    }
    let text = |kind| match e.get(kind) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        Some(ContextValue::Strings(s)) => Some(s.join(", ")),
        _ => None,
    };
    // "--view <VIEW>": the flag alone.
    let flag = text(ContextKind::InvalidArg)?;
    let flag = flag.split([' ', '=']).next().unwrap_or(&flag).to_string();
    let value = text(ContextKind::InvalidValue).unwrap_or_default();
    let why = match (std::error::Error::source(e), text(ContextKind::ValidValue)) {
        (Some(source), _) => source.to_string(),
        (None, Some(valid)) => format!("choose one of {valid}"),
        (None, None) => "not a value it takes".to_string(),
    };
    Some(format!("{flag} {value}: {why}"))
}

/// Carries out `cli`'s command.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Reproduce(args) => reproduce::reproduce(args, Report::Paper),
        Command::Benchmark(args) => reproduce::reproduce(args, Report::BlocksWorld),
        Command::Run(args) => run::run(args),
        Command::Render(args) => render::render(args),
        Command::Solve(args) => solve::solve(args),
        Command::SolveAll(args) => solve_all::solve_all(args),
        Command::Generate(args) => generate::generate(args),
        Command::Train(args) => train::train(args),
        Command::Eval(args) => eval::eval(args),
        Command::Demo(args) => demo::demo(args),
        Command::Correct(args) => correct::correct(args),
        Command::LearnFromDemos(args) => learn_from_demos::learn_from_demos(args),
        Command::Dqn(args) => dqn::dqn(*args),
        Command::Serve(args) => serve::serve(args),
        Command::Pilot(args) => pilot::pilot(args),
    }
}
