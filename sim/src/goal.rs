//! Goals: the order of the stack, bottom to top, and what it asks of every block
//! (docs/world.md sections 3 and 6).

use std::fmt;

use rand::RngExt;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid};
use crate::state::{BlockId, MAX_BLOCKS, MIN_BLOCKS, State};

/// The most goals [`Goal::all`] builds: every goal of 7 blocks (`7! = 5040`).
pub const MAX_ALL_GOALS: usize = 5040;

/// A goal: every block id once, bottom to top. `[1, 0, 2]` asks for block 1 at the bottom,
/// 0 on top of 1 and 2 on top of 0, anywhere on the grid. Written `1,0,2`.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Goal {
    order: [BlockId; MAX_BLOCKS],
    /// `place[b]` is block `b`'s position in `order` (0 = bottom).
    place: [u8; MAX_BLOCKS],
    count: u8,
}

impl Goal {
    /// A goal from its order bottom to top; an error unless it is a permutation of `0..N`
    /// with `MIN_BLOCKS <= N <= MAX_BLOCKS`.
    pub fn new(order: &[BlockId]) -> Result<Goal> {
        let count = order.len();
        let bad = |reason: String| SimError::BadGoal {
            goal: join(order),
            count,
            reason,
        };
        if !(MIN_BLOCKS..=MAX_BLOCKS).contains(&count) {
            return Err(SimError::BadBlockCount {
                count,
                min: MIN_BLOCKS,
                max: MAX_BLOCKS,
            });
        }
        let mut place = [u8::MAX; MAX_BLOCKS];
        for (i, b) in order.iter().enumerate() {
            if b.index() >= count {
                return Err(bad(format!("block {b} does not exist")));
            }
            if place[b.index()] != u8::MAX {
                return Err(bad(format!("block {b} appears twice")));
            }
            place[b.index()] = i as u8;
        }
        let mut all = [BlockId::default(); MAX_BLOCKS];
        all[..count].copy_from_slice(order);
        Ok(Goal {
            order: all,
            place,
            count: count as u8,
        })
    }

    /// A goal from plain indices, e.g. `Goal::from_indices(&[1, 0, 2])`.
    pub fn from_indices(order: &[usize]) -> Result<Goal> {
        let count = order.len();
        if let Some(&b) = order.iter().find(|&&b| b >= count) {
            return Err(SimError::BadGoal {
                goal: order.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(","),
                count,
                reason: format!("block {b} does not exist"),
            });
        }
        let ids: Vec<BlockId> = order.iter().map(|&b| BlockId(b as u8)).collect();
        Goal::new(&ids)
    }

    /// Reads `"1,0,2"`; `blocks`, when given, is the block count the goal must have.
    pub fn parse(text: &str, blocks: Option<usize>) -> Result<Goal> {
        let mut order = Vec::new();
        for part in text.split(',') {
            let b = part.trim().parse::<usize>().map_err(|_| SimError::Parse {
                what: "goal",
                text: text.to_string(),
                reason: format!(
                    "{:?} is not a block number; write the blocks bottom to top, e.g. 1,0,2",
                    part.trim()
                ),
            })?;
            order.push(b);
        }
        let goal = Goal::from_indices(&order)?;
        if let Some(n) = blocks {
            if n != goal.block_count() {
                return Err(SimError::BadGoal {
                    goal: text.to_string(),
                    count: n,
                    reason: format!("it has {} blocks", goal.block_count()),
                });
            }
        }
        Ok(goal)
    }

    /// Reads goals separated by `:`, e.g. `"0,1,2:1,0,2"`, each of `blocks` blocks (the
    /// same goal may come more than once).
    pub fn parse_list(text: &str, blocks: usize) -> Result<Vec<Goal>> {
        text.split(':').map(|g| Goal::parse(g, Some(blocks))).collect()
    }

    /// The identity goal `0, 1, ..., blocks - 1`.
    pub fn identity(blocks: usize) -> Result<Goal> {
        Goal::from_indices(&(0..blocks).collect::<Vec<_>>())
    }

