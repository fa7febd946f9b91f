//! The relational network as a policy: one forward pass, the best-scored legal move.

use oracle::towers::{Move, Place, TowerGoal, Towers};

use super::graph::{Graph, TABLE};
use super::net::{RelationalNet, Tape};

/// A greedy policy over a relational network: each choice is one forward pass and the
/// legal move with the highest score (the first in [`Towers::moves`] order on a tie).
pub struct Policy<'n> {
    net: &'n RelationalNet,
    tape: Tape,
}

impl<'n> Policy<'n> {
    /// The policy of `net`.
    pub fn new(net: &'n RelationalNet) -> Policy<'n> {
        Policy { net, tape: Tape::new() }
    }

    /// The move it makes from `state` towards `goal`; `None` if the goal holds (or no move
    /// is legal: a state of one block on the table).
    pub fn choose(&mut self, state: &Towers, goal: &TowerGoal) -> Option<Move> {
        if goal.holds(state) {
            return None;
        }
        let graph = Graph::of([(state, goal)]);
        self.net.forward(&graph, &mut self.tape);
        let (x, to) = self.net.best_move(&graph, &self.tape, 0, true)?;
        Some(Move {
            block: x as usize,
            to: if to == TABLE { Place::Table } else { Place::On(to as usize) },
        })
    }
}
