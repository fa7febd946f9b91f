//! `blockstack solve`: a plan from a given state, by the exact solver or the oracle in the
//! top view; in the side view, in block moves by the planners of `oracle::towers`, or in
//! gripper steps by the exact solver's side-view search or a near-optimal block-move plan
//! carried out by the gripper.

use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};

use oracle::pddl::{Domain, Problem};
use oracle::towers::{Certificate, CertifiedPlan, Place};
use oracle::{Cost, CountedPlan, OracleError, PlannerKind};
use serde::Serialize;
use sim::{Goal, Grid, State, View};

use super::solver_budget::{SolverBudgetArg, TimeLimitArg};
use super::stdout::line;

/// Arguments of `blockstack solve`.
#[derive(Debug, Args)]
pub struct SolveArgs {
    /// Every block's cell, block 0 first: x,y pairs separated by ';', e.g. "0,0;3,0;5,2".
    #[arg(long, required_unless_present = "pddl")]
    pub start: Option<String>,
    /// The goal, bottom to top, e.g. 1,0,2.
    #[arg(long, required_unless_present = "pddl")]
    pub goal: Option<String>,
    /// A Blocks World problem in PDDL (the planning competitions' 4-operator domain) in
    /// place of --start and --goal: the plan is printed in the competitions' format, one
    /// action per line ((unstack b3 b5), (putdown b3), (pickup b4), (stack b4 b3)), then
    /// "; lower bound = L" and, when proven, "; optimal"; by --solver near-optimal (the
    /// default here), optimal or exact.
    #[arg(long, value_name = "PROBLEM.pddl", conflicts_with_all = ["start", "goal", "held", "grid", "view", "cost", "protocol"])]
    pub pddl: Option<PathBuf>,
    /// With --pddl: the problem's domain file, checked to be the 4-operator Blocks World
    /// (in either spelling: pickup/putdown or pick-up/put-down); the plan names its actions
    /// as the domain does, and the problem must name this domain.
    #[arg(long, value_name = "DOMAIN.pddl", requires = "pddl")]
    pub domain: Option<PathBuf>,
    /// With --pddl: write the plan to this file (replaced atomically; a regular file or a
    /// new path only), in the format printed without it, and print one line saying what
    /// was written (with --json, the JSON report as without it).
    #[arg(long, value_name = "FILE", requires = "pddl")]
    pub plan_file: Option<PathBuf>,
    /// The block held at the start (default: none; in the side view only with --cost steps
    /// --solver exact).
    #[arg(long)]
    pub held: Option<usize>,
    /// Grid size, WxH [default: 7x7; in the side view, 7x7 up to 7 blocks and N x (N+1)
    /// beyond]
    #[arg(long)]
    pub grid: Option<Grid>,
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
    /// near-optimal (at most twice the fewest block moves; side view), optimal (the fewest
    /// block moves at any size, with its proof within --time-limit; side view) or oracle
    /// (the view's: centroid + A* from above, near-optimal from the side) [default: exact;
    /// with --pddl, near-optimal]
    #[arg(long)]
    pub solver: Option<PlannerKind>,
    /// With --pddl: plan with a learned policy of block moves (`dqn --preset general`) in
    /// place of --solver, greedily, one forward pass per move.
    #[arg(long, value_name = "FILE", requires = "pddl", conflicts_with = "solver")]
    pub model: Option<PathBuf>,
    /// The action protocol the plan keeps to: free (every action legal) or paper (nothing
    /// held: only pick; holding: only moves and drop); the exact plan is the shortest legal
    /// one.
    #[arg(long, default_value = "free")]
    pub protocol: sim::ActionProtocol,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
    #[command(flatten)]
    pub time_limit: TimeLimitArg,
    /// Print the plan as one JSON object: {"length":L,"actions":[indices],"solver":"exact"};
    /// a plan of block moves adds "lower_bound" and "optimal".
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
    if let Some(path) = &args.pddl {
        return solve_pddl(path, &args);
    }
    // clap's `requires` does not hold these to --pddl here (start and goal are required
    // unless it is given), so they are checked by hand.
    for (flag, given) in [
        ("--domain", args.domain.is_some()),
        ("--plan-file", args.plan_file.is_some()),
        ("--model", args.model.is_some()),
    ] {
        anyhow::ensure!(!given, "{flag} goes with --pddl PROBLEM.pddl");
    }
    let solver = args.solver.unwrap_or(PlannerKind::Exact);
    anyhow::ensure!(
        args.time_limit.time_limit.is_none(),
        "--time-limit applies to --pddl with --solver optimal; from --start the optimal solver searches for its default 10 s"
    );
    let (Some(start), Some(goal)) = (&args.start, &args.goal) else {
        anyhow::bail!("solve needs --start and --goal, or --pddl PROBLEM.pddl")
    };
    // The blocks `--start` lists (the side view's default grid grows with them).
    let blocks = start.split(';').count();
    let grid = args
        .grid
        .unwrap_or_else(|| super::world::default_grid(Grid::default(), args.view, blocks));
    if args.view == View::Side {
        return solve_side(&args, grid, start, goal);
    }
    View::Top.check_world(grid, sim::MIN_BLOCKS).context("--grid")?;
    anyhow::ensure!(
        args.cost != Some(Cost::Moves),
        "--cost moves counts block moves, which the side view plans: add --view side"
    );
    solver
        .check_view(View::Top)
        .map_err(|e| anyhow::anyhow!("--solver {solver}: {e}: add --view side"))?;
    let state = State::parse(start, args.held, grid).with_context(|| {
        if args.held.is_some() {
            "--start and --held"
        } else {
            "--start"
        }
    })?;
    View::Top.check_world(grid, state.block_count()).context("--start")?;
    let goal = Goal::parse(goal, Some(state.block_count())).context("--goal")?;
    anyhow::ensure!(
        solver == PlannerKind::Exact || args.budget.solver_budget.is_none(),
        "--solver-budget is the exact solver's: it does not apply to --solver {solver}"
    );
    let planning = args.budget.solver(grid).with_protocol(args.protocol);
    let plan = solver
        .plan_steps(&planning, &state, &goal)
        .map_err(|e| args.budget.explain(e))?;
    if args.json {
        let report = SolveReport {
            length: plan.len(),
            cost: None,
            actions: plan.actions.iter().map(|a| a.index()).collect(),
            solver: solver.name(),
        };
        line(serde_json::to_string(&report)?)?;
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}: {} actions",
            solver,
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
fn solve_side(args: &SolveArgs, grid: Grid, start: &str, goal: &str) -> Result<()> {
    let solver = args.solver.unwrap_or(PlannerKind::Exact);
    let cost = args.cost.unwrap_or(Cost::default_in(View::Side));
    let exact_steps = cost == Cost::Steps && solver == PlannerKind::Exact;
    anyhow::ensure!(
        args.held.is_none() || exact_steps,
        "--held: a block-move plan starts with nothing held; --cost steps --solver exact plans from a held block"
    );
    anyhow::ensure!(
        args.budget.solver_budget.is_none() || exact_steps,
        "--solver-budget is the exact gripper-step search's: it applies to --view side only with --cost steps --solver exact"
    );
    let state = State::parse(start, args.held, grid).with_context(|| {
        if args.held.is_some() {
            "--start and --held"
        } else {
            "--start"
        }
    })?;
    View::Side.check_world(grid, state.block_count()).context("--start")?;
    View::Side.check_state(&state).context("--start")?;
    let goal = Goal::parse(goal, Some(state.block_count())).context("--goal")?;
    goal.check_fits(grid).context("--goal")?;
    let planning = args.budget.solver(grid).with_view(View::Side);
    let plan = match solver.plan(&planning, cost, &state, &goal) {
        Ok(CountedPlan::Moves(plan)) => return print_moves(args, solver, grid, &goal, &plan),
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
            solver: solver.name(),
        };
        line(serde_json::to_string(&report)?)
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}, side view: {} gripper steps",
            solver,
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
    /// No plan has fewer block moves.
    lower_bound: usize,
    /// The bound's parts.
    certificate: CertificateReport,
    /// Whether the plan's length meets the bound.
    optimal: bool,
    solver: &'static str,
}