    /// A goal drawn uniformly at random from the `blocks!` permutations.
    pub fn random(blocks: usize, rng: &mut impl rand::Rng) -> Result<Goal> {
        let mut order: Vec<usize> = (0..blocks).collect();
        // Fisher-Yates, written out so the draw does not depend on rand's shuffle internals.
        for i in (1..order.len()).rev() {
            let j = rng.random_range(0..=i);
            order.swap(i, j);
        }
        Goal::from_indices(&order)
    }

    /// Every goal of `blocks` blocks, in lexicographic order (`blocks!` of them); an error
    /// ([`SimError::TooManyGoals`]) past [`MAX_ALL_GOALS`], 7 blocks: 8 blocks have 40,320
    /// goals and 12 almost half a billion, which nothing should build by default.
    pub fn all(blocks: usize) -> Result<Vec<Goal>> {
        let identity = Goal::identity(blocks)?;
        let goals = (1..=blocks as u128).product::<u128>();
        if goals > MAX_ALL_GOALS as u128 {
            return Err(SimError::TooManyGoals {
                blocks,
                goals: goals.to_string(),
                max: MAX_ALL_GOALS,
                example: identity.to_string(),
            });
        }
        let mut out = Vec::new();
        let mut order: Vec<usize> = (0..blocks).collect();
        loop {
            out.push(Goal::from_indices(&order)?);
            // Next permutation in lexicographic order.
            let Some(i) = (0..blocks - 1).rev().find(|&i| order[i] < order[i + 1]) else {
                break;
            };
            let j = (i + 1..blocks)
                .rev()
                .find(|&j| order[j] > order[i])
                .expect("a larger element exists");
            order.swap(i, j);
            order[i + 1..].reverse();
        }
        Ok(out)
    }

    /// Whether the goal can be reached from `state` on `grid` by the rules (docs/world.md section 2).
    ///
    /// On a grid at least two cells wide it always can (the `oracle` crate's docs give the
    /// argument, and its tests check it against a search of every state on small grids).
    /// On a grid one cell wide blocks cannot pass each other, so it can exactly when the
    /// blocks stand, bottom to top, in the goal's order.
    pub fn can_be_reached(&self, grid: Grid, state: &State) -> bool {
        grid.width() > 1 || self.order().windows(2).all(|p| state.cell(p[0]).y < state.cell(p[1]).y)
    }

    /// An error if the stack cannot stand in `grid` (taller than its rows).
    pub fn check_fits(&self, grid: Grid) -> Result<()> {
        if self.block_count() > grid.height() {
            return Err(SimError::StackTooTall {
                blocks: self.block_count(),
                height: grid.height(),
            });
        }
        Ok(())
    }

    /// Number of blocks.
    #[inline]
    pub const fn block_count(&self) -> usize {
        self.count as usize
    }

    /// The blocks bottom to top.
    #[inline]
    pub fn order(&self) -> &[BlockId] {
        &self.order[..self.count as usize]
    }

    /// Where `block` stands in the stack: 0 at the bottom.
    #[inline]
    pub fn place_of(&self, block: BlockId) -> usize {
        self.place[block.index()] as usize
    }

    /// The block at `place` in the stack (0 = bottom).
    #[inline]
    pub fn block_at_place(&self, place: usize) -> BlockId {
        self.order[place]
    }

