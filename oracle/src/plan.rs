//! A plan: the actions a planner proposes, in order.

use std::fmt;

use sim::Action;

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
