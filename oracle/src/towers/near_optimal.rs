//! The near-optimal block-move planner: constructive moves first, deadlocks broken at the
//! table (the US / GN1 family of Slaney & Thiebaux, after Gupta & Nau).
//!
//! Repeat until the goal holds:
//!
//! 1. if a misplaced clear block can go where it ends, move it there: a named block onto
//!    its goal support once that is well placed and clear (or to the table if it is a
//!    bottom block), a free block to the table;
//! 2. otherwise move a misplaced clear block that stands on another block to the table,
//!    chosen to break a deadlock: one on a cycle of the "moves before" graph if one is
//!    clear, else the clear top with the fewest blocks above such a cycle.
//!
//! When no move of step 1 exists a block of step 2 does (if every misplaced clear block
//! stood alone on the table, the lowest misplaced block of some goal tower could be
//! placed). A block moves in step 2 at most once (it then waits alone on the table until
//! step 1 places it) and in step 1 at most once (it lands for good), so the plan has at
//! most twice as many moves as there are misplaced blocks, which every plan must move: at
//! most twice the optimum. Step 1 is driven by a work list of blocks whose status a move
//! may have changed (constant work per move); step 2 recomputes the deadlock cycles
//! (linear), so the planner takes linear time plus linear time per deadlock broken.
//!
//! Tower heights: the plan builds only goal towers and moves other blocks to the table, so
//! no tower grows taller than the tallest of the start and the goal.

use crate::error::Result;

use super::deadlock::on_cycle;
use super::error::{Part, TowersError};
use super::goal::TowerGoal;
use super::plan::TowerPlan;
use super::state::{Move, NONE, Place, Table, Towers};

/// The near-optimal block-move planner (see the module docs): at most twice the optimum,
/// in near-linear time, for any number of blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NearOptimal {
    /// The table the plan must fit.
    table: Table,
}

impl NearOptimal {
    /// The planner on an unbounded table.
    pub fn new() -> Self {
        Self::default()
    }

    /// This planner, checking its plans against `table`: the planner itself does not
    /// plan around a narrow table; a plan that would need more towers at once than the
    /// table has columns is refused with [`TowersError::TableTooNarrow`] (the exact
    /// solver, [`super::ExactMoves`], plans on a narrow table).
    pub fn with_table(self, table: Table) -> Self {
        NearOptimal { table }
    }

    /// A plan from `start` to `goal`, at most twice as long as a shortest one.
    pub fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        goal.check_blocks(start.blocks())?;
        self.table.check(Part::State, start.tower_count())?;
        self.table.check(Part::Goal, goal.towers().len())?;
        let mut run = Run::new(start.clone(), goal);
        run.solve();
        if let Table::Columns(columns) = self.table
            && run.most_towers > columns
        {
            return Err(TowersError::TableTooNarrow {
                columns,
                needed: run.most_towers,
            }
            .into());
        }
        Ok(TowerPlan { moves: run.moves })
    }
}

/// One planning run's working state.
struct Run<'g> {
    /// The current state.
    state: Towers,
    /// The goal.
    goal: &'g TowerGoal,
    /// Which blocks are well placed now.
    wp: Vec<bool>,
    /// How many blocks are not.
    misplaced: usize,
    /// Blocks that may have a constructive move.
    work: Vec<usize>,
    /// The moves made.
    moves: Vec<Move>,
    /// The most towers standing at once.
    most_towers: usize,
}

impl<'g> Run<'g> {
    /// A run from `state`: every clear block is worth a look.
    fn new(state: Towers, goal: &'g TowerGoal) -> Self {
        let wp = goal.well_placed(state.below(), state.above());
        let misplaced = wp.iter().filter(|&&w| !w).count();
        let work = (0..state.blocks()).rev().filter(|&b| state.is_clear(b)).collect();
        let most_towers = state.tower_count();
        Run {
            state,
            goal,
            wp,
            misplaced,
            work,
            moves: Vec::new(),
            most_towers,
        }
    }

    /// Plans until the goal holds.
    fn solve(&mut self) {
        while self.misplaced > 0 {
            while let Some(x) = self.work.pop() {
                if let Some(to) = self.constructive(x) {
                    self.make(Move { block: x, to });
                }
            }
            if self.misplaced > 0 {
                let x = self.deadlock_breaker();
                self.make(Move {
                    block: x,
                    to: Place::Table,
                });
            }
        }
    }

    /// Where `x` can go for good now, if anywhere.
    fn constructive(&self, x: usize) -> Option<Place> {
        if self.wp[x] || !self.state.is_clear(x) {
            return None;
        }
        if !self.goal.is_named(x) {
            // A misplaced free block stands on something (on the table it would be well
            // placed); the table is its place.
            return Some(Place::Table);
        }
        match self.goal.below_of(x) {
            NONE => Some(Place::Table),
            y if self.wp[y] && self.state.is_clear(y) => Some(Place::On(y)),
            _ => None,
        }
    }

    /// The block step 2 moves to the table (see the module docs).
    fn deadlock_breaker(&self) -> usize {
        let below = self.state.below();
        let cycle = on_cycle(below, self.goal, &self.wp);
        let mut best: Option<(usize, usize)> = None;
        for x in (0..self.state.blocks()).filter(|&x| !self.wp[x] && self.state.is_clear(x) && below[x] != NONE) {
            // Blocks above the highest cycle block of x's tower (none: no cycle below).
            let mut depth = 0;
            let mut b = x;
            while b != NONE && !cycle[b] {
                b = below[b];
                depth += 1;
            }
            let rank = if b == NONE { usize::MAX } else { depth };
            if best.is_none_or(|(r, _)| rank < r) {
                best = Some((rank, x));
            }
        }
        // The module docs show a candidate exists whenever the goal does not hold.
        best.map_or(0, |(_, x)| x)
    }

    /// Makes a move and queues the blocks whose constructive move it may have enabled.
    fn make(&mut self, mv: Move) {
        let x = mv.block;
        let from = self.state.below()[x];
        self.state.apply_unchecked(mv);
        self.most_towers = self.most_towers.max(self.state.tower_count());
        self.moves.push(mv);
        let now = match mv.to {
            Place::Table => !self.goal.is_named(x) || self.goal.below_of(x) == NONE,
            Place::On(y) => self.wp[y] && self.goal.is_named(x) && self.goal.below_of(x) == y,
        };
        if now != self.wp[x] {
            self.wp[x] = now;
            if now {
                self.misplaced -= 1;
            } else {
                self.misplaced += 1;
            }
        }
        if now {
            // x is final and clear: the block that goes on it may be ready.
            self.push(self.goal.above_of(x));
        }
        if from != NONE {
            // The old support is clear: it may move, or receive its goal block.
            self.push(from);
            if self.wp[from] {
                self.push(self.goal.above_of(from));
            }
        }
    }

    /// Queues a block (ignores [`NONE`]).
    fn push(&mut self, b: usize) {
        if b != NONE {
            self.work.push(b);
        }
    }
}
