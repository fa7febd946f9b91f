//! `blockstack solve-all`: a block-move planner over every PDDL problem of a folder
//! (`oracle::pddl::suite`: each plan checked by replaying its actions over the file's facts,
//! its cost set against its lower bound and the best known cost of an `upper_bounds.json`,
//! the 2023 planning competition's `solutions/upper_bounds.json`): a table and a summary per
//! subfolder.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use oracle::PlannerKind;
use oracle::pddl::suite::{self, BestKnown, SuiteReport, Yardsticks};

use super::solver_budget::{SolverBudgetArg, TimeLimitArg};
use super::stdout::line;

/// Arguments of `blockstack solve-all`.
#[derive(Debug, Args)]
pub struct SolveAllArgs {
    /// The folder of problems: every `*.pddl` in it and its subfolders (but `domain.pddl`),
    /// links followed once each, grouped by subfolder in the summary.
    #[arg(long, value_name = "DIR")]
    pub tasks: PathBuf,
    /// Best known costs, in actions, as a JSON object from a task's path to its cost
    /// (`{"blocksworld/testing/easy/p01.pddl": 10, ...}`); a task takes the most specific
    /// entry its path ends with.
    #[arg(long, value_name = "upper_bounds.json")]
    pub bounds: Option<PathBuf>,
    /// Proven optima: the JSON report of `solve-all --solver optimal --json` (as
    /// docs/results/ipc/optima.json); each plan is set against its task's optimum where that
    /// report proved it.
    #[arg(long, value_name = "optima.json")]
    pub optima: Option<PathBuf>,
    /// The planner: near-optimal (at most twice the optimum, any size), optimal (the
    /// fewest moves with its proof within --time-limit, else its best plan and bound) or
    /// exact (the fewest moves; refuses what its budget cannot finish); exact-moves and
    /// oracle, as the side view names them, are exact and near-optimal here (a PDDL plan
    /// counts block moves) [default: near-optimal]
    #[arg(long)]
    pub solver: Option<PlannerKind>,
    /// Play every task with a learned policy of block moves (`dqn --preset general`) in
    /// place of --solver, greedily; a task it does not finish within 4 moves per block
    /// is a row with its error.
    #[arg(long, value_name = "FILE", conflicts_with = "solver")]
    pub model: Option<PathBuf>,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
    #[command(flatten)]
    pub time_limit: TimeLimitArg,
    /// Print one JSON object: {"solver", "tasks": [...], "groups": [...], "overall"}.
    #[arg(long)]
    pub json: bool,
}

/// Plans every task and prints the table and the summary.
pub fn solve_all(args: SolveAllArgs) -> Result<()> {
    let planner = args
        .budget
        .task_planner(args.time_limit, args.solver, args.model.as_deref())?;
    let best_known = args
        .bounds
        .as_deref()
        .map(BestKnown::read)
        .transpose()
        .context("--bounds")?;
    let optima = args
        .optima
        .as_deref()
        .map(BestKnown::read_optima)
        .transpose()
        .context("--optima")?;
    let against = Yardsticks {
        best_known: best_known.as_ref(),
        optima: optima.as_ref(),
    };
    let mut bar = None;
    let report = suite::run(&args.tasks, planner.as_ref(), against, &mut |_, total| {
        bar.get_or_insert_with(|| super::progress::bar(total as u64, "tasks"))
            .inc(1);
    })
    .with_context(|| format!("--tasks {}", args.tasks.display()))?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    if args.json {
        line(serde_json::to_string(&report)?)
    } else {
        print_report(&report)
    }
}

fn print_report(r: &SuiteReport) -> Result<()> {
    let width = r.tasks.iter().map(|t| t.task.len()).max().unwrap_or(4).max(4);
    let opt = |v: Option<usize>| v.map_or("-".to_string(), |v| v.to_string());
    line(format_args!(
        "{:width$}  {:>6}  {:>6}  {:>7}  {:>7}  {:>4}  {:>7}  {:>10}  {:>6}  {:>7}  {:>6}  {:>8}  {:>8}",
        "task",
        "blocks",
        "moves",
        "actions",
        "l.bound",
        "gap",
        "optimal",
        "best known",
        "ratio",
        "optimum",
        "/ opt.",
        "seconds",
        "cpu s."
    ))?;
    for t in &r.tasks {
        line(format_args!(
            "{:width$}  {:>6}  {:>6}  {:>7}  {:>7}  {:>4}  {:>7}  {:>10}  {:>6}  {:>7}  {:>6}  {:>8.3}  {:>8.3}{}",
            t.task,
            opt(t.blocks),
            opt(t.moves),
            opt(t.actions),
            opt(t.lower_bound),
            opt(t.gap),
            t.optimal.map_or("-", |o| if o { "yes" } else { "no" }),
            t.best_known.map_or("-".to_string(), |b| b.to_string()),
            t.ratio.map_or("-".to_string(), |x| format!("{x:.3}")),
            t.optimum.map_or("-".to_string(), |o| o.to_string()),
            t.over_optimum.map_or("-".to_string(), |x| format!("{x:.3}")),
            t.seconds,
            t.cpu_seconds,
            t.error.as_deref().map_or(String::new(), |e| format!("  {e}"))
        ))?;
    }
    line("")?;
    line(format_args!(
        "{} plans, each replayed over its file's facts; gap = actions - lower bound (0: proven optimal); \
         ratio = actions / best known; / opt. = actions / proven optimum; \
         seconds = wall time, cpu s. = CPU time of the one thread that planned the task",
        r.solver
    ))?;
    line(format_args!(
        "{:8}  {:>5}  {:>6}  {:>7}  {:>7}  {:>10}  {:>9}  {:>14}  {:>10}  {:>9}",
        "group",
        "tasks",
        "solved",
        "optimal",
        "bounded",
        "mean ratio",
        "max ratio",
        "mean / l.bound",
        "mean / opt",
        "max / opt"
    ))?;
    for s in r.groups.iter().chain(std::iter::once(&r.overall)) {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
        line(format_args!(
            "{:8}  {:>5}  {:>6}  {:>7}  {:>7}  {:>10}  {:>9}  {:>14}  {:>10}  {:>9}",
            s.group,
            s.tasks,
            s.solved,
            s.optimal,
            s.bounded,
            f(s.mean_ratio),
            f(s.max_ratio),
            f(s.mean_over_bound),
            f(s.mean_over_optimum),
            f(s.max_over_optimum)
        ))?;
    }
    Ok(())
}
