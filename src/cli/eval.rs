//! `blockstack eval`: play a trained model on seeded starts, per goal and overall.

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};

use agent::Summary;
use agent::eval::EvalReport;
use agent::optimality::Optimality;
use anyhow::{Context, Result};
use clap::Args;
use neural::AnyModel;
use sim::{Backend, EnvConfig};

use super::profile::{PlayRulesArgs, ProfileArg, played};
use super::solver_budget::SolverBudgetArg;
use super::stdout::line;

/// Arguments of `blockstack eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The model file to evaluate: a tabular agent (`train`) or a network (`dqn`).
    #[arg(long)]
    pub model: PathBuf,
    /// Goals to evaluate on, separated by ':', e.g. 2,1,0:1,2,0 (default: every goal of the
    /// model's world: one tower of every block from above, every goal of towers from the side).
    #[arg(long)]
    pub goals: Option<String>,
    /// Episodes per goal.
    #[arg(long, default_value_t = 500)]
    pub episodes: u64,
    /// Base seed: episode k of every goal starts from seed episode_seed(seed, k).
    #[arg(long, default_value_t = 2)]
    pub seed: u64,
    /// Probability of a random legal action (the paper's test policy: 0.1; 0 is greedy).
    #[arg(long, default_value_t = agent::profile::TEST_EPSILON)]
    pub epsilon: f64,
    /// Steps before an episode is cut off.
    #[arg(long, default_value_t = sim::DEFAULT_HORIZON)]
    pub horizon: u32,
    /// World backend: physics (rapier2d) or grid (occupancy model).
    #[arg(long, default_value = "physics")]
    pub backend: String,
    /// Print the result as one JSON object.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub play: PlayRulesArgs,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
}

/// Evaluates the model ([`neural::AnyModel::evaluate_with`], the library's one evaluation)
/// and prints the figures.
pub fn eval(args: EvalArgs) -> Result<()> {
    let model = load_model(&args.model)?;
    let goals = match args.goals.as_deref() {
        Some(text) => sim::Goal::parse_list(text, model.blocks())?,
        None => sim::Goal::all_in(model.world().view, model.blocks())
            .context("without --goals every goal of the model's world is used")?,
    };
    let backend: Backend = args.backend.parse()?;
    // The model's own world (protocol, start rule) unless the command line says otherwise;
    // the reward only sums up in trajectories, so it is the model's training reward.
    let rules = played(model.parts(), args.profile, args.play, None)?;
    let reward = match (args.profile.profile, model.training_reward()) {
        (None, Some(r)) => r,
        _ => rules.reward,
    };
    let mut plan = model.eval_plan(goals, args.episodes, args.seed);
    plan.profile = rules.profile;
    plan.world = EnvConfig {
        horizon: args.horizon,
        reward,
        backend,
        protocol: rules.protocol,
        start: rules.start,
        ..plan.world
    };
    plan.world.validate()?;
    let solver = args
        .budget
        .solver(model.grid())
        .with_protocol(rules.protocol)
        .with_view(plan.world.view);
    // Each episode counts twice: played, then solved exactly.
    let bar = super::progress::bar(
        2 * args.episodes * plan.goals.len() as u64,
        "episodes played and solved",
    );
    let evaluation = model
        .evaluate_with(
            &plan,
            &args.model.display().to_string(),
            args.epsilon,
            &solver,
            &mut || {
                bar.inc(1);
                Ok(())
            },
        )
        .map_err(|e| args.budget.explain(e))?;
    bar.finish_and_clear();
    let report = evaluation.report;
    if args.json {
        line(serde_json::to_string(&report)?)
    } else {
        print_report(&report)
    }
}

fn print_report(r: &EvalReport) -> Result<()> {
    let run = &r.run;
    line(format_args!(
        "agent {} from {}, {} blocks, grid {}, horizon {}, {} backend, seed {}, epsilon {}; profile {} (protocol {}, start {})",
        run.agent,
        r.model,
        run.blocks,
        run.grid,
        run.horizon,
        run.backend,
        run.seed,
        r.epsilon,
        run.profile,
        run.protocol,
        run.start
    ))?;
    let fmt = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.2}"));
    line(format_args!(
        "{:<10} {:>8} {:>8} {:>10} {:>12} {:>12} {:>10} {:>14}",
        "goal", "episodes", "failures", "mean steps", "median steps", "mean optimum", "mean ratio", "mean, fail=H"
    ))?;
    let row = |name: &str, s: &Summary, o: &Optimality, with_failures: f64| {
        line(format_args!(
            "{:<10} {:>8} {:>8} {:>10} {:>12} {:>12} {:>10} {:>14.2}",
            name,
            s.episodes,
            s.failures,
            fmt(s.mean_steps),
            fmt(s.median_steps),
            fmt(o.mean_optimal_steps),
            o.mean_ratio_to_optimum.map_or("-".to_string(), |v| format!("{v:.4}")),
            with_failures
        ))
    };
    for g in &r.per_goal {
        row(&g.goal, &g.summary, &g.optimality, g.mean_steps_failures_as_horizon)?;
    }
    row("all", &run.summary, &r.optimality, run.mean_steps_failures_as_horizon)?;
    line("steps, optimum and ratio are over the episodes that reached the goal; the optimum is the")?;
    line("exact solver's shortest legal plan from each start; the last column counts a failure as the horizon H")
}

/// Reads the model file `--model PATH`. A pipe or a device (`<(cat m)`) is refused with a
/// line that says so: a model is read twice (its header says which reader reads the file),
/// and the second reading of a pipe finds it empty.
pub(super) fn load_model(path: &Path) -> Result<AnyModel> {
    if let Ok(meta) = std::fs::metadata(path) {
        let kind = meta.file_type();
        anyhow::ensure!(
            !(kind.is_fifo() || kind.is_socket() || kind.is_char_device() || kind.is_block_device()),
            "--model {}: a pipe or a device is not supported as a model file (it is read twice); save the model to a file first",
            path.display()
        );
    }
    Ok(AnyModel::load(path)?)
}
