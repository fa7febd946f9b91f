//! Every optimal first move of a problem at any size, each proven by the optimal solver:
//! the labels a learner imitates past the sizes whose whole state space fits in memory
//! ([`StateSpace`](super::StateSpace) holds at most 8 blocks).
//!
//! A move `m` from a state `s` starts a shortest plan exactly when the optimum after it is
//! one less than the optimum from `s` (it can never be less). Both optima come from
//! [`OptimalMoves`], which proves them by its certificate. Most moves are ruled out without
//! a search: the certificate's parts that need none ([`Certificate::quick`]: the misplaced
//! blocks and those forced to move twice) bound the optimum after `m` from below, and a move
//! whose bound is already the optimum from `s` is not optimal. Only the others are solved.

use crate::error::Result;

use super::goal::TowerGoal;
use super::optimal::{Certificate, OptimalMoves};
use super::state::{Move, Table, Towers};

/// The optimum from `state` to `goal` and every move that starts a shortest plan, in
/// [`Towers::moves`] order (none where the goal holds), on the unbounded table; `None` where
/// a proof the answer needs did not close within `solver`'s time limit. An error if the goal
/// names a block the state lacks.
pub fn optimal_first_moves(
    solver: &OptimalMoves,
    state: &Towers,
    goal: &TowerGoal,
) -> Result<Option<(usize, Vec<Move>)>> {
    let Some(here) = optimum(solver, state, goal)? else {
        return Ok(None);
    };
    if here == 0 {
        return Ok(Some((0, Vec::new())));
    }
    let mut optimal = Vec::new();
    for mv in state.moves(Table::Unbounded) {
        let mut next = state.clone();
        next.apply(mv, Table::Unbounded)?;
        if Certificate::quick(&next, goal)?.lower_bound() >= here {
            continue;
        }
        match optimum(solver, &next, goal)? {
            Some(after) if after + 1 == here => optimal.push(mv),
            Some(_) => {}
            None => return Ok(None),
        }
    }
    Ok(Some((here, optimal)))
}

/// The proven optimum from `state` to `goal`, `None` if the proof did not close.
fn optimum(solver: &OptimalMoves, state: &Towers, goal: &TowerGoal) -> Result<Option<usize>> {
    let solved = solver.solve(state, goal)?;
    Ok(solved.is_optimal().then(|| solved.plan.len()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::towers::{StateSpace, random_goal, random_state};
    use proptest::prelude::*;

    #[test]
    fn on_every_state_of_four_blocks_the_labels_are_the_breadth_first_searchs() {
        let space = StateSpace::new(4).unwrap();
        let solver = OptimalMoves::new();
        for g in 0..space.len() {
            let goal = TowerGoal::new(&space.state(g).towers()).unwrap();
            let distances = space.distances(&goal).unwrap();
            for s in 0..space.len() {
                let state = space.state(s);
                let (here, moves) = optimal_first_moves(&solver, state, &goal).unwrap().unwrap();
                assert_eq!(here as u32, distances.of(&space, state).unwrap());
                assert_eq!(
                    moves,
                    distances.optimal_moves(&space, state).unwrap(),
                    "{state} to {goal}"
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Up to 7 blocks, with goals naming some or all blocks, the optimal moves are those
        /// a breadth-first search over every state finds.
        #[test]
        fn the_labels_are_the_breadth_first_searchs(
            blocks in 1usize..=7,
            stacks in 1usize..=3,
            named in 1usize..=7,
            seed in any::<u64>(),
        ) {
            let named = named.min(blocks);
            let stacks = stacks.min(named);
            let state = random_state(blocks, seed);
            let goal = random_goal(blocks, stacks, named, seed ^ 0x1abe1).unwrap();
            let space = crate::towers::space::shared_space(blocks);
            let distances = space.distances(&goal).unwrap();
            let (here, moves) = optimal_first_moves(&OptimalMoves::new(), &state, &goal).unwrap().unwrap();
            prop_assert_eq!(here as u32, distances.of(space, &state).unwrap());
            prop_assert_eq!(moves, distances.optimal_moves(space, &state).unwrap());
        }
    }
}
