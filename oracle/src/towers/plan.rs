//! A block-move plan: the moves, in order, and a replay that checks them.

use std::fmt;

use crate::error::Result;

use super::state::{Move, Table, Towers};

/// A sequence of block moves; its length is the block-move count.
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct TowerPlan {
    /// The moves, first to last.
    pub moves: Vec<Move>,
}

impl TowerPlan {
    /// Number of block moves.
    pub fn len(&self) -> usize {
        self.moves.len()
    }

    /// Whether the plan has no move (the goal held already).
    pub fn is_empty(&self) -> bool {
        self.moves.is_empty()
    }

    /// The state the plan leads to from `start` on `table`; an error at the first illegal
    /// move.
    pub fn replay(&self, start: &Towers, table: Table) -> Result<Towers> {
        let mut state = start.clone();
        for &mv in &self.moves {
            state.apply(mv, table)?;
        }
        Ok(state)
    }
}

impl fmt::Display for TowerPlan {
    /// The moves joined by `", "`, e.g. `2->table, 0->1`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, mv) in self.moves.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{mv}")?;
        }
        Ok(())
    }
}
