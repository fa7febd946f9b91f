//! The greedy choice of block moves, shared by the policy that plays and the trainer that
//! tests it: the legal move with the highest score, read from a pass kept up to date move
//! by move ([`LivePass`]).

use oracle::towers::{Move, Table, TowerGoal, Towers};

use super::incremental::LivePass;
use super::net::RelationalNet;

/// The greedy choice of block moves: the legal move with the highest score
/// ([`RelationalNet::best_move`]). It keeps the pass of the last state it was asked about:
/// asked next about that state after one move, it brings the pass up to date for the move
/// rather than passing over every block again.
pub struct MovePolicy<'n> {
    net: &'n RelationalNet,
    live: Option<(TowerGoal, LivePass<'n>)>,
}

impl<'n> MovePolicy<'n> {
    /// The policy of `net`.
    pub fn new(net: &'n RelationalNet) -> MovePolicy<'n> {
        MovePolicy { net, live: None }
    }

    /// The move it makes from `state` towards `goal` on `table` (a move to the table only
    /// where a column is free); `None` if the goal holds, no move is legal, or the goal
    /// names a block the state lacks.
    pub fn choose(&mut self, state: &Towers, goal: &TowerGoal, table: Table) -> Option<Move> {
        let live = self.follow(state, goal)?;
        if live.goal_holds() {
            return None;
        }
        live.best_move(table.has_free_column(state.tower_count()))
    }

    /// The pass over `state` towards `goal`: the kept one, brought up to date if `state` is
    /// one move from it, or a new one.
    fn follow(&mut self, state: &Towers, goal: &TowerGoal) -> Option<&mut LivePass<'n>> {
        let kept = match self.live.take() {
            Some((kept_goal, mut live)) if &kept_goal == goal => match one_move_between(live.state(), state) {
                Some(None) => Some((kept_goal, live)),
                Some(Some(mv)) if live.apply(mv, Table::Unbounded).is_ok() && live.state() == state => {
                    Some((kept_goal, live))
                }
                _ => None,
            },
            _ => None,
        };
        let kept = match kept {
            Some(kept) => kept,
            None => (goal.clone(), LivePass::new(self.net, state, goal).ok()?),
        };
        Some(&mut self.live.insert(kept).1)
    }
}

/// How `to` differs from `from`: `Some(None)` if not at all, `Some(Some(mv))` if only in
/// where one block stands (the move that would make it), `None` otherwise.
fn one_move_between(from: &Towers, to: &Towers) -> Option<Option<Move>> {
    if from.blocks() != to.blocks() {
        return None;
    }
    let mut moved = (0..to.blocks()).filter(|&b| from.support(b) != to.support(b));
    match (moved.next(), moved.next()) {
        (None, _) => Some(None),
        (Some(block), None) => Some(Some(Move {
            block,
            to: to.support(block),
        })),
        _ => None,
    }
}
