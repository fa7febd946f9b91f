//! The planners from Python: a plan from any state, by the exact solver or the oracle in
//! the top view; in the side view, in block moves by the block-move planners, or in gripper
//! steps by the exact solver's side-view search or a block-move plan carried out.

use std::time::Duration;

use oracle::pddl::{BestKnown, Domain, PddlPlan, Problem};
use oracle::towers::Place;
use oracle::{Cost, CountedPlan, ExactSolver, PlanOptions, PlannerKind};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{Action, ActionProtocol, Grid, View};

use crate::boundary::{OrValueError, guard, value_error};
use crate::config::goal_from;
use crate::env::state_from;

/// A plan from the state where block `i` stands on `cells[i]` (and `held` is held) to
/// `goal` by the planner named `solver` (`oracle::PlannerKind`, the names `blockstack solve
/// --solver` takes). In the top view, a list of action indices: a shortest one by the exact
/// solver (`"exact"`) under `protocol`, or the oracle's (`"oracle"`); empty when the goal
/// holds already. In the side view (`view="side"`), counted in `cost`: `"moves"` (the
/// default) is a list of block moves, each `{"block": B, "onto": "table" | C}`, the fewest
/// (`"exact"` or `"exact-moves"`) or the near-optimal planner's (`"near-optimal"`, or
/// `"oracle"`); `"steps"` a list of action indices, the fewest gripper steps (`"exact"`)
/// or a block-move plan carried out by the gripper; as `blockstack solve --view side --cost
/// ... --json` prints them.
#[pyfunction]
#[pyo3(signature = (cells, goal, held=None, grid=(7, 7), solver="exact", protocol="free", view="top", cost=None))]
#[allow(clippy::too_many_arguments)]
pub fn solve<'py>(
    py: Python<'py>,
    cells: Vec<(u16, u16)>,
    goal: &Bound<'_, PyAny>,
    held: Option<u16>,
    grid: (usize, usize),
    solver: &str,
    protocol: &str,
    view: &str,
    cost: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let grid = Grid::new(grid.0, grid.1).or_value_error()?;
    let goal = goal_from(goal, Some(cells.len()))?;
    let state = state_from(&cells, held)?;
    state.check_fits(grid).or_value_error()?;
    goal.check_fits(grid).or_value_error()?;
    let protocol: ActionProtocol = protocol.parse().or_value_error()?;
    let planner: PlannerKind = solver.parse().or_value_error()?;
    let view: View = view.parse().or_value_error()?;
    let cost = match cost {
        Some(name) => name.parse::<Cost>().or_value_error()?,
        None => Cost::default_in(view),
    };
    if view == View::Top && cost == Cost::Moves {
        return Err(value_error(
            "cost=\"moves\" counts block moves, which the side view plans: pass view=\"side\"",
        ));
    }
    view.check_state(&state).or_value_error()?;
    let solver = ExactSolver::new(grid).with_protocol(protocol).with_view(view);
    let plan = py.detach(|| guard(|| planner.plan(&solver, cost, &state, &goal).or_value_error()))?;
    match plan {
        CountedPlan::Steps(plan) => indices(py, &plan.actions),
        CountedPlan::Moves(certified) => {
            let moves = certified
                .plan
                .moves
                .iter()
                .map(|m| {
                    let d = PyDict::new(py);
                    d.set_item("block", m.block)?;
                    match m.to {
                        Place::Table => d.set_item("onto", "table")?,
                        Place::On(b) => d.set_item("onto", b)?,
                    }
                    Ok(d)
                })
                .collect::<PyResult<Vec<_>>>()?;
            moves.into_pyobject(py).map(|l| l.into_any())
        }
    }
}

/// Actions as a Python list of their indices.
fn indices<'py>(py: Python<'py>, actions: &[Action]) -> PyResult<Bound<'py, PyAny>> {
    let indices: Vec<usize> = actions.iter().map(|a| a.index()).collect();
    indices.into_pyobject(py).map(|l| l.into_any())
}

