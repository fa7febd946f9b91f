//! The planners from Python: a plan from any state, by the exact solver or the oracle in
//! the top view, or by the block-move planners in the side view.

use oracle::towers::{MovePlanner, Place, plan_side};
use oracle::{ExactSolver, Oracle, Planner};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{ActionProtocol, Grid, View};

use crate::boundary::{OrValueError, guard, value_error};
use crate::config::goal_from;
use crate::env::state_from;

/// A plan from the state where block `i` stands on `cells[i]` (and `held` is held) to
/// `goal`. In the top view, a list of action indices: a shortest one by the exact solver
/// (`"exact"`) under `protocol`, or the oracle's (`"oracle"`); empty when the goal holds
/// already. In the side view (`view="side"`), a list of block moves, each
/// `{"block": B, "onto": "table" | C}`: the fewest (`"exact"`) or the near-optimal
/// planner's (`"near-optimal"`), as `blockstack solve --view side --json` prints them.
#[pyfunction]
#[pyo3(signature = (cells, goal, held=None, grid=(7, 7), solver="exact", protocol="free", view="top"))]
#[allow(clippy::too_many_arguments)]
pub fn solve<'py>(
    py: Python<'py>,
    cells: Vec<(u8, u8)>,
    goal: &Bound<'_, PyAny>,
    held: Option<u8>,
    grid: (usize, usize),
    solver: &str,
    protocol: &str,
    view: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let grid = Grid::new(grid.0, grid.1).or_value_error()?;
    let goal = goal_from(goal, Some(cells.len()))?;
    let state = state_from(&cells, held)?;
    state.check_fits(grid).or_value_error()?;
    goal.check_fits(grid).or_value_error()?;
    let protocol: ActionProtocol = protocol.parse().or_value_error()?;
    if view.parse::<View>().or_value_error()? == View::Side {
        View::Side.check_state(&state).or_value_error()?;
        let planner: MovePlanner = solver.parse().or_value_error()?;
        let plan = py.detach(|| guard(|| plan_side(planner, grid, &state, &goal).or_value_error()))?;
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
        return moves.into_pyobject(py).map(|l| l.into_any());
    }
    let planner: Box<dyn Planner + Send + Sync> = match solver {
        "exact" => Box::new(ExactSolver::new(grid).with_protocol(protocol)),
        "oracle" => Box::new(Oracle::new(grid).with_protocol(protocol)),
        _ => {
            return Err(value_error(format!(
                "cannot read solver from {solver:?}: choose exact or oracle"
            )));
        }
    };
    let actions: Vec<usize> = py
        .detach(|| guard(|| planner.plan(&state, &goal).or_value_error()))
        .map(|plan| plan.actions.iter().map(|a| a.index()).collect())?;
    actions.into_pyobject(py).map(|l| l.into_any())
}