impl CertificateReport {
    fn of(c: Certificate) -> Self {
        CertificateReport {
            misplaced: c.misplaced,
            forced: c.forced,
            breakers: c.breakers,
        }
    }
}

/// Prints a block-move plan, as JSON or text.
fn print_moves(
    args: &SolveArgs,
    solver: PlannerKind,
    grid: Grid,
    goal: &Goal,
    certified: &CertifiedPlan,
) -> Result<()> {
    let plan = &certified.plan;
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
            lower_bound: certified.lower_bound,
            certificate: CertificateReport::of(certified.certificate),
            optimal: certified.is_optimal(),
            solver: solver.name(),
        };
        line(serde_json::to_string(&report)?)
    } else {
        line(format_args!(
            "{} plan, goal {goal}, grid {grid}, side view: {} block moves (lower bound {}{})",
            solver,
            plan.len(),
            certified.lower_bound,
            if certified.is_optimal() { ", optimal" } else { "" }
        ))?;
        if plan.is_empty() {
            return Ok(());
        }
        let moves: Vec<String> = plan.moves.iter().map(ToString::to_string).collect();
        line(moves.join(" "))
    }
}

/// A PDDL plan as JSON: `{"moves": M, "actions": A, "lower_bound": L, "optimal": B, "plan":
/// ["(unstack b3 b5)", ...]}`; costs in actions.
#[derive(Debug, Serialize)]
struct PddlPlanReport {
    /// Block moves.
    moves: usize,
    /// Actions: two per move, the competitions' cost.
    actions: usize,
    /// No plan costs fewer actions.
    lower_bound: usize,
    /// The bound's parts, in block moves.
    certificate: CertificateReport,
    /// Whether the plan's cost meets the bound.
    optimal: bool,
    solver: String,
    /// The actions as PDDL.
    plan: Vec<String>,
}

