//! The near-optimal block-move planner: constructive moves first, deadlocks broken at the
//! table (the GN1 algorithm of Slaney & Thiebaux, after Gupta & Nau).
//!
//! Repeat until the goal holds:
//!
//! 1. if a misplaced clear block can go where it ends, move it there: a named block onto
//!    its goal support once that is well placed and clear (or to the table if it is a
//!    bottom block), a free block to the table;
//! 2. otherwise break a deadlock: move to the table a clear block that stands in the way
//!    of a cycle of waiting blocks (found as below).
//!
//! When no move of step 1 exists, every misplaced clear block `x` is named and waits: its
//! goal support `y` is misplaced, or well placed with a block on it. The tower holding `y`
//! (or the block on it) has a clear top, itself a waiting block: call it `next(x)`.
//! Following `next` from any waiting block must close a cycle, and `next(x)` is "in the
//! way" of `x` unless it is `y` itself. Not every block of the cycle can be its
//! predecessor's goal support (goal towers have no cycles), so one is in the way; as the
//! top of a tower above `y`, or on `y`, it stands on a block, and moving it to the table
//! breaks this cycle of waiting (it is a deadlock in the sense of the `deadlock` module).
//!
//! # Guarantee and cost
//!
//! A block moves in step 2 at most once (it then waits alone on the table until step 1
//! places it) and in step 1 at most once (it lands for good), so the plan has at most two
//! moves per misplaced block, and every plan moves each misplaced block at least once: at
//! most twice the optimum (Gupta & Nau 1992). Step 1 is driven by a work list of the
//! blocks a move may have made ready (constant work per move); `next` is constant time
//! (each block knows the bottom of its tower, each bottom its top); a cycle is sought from
//! the block that waited on the last one broken, so a search mostly retraces what is left
//! of the cycle just broken. Those searches can grow faster than linearly on goals of a few
//! tall towers (long chains of blocks waiting on the table for one another): measured on
//! this machine, 100 blocks take about 20 us, 1,000 about 0.1-0.3 ms, 10,000 1-30 ms and
//! 100,000 0.1-0.7 s; on a machine busy with other builds, 10,000 blocks took 43 ms
//! (uniform starts, goals of one to three towers) and 35 ms (the planning competition's
//! shape, about one tower per ten blocks). `cargo bench -p oracle --bench towers` times 100
//! to 10,000 blocks of both kinds.
//!
//! # A table of few columns
//!
//! With [`Table::Columns`] a move to the table needs a free column. When none is free, a
//! block that must leave its tower (step 2, or a free block in step 1) parks instead on a
//! parking place: a clear, well-placed block that no named block must stand on (a free
//! block there is well placed; a named one waits there, clear, until step 1 places it).
//! A goal's bottom block that waits for a column and stands on a misplaced block parks
//! too. Each block still moves at most twice, so the guarantee holds; when there is
//! neither a column nor a parking place the planner gives up
//! ([`TowersError::TableTooNarrow`]). On 7 columns its plans fit for every uniformly
//! random start of 6 blocks against random goals of one to three towers, about 89 % of
//! starts of 8 blocks, 56 % of 10 and 27 % of 12.
//!
//! Tower heights: on an unbounded table the plan builds only goal towers and moves other
//! blocks to the table, so no tower grows taller than the tallest of the start and the
//! goal; parking on a narrow table can pile free blocks higher.

use crate::error::Result;

use super::error::{Part, TowersError};
use super::goal::TowerGoal;
use super::plan::TowerPlan;
use super::state::{Move, NONE, Place, Table, Towers};