/// The Blocks World problem in the PDDL file at `path` (the planning competitions'
/// 4-operator domain, read by `oracle::pddl`): a dict of its `name`, `domain`, the blocks'
/// names (`blocks`; block `i` is `blocks[i]`), the `start` and the `goal` as lists of towers,
/// each bottom to top by block index (blocks the goal does not place are free), and the
/// near-optimal planner's `plan` in the competitions' format (a list of actions such as
/// `"(unstack b3 b5)"`, checked by `Problem::solve`). A file refused is a `ValueError`
/// naming the file, the line and the problem.
#[pyfunction]
pub fn read_pddl<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let (problem, plan) = py.detach(|| {
        guard(|| {
            let problem = Problem::read(&path).or_value_error()?;
            let plan = problem.solve(&oracle::towers::NearOptimal::new()).or_value_error()?;
            Ok((problem, plan))
        })
    })?;
    let out = PyDict::new(py);
    out.set_item("name", problem.name())?;
    out.set_item("domain", problem.domain())?;
    out.set_item("blocks", problem.block_names().to_vec())?;
    out.set_item("start", problem.start().towers())?;
    out.set_item("goal", problem.goal().towers().to_vec())?;
    out.set_item("plan", actions_of(&problem, &plan))?;
    Ok(out)
}

/// The plan's actions as PDDL.
fn actions_of(problem: &Problem, plan: &PddlPlan) -> Vec<String> {
    plan.actions.iter().map(|&a| problem.action_text(a)).collect()
}

/// The planner of a task: `solver` by name, or the relational policy of the model file
/// `model` (`neural::planning::block_planner`), with a search budget or a time limit.
fn task_planner(
    solver: Option<&str>,
    model: Option<std::path::PathBuf>,
    budget: Option<usize>,
    time_limit: Option<f64>,
) -> PyResult<Box<dyn oracle::towers::BlockPlanner>> {
    let solver = solver.map(|s| s.parse::<PlannerKind>()).transpose().or_value_error()?;
    let time_limit = match time_limit {
        Some(s) if s.is_finite() && s > 0.0 && s <= 86_400.0 => Some(Duration::from_secs_f64(s)),
        Some(s) => {
            return Err(value_error(format!(
                "time_limit is seconds above 0 and at most 86400, not {s}"
            )));
        }
        None => None,
    };
    let options = PlanOptions { budget, time_limit };
    neural::planning::block_planner(solver, model.as_deref(), &options).or_value_error()
}

/// The plan of the PDDL problem at `path` by `solver` (a name, as `blockstack solve --pddl
/// --solver` takes; the near-optimal planner if neither it nor `model` is given) or by the
/// relational policy in the file `model`, checked by replaying it over the file's facts:
/// a dict of `solver`, `moves`, `cost` (actions), `lower_bound` (no plan costs less),
/// `optimal` (the cost meets the bound), `certificate` (the bound's parts in block moves:
/// `misplaced`, `forced`, `breakers`), `plan` (the actions as PDDL) and `text` (the plan
/// file `blockstack solve --pddl` prints). `budget` is the exact solver's, `time_limit`
/// (seconds) the optimal solver's. `domain` is the problem's domain file, checked to be the
/// 4-operator Blocks World, whose action names the plan takes; `plan_file` a file the plan
/// text is written to (atomically; a regular file or a new path), as `--plan-file`.
#[pyfunction]
#[pyo3(signature = (path, solver=None, model=None, budget=None, time_limit=None, domain=None, plan_file=None))]
#[allow(clippy::too_many_arguments)]
pub fn solve_pddl<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    solver: Option<&str>,
    model: Option<std::path::PathBuf>,
    budget: Option<usize>,
    time_limit: Option<f64>,
    domain: Option<std::path::PathBuf>,
    plan_file: Option<std::path::PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let planner = task_planner(solver, model, budget, time_limit)?;
    let (problem, plan) = py.detach(|| {
        guard(|| {
            // The plan file is checked before planning, as the command does.
            let out = plan_file
                .as_deref()
                .map(|out| -> PyResult<files::OutputPath> {
                    let checked = files::OutputPath::check_regular(out).or_value_error()?;
                    files::refuse_same_file(out, &path).or_value_error()?;
                    if let Some(domain) = &domain {
                        files::refuse_same_file(out, domain).or_value_error()?;
                    }
                    Ok(checked)
                })
                .transpose()?;
            let domain = domain.as_deref().map(Domain::read).transpose().or_value_error()?;
            let problem = Problem::read_in(&path, domain.as_ref()).or_value_error()?;
            let plan = problem.solve(planner.as_ref()).or_value_error()?;
            if let Some(out) = &out {
                out.write(plan.text(&problem).as_bytes()).or_value_error()?;
            }
            Ok((problem, plan))
        })
    })?;
    let out = PyDict::new(py);
    out.set_item("solver", planner.name())?;
    out.set_item("moves", plan.moves.len())?;
    out.set_item("cost", plan.cost())?;
    out.set_item("lower_bound", plan.lower_bound_cost())?;
    out.set_item("optimal", plan.is_optimal())?;
    let certificate = PyDict::new(py);
    certificate.set_item("misplaced", plan.certificate.misplaced)?;
    certificate.set_item("forced", plan.certificate.forced)?;
    certificate.set_item("breakers", plan.certificate.breakers)?;
    out.set_item("certificate", certificate)?;
    out.set_item("plan", actions_of(&problem, &plan))?;
    out.set_item("text", plan.text(&problem))?;
    Ok(out)
}