/// A certificate's parts, in block moves.
#[derive(Debug, Serialize)]
struct CertificateReport {
    misplaced: usize,
    forced: usize,
    breakers: usize,
}

/// `solve --pddl`: the plan for the problem file, in the competitions' format.
fn solve_pddl(path: &Path, args: &SolveArgs) -> Result<()> {
    let planner = args
        .budget
        .task_planner(args.time_limit, args.solver, args.model.as_deref())?;
    // The plan file is checked before planning: a wrong destination fails at once.
    let plan_file = args
        .plan_file
        .as_deref()
        .map(|out| -> Result<files::OutputPath> {
            let checked = files::OutputPath::check_regular(out).context("--plan-file")?;
            files::refuse_same_file(out, path).context("--plan-file and --pddl")?;
            if let Some(domain) = &args.domain {
                files::refuse_same_file(out, domain).context("--plan-file and --domain")?;
            }
            Ok(checked)
        })
        .transpose()?;
    let domain = args.domain.as_deref().map(Domain::read).transpose()?;
    let problem = Problem::read_in(path, domain.as_ref())?;
    let plan = problem.solve(planner.as_ref()).map_err(|e| args.budget.explain(e))?;
    if let Some(out) = &plan_file {
        out.write(plan.text(&problem).as_bytes())?;
    }
    if args.json {
        let report = PddlPlanReport {
            moves: plan.moves.len(),
            actions: plan.cost(),
            lower_bound: plan.lower_bound_cost(),
            certificate: CertificateReport::of(plan.certificate),
            optimal: plan.is_optimal(),
            solver: planner.name().to_string(),
            plan: plan.actions.iter().map(|&a| problem.action_text(a)).collect(),
        };
        line(serde_json::to_string(&report)?)
    } else if let Some(out) = &plan_file {
        line(format_args!(
            "wrote the plan to {}: cost {}, lower bound {}{}",
            out.path().display(),
            plan.cost(),
            plan.lower_bound_cost(),
            if plan.is_optimal() { ", optimal" } else { "" }
        ))
    } else {
        super::stdout::text(&plan.text(&problem))
    }
}