/// The near-optimal block-move planner (see the module docs): at most twice the optimum,
/// for any number of blocks.
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

    /// This planner, on `table`. On a table of `c` columns a block goes to the table only
    /// if a column is free; otherwise a block that must leave its tower parks on a clear
    /// well-placed block that no named block must stand on (where a free block is well
    /// placed too), and if there is none the planner gives up with
    /// [`TowersError::TableTooNarrow`] (the exact solver, [`super::ExactMoves`], plans
    /// on any table). Parking keeps the "at most twice the optimum" guarantee.
    pub fn with_table(self, table: Table) -> Self {
        NearOptimal { table }
    }

    /// A plan from `start` to `goal`, at most twice as long as a shortest one.
    pub fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        goal.check_blocks(start.blocks())?;
        self.table.check(Part::State, start.tower_count())?;
        self.table.check(Part::Goal, goal.towers().len())?;
        let mut run = Run::new(start.clone(), goal, self.table);
        match run.solve() {
            Some(()) => Ok(TowerPlan { moves: run.moves }),
            // Only a narrow table leaves no room (on an unbounded one a column is free).
            None => Err(TowersError::TableTooNarrow {
                columns: match self.table {
                    Table::Columns(c) => c,
                    Table::Unbounded => start.blocks(),
                },
            }
            .into()),
        }
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
    /// The bottom block of each block's tower.
    bottom: Vec<usize>,
    /// The top block of the tower standing on each bottom block.
    top: Vec<usize>,
    /// Where to start the next search for a cycle of waiting: the block that waited on
    /// the last block moved in step 2.
    resume: usize,
    /// The search each block was last seen in, and its place on that search's path.
    seen: Vec<(u32, usize)>,
    /// The number of the current search.
    search: u32,
    /// The moves made.
    moves: Vec<Move>,
    /// The table.
    table: Table,
    /// On a narrow table: blocks that may be parking places (clear, well placed, with
    /// no named block to stand on them; checked when used).
    spots: Vec<usize>,
}

impl<'g> Run<'g> {
    /// A run from `state`: every clear block is worth a look.
    fn new(state: Towers, goal: &'g TowerGoal, table: Table) -> Self {
        let n = state.blocks();
        let wp = goal.well_placed(state.below(), state.above());
        let misplaced = wp.iter().filter(|&&w| !w).count();
        let work: Vec<usize> = (0..n).rev().filter(|&b| state.is_clear(b)).collect();
        let (mut bottom, mut top) = (vec![NONE; n], vec![NONE; n]);
        for tower in state.towers() {
            for &b in &tower {
                bottom[b] = tower[0];
            }
            top[tower[0]] = tower[tower.len() - 1];
        }
        let spots = match table {
            Table::Unbounded => Vec::new(),
            Table::Columns(_) => (0..n)
                .filter(|&b| state.is_clear(b) && wp[b] && goal.above_of(b) == NONE)
                .collect(),
        };
        Run {
            table,
            spots,
            state,
            goal,
            wp,
            misplaced,
            work,
            bottom,
            top,
            resume: NONE,
            seen: vec![(0, 0); n],
            search: 0,
            moves: Vec::new(),
        }
    }

    /// Plans until the goal holds; `None` if a narrow table leaves no room.
    fn solve(&mut self) -> Option<()> {
        while self.misplaced > 0 {
            while let Some(x) = self.work.pop() {
                if let Some(to) = self.constructive(x) {
                    self.make(Move { block: x, to });
                }
            }
            if self.misplaced == 0 {
                break;
            }
            if self.table != Table::Unbounded {
                // Room (a column, a parking place) appears without a work-list event: look
                // at every clear block again.
                let n = self.state.blocks();
                if let Some((x, to)) = (0..n).find_map(|x| Some((x, self.constructive(x)?))) {
                    self.make(Move { block: x, to });
                    continue;
                }
            }
            let mv = self.break_deadlock()?;
            self.make(mv);
        }
        Some(())
    }

    /// Where a block that must leave its tower can go: the table if a column is free,
    /// else a parking place.
    fn room(&self) -> Option<Place> {
        if self.table.has_free_column(self.state.tower_count()) {
            return Some(Place::Table);
        }
        self.spots
            .iter()
            .rev()
            .find(|&&d| self.state.is_clear(d) && self.wp[d] && self.goal.above_of(d) == NONE)
            .map(|&d| Place::On(d))
    }

