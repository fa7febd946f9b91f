//! `blockstack eval`: play a trained model on seeded starts, per goal and overall.

use std::path::{Path, PathBuf};

use agent::Summary;
use agent::eval::{EvalOverrides, EvalReport};
use agent::optimality::Optimality;
use anyhow::{Context, Result};
use clap::Args;
use neural::AnyModel;
use oracle::ExactSolver;

use super::profile::{PlayRulesArgs, ProfileArg};
use super::solver_budget::SolverBudgetArg;
use super::stdout::line;
use super::world::WorldArgs;

/// Arguments of `blockstack eval`.
#[derive(Debug, Args)]
#[command(mut_arg("blocks", |a| a.help("Number of blocks: the model's (another is refused) [default: the model's]")))]
#[command(mut_arg("grid", |a| a.help("Grid size, WxH: the model's (another is refused) [default: the model's]")))]
#[command(mut_arg("reward", |a| a.help("Reward model summed in the episodes: sparse, dense, paper, step-cost or paper-code [default: the model's training reward, or --profile's]")))]
#[command(mut_arg("view", |a| a.help("The world: the model's (the other is refused) [default: the model's]")))]
pub struct EvalArgs {
    /// The model file to evaluate: a tabular agent (`train`), a network (`dqn`) or a
    /// relational policy (`dqn --preset general`).
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
    /// Probability of a random legal action; 0 is greedy [default: the model's own: its
    /// profile's test policy, 0.1, for a tabular model or a network; 0 for a relational
    /// policy]
    #[arg(long)]
    pub epsilon: Option<f64>,
    #[command(flatten)]
    pub world: WorldArgs,
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
    let goals = args
        .goals
        .as_deref()
        .map(|text| sim::Goal::parse_list(text, model.blocks()))
        .transpose()?;
    let w = &args.world;
    let overrides = EvalOverrides {
        goals,
        episodes: args.episodes,
        seed: args.seed,
        profile: args.profile.profile,
        protocol: args.play.protocol,
        start: args.play.start.start,
        reward: w.reward,
        horizon: w.horizon,
        backend: w.backend,
        blocks: w.blocks,
        grid: w.grid,
        view: w.view,
    };
    let plan = model.eval_plan_with(&overrides).map_err(|e| match e {
        // The goals were the default's: say which flag chooses others.
        neural::NeuralError::Sim(sim::SimError::TooManyGoals { .. }) if args.goals.is_none() => {
            anyhow::Error::new(e).context("without --goals every goal of the model's world is used")
        }
        e => e.into(),
    })?;
    let solver = ExactSolver::for_world(&plan.world).with_node_budget(args.budget.budget());
    // Each episode counts twice: played, then solved exactly.
    let bar = super::progress::bar(
        2 * args.episodes * plan.goals.len() as u64,
        "episodes played and solved",
    );
    let evaluation = model
        .evaluate_with(
            &plan,
            &args.model.display().to_string(),
            args.epsilon.unwrap_or(model.default_epsilon()),
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

/// Reads the model file `--model PATH` ([`AnyModel::load`], which refuses a pipe or a
/// device, as Python's `blockstack.load` and `serve` do).
pub(super) fn load_model(path: &Path) -> Result<AnyModel> {
    AnyModel::load(path).context("--model")
}
