//! The exact solver in the side view (docs/world.md section 12): the fewest gripper steps
//! (Pick, moves, Drop) from a side-view state to a goal of towers.
//!
//! The search is the top view's A* ([`super::ExactSolver`]) over the grid backend's joint
//! state, with the side view's successors and goal test, and its own heuristic.
//!
//! # Actions searched
//!
//! Successors come from [`sim::World::act`] on a [`GridWorld`] in the side view: the rules
//! (only a clear block is picked, a released block falls) stay in `sim`. The side view's
//! legal actions are the same under every action protocol ([`View::legal_actions`]): with
//! nothing held the picks of clear blocks, while holding the moves and Drop. Those that
//! change the state are searched; under `free` an action outside them changes nothing, and
//! an action that changes nothing never shortens a plan. So the optimum is the same under
//! both protocols.
//!
//! Unlike the top view's, a shortest plan here does drop: a block is let go to change which
//! block is held (a pick needs nothing held), and the goal holds only once every block of
//! its towers is let go. The top view's "never drop" pruning does not hold, and Drop is
//! searched under every protocol.
//!
//! # The heuristic, and why it is admissible and consistent
//!
//! A block that is not held *must be picked* (the set `M`) if
//!
//! - (a) the goal names it and it stands on the wrong thing: a tower's bottom not on the
//!   table, or a block not on the one the goal puts it on; or
//! - (b) the goal puts another block on the one it stands on; or
//! - (c) it stands, directly or higher up, on a block of `M`.
//!
//! What a block stands on changes only when it is picked (the block under it cannot be
//! picked while it stands there), so a block of (a) or (b) is picked before the goal holds;
//! a block of `M` can only be picked once it is clear, so everything above it is picked
//! first (c).
//!
//! Split any plan at its picks: an *episode* is a Pick, the actions while holding, and the
//! Drop that ends it. A shortest plan has no action that changes nothing, and every episode
//! in it moves its block sideways at least once: a block picked and let go in its own
//! column falls back onto its cell, since nothing else moved, and the episode could be
//! removed. It ends with a Drop: picking or carrying a block the goal does not name changes
//! no block the goal names, and picking or carrying one it names leaves the goal false, so
//! the goal held before such an action. So every episode costs at least Pick + one move +
//! Drop = 3 steps, and each block of `M` needs an episode of its own (one pick each).
//! Before the first episode, a block held at the start is let go: at least its Drop, and
//! at least 2 steps if letting it go where it is would make it a block of `M` (it then needs
//! a move, or a Drop now and another episode later).
//!
//! `h = 0` where the goal holds; otherwise `h = 3 |M| + t`, with `t = 0` if nothing is held,
//! `2` if dropping the held block now would make it a block of `M`, and `1` otherwise. By
//! the above `h` is at most the length of a shortest plan: *admissible*. (It is 3 times a
//! lower bound on the block moves, plus the held block's due, and is never above 3 times
//! the fewest block moves: `ExactMoves`.)
//!
//! It is *consistent*: one action lowers it by at most 1. A Pick of a block of `M` takes
//! 3 off and puts 2 on (dropping it at once would put it back where it was, in `M`); of
//! any other block it adds 1. A move changes only `t`, between 1 and 2. A Drop takes `t`
//! off and adds 3 exactly when `t` was 2. Lifting or letting go a block changes no other
//! block's membership (their supports, and what stands on their supports, are unchanged).
//! Where an action reaches the goal, the state before has `h <= 1`: it is a Drop onto the
//! goal with nothing else out of place, or a move or Pick of a free block in a state where
//! the goal held already.

use sim::{Action, ActionProtocol, BlockId, Cell, Effect, Goal, Grid, GridWorld, State, View, World};

use crate::error::{OracleError, Result};

/// What the goal asks a named block to stand on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Wanted {
    /// A block the goal leaves free.
    Free,
    /// A tower's bottom block: the table.
    Table,
    /// The block below it in its tower.
    On(BlockId),
}

