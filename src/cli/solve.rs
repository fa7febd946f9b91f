//! `blockstack solve`: a plan from a given state, by the exact solver or the oracle.

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use oracle::Oracle;
use serde::Serialize;
use sim::{Goal, Grid, State};

use super::solver_budget::SolverBudgetArg;
use super::stdout::line;

/// Which planner solves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SolverKind {
    /// The exact solver: a shortest plan.
    Exact,
    /// The centroid + A* oracle.
    Oracle,
}

impl SolverKind {
    fn name(self) -> &'static str {
        match self {
            SolverKind::Exact => "exact",
            SolverKind::Oracle => "oracle",
        }
    }
}

/// Arguments of `blockstack solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Every block's cell, block 0 first: x,y pairs separated by ';', e.g. "0,0;3,0;5,2".
    #[arg(long)]
    pub start: String,
    /// The goal, bottom to top, e.g. 1,0,2.
    #[arg(long)]
    pub goal: String,
    /// The block held at the start (default: none).
    #[arg(long)]
    pub held: Option<usize>,
    /// Grid size, WxH.
    #[arg(long, default_value = "7x7")]
    pub grid: String,
    /// The planner.
    #[arg(long, value_enum, default_value_t = SolverKind::Exact)]
    pub solver: SolverKind,
    /// The action protocol the plan keeps to: free (every action legal) or paper (nothing
    /// held: only pick; holding: only moves and drop); the exact plan is the shortest legal
    /// one.
    #[arg(long, default_value = "free")]
    pub protocol: sim::ActionProtocol,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
    /// Print the plan as one JSON object: {"length":L,"actions":[indices],"solver":"exact"}.
    #[arg(long)]
    pub json: bool,
}

/// The machine-readable plan.
#[derive(Debug, Serialize)]
struct SolveReport {
    length: usize,
    actions: Vec<usize>,
    solver: &'static str,
}

/// Plans and prints the plan.
pub fn solve(args: SolveArgs) -> Result<()> {
    let grid: Grid = args.grid.parse().context("--grid")?;
    let state = State::parse(&args.start, args.held, grid).with_context(|| {
        if args.held.is_some() {
            "--start and --held"
        } else {
            "--start"
        }
    })?;
    let goal = Goal::parse(&args.goal, Some(state.block_count())).context("--goal")?;
    anyhow::ensure!(
        args.solver == SolverKind::Exact || args.budget.solver_budget.is_none(),
        "--solver-budget is the exact solver's: it does not apply to --solver {}",
        args.solver.name()
    );
    let plan = match args.solver {
        SolverKind::Exact => args
            .budget
            .solver(grid)
            .with_protocol(args.protocol)
            .solve(&state, &goal)
            .map_err(|e| args.budget.explain(e))?,
        SolverKind::Oracle => Oracle::new(grid).with_protocol(args.protocol).plan(&state, &goal)?,
    };
    if args.json {
        let report = SolveReport {
            length: plan.len(),
            actions: plan.actions.iter().map(|a| a.index()).collect(),
            solver: args.solver.name(),
        };
        line(serde_json::to_string(&report)?)?;
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}: {} actions",
            args.solver.name(),
            plan.len()
        ))?;
        if !plan.is_empty() {
            line(&plan)?;
        }
    }
    Ok(())
}
