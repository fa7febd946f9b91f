//! Goals: the order of the stack, bottom to top, and what it asks of every block
//! (docs/world.md sections 3 and 6); or several towers, each bottom to top (docs/world.md,
//! "The side view"), in either view.

use std::fmt;

use rand::RngExt;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid};
use crate::state::{BlockId, MAX_BLOCKS, MIN_BLOCKS, State};
use crate::view::View;

/// The most goals [`Goal::all`] builds: every goal of 7 blocks (`7! = 5040`).
pub const MAX_ALL_GOALS: usize = 5040;

/// A goal: towers of blocks, each bottom to top.
///
/// The classic goal is one tower of every block: `[1, 0, 2]` asks for block 1 at the
/// bottom, 0 on top of 1 and 2 on top of 0, anywhere on the grid. Written `1,0,2`.
///
/// A goal of several towers is written with `/` between them: `0,1,2/3,4` asks for two
/// towers, each anywhere (as a single tower is). Blocks a goal of towers leaves unnamed are
/// free, and a tower may carry more blocks on top. In the side view a tower's bottom block
/// must also stand on the table ([`Goal::holds_in`]). Everything that handles only the
/// classic goal asks [`Goal::is_one_tower`] (or [`Goal::one_tower`]) first and refuses
/// others with [`SimError::NotOneTower`].
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Goal {
    /// The named blocks, tower by tower, each bottom to top.
    order: [BlockId; MAX_BLOCKS],
    /// `place[b]` is block `b`'s position in `order` (0 = bottom of the first tower);
    /// `u8::MAX` for a block the goal leaves free.
    place: [u8; MAX_BLOCKS],
    /// Bit `i` set: `order[i]` is the top of its tower.
    tops: u32,
    /// How many blocks `order` names.
    named: u8,
    /// How many blocks the world has.
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
            tops: 1 << (count - 1),
            named: count as u8,
            count: count as u8,
        })
    }

    /// A goal of `towers` (each bottom to top, each non-empty) in a world of `blocks`
    /// blocks; blocks no tower names are free. An error if a block does not exist or is
    /// named twice, or if the block count is out of range.
    pub fn of_towers(towers: &[Vec<usize>], blocks: usize) -> Result<Goal> {
        let text = towers_text(towers);
        let bad = |reason: String| SimError::BadGoal {
            goal: text.clone(),
            count: blocks,
            reason,
        };
        if !(MIN_BLOCKS..=MAX_BLOCKS).contains(&blocks) {
            return Err(SimError::BadBlockCount {
                count: blocks,
                min: MIN_BLOCKS,
                max: MAX_BLOCKS,
            });
        }
        let mut order = [BlockId::default(); MAX_BLOCKS];
        let mut place = [u8::MAX; MAX_BLOCKS];
        let (mut named, mut tops) = (0usize, 0u32);
        for tower in towers {
            if tower.is_empty() {
                return Err(bad("a tower names no block".into()));
            }
            for &b in tower {
                if b >= blocks {
                    return Err(bad(format!("block {b} does not exist")));
                }
                if place[b] != u8::MAX {
                    return Err(bad(format!("block {b} appears twice")));
                }
                place[b] = named as u8;
                order[named] = BlockId(b as u8);
                named += 1;
            }
            tops |= 1 << (named - 1);
        }
        if named == 0 {
            return Err(bad("it names no block".into()));
        }
        Ok(Goal {
            order,
            place,
            tops,
            named: named as u8,
            count: blocks as u8,
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

    /// Reads `"1,0,2"`, one tower of every block, or towers separated by `/`
    /// (`"0,1,2/3,4"`, a goal of towers: [`Goal::of_towers`]); `blocks`, when given, is the
    /// block count the goal must have (a goal of towers then leaves the blocks it does not
    /// name free; without it, its blocks are `0..` one past the largest it names). A single
    /// tower naming only some blocks is written with a trailing `/` (`"0,1/"`).
    pub fn parse(text: &str, blocks: Option<usize>) -> Result<Goal> {
        if text.contains('/') {
            return Goal::parse_towers(text, blocks);
        }
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
        if let Some(n) = blocks
            && n != goal.block_count()
        {
            return Err(SimError::BadGoal {
                goal: text.to_string(),
                count: n,
                reason: format!("it has {} blocks", goal.block_count()),
            });
        }
        Ok(goal)
    }

    /// Reads a goal of towers, `"0,1,2/3,4"` ([`Goal::parse`]).
    fn parse_towers(text: &str, blocks: Option<usize>) -> Result<Goal> {
        let mut towers = Vec::new();
        for part in text.split('/').map(str::trim).filter(|p| !p.is_empty()) {
            let tower = part
                .split(',')
                .map(|b| {
                    b.trim().parse::<usize>().map_err(|_| SimError::Parse {
                        what: "goal",
                        text: text.to_string(),
                        reason: format!(
                            "{:?} is not a block number; write each tower bottom to top, towers separated by '/', e.g. 0,1,2/3,4",
                            b.trim()
                        ),
                    })
                })
                .collect::<Result<Vec<usize>>>()?;
            towers.push(tower);
        }
        let largest = towers.iter().flatten().max().map_or(0, |&b| b + 1);
        Goal::of_towers(&towers, blocks.unwrap_or(largest))
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

    /// Every goal naming every one of `blocks` blocks in one to `blocks` towers, each goal
    /// once: the goals of one tower first ([`Goal::all`]'s order), then those of two towers,
    /// and so on, each listing its towers by their bottom block (13 goals of 3 blocks, 73 of
    /// 4, 501 of 5, 4,051 of 6). An error ([`SimError::TooManyGoals`]) past
    /// [`MAX_ALL_GOALS`] goals, from 7 blocks on.
    pub fn all_towers(blocks: usize) -> Result<Vec<Goal>> {
        Goal::identity(blocks)?;
        // The ways to split N named blocks into ordered towers: the Lah numbers' row sum.
        let count = (1..=blocks).map(|k| lah(blocks, k)).sum::<u128>();
        if count > MAX_ALL_GOALS as u128 {
            return Err(SimError::TooManyGoals {
                blocks,
                goals: count.to_string(),
                max: MAX_ALL_GOALS,
                example: "0,1/2".to_string(),
            });
        }
        let mut out = Goal::all(blocks)?;
        for towers in 2..=blocks {
            let mut goals: Vec<Vec<Vec<usize>>> = Vec::new();
            for order in Goal::all(blocks)? {
                let order: Vec<usize> = order.order().iter().map(|b| b.index()).collect();
                for cuts in cut_sets(blocks, towers) {
                    let split = canonical_towers(split_at(&order, &cuts));
                    if !goals.contains(&split) {
                        goals.push(split);
                    }
                }
            }
            goals.sort();
            for split in goals {
                out.push(Goal::of_towers(&split, blocks)?);
            }
        }
        Ok(out)
    }

    /// One goal of each shape of `blocks` blocks: for every way to split them into towers
    /// (tower heights, tallest first), the blocks `0, 1, ...` in towers of those heights
    /// (`0,1,2`, `0,1/2` and `0/1/2` for 3 blocks). A learner that names blocks by their
    /// place in the goal meets every goal in these.
    pub fn shapes(blocks: usize) -> Result<Vec<Goal>> {
        Goal::identity(blocks)?;
        let mut out = Vec::new();
        for heights in partitions(blocks, blocks) {
            let mut next = 0;
            let towers: Vec<Vec<usize>> = heights
                .iter()
                .map(|&h| {
                    next += h;
                    (next - h..next).collect()
                })
                .collect();
            out.push(Goal::of_towers(&towers, blocks)?);
        }
        Ok(out)
    }

    /// Every goal a world of `view` is trained and tested on by default: one tower of every
    /// block from above ([`Goal::all`]), every goal of towers naming every block from the
    /// side ([`Goal::all_towers`]).
    pub fn all_in(view: View, blocks: usize) -> Result<Vec<Goal>> {
        match view {
            View::Top => Goal::all(blocks),
            View::Side => Goal::all_towers(blocks),
        }
    }

    /// A goal naming every one of `blocks` blocks in exactly `towers` towers, drawn
    /// uniformly among them, its towers listed by their bottom block. An error unless
    /// `1 <= towers <= blocks`.
    pub fn random_towers(blocks: usize, towers: usize, rng: &mut impl rand::Rng) -> Result<Goal> {
        if !(1..=blocks).contains(&towers) {
            return Err(SimError::BadGoal {
                goal: format!("{towers} towers"),
                count: blocks,
                reason: format!("a goal of {blocks} blocks has 1 to {blocks} towers"),
            });
        }
        // A uniform order cut at `towers - 1` cut points drawn uniformly: every goal comes
        // from the same number of (order, cuts) pairs (its towers in any order), so every
        // goal is as likely.
        let order: Vec<usize> = Goal::random(blocks, rng)?.order().iter().map(|b| b.index()).collect();
        let mut positions: Vec<usize> = (1..blocks).collect();
        let mut cuts = Vec::with_capacity(towers - 1);
        for _ in 1..towers {
            let i = rng.random_range(0..positions.len());
            cuts.push(positions.swap_remove(i));
        }
        cuts.sort_unstable();
        Goal::of_towers(&canonical_towers(split_at(&order, &cuts)), blocks)
    }

    /// Whether the goal can be reached from `state` on `grid` by the rules (docs/world.md section 2).
    ///
    /// On a grid at least two cells wide it always can (the `oracle` crate's docs give the
    /// argument, and its tests check it against a search of every state on small grids).
    /// On a grid one cell wide blocks cannot pass each other, so it can exactly when the
    /// blocks stand, bottom to top, in the goal's order.
    pub fn can_be_reached(&self, grid: Grid, state: &State) -> bool {
        grid.width() > 1 || self.pairs().all(|(a, b)| state.cell(a).y < state.cell(b).y)
    }

    /// An error if a tower cannot stand in `grid` (taller than its rows).
    pub fn check_fits(&self, grid: Grid) -> Result<()> {
        let tallest = self.towers().map(<[BlockId]>::len).max().unwrap_or(0);
        if tallest > grid.height() {
            return Err(SimError::StackTooTall {
                blocks: tallest,
                height: grid.height(),
            });
        }
        Ok(())
    }

    /// Number of blocks of the world the goal is for.
    #[inline]
    pub const fn block_count(&self) -> usize {
        self.count as usize
    }

    /// Whether this is the classic goal: one tower of every block.
    #[inline]
    pub const fn is_one_tower(&self) -> bool {
        self.named == self.count && self.tops == 1 << (self.count - 1)
    }

    /// The goal's one tower, bottom to top, if it is one tower of every block; otherwise
    /// [`SimError::NotOneTower`] naming `what` refuses it.
    pub fn one_tower(&self, what: &'static str) -> Result<&[BlockId]> {
        if self.is_one_tower() {
            Ok(self.order())
        } else {
            Err(SimError::NotOneTower {
                goal: self.to_string(),
                what,
            })
        }
    }

    /// The towers, each bottom to top.
    pub fn towers(&self) -> impl Iterator<Item = &[BlockId]> + '_ {
        let mut start = 0;
        (0..self.named as usize)
            .filter(|&i| self.tops & (1 << i) != 0)
            .map(move |top| {
                let tower = &self.order[start..=top];
                start = top + 1;
                tower
            })
    }

    /// The towers as plain indices, each bottom to top (what the block-move planners take).
    pub fn tower_lists(&self) -> Vec<Vec<usize>> {
        self.towers().map(|t| t.iter().map(|b| b.index()).collect()).collect()
    }

    /// Number of consecutive pairs `(below, above)` the goal asks for ([`Goal::pairs`]).
    #[inline]
    pub const fn pair_count(&self) -> usize {
        self.named as usize - self.tower_count()
    }

    /// Number of towers.
    #[inline]
    pub const fn tower_count(&self) -> usize {
        self.tops.count_ones() as usize
    }

    /// Whether the goal names `block` (a goal of towers may leave blocks free).
    #[inline]
    pub fn names(&self, block: BlockId) -> bool {
        self.place[block.index()] != u8::MAX
    }

    /// The blocks bottom to top: for a goal of one tower of every block, all of them; for
    /// a goal of towers, the named blocks tower by tower ([`Goal::towers`] keeps them apart).
    #[inline]
    pub fn order(&self) -> &[BlockId] {
        &self.order[..self.named as usize]
    }

    /// Where `block` stands in [`Goal::order`]: 0 at the bottom. Meaningful for a block the
    /// goal names ([`Goal::names`]).
    #[inline]
    pub fn place_of(&self, block: BlockId) -> usize {
        self.place[block.index()] as usize
    }

    /// The block at `place` in the stack (0 = bottom).
    #[inline]
    pub fn block_at_place(&self, place: usize) -> BlockId {
        self.order[place]
    }

    /// The goal's consecutive pairs `(below, above)` within each tower, bottom first.
    pub fn pairs(&self) -> impl Iterator<Item = (BlockId, BlockId)> + '_ {
        (0..(self.named as usize).saturating_sub(1))
            .filter(|&i| self.tops & (1 << i) == 0)
            .map(|i| (self.order[i], self.order[i + 1]))
    }

    /// How many consecutive pairs of the goal stand in place (`above` directly on `below`).
    pub fn pairs_in_place(&self, state: &State) -> usize {
        self.pairs()
            .filter(|&(a, b)| on_top(state.cell(a), state.cell(b)))
            .count()
    }

    /// Whether the goal holds in the top view: every consecutive pair in place. The held
    /// block does not matter. [`Goal::holds_in`] with [`View::Top`].
    #[inline]
    pub fn holds(&self, state: &State) -> bool {
        self.pairs().all(|(a, b)| on_top(state.cell(a), state.cell(b)))
    }

    /// Whether the goal holds in `view`: every consecutive pair in place; in the side view
    /// also every tower's bottom block on the table (row 0) and no block of a tower held (a
    /// held block stands on nothing).
    #[inline]
    pub fn holds_in(&self, view: View, state: &State) -> bool {
        match view {
            View::Top => self.holds(state),
            View::Side => {
                self.holds(state)
                    && state.held_block().is_none_or(|h| !self.names(h))
                    && self.towers().all(|t| state.cell(t[0]).y == 0)
            }
        }
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
    /// top block, the one below it. For a goal of one tower of every block
    /// ([`Goal::is_one_tower`]).
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
    /// is outside the grid. For a goal of one tower of every block.
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
    /// its distance is measured all the same. For a goal of one tower of every block.
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

/// Towers written as the parser reads them: `0,1,2/3,4`.
fn towers_text(towers: &[Vec<usize>]) -> String {
    towers
        .iter()
        .map(|t| t.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(","))
        .collect::<Vec<_>>()
        .join("/")
}

impl fmt::Display for Goal {
    /// `1,0,2` for one tower of every block; `0,1,2/3,4` for towers (a single tower naming
    /// only some blocks gets a trailing `/`, `0,1/`, so that it reads back the same).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.is_one_tower() {
            return f.write_str(&join(self.order()));
        }
        let towers: Vec<String> = self.towers().map(join).collect();
        f.write_str(&towers.join("/"))?;
        if towers.len() == 1 {
            f.write_str("/")?;
        }
        Ok(())
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

/// How a goal is written in JSON: one tower of every block as its list of ids bottom to
/// top (as before goals of towers existed), others as their towers and block count.
#[derive(Serialize, Deserialize)]
#[serde(untagged)]
enum GoalRepr {
    OneTower(Vec<usize>),
    Towers { towers: Vec<Vec<usize>>, blocks: usize },
}

impl Serialize for Goal {
    /// One tower of every block is written as its list of block ids, bottom to top
    /// (`[1,0,2]`); a goal of towers as `{"towers":[[0,1],[2]],"blocks":4}`.
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.is_one_tower() {
            self.order().serialize(s)
        } else {
            GoalRepr::Towers {
                towers: self.tower_lists(),
                blocks: self.block_count(),
            }
            .serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for Goal {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Goal, D::Error> {
        match GoalRepr::deserialize(d)? {
            GoalRepr::OneTower(order) => Goal::from_indices(&order),
            GoalRepr::Towers { towers, blocks } => Goal::of_towers(&towers, blocks),
        }
        .map_err(serde::de::Error::custom)
    }
}

/// The partitions of `n` into parts of at most `largest`, each listed tallest first, the
/// partitions in decreasing order (`[3]`, `[2, 1]`, `[1, 1, 1]`).
fn partitions(n: usize, largest: usize) -> Vec<Vec<usize>> {
    if n == 0 {
        return vec![Vec::new()];
    }
    let mut out = Vec::new();
    for first in (1..=largest.min(n)).rev() {
        for mut rest in partitions(n - first, first) {
            rest.insert(0, first);
            out.push(rest);
        }
    }
    out
}

/// The Lah number L(n, k): the ways to split `n` labelled blocks into `k` non-empty towers.
fn lah(n: usize, k: usize) -> u128 {
    // L(n, k) = C(n - 1, k - 1) n! / k!
    let factorial = |m: usize| (1..=m as u128).product::<u128>();
    let choose = factorial(n - 1) / (factorial(k - 1) * factorial(n - k));
    choose * factorial(n) / factorial(k)
}

/// Every set of `towers - 1` cut points in `1..blocks`, increasing.
fn cut_sets(blocks: usize, towers: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    for mask in 0u32..1 << (blocks - 1) {
        if mask.count_ones() as usize == towers - 1 {
            out.push((1..blocks).filter(|i| mask & (1 << (i - 1)) != 0).collect());
        }
    }
    out
}

/// `order` cut before each of `cuts` (increasing).
fn split_at(order: &[usize], cuts: &[usize]) -> Vec<Vec<usize>> {
    let mut towers = Vec::with_capacity(cuts.len() + 1);
    let mut start = 0;
    for &cut in cuts.iter().chain(std::iter::once(&order.len())) {
        towers.push(order[start..cut].to_vec());
        start = cut;
    }
    towers
}

/// The towers listed by their bottom block: one written form for each goal of towers.
fn canonical_towers(mut towers: Vec<Vec<usize>>) -> Vec<Vec<usize>> {
    towers.sort_by_key(|t| t[0]);
    towers
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
