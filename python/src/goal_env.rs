//! The goal-conditioned view of a world, behind `blockstack.StackGoalEnv` (Gymnasium-Robotics'
//! `GoalEnv`): the goal a state achieves, and the reward of a step that reaches a goal or
//! misses it. Both are `sim`'s ([`sim::Goal::standing`], [`sim::RewardModel`]): Python only
//! compares arrays.
//!
//! A goal is its block ids bottom to top; a state where no goal stands achieves `[-1, ...]`,
//! which no goal equals.

use pyo3::prelude::*;
use sim::reward::Transition;
use sim::{Action, BlockId, Cell, Goal, Grid, RewardModel, State, View};

use crate::boundary::{OrValueError, guard, value_error};
use crate::env::state_from;

/// The goal standing in the state of `cells` (every block's `(x, y)`) and `held` in `view`
/// (`top` or `side`, where a stack stands on the table and holds no held block), bottom to
/// top, or `-1` for every block when none does: the stack whose goal
/// [`sim::Goal::holds_in`] that state, as the environment's reward and termination see it.
#[pyfunction]
#[pyo3(signature = (cells, held=None, view="top"))]
pub fn achieved_goal(cells: Vec<(u16, u16)>, held: Option<u16>, view: &str) -> PyResult<Vec<i64>> {
    let state = state_from(&cells, held)?;
    let view: View = view.parse().or_value_error()?;
    Ok(match Goal::standing(&state).filter(|g| g.holds_in(view, &state)) {
        Some(goal) => goal.order().iter().map(|b| i64::from(b.0)).collect(),
        None => vec![-1; cells.len()],
    })
}

/// A `ValueError` unless `goal` is a goal a goal environment can relabel: one stack of all
/// `blocks` blocks. Its achieved goal is the stack standing, one array of block ids, which a
/// goal of towers (`0,1/2`, blocks free) is not: the environment would pay for a goal that
/// `compute_reward` never sees reached.
#[pyfunction]
pub fn check_stack_goal(goal: &str, blocks: usize) -> PyResult<()> {
    let goal = Goal::parse(goal, Some(blocks)).or_value_error()?;
    goal.one_tower("a goal environment (blockstack/Stack-v0 plays goals of towers)")
        .or_value_error()?;
    Ok(())
}

/// `(reached, missed)`: the reward model `reward`'s reward for a step of a world of `blocks`
/// blocks on `grid` after which the goal holds, and for one after which it does not. A
/// `ValueError` for a model whose reward depends on more than that (`dense` and `paper`
/// weigh distances, `paper-code` the moves): a goal environment's reward must be a function
/// of the achieved and desired goals alone.
#[pyfunction]
pub fn goal_rewards(reward: &str, blocks: usize, grid: (usize, usize)) -> PyResult<(f64, f64)> {
    let model = RewardModel::from_name(reward).or_value_error()?;
    if !matches!(model, RewardModel::Sparse(_) | RewardModel::StepCost(_)) {
        return Err(value_error(format!(
            "a goal environment's reward depends only on whether the goal is reached: choose sparse or step-cost, not {reward}"
        )));
    }
    guard(|| {
        let grid = Grid::new(grid.0, grid.1).or_value_error()?;
        let goal = Goal::identity(blocks).or_value_error()?;
        if blocks > grid.height() {
            return Err(value_error(format!(
                "a stack of {blocks} blocks does not fit a grid {} cells high",
                grid.height()
            )));
        }
        // The goal stacked in column 0, and the same blocks stacked the other way round.
        let column = |order: &mut dyn Iterator<Item = usize>| -> PyResult<State> {
            let mut cells = vec![Cell::new(0, 0); blocks];
            for (y, b) in order.enumerate() {
                cells[b] = Cell::new(0, y as u16);
            }
            State::new(&cells, None::<BlockId>).or_value_error()
        };
        let reached = column(&mut (0..blocks))?;
        let missed = column(&mut (0..blocks).rev())?;
        let step = |after: &State| {
            model.reward(&Transition {
                grid,
                view: sim::View::Top,
                goal: &goal,
                before: &missed,
                action: Action::Drop,
                previous_action: None,
                after,
            })
        };
        Ok((step(&reached), step(&missed)))
    })
}
