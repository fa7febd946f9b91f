//! The planners from Python: a plan from any state, by the exact solver or the oracle.

use oracle::{ExactSolver, Oracle, Planner};
use pyo3::prelude::*;
use sim::Grid;

use crate::boundary::{OrValueError, guard, value_error};
use crate::config::goal_from;
use crate::env::state_from;

/// A plan from the state where block `i` stands on `cells[i]` (and `held` is held) to
/// `goal`, as a list of action indices: a shortest one by the exact solver (`"exact"`),
/// or the oracle's (`"oracle"`). Empty when the goal holds already.
#[pyfunction]
#[pyo3(signature = (cells, goal, held=None, grid=(7, 7), solver="exact"))]
pub fn solve(
    py: Python<'_>,
    cells: Vec<(u8, u8)>,
    goal: &Bound<'_, PyAny>,
    held: Option<u8>,
    grid: (usize, usize),
    solver: &str,
) -> PyResult<Vec<usize>> {
    let grid = Grid::new(grid.0, grid.1).or_value_error()?;
    let goal = goal_from(goal, Some(cells.len()))?;
    let state = state_from(&cells, held)?;
    state.check_fits(grid).or_value_error()?;
    goal.check_fits(grid).or_value_error()?;
    let planner: Box<dyn Planner + Send + Sync> = match solver {
        "exact" => Box::new(ExactSolver::new(grid)),
        "oracle" => Box::new(Oracle::new(grid)),
        _ => {
            return Err(value_error(format!(
                "cannot read solver from {solver:?}: choose exact or oracle"
            )));
        }
    };
    py.detach(|| guard(|| planner.plan(&state, &goal).or_value_error()))
        .map(|plan| plan.actions.iter().map(|a| a.index()).collect())
}
