//! The planners from Python: a plan from any state, by the exact solver or the oracle in
//! the top view; in the side view, in block moves by the block-move planners, or in gripper
//! steps by the exact solver's side-view search or a block-move plan carried out.

use oracle::towers::Place;
use oracle::{Cost, CountedPlan, ExactSolver, PlannerKind};
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
        CountedPlan::Moves(plan) => {
            let moves = plan
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
/// `"(unstack b3 b5)"`, checked by replaying it over the file's facts). A file refused is
/// a `ValueError` naming the file, the line and the problem.
#[pyfunction]
pub fn read_pddl<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let (problem, plan) = py.detach(|| {
        guard(|| {
            let problem = oracle::pddl::Problem::read(&path).or_value_error()?;
            let moves = oracle::towers::NearOptimal::new()
                .plan(problem.start(), problem.goal())
                .or_value_error()?;
            let actions = oracle::pddl::actions(problem.start(), &moves).or_value_error()?;
            problem.replay(&actions).or_value_error()?;
            let plan: Vec<String> = actions.iter().map(|a| a.to_pddl(problem.block_names())).collect();
            Ok((problem, plan))
        })
    })?;
    let out = PyDict::new(py);
    out.set_item("name", problem.name())?;
    out.set_item("domain", problem.domain())?;
    out.set_item("blocks", problem.block_names().to_vec())?;
    out.set_item("start", problem.start().towers())?;
    out.set_item("goal", problem.goal().towers().to_vec())?;
    out.set_item("plan", plan)?;
    Ok(out)
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
            let problem = oracle::pddl::Problem::read(&path).or_value_error()?;
            let task = problem
                .side_task()
                .map_err(|e| value_error(format!("{}: {e}", path.display())))?;
            // A Gymnasium reset cannot return an episode that is already over.
            if task.goal.holds_in(View::Side, &task.start) {
                return Err(value_error(format!(
                    "{}: the task's start already meets its goal, so there is no episode to play (blockstack.read_pddl gives its empty plan)",
                    path.display()
                )));
            }
            Ok(task)
        })
    })?;
    let out = PyDict::new(py);
    out.set_item("blocks", task.start.block_count())?;
    out.set_item("goal", task.goal.to_string())?;
    let cells: Vec<(u16, u16)> = task.start.cells().iter().map(|c| (c.x, c.y)).collect();
    out.set_item("cells", cells)?;
    Ok(out)
}
