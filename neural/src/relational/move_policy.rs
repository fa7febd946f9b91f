//! The greedy choice of block moves, shared by the policy that plays and the trainer that
//! tests it: one forward pass per move, the legal move with the highest score.

use oracle::towers::{Move, Place, Table, TowerGoal, Towers};

use super::graph::{Graph, TABLE};
use super::net::{RelationalNet, Tape};

/// The greedy choice of block moves: one forward pass per move, the legal move with the
/// highest score ([`RelationalNet::best_move`]). It keeps its buffers from one choice to the
/// next.
pub struct MovePolicy<'n> {
    net: &'n RelationalNet,
    tape: Tape,
}

impl<'n> MovePolicy<'n> {
    /// The policy of `net`.
    pub fn new(net: &'n RelationalNet) -> MovePolicy<'n> {
        MovePolicy { net, tape: Tape::new() }
    }

    /// The move it makes from `state` towards `goal` on `table` (a move to the table only
    /// where a column is free); `None` if the goal holds or no move is legal.
    pub fn choose(&mut self, state: &Towers, goal: &TowerGoal, table: Table) -> Option<Move> {
        if goal.holds(state) {
            return None;
        }
        let graph = Graph::of([(state, goal)]);
        self.net.forward(&graph, &mut self.tape);
        let table_free = table.has_free_column(state.tower_count());
        let (x, to) = self.net.best_move(&graph, &self.tape, 0, table_free)?;
        Some(Move {
            block: x as usize,
            to: if to == TABLE {
                Place::Table
            } else {
                Place::On(to as usize)
            },
        })
    }
}
