//! Every state of a few blocks, and the exact number of moves from each to a goal: the
//! optimal value function, from which every optimal move of every state can be read.
//!
//! [`ExactMoves`](super::ExactMoves) finds one shortest plan from one state. A learner that
//! imitates the optimum needs more: for each state it meets, *every* move that starts a
//! shortest plan, so that no optimal move is taught as a mistake. Over a few blocks the
//! whole state space is small (1, 3, 13, 73, 501, 4,051, 37,633 and 394,353 states for 1
//! to 8 blocks), so one breadth-first search from the states where the goal holds gives the
//! distance of every state at once, and the optimal moves of a state are those that lead to
//! a state one move closer. Block moves are reversible on an unbounded table (a block put
//! somewhere can go back where it came from), so the search runs over the same neighbours
//! forwards and backwards.

use std::collections::HashMap;
use std::collections::VecDeque;

use crate::error::Result;

use super::error::TowersError;
use super::goal::TowerGoal;
use super::state::{Move, NONE, Table, Towers};

/// Bits per block in a state's key.
const KEY_BITS: usize = 4;
/// The key's code for "on the table".
const KEY_TABLE: u64 = (1 << KEY_BITS) - 1;

/// Every state of `n` blocks on an unbounded table, and which states one move joins.
#[derive(Debug, Clone)]
pub struct StateSpace {
    /// The number of blocks.
    blocks: usize,
    /// The states, in the order a breadth-first search from "every block on the table" met them.
    states: Vec<Towers>,
    /// Each state's index, by key.
    index: HashMap<u64, u32>,
    /// Where each state's neighbours start in `neighbours` (one more entry than states).
    starts: Vec<u32>,
    /// The neighbours of every state, one list after another, each in [`Towers::moves`] order.
    neighbours: Vec<u32>,
}

impl StateSpace {
    /// The most blocks a state space takes: 8 blocks are 394,353 states and about 5 million
    /// neighbour links (some 30 MB); 9 would be ten times that.
    pub const MAX_BLOCKS: usize = 8;

    /// Every state of `blocks` blocks (1 to [`StateSpace::MAX_BLOCKS`]).
    pub fn new(blocks: usize) -> Result<StateSpace> {
        if blocks == 0 || blocks > Self::MAX_BLOCKS {
            return Err(TowersError::SpaceSize {
                blocks,
                max: Self::MAX_BLOCKS,
            }
            .into());
        }
        let flat = Towers::from_below(vec![NONE; blocks]);
        let mut index = HashMap::from([(key(&flat), 0u32)]);
        let mut states = vec![flat];
        let mut starts = vec![0u32];
        let mut neighbours = Vec::new();
        // Breadth-first: state i's neighbours are found when i is taken, so they are listed
        // in the order the states were met, and `starts` grows one state at a time.
        let mut next = 0;
        while next < states.len() {
            for mv in states[next].moves(Table::Unbounded) {
                let mut to = states[next].clone();
                to.apply_unchecked(mv);
                let k = key(&to);
                let id = match index.get(&k) {
                    Some(&id) => id,
                    None => {
                        let id = states.len() as u32;
                        index.insert(k, id);
                        states.push(to);
                        id
                    }
                };
                neighbours.push(id);
            }
            starts.push(neighbours.len() as u32);
            next += 1;
        }
        Ok(StateSpace {
            blocks,
            states,
            index,
            starts,
            neighbours,
        })
    }

    /// The number of blocks.
    pub fn blocks(&self) -> usize {
        self.blocks
    }

    /// The number of states.
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Whether there is no state (never: a space has at least one).
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// The state with index `i`.
    ///
    /// # Panics
    /// If `i` is not below [`StateSpace::len`].
    pub fn state(&self, i: usize) -> &Towers {
        &self.states[i]
    }

    /// The index of `state`; an error if it has another number of blocks.
    pub fn index_of(&self, state: &Towers) -> Result<usize> {
        if state.blocks() != self.blocks {
            return Err(TowersError::BlockCount {
                blocks: state.blocks(),
                expected: self.blocks,
            }
            .into());
        }
        Ok(self.index[&key(state)] as usize)
    }

    /// The indices of the states one move from state `i`, in [`Towers::moves`] order.
    fn neighbours(&self, i: usize) -> &[u32] {
        &self.neighbours[self.starts[i] as usize..self.starts[i + 1] as usize]
    }