    /// The goal's consecutive pairs `(below, above)`, bottom first.
    pub fn pairs(&self) -> impl Iterator<Item = (BlockId, BlockId)> + '_ {
        self.order().windows(2).map(|w| (w[0], w[1]))
    }

    /// How many consecutive pairs of the goal stand in place (`above` directly on `below`).
    pub fn pairs_in_place(&self, state: &State) -> usize {
        self.pairs()
            .filter(|&(a, b)| on_top(state.cell(a), state.cell(b)))
            .count()
    }

    /// Whether the goal holds: every consecutive pair in place. The held block does not matter.
    #[inline]
    pub fn holds(&self, state: &State) -> bool {
        self.pairs().all(|(a, b)| on_top(state.cell(a), state.cell(b)))
    }

    /// The goal that holds in `state`, if one does: every block in one column, each
    /// directly on the one below (a goal is the whole stack, so at most one holds). Hindsight
    /// relabelling and Python's goal environment read a state's achieved goal here.
    pub fn standing(state: &State) -> Option<Goal> {
        let mut order: Vec<BlockId> = state.blocks().collect();
        order.sort_by_key(|&b| state.cell(b).y);
        let goal = Goal::new(&order).ok()?;
        goal.holds(state).then_some(goal)
    }

    /// The block `block` chases (docs/world.md section 6): the one above it in the goal, or, for the
    /// top block, the one below it.
    pub fn chased_block(&self, block: BlockId) -> BlockId {
        let p = self.place_of(block);
        if p + 1 < self.block_count() {
            self.order[p + 1]
        } else {
            self.order[p - 1]
        }
    }

    /// The cell `block` chases (docs/world.md section 6): directly below the block above it in the
    /// goal, or, for the top block, directly above the block below it. `None` when that cell
    /// is outside the grid.
    pub fn chased_cell(&self, block: BlockId, state: &State, grid: Grid) -> Option<Cell> {
        let p = self.place_of(block);
        if p + 1 < self.block_count() {
            state.cell(self.order[p + 1]).below(grid)
        } else {
            state.cell(self.order[p - 1]).above(grid)
        }
    }

    /// The Manhattan distance from `block` to the cell it chases. The chased cell may lie
    /// just outside the grid (below a block on the bottom row, above one on the top row);
    /// its distance is measured all the same.
    pub fn chased_distance(&self, block: BlockId, state: &State) -> u32 {
        let p = self.place_of(block);
        let (target, dy) = if p + 1 < self.block_count() {
            (state.cell(self.order[p + 1]), -1)
        } else {
            (state.cell(self.order[p - 1]), 1)
        };
        let from = state.cell(block);
        let ty = i32::from(target.y) + dy;
        u32::from(from.x.abs_diff(target.x)) + (i32::from(from.y) - ty).unsigned_abs()
    }

    /// Sum over the goal's consecutive pairs of the Manhattan distance between the two blocks.
    pub fn chain_distance(&self, state: &State) -> u32 {
        self.pairs().map(|(a, b)| state.cell(a).manhattan(state.cell(b))).sum()
    }
}

/// Whether `above` stands directly on `below`.
#[inline]
fn on_top(below: Cell, above: Cell) -> bool {
    above.x == below.x && above.y == below.y.wrapping_add(1)
}

fn join(order: &[BlockId]) -> String {
    order.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(",")
}

impl fmt::Display for Goal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&join(self.order()))
    }
}

impl fmt::Debug for Goal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Goal[{self}]")
    }
}

impl std::str::FromStr for Goal {
    type Err = SimError;

    fn from_str(text: &str) -> Result<Goal> {
        Goal::parse(text, None)
    }
}

impl Serialize for Goal {
    /// A goal is written as its list of block ids, bottom to top.
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.order().serialize(s)
    }
}

impl<'de> Deserialize<'de> for Goal {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Goal, D::Error> {
        let order = Vec::<usize>::deserialize(d)?;
        Goal::from_indices(&order).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_standing_goal_is_the_whole_stack_or_none() {
        let grid = Grid::default();
        let stacked = State::parse("1,1;1,3;1,2", None, grid).unwrap();
        assert_eq!(Goal::standing(&stacked), Some("0,2,1".parse().unwrap()));
        // Two of three stacked, or a gap in the column: no goal holds.
        for text in ["1,1;1,2;4,4", "1,1;1,2;1,4", "0,0;1,1;2,2"] {
            let state = State::parse(text, None, grid).unwrap();
            assert_eq!(Goal::standing(&state), None, "{text}");
        }
        for goal in Goal::all(3).unwrap() {
            let held = Goal::standing(&stacked).is_some_and(|g| g == goal);
            assert_eq!(goal.holds(&stacked), held);
        }
    }
}
