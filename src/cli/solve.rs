//! `blockstack solve`: a plan from a given state, by the exact solver or the oracle.

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use oracle::{ExactSolver, Oracle};
use serde::Serialize;
use sim::{BlockId, Cell, Goal, Grid, State};

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

/// Reads `--start`: `x,y` cells separated by `;`, each inside `grid`.
fn parse_start(text: &str, grid: Grid) -> Result<Vec<Cell>> {
    text.split(';')
        .map(|part| {
            let coords: Vec<Option<i64>> = part.split(',').map(|v| v.trim().parse().ok()).collect();
            let [Some(x), Some(y)] = coords[..] else {
                bail!("cannot read cell {:?}: write each block's cell as x,y, blocks separated by ';', e.g. \"0,0;3,0;5,2\"", part.trim());
            };
            Ok(grid.cell(x, y)?)
        })
        .collect()
}

/// Plans and prints the plan.
pub fn solve(args: SolveArgs) -> Result<()> {
    let grid: Grid = args.grid.parse().context("--grid")?;
    let cells = parse_start(&args.start, grid).context("--start")?;
    let held = args.held.map(|b| BlockId(b.min(usize::from(u8::MAX)) as u8));
    let state = State::new(&cells, held).context("--start")?;
    let goal = Goal::parse(&args.goal, Some(state.block_count())).context("--goal")?;
    let plan = match args.solver {
        SolverKind::Exact => ExactSolver::new(grid)
            .with_protocol(args.protocol)
            .solve(&state, &goal)?,
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