    /// The fewest moves from every state to `goal`, by one breadth-first search from the
    /// states where it holds; an error if the goal names a block the states lack.
    pub fn distances(&self, goal: &TowerGoal) -> Result<Distances> {
        goal.check_blocks(self.blocks)?;
        let mut moves = vec![u8::MAX; self.len()];
        let mut queue = VecDeque::new();
        for (i, state) in self.states.iter().enumerate() {
            if goal.holds(state) {
                moves[i] = 0;
                queue.push_back(i);
            }
        }
        while let Some(i) = queue.pop_front() {
            let d = moves[i] + 1;
            for &j in self.neighbours(i) {
                if moves[j as usize] == u8::MAX {
                    moves[j as usize] = d;
                    queue.push_back(j as usize);
                }
            }
        }
        Ok(Distances { moves })
    }
}

/// The fewest moves from every state of a [`StateSpace`] to one goal.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Distances {
    /// By state index.
    moves: Vec<u8>,
}

impl Distances {
    /// The fewest moves from `state` to the goal.
    pub fn of(&self, space: &StateSpace, state: &Towers) -> Result<u32> {
        Ok(u32::from(self.moves[space.index_of(state)?]))
    }

    /// Every move from `state` that starts a shortest plan to the goal, in [`Towers::moves`]
    /// order; empty where the goal holds.
    pub fn optimal_moves(&self, space: &StateSpace, state: &Towers) -> Result<Vec<Move>> {
        let i = space.index_of(state)?;
        let here = self.moves[i];
        if here == 0 {
            return Ok(Vec::new());
        }
        Ok(state
            .moves(Table::Unbounded)
            .into_iter()
            .zip(space.neighbours(i))
            .filter(|&(_, &j)| self.moves[j as usize] + 1 == here)
            .map(|(mv, _)| mv)
            .collect())
    }
}

/// A state's key: each block's support in [`KEY_BITS`] bits.
fn key(state: &Towers) -> u64 {
    state.below().iter().enumerate().fold(0, |acc, (b, &s)| {
        let code = if s == NONE { KEY_TABLE } else { s as u64 };
        acc | code << (KEY_BITS * b)
    })
}

/// The state space of `blocks` blocks (at most 8), made once per size for every test that
/// asks: the solvers' tests compare with it, and making one of 8 blocks takes a while.
#[cfg(test)]
pub(crate) fn shared_space(blocks: usize) -> &'static StateSpace {
    static SPACES: [std::sync::OnceLock<StateSpace>; 9] = [const { std::sync::OnceLock::new() }; 9];
    SPACES[blocks].get_or_init(|| StateSpace::new(blocks).unwrap())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::towers::{ExactMoves, random_goal, random_state};

    #[test]
    fn the_spaces_hold_every_state_once() {
        // The number of Blocks World states of n blocks (OEIS A000262).
        let counts: Vec<usize> = (1..=7).map(|n| StateSpace::new(n).unwrap().len()).collect();
        assert_eq!(counts, [1, 3, 13, 73, 501, 4051, 37633]);
        assert!(StateSpace::new(0).is_err() && StateSpace::new(9).is_err());
    }

    #[test]
    fn distances_are_the_exact_solvers_and_optimal_moves_keep_them() {
        let space = StateSpace::new(6).unwrap();
        for seed in 0..40 {
            let named = 3 + seed as usize % 4;
            let goal = random_goal(6, 1 + seed as usize % 3, named, seed).unwrap();
            let distances = space.distances(&goal).unwrap();
            let start = random_state(6, seed + 100);
            let exact = ExactMoves::new().solve(&start, &goal).unwrap().len() as u32;
            assert_eq!(distances.of(&space, &start).unwrap(), exact, "seed {seed}");
            let optimal = distances.optimal_moves(&space, &start).unwrap();
            assert_eq!(optimal.is_empty(), exact == 0);
            for mv in start.moves(Table::Unbounded) {
                let mut next = start.clone();
                next.apply(mv, Table::Unbounded).unwrap();
                let after = ExactMoves::new().solve(&next, &goal).unwrap().len() as u32;
                assert_eq!(optimal.contains(&mv), after + 1 == exact, "seed {seed} {mv}");
            }
        }
    }
}