/// Every task below `folder` planned as `solve_pddl` plans one (`oracle::pddl::suite`): the
/// report `blockstack solve-all --json` prints, as JSON text (its rows, groups and overall
/// summary); `bounds` a file of best known costs.
#[pyfunction]
#[pyo3(signature = (folder, solver=None, model=None, bounds=None, budget=None, time_limit=None))]
pub fn solve_all(
    py: Python<'_>,
    folder: std::path::PathBuf,
    solver: Option<&str>,
    model: Option<std::path::PathBuf>,
    bounds: Option<std::path::PathBuf>,
    budget: Option<usize>,
    time_limit: Option<f64>,
) -> PyResult<String> {
    let planner = task_planner(solver, model, budget, time_limit)?;
    py.detach(|| {
        guard(|| {
            let known = bounds.as_deref().map(BestKnown::read).transpose().or_value_error()?;
            let report = oracle::pddl::suite::run(
                &folder,
                planner.as_ref(),
                oracle::pddl::suite::Yardsticks {
                    best_known: known.as_ref(),
                    optima: None,
                },
                &mut |_, _| {},
            )
            .or_value_error()?;
            serde_json::to_string(&report).or_value_error()
        })
    })
}

/// The PDDL problem at `path` as the side view plays it (`oracle::pddl::Problem::side_task`,
/// as `blockstack run --pddl` does): a dict of `blocks` (the count), `goal` (its towers as
/// the text the world's `goal` takes, e.g. `"1,2/0"`) and `cells` (the start state, every
/// block's `(x, y)`, as `reset(options={"cells": ...})` takes it), for `BlocksWorld-v0`
/// built from a task. A file refused, a task larger than the side view holds, or one whose
/// start already meets its goal (a Gymnasium episode cannot begin over) is a `ValueError`
/// naming it.
#[pyfunction]
pub fn pddl_task<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let task = py.detach(|| {
        guard(|| {
            let problem = Problem::read(&path).or_value_error()?;
            // A task with nothing to play is refused there, as `run --pddl` refuses it: a
            // Gymnasium reset cannot return an episode that is already over.
            problem
                .side_task()
                .map_err(|e| value_error(format!("{}: {e}", path.display())))
        })
    })?;
    let out = PyDict::new(py);
    out.set_item("blocks", task.start.block_count())?;
    out.set_item("goal", task.goal.to_string())?;
    let cells: Vec<(u16, u16)> = task.start.cells().iter().map(|c| (c.x, c.y)).collect();
    out.set_item("cells", cells)?;
    Ok(out)
}
