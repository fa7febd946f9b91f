//! Start rules: how [`Env::reset`](crate::Env::reset) places the blocks.
//!
//! - [`StartRule::Uniform`] (the default, docs/world.md section 3): every block on a distinct cell
//!   drawn uniformly from the whole grid; a start in which the goal already holds is drawn
//!   again. On a grid one cell wide, where blocks cannot pass each other and the goal can
//!   be reached only from starts where they stand in its order
//!   ([`Goal::can_be_reached`]), the drawn cells are handed to the blocks in the goal's
//!   order, bottom up: a start drawn uniformly among those from which the goal can be
//!   reached, so that no episode is lost before it begins. (On wider grids every start can
//!   reach every goal, and the draw is the SPEC's, seed for seed.)
//! - [`StartRule::Paper`]: the authors' start (docs/world.md section 10, "World"; their
//!   `BlockWorld_t.py:381`, `25 + 50 * randint(6)` for a block's pixel column and then its
//!   pixel row). Each block's column is uniform in `0..W-1` and its row uniform in `1..H`:
//!   with our `y` upward, that is the 6 x 6 corner of the 7 x 7 grid that leaves out the
//!   right column and the bottom row. A start that meets the goal is **kept**: the episode
//!   runs, and under [`Termination::Goal`](crate::Termination::Goal) it ends on its first
//!   action if the goal still holds after it (as the authors' game ended on its first
//!   step). The authors let two blocks share a cell; a world that cannot hold two blocks on
//!   one cell draws a block whose cell is taken again (docs/world.md section 10: this changes no figure
//!   measurably). Their code then hands the drawn cells to the blocks in a random order;
//!   the draws are independent and identically distributed, so that shuffle changes nothing
//!   and is left out.

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::seeding::SimRng;
use crate::state::{MAX_BLOCKS, State};
use crate::uniform::UniformStates;
use crate::view::{self, View};

/// How a reset places the blocks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StartRule {
    /// docs/world.md section 3: distinct cells uniform over the grid, never a start meeting the goal.
    #[default]
    Uniform,
    /// The authors' code: column uniform in `0..W-1`, row uniform in `1..H`, a taken cell
    /// drawn again, a start meeting the goal kept.
    Paper,
}

crate::names!(StartRule { Uniform = "uniform", Paper = "paper" } unknown(name) -> SimError {
    SimError::Parse {
        what: "start rule",
        text: name.to_string(),
        reason: format!("choose one of {}", StartRule::NAMES.join(", ")),
    }
});

impl StartRule {
    /// Whether a start in which the goal already holds is kept (the episode then runs)
    /// rather than drawn again.
    pub const fn keeps_goal_starts(self) -> bool {
        matches!(self, StartRule::Paper)
    }

    /// The cells this rule draws from on `grid`, as (columns, rows): the whole grid for
    /// [`StartRule::Uniform`], `(W - 1, H - 1)` for [`StartRule::Paper`].
    pub const fn region(self, grid: Grid) -> (usize, usize) {
        match self {
            StartRule::Uniform => (grid.width(), grid.height()),
            StartRule::Paper => (grid.width().saturating_sub(1), grid.height().saturating_sub(1)),
        }
    }

    /// An error if this rule cannot place `blocks` blocks on distinct cells of `grid`.
    pub fn check_fits(self, grid: Grid, blocks: usize) -> Result<()> {
        let (columns, rows) = self.region(grid);
        if columns * rows < blocks {
            return Err(SimError::StartDoesNotFit {
                rule: self,
                cells: columns * rows,
                blocks,
                width: grid.width(),
                height: grid.height(),
            });
        }
        Ok(())
    }

    /// A start for `goal` on `grid`, nothing held, drawn from `rng`. The rule must fit
    /// ([`StartRule::check_fits`]; [`Env::new`](crate::Env::new) checks it), or this never
    /// returns.
    pub fn draw(self, grid: Grid, goal: &Goal, rng: &mut SimRng) -> State {
        match self {
            StartRule::Uniform => uniform(grid, goal, rng),
            StartRule::Paper => paper(grid, goal.block_count(), rng),
        }
    }

    /// A start for `goal` on `grid` in `view`. In the top view [`StartRule::draw`]; in the
    /// side view (which takes only [`StartRule::Uniform`]) a state drawn uniformly over the
    /// Blocks World states that fit the grid ([`view::uniform_state`]), drawn again while the
    /// goal holds, as the uniform rule does, unless the goal holds in every state (one block
    /// on the table: the episode is then over at its start).
    pub fn draw_in(self, view: View, grid: Grid, goal: &Goal, rng: &mut SimRng) -> State {
        match view {
            View::Top => self.draw(grid, goal, rng),
            View::Side => {
                let states = UniformStates::shared(goal.block_count());
                let everywhere = goal.holds_everywhere_in(View::Side, grid);
                loop {
                    let state = view::uniform_state(grid, &states, rng);
                    if everywhere || !goal.holds_in(View::Side, &state) {
                        return state;
                    }
                }
            }
        }
    }
}

/// Distinct cells drawn uniformly, drawn again while the goal holds; on a grid one cell
/// wide, handed to the blocks in the goal's order (module docs).
fn uniform(grid: Grid, goal: &Goal, rng: &mut SimRng) -> State {
    let n = goal.block_count();
    let mut cells = [Cell::default(); MAX_BLOCKS];
    loop {
        let mut k = 0;
        while k < n {
            let c = grid.cell_at(rng.random_range(0..grid.cell_count()));
            if !cells[..k].contains(&c) {
                cells[k] = c;
                k += 1;
            }
        }
        if grid.width() == 1 {
            let mut column = cells;
            column[..n].sort_unstable_by_key(|c| c.y);
            for (place, &b) in goal.order().iter().enumerate() {
                cells[b.index()] = column[place];
            }
        }
        let state = State::new(&cells[..n], None).expect("distinct cells");
        if !goal.holds(&state) {
            return state;
        }
    }
}

/// Block by block, a column in `0..W-1` then a row in `1..H`, both drawn again while the
/// cell is taken.
fn paper(grid: Grid, n: usize, rng: &mut SimRng) -> State {
    let mut cells = [Cell::default(); MAX_BLOCKS];
    let mut k = 0;
    while k < n {
        let x = rng.random_range(0..grid.width() - 1);
        let y = rng.random_range(1..grid.height());
        let c = Cell::new(x as u16, y as u16);
        if !cells[..k].contains(&c) {
            cells[k] = c;
            k += 1;
        }
    }
    State::new(&cells[..n], None).expect("distinct cells")
}