    /// Where `x` can go for good now, if anywhere.
    fn constructive(&self, x: usize) -> Option<Place> {
        if self.wp[x] || !self.state.is_clear(x) {
            return None;
        }
        if !self.goal.is_named(x) {
            // A misplaced free block stands on something (on the table it would be well
            // placed); the table is its place, or a parking place, where it is well placed
            // too.
            return self.room();
        }
        match self.goal.below_of(x) {
            NONE if self.table.has_free_column(self.state.tower_count()) => Some(Place::Table),
            NONE => None,
            y if self.wp[y] && self.state.is_clear(y) => Some(Place::On(y)),
            _ => None,
        }
    }

    /// Step 2: the move that breaks a cycle of waiting blocks (see the module docs), or a
    /// constructive move if the search meets one.
    fn break_deadlock(&mut self) -> Option<Move> {
        let room = self.room()?;
        let n = self.state.blocks();
        let start = if self.resume != NONE && self.waits(self.resume) {
            self.resume
        } else {
            // A waiting block: the top of a tower with a misplaced block (its top is one).
            (0..n).find(|&b| self.waits(b))?
        };
        self.search += 1;
        let mut path: Vec<usize> = Vec::new();
        let mut v = start;
        while self.seen[v].0 != self.search {
            if let Some(to) = self.constructive(v) {
                return Some(Move { block: v, to });
            }
            self.seen[v] = (self.search, path.len());
            path.push(v);
            v = match self.next(v) {
                Some(next) => next,
                None => {
                    // v waits for a column; parking it uncovers what it stands on, unless
                    // that is a parking place already (then moving it gains nothing).
                    let s = self.state.below()[v];
                    return (s != NONE && !self.wp[s]).then_some(Move { block: v, to: room });
                }
            };
        }
        // path[from..] is a cycle, each block waiting on the next (the last on path[from]).
        let from = self.seen[v].1;
        let cycle = &path[from..];
        let k = cycle.len();
        let i = (0..k)
            .find(|&i| cycle[(i + 1) % k] != self.goal.below_of(cycle[i]))
            .unwrap_or(0);
        self.resume = cycle[i];
        Some(Move {
            block: cycle[(i + 1) % k],
            to: room,
        })
    }

    /// Whether `x` is a clear misplaced block with no constructive move.
    fn waits(&self, x: usize) -> bool {
        self.state.is_clear(x) && !self.wp[x] && self.constructive(x).is_none()
    }

    /// The clear top of the tower that holds what the waiting block `x` waits for: its
    /// goal support if misplaced, else the block on that support. `None` if it waits for
    /// a free column (a bottom block of the goal on a full table).
    fn next(&self, x: usize) -> Option<usize> {
        let y = self.goal.below_of(x);
        if y == NONE || !self.goal.is_named(x) {
            return None;
        }
        let target = if self.wp[y] { self.state.above()[y] } else { y };
        Some(self.top[self.bottom[target]])
    }

    /// Makes a move and queues the blocks whose constructive move it may have enabled.
    fn make(&mut self, mv: Move) {
        debug_assert!(self.state.check(mv, self.table).is_ok(), "{mv} in {}", self.state);
        let x = mv.block;
        let from = self.state.below()[x];
        self.state.apply_unchecked(mv);
        self.moves.push(mv);
        if from != NONE {
            self.top[self.bottom[from]] = from;
        }
        let bottom = match mv.to {
            Place::Table => x,
            Place::On(y) => self.bottom[y],
        };
        self.bottom[x] = bottom;
        self.top[bottom] = x;
        let now = match mv.to {
            Place::Table => !self.goal.is_named(x) || self.goal.below_of(x) == NONE,
            Place::On(y) if self.goal.is_named(x) => self.wp[y] && self.goal.below_of(x) == y,
            // A free block parked on a parking place.
            Place::On(y) => self.wp[y] && self.goal.above_of(y) == NONE,
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
        if self.table != Table::Unbounded {
            for b in [x, from] {
                if b != NONE && self.wp[b] && self.goal.above_of(b) == NONE {
                    self.spots.push(b);
                }
            }
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
