//! A plan: the actions a planner proposes, in order.

use std::fmt;

use sim::{Action, ActionProtocol, Goal, State};

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
///
/// A planner plans under an [`ActionProtocol`]: every action of its plans is legal under
/// that protocol in the state it is taken from.
pub trait Planner {
    /// A short name for reports: `oracle` or `exact`.
    fn name(&self) -> &'static str;

    /// The action protocol its plans obey.
    fn protocol(&self) -> ActionProtocol;

    /// This planner, planning under `protocol`.
    fn with_protocol(self, protocol: ActionProtocol) -> Self
    where
        Self: Sized;

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

/// `actions`, taken from a state holding `held`, made legal under `protocol`: under `free`
/// unchanged; under `paper` a Drop goes before every Pick taken while a block is held (the
/// protocol's way of changing blocks), and an action that would change nothing in the
/// `free` world and is illegal here (a pick of the block held, a move or Drop with nothing
/// held) is left out. The result does what `actions` do, state for state at every Pick.
pub fn legalize(actions: &[Action], held: Option<sim::BlockId>, protocol: ActionProtocol) -> Vec<Action> {
    if protocol == ActionProtocol::Free {
        return actions.to_vec();
    }
    let mut held = held;
    let mut out = Vec::with_capacity(actions.len() + 2);
    for &action in actions {
        match (action, held) {
            (Action::Pick(b), Some(h)) if b == h => continue,
            (Action::Pick(b), Some(_)) => {
                out.extend([Action::Drop, action]);
                held = Some(b);
            }
            (Action::Pick(b), None) => {
                out.push(action);
                held = Some(b);
            }
            (_, None) => continue,
            (Action::Drop, Some(_)) => {
                out.push(action);
                held = None;
            }
            (_, Some(_)) => out.push(action),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::BlockId;

    #[test]
    fn a_pick_while_holding_gets_a_drop_before_it_under_paper() {
        let (p0, p1) = (Action::Pick(BlockId(0)), Action::Pick(BlockId(1)));
        let plan = [p0, Action::Up, p1, Action::Left, p1, Action::Drop, Action::Up, p0];
        assert_eq!(legalize(&plan, None, ActionProtocol::Free), plan);
        assert_eq!(
            legalize(&plan, None, ActionProtocol::Paper),
            [p0, Action::Up, Action::Drop, p1, Action::Left, Action::Drop, p0]
        );
        assert_eq!(
            legalize(&[p1, Action::Right], Some(BlockId(0)), ActionProtocol::Paper),
            [Action::Drop, p1, Action::Right]
        );
    }
}
