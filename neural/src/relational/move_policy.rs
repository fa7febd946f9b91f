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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relational::incremental::full_pass_move;
    use crate::relational::net::Shape;
    use oracle::towers::random_state;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Asked about states one move apart, two moves apart, the same state again, a new
        /// state or a new goal, the policy chooses what a full pass over that state does.
        #[test]
        fn it_chooses_as_a_full_pass_whatever_it_is_asked_next(weights in 0u64..1000, n in 2usize..40, seed in 0u64..1000, steps in proptest::collection::vec(0u8..5, 1..30)) {
            let shape = Shape { width: 6, hidden: 5, score_hidden: 4, rounds: 2 };
            let net = RelationalNet::new(shape, &mut sim::seeding::rng(weights)).unwrap();
            let mut policy = MovePolicy::new(&net);
            let mut goal = TowerGoal::new(&random_state(n, seed ^ 1).towers()).unwrap();
            let mut state = random_state(n, seed);
            let mut rng = sim::seeding::rng(seed);
            for (i, step) in steps.into_iter().enumerate() {
                let table = Table::Unbounded;
                prop_assert_eq!(policy.choose(&state, &goal, table), full_pass_move(&net, &state, &goal, table));
                let random_move = |state: &mut Towers, rng: &mut sim::seeding::SimRng| {
                    let legal = state.moves(table);
                    let mv = legal[rand::RngExt::random_range(rng, 0..legal.len())];
                    state.apply(mv, table).unwrap();
                };
                match step {
                    0 => {}
                    1 => state = random_state(n, seed + i as u64 + 7),
                    2 => goal = TowerGoal::new(&random_state(n, seed + i as u64 + 9).towers()).unwrap(),
                    3 => {
                        random_move(&mut state, &mut rng);
                        random_move(&mut state, &mut rng);
                    }
                    _ => random_move(&mut state, &mut rng),
                }
            }
        }
    }
}
