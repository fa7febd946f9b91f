//! A plan: the actions a planner proposes, in order.

use std::fmt;

use sim::{Action, Goal, State};

use crate::error::{OracleError, Result};

/// A sequence of actions that takes a state to its goal.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Plan {
    /// The actions, first to last.
    pub actions: Vec<Action>,
}

impl Plan {
    /// Number of actions (steps to goal).
    pub fn len(&self) -> usize {
        self.actions.len()
    }

    /// Whether the plan has no action (the goal held already).
    pub fn is_empty(&self) -> bool {
        self.actions.is_empty()
    }
}

impl fmt::Display for Plan {
    /// The action names joined by `", "`, e.g. `pick 1, up, up`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, a) in self.actions.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{a}")?;
        }
        Ok(())
    }
}

/// Something that plans from any state to a goal: the [`Oracle`](crate::Oracle) and the
/// [`ExactSolver`](crate::ExactSolver). Agents and demonstrators that only need "a plan" or
/// "the next action" take any planner through this trait.
pub trait Planner {
    /// A short name for reports: `oracle` or `exact`.
    fn name(&self) -> &'static str;

    /// A plan from `state`, which may hold a block, to `goal` (empty if the goal holds).
    fn plan(&self, state: &State, goal: &Goal) -> Result<Plan>;

    /// The first action of [`Planner::plan`]; an error if the goal holds already.
    fn next_action(&self, state: &State, goal: &Goal) -> Result<Action> {
        self.plan(state, goal)?
            .actions
            .first()
            .copied()
            .ok_or_else(|| OracleError::GoalAlreadyHolds { goal: goal.to_string() })
    }
}