/// A side-view problem, checked, with the goal read for the heuristic.
pub(super) struct SideProblem<'a> {
    goal: &'a Goal,
    /// What each block must stand on.
    wanted: Vec<Wanted>,
    /// The block the goal puts on each block, if any.
    above: Vec<Option<BlockId>>,
}

impl<'a> SideProblem<'a> {
    /// Checks that `state` and `goal` make a side-view problem on `grid`: the same block
    /// count, the state inside the grid with every block standing, the goal's towers no
    /// taller than the grid and no more than its columns.
    pub fn new(grid: Grid, state: &State, goal: &'a Goal) -> Result<Self> {
        if state.block_count() != goal.block_count() {
            return Err(OracleError::BlockCountMismatch {
                state: state.block_count(),
                goal: goal.block_count(),
            });
        }
        state.check_fits(grid)?;
        View::Side.check_state(state)?;
        goal.check_fits(grid)?;
        if goal.tower_count() > grid.width() {
            return Err(OracleError::GoalUnreachable {
                goal: goal.to_string(),
                reason: format!(
                    "its {} towers need as many columns and the grid has {}",
                    goal.tower_count(),
                    grid.width()
                ),
            });
        }
        let n = state.block_count();
        let mut wanted = vec![Wanted::Free; n];
        let mut above = vec![None; n];
        for tower in goal.towers() {
            wanted[tower[0].index()] = Wanted::Table;
            for pair in tower.windows(2) {
                wanted[pair[1].index()] = Wanted::On(pair[0]);
                above[pair[0].index()] = Some(pair[1]);
            }
        }
        Ok(Self { goal, wanted, above })
    }

    /// Whether `block`, standing on `support` (`None`: the table), must be picked (module
    /// docs), given which blocks below it must.
    #[inline]
    fn must_move(&self, block: BlockId, support: Option<BlockId>, must: &[bool]) -> bool {
        if let Some(s) = support
            && (must[s.index()] || self.above[s.index()].is_some_and(|a| a != block))
        {
            return true;
        }
        match self.wanted[block.index()] {
            Wanted::Free => false,
            Wanted::Table => support.is_some(),
            Wanted::On(b) => support != Some(b),
        }
    }

    /// The heuristic `h` (module docs): a lower bound on the gripper steps to the goal.
    pub fn lower_bound(&self, state: &State) -> u32 {
        if self.goal.holds_in(View::Side, state) {
            return 0;
        }
        let held = state.held_block();
        let support = |cell: Cell| {
            if cell.y == 0 {
                None
            } else {
                state.block_at(Cell::new(cell.x, cell.y - 1))
            }
        };
        // Bottom up, so that what a block stands on is decided before it.
        let mut order: Vec<BlockId> = state.blocks().filter(|&b| Some(b) != held).collect();
        order.sort_unstable_by_key(|&b| state.cell(b).y);
        let mut must = vec![false; state.block_count()];
        let mut count = 0;
        for b in order {
            let m = self.must_move(b, support(state.cell(b)), &must);
            must[b.index()] = m;
            count += u32::from(m);
        }
        let held_due = held.map_or(0, |h| {
            let landing = sim::view::landing_cell(state.cell(h), |c| state.block_at(c).is_some());
            if self.must_move(h, support(landing), &must) {
                2
            } else {
                1
            }
        });
        3 * count + held_due
    }
}

/// The searched successors of the side-view `state` (module docs), each with the action
/// that leads there: the picks of clear blocks with nothing held; while holding, the moves
/// that move and Drop.
pub(super) fn successors(grid: Grid, state: &State) -> Vec<(Action, State)> {
    let world =
        GridWorld::new_in(View::Side, grid, state.clone()).expect("states reached by act fit the grid and stand");
    View::Side
        .legal_actions(ActionProtocol::Free, state)
        .iter()
        .filter_map(|a| {
            let mut w = world.clone();
            match w.act(a) {
                Ok(Effect::Moved | Effect::Picked | Effect::Dropped) => Some((a, w.into_state())),
                _ => None,
            }
        })
        .collect()
}
