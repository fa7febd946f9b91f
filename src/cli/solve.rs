//! `blockstack solve`: a plan from a given state, by the exact solver or the oracle in the
//! top view; in the side view, in block moves by the planners of `oracle::towers`, or in
//! gripper steps by the exact solver's side-view search or a near-optimal block-move plan
//! carried out by the gripper.

use anyhow::{Context, Result};
use clap::Args;
use oracle::towers::{Place, TowerPlan};
use oracle::{Cost, CountedPlan, OracleError, PlannerKind};
use serde::Serialize;
use sim::{Goal, Grid, State, View};

use super::solver_budget::SolverBudgetArg;
use super::stdout::line;

/// Arguments of `blockstack solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Every block's cell, block 0 first: x,y pairs separated by ';', e.g. "0,0;3,0;5,2".
    #[arg(long)]
    pub start: String,
    /// The goal, bottom to top, e.g. 1,0,2.
    #[arg(long)]
    pub goal: String,
    /// The block held at the start (default: none; in the side view only with --cost steps
    /// --solver exact).
    #[arg(long)]
    pub held: Option<usize>,
    /// Grid size, WxH.
    #[arg(long, default_value = "7x7")]
    pub grid: String,
    /// The world: top (the paper's, seen from above) or side (the classic Blocks World; the
    /// goal may be several towers, e.g. 0,1/2).
    #[arg(long, default_value = "top")]
    pub view: View,
    /// What the plan's length counts: steps (gripper actions; the top view's default and
    /// only count) or moves (block moves; the side view's default).
    #[arg(long)]
    pub cost: Option<Cost>,
    /// The planner: exact (the shortest plan in the count asked for: the fewest gripper
    /// steps, or from the side the fewest block moves with --cost moves), exact-moves (the
    /// fewest block moves, carried out by the gripper with --cost steps; side view),
    /// near-optimal (at most twice the fewest block moves; side view) or oracle (the view's:
    /// centroid + A* from above, near-optimal from the side).
    #[arg(long, default_value = "exact")]
    pub solver: PlannerKind,
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
    /// `"steps"` in the side view (where moves may be counted too); absent in the top view.
    #[serde(skip_serializing_if = "Option::is_none")]
    cost: Option<&'static str>,
    actions: Vec<usize>,
    solver: &'static str,
}

/// Plans and prints the plan.
pub fn solve(args: SolveArgs) -> Result<()> {
    let grid: Grid = args.grid.parse().context("--grid")?;
    if args.view == View::Side {
        return solve_side(&args, grid);
    }
    anyhow::ensure!(
        args.cost != Some(Cost::Moves),
        "--cost moves counts block moves, which the side view plans: add --view side"
    );
    args.solver
        .check_view(View::Top)
        .map_err(|e| anyhow::anyhow!("--solver {}: {e}: add --view side", args.solver))?;
    let state = State::parse(&args.start, args.held, grid).with_context(|| {
        if args.held.is_some() {
            "--start and --held"
        } else {
            "--start"
        }
    })?;
    let goal = Goal::parse(&args.goal, Some(state.block_count())).context("--goal")?;
    anyhow::ensure!(
        args.solver == PlannerKind::Exact || args.budget.solver_budget.is_none(),
        "--solver-budget is the exact solver's: it does not apply to --solver {}",
        args.solver
    );
    let solver = args.budget.solver(grid).with_protocol(args.protocol);
    let plan = args
        .solver
        .plan_steps(&solver, &state, &goal)
        .map_err(|e| args.budget.explain(e))?;
    if args.json {
        let report = SolveReport {
            length: plan.len(),
            cost: None,
            actions: plan.actions.iter().map(|a| a.index()).collect(),
            solver: args.solver.name(),
        };
        line(serde_json::to_string(&report)?)?;
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}: {} actions",
            args.solver,
            plan.len()
        ))?;
        if !plan.is_empty() {
            line(&plan)?;
        }
    }
    Ok(())
}

/// `solve --view side`: a plan from the side-view state `--start` to `--goal`'s towers, in
/// block moves (on a table as wide as the grid) or in gripper steps.
fn solve_side(args: &SolveArgs, grid: Grid) -> Result<()> {
    let cost = args.cost.unwrap_or(Cost::default_in(View::Side));
    let exact_steps = cost == Cost::Steps && args.solver == PlannerKind::Exact;
    anyhow::ensure!(
        args.held.is_none() || exact_steps,
        "--held: a block-move plan starts with nothing held; --cost steps --solver exact plans from a held block"
    );
    anyhow::ensure!(
        args.budget.solver_budget.is_none() || exact_steps,
        "--solver-budget is the exact gripper-step search's: it applies to --view side only with --cost steps --solver exact"
    );
    let state = State::parse(&args.start, args.held, grid).with_context(|| {
        if args.held.is_some() {
            "--start and --held"
        } else {
            "--start"
        }
    })?;
    View::Side.check_state(&state).context("--start")?;
    let goal = Goal::parse(&args.goal, Some(state.block_count())).context("--goal")?;
    goal.check_fits(grid).context("--goal")?;
    let solver = args.budget.solver(grid).with_view(View::Side);
    let plan = match args.solver.plan(&solver, cost, &state, &goal) {
        Ok(CountedPlan::Moves(plan)) => return print_moves(args, grid, &goal, &plan),
        Ok(CountedPlan::Steps(plan)) => plan,
        Err(OracleError::BudgetExceeded { budget, blocks, grid }) => anyhow::bail!(
            "the exact gripper-step search stored its budget of {budget} states for {blocks} blocks \
             on a {grid} grid without finding a shortest plan: use --solver near-optimal or --cost moves, \
             or raise --solver-budget"
        ),
        Err(e) => return Err(e.into()),
    };
    if args.json {
        let report = SolveReport {
            length: plan.len(),
            cost: Some("steps"),
            actions: plan.actions.iter().map(|a| a.index()).collect(),
            solver: args.solver.name(),
        };
        line(serde_json::to_string(&report)?)
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}, side view: {} gripper steps",
            args.solver,
            plan.len()
        ))?;
        if plan.is_empty() {
            return Ok(());
        }
        line(&plan)
    }
}

/// The machine-readable block-move plan.
#[derive(Debug, Serialize)]
struct MovesReport {
    length: usize,
    cost: &'static str,
    /// Each move as `{"block": B, "onto": "table"}` or `{"block": B, "onto": C}`.
    moves: Vec<serde_json::Value>,
    solver: &'static str,
}

/// Prints a block-move plan, as JSON or text.
fn print_moves(args: &SolveArgs, grid: Grid, goal: &Goal, plan: &TowerPlan) -> Result<()> {
    if args.json {
        let moves = plan
            .moves
            .iter()
            .map(|m| match m.to {
                Place::Table => serde_json::json!({"block": m.block, "onto": "table"}),
                Place::On(b) => serde_json::json!({"block": m.block, "onto": b}),
            })
            .collect();
        let report = MovesReport {
            length: plan.len(),
            cost: "moves",
            moves,
            solver: args.solver.name(),
        };
        line(serde_json::to_string(&report)?)
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}, side view: {} block moves",
            args.solver,
            plan.len()
        ))?;
        if plan.is_empty() {
            return Ok(());
        }
        let moves: Vec<String> = plan.moves.iter().map(ToString::to_string).collect();
        line(moves.join(" "))
    }
}
