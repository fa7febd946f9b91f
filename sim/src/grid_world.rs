//! The pure occupancy-grid backend: the reference model, and what planners search over.
//!
//! It keeps the state and an index of the occupied cells beside it, one per view:
//!
//! - **Top view**: one bit per cell ([`Occupancy`]), at most [`crate::MAX_CELLS`] cells: a
//!   move is a bit test and two bit flips, the hottest path of every top-view planner.
//! - **Side view**: no `W x H` structure, so a world of thousands of blocks on a table as wide
//!   as it needs costs O(N + W) memory. Every block that is not held stands on the table or
//!   on another block, so a column's standing blocks fill its rows from 0 up: the column
//!   heights ([`Columns`]) say which cells they occupy, and the held block's cell is the only
//!   other one. A cell's occupancy, whether a block is clear and where a released block comes
//!   to rest ([`crate::view::landing_cell`]: the top of the column below it) are O(1).

use crate::action::Action;
use crate::error::Result;
use crate::grid::{Cell, Direction, Grid};
use crate::inline_vec::InlineVec;
use crate::occupancy::Occupancy;
use crate::protocol::{ActionMask, MOVES_AND_DROP};
use crate::state::{BlockId, MAX_BLOCKS, State};
use crate::view::View;
use crate::world::World;

/// Blocks on a grid, with an index of the occupied cells deciding every move (module docs).
///
/// A few dozen bytes up to [`MAX_BLOCKS`] blocks on a grid of at most 16 columns, with no
/// allocation: cloning one is how a planner tries an action.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct GridWorld {
    grid: Grid,
    state: State,
    index: CellIndex,
}

/// Which cells are occupied, kept beside the state (module docs).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum CellIndex {
    /// The top view's bit per cell.
    Top(Occupancy),
    /// The side view's column heights.
    Side(Columns),
}

/// The side view's index: how many blocks stand in each column, the held block not counted
/// (it is carried, and counted again once a drop has brought it to rest). The standing blocks
/// of column `x` occupy its rows `0..heights[x]`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Columns {
    heights: InlineVec<u16, MAX_BLOCKS>,
}

impl Columns {
    /// The columns of the side-view `state` (every block not held standing) on `grid`.
    fn of(grid: Grid, state: &State) -> Columns {
        let mut heights = InlineVec::from_elem(0u16, grid.width());
        for b in state.blocks().filter(|&b| state.held_block() != Some(b)) {
            heights[usize::from(state.cell(b).x)] += 1;
        }
        Columns { heights }
    }

    /// How many blocks stand in column `x`: its lowest free row.
    #[inline]
    pub fn height(&self, x: u16) -> u16 {
        self.heights[usize::from(x)]
    }

    /// Every column's height, from the left.
    #[inline]
    pub fn heights(&self) -> &[u16] {
        &self.heights
    }
}

impl GridWorld {
    /// A top-view world on `grid` in `state`; an error if the state does not fit the grid.
    pub fn new(grid: Grid, state: State) -> Result<Self> {
        Self::new_in(View::Top, grid, state)
    }

    /// A world of `view` on `grid` in `state`; an error if the view does not take the world
    /// ([`View::check_world`]), or the state does not fit the grid (or, in the side view, has
    /// a block standing on nothing).
    pub fn new_in(view: View, grid: Grid, state: State) -> Result<Self> {
        view.check_world(grid, state.block_count())?;
        state.check_fits(grid)?;
        view.check_state(&state)?;
        let index = Self::index_of(view, grid, &state);
        Ok(Self { grid, state, index })
    }

    fn index_of(view: View, grid: Grid, state: &State) -> CellIndex {
        match view {
            View::Top => CellIndex::Top(Occupancy::of(grid, state)),
            View::Side => CellIndex::Side(Columns::of(grid, state)),
        }
    }

    /// The occupied cells, in the top view (`None` in the side view, which keeps
    /// [`GridWorld::columns`] instead).
    pub fn occupancy(&self) -> Option<&Occupancy> {
        match &self.index {
            CellIndex::Top(occupancy) => Some(occupancy),
            CellIndex::Side(_) => None,
        }
    }

    /// The column heights, in the side view (`None` in the top view).
    pub fn columns(&self) -> Option<&Columns> {
        match &self.index {
            CellIndex::Top(_) => None,
            CellIndex::Side(columns) => Some(columns),
        }
    }

    /// Whether `cell` has a block on it.
    #[inline]
    pub fn is_occupied(&self, cell: Cell) -> bool {
        match &self.index {
            CellIndex::Top(occupancy) => occupancy.contains(self.grid, cell),
            CellIndex::Side(columns) => {
                cell.y < columns.height(cell.x) || self.state.held_block().is_some_and(|h| self.state.cell(h) == cell)
            }
        }
    }

    /// The state as a reference, without the copy [`World::state`] makes.
    #[inline]
    pub fn state_ref(&self) -> &State {
        &self.state
    }

    /// The state, the world given up (no copy).
    #[inline]
    pub fn into_state(self) -> State {
        self.state
    }

    /// The block standing on `cell`, if any.
    #[inline]
    pub fn block_at(&self, cell: Cell) -> Option<BlockId> {
        if self.is_occupied(cell) {
            self.state.block_at(cell)
        } else {
            None
        }
    }

    /// The side view's legal actions ([`crate::view::side_mask`]) from the column heights,
    /// O(N) without allocating past the mask: with nothing held, a block is clear when it is
    /// the top of its column. (In the top view, the side view's mask of the same state.)
    pub fn side_mask(&self) -> ActionMask {
        let n = self.state.block_count();
        let CellIndex::Side(columns) = &self.index else {
            return crate::view::side_mask(&self.state);
        };
        if self.state.held_block().is_some() {
            return ActionMask::with_first_word(MOVES_AND_DROP, n);
        }
        let mut mask = ActionMask::none(n);
        for (b, c) in self.state.cells().iter().enumerate() {
            if c.y + 1 == columns.height(c.x) {
                mask.insert_index(5 + b);
            }
        }
        mask
    }

    /// Side view: puts the held block on `cell` at once, as the moves of a block move carry
    /// it there ([`Env::step_block_move`](crate::Env::step_block_move)); the caller has found
    /// the way free ([`crate::block_move::route_in`]).
    pub(crate) fn carry_held(&mut self, cell: Cell) {
        let held = self.state.held_block().expect("a block is held");
        debug_assert!(matches!(self.index, CellIndex::Side(_)) && !self.is_occupied(cell));
        self.state.set_cell(held, cell);
    }

    /// Carries out `actions` by the rules: the states the world passes through, the current
    /// one first (`actions.len() + 1` of them). How a plan becomes the states it visits; an
    /// error for an action of a block the world does not have.
    pub fn replay(&mut self, actions: &[Action]) -> Result<Vec<State>> {
        let mut states = Vec::with_capacity(actions.len() + 1);
        states.push(self.state.clone());
        for &action in actions {
            self.act(action)?;
            states.push(self.state.clone());
        }
        Ok(states)
    }
}

impl World for GridWorld {
    #[inline]
    fn grid(&self) -> Grid {
        self.grid
    }

    #[inline]
    fn view(&self) -> View {
        match self.index {
            CellIndex::Top(_) => View::Top,
            CellIndex::Side(_) => View::Side,
        }
    }

    #[inline]
    fn block_count(&self) -> usize {
        self.state.block_count()
    }

    #[inline]
    fn cell_of(&self, block: BlockId) -> Cell {
        self.state.cell(block)
    }

    #[inline]
    fn held_block(&self) -> Option<BlockId> {
        self.state.held_block()
    }

    #[inline]
    fn set_held(&mut self, held: Option<BlockId>) {
        if let CellIndex::Side(columns) = &mut self.index {
            // A block picked leaves its column (it is clear: the top of it); a block let go
            // is counted again by `settle`, once it has come to rest.
            if let Some(b) = held
                && self.state.held_block() != Some(b)
            {
                columns.heights[usize::from(self.state.cell(b).x)] -= 1;
            }
        }
        self.state.set_held(held);
    }

    #[inline]
    fn try_move(&mut self, block: BlockId, dir: Direction) -> bool {
        let from = self.state.cell(block);
        let Some(to) = self.grid.neighbour(from, dir) else {
            return false;
        };
        match &mut self.index {
            CellIndex::Top(occupancy) => {
                // Index arithmetic once: this is the hottest path of every planner.
                let (fi, ti) = (self.grid.index(from), self.grid.index(to));
                if occupancy.contains_index(ti) {
                    return false;
                }
                occupancy.move_index(fi, ti);
            }
            // Only the held block moves, and it is not counted in its column.
            CellIndex::Side(columns) => {
                if to.y < columns.height(to.x) {
                    return false;
                }
            }
        }
        self.state.set_cell(block, to);
        true
    }

    #[inline]
    fn is_occupied(&self, cell: Cell) -> bool {
        GridWorld::is_occupied(self, cell)
    }

    #[inline]
    fn is_clear(&self, block: BlockId) -> bool {
        let c = self.state.cell(block);
        usize::from(c.y) + 1 >= self.grid.height() || !self.is_occupied(Cell::new(c.x, c.y + 1))
    }

    #[inline]
    fn landing_cell(&self, from: Cell) -> Cell {
        match &self.index {
            CellIndex::Top(occupancy) => crate::view::landing_cell(from, |c| occupancy.contains(self.grid, c)),
            // The top of the column below (a released block is above it: it was carried
            // through free cells).
            CellIndex::Side(columns) => Cell::new(from.x, columns.height(from.x).min(from.y)),
        }
    }

    #[inline]
    fn settle(&mut self, block: BlockId) -> Result<()> {
        let from = self.state.cell(block);
        let to = self.landing_cell(from);
        match &mut self.index {
            CellIndex::Top(occupancy) => {
                if to != from {
                    occupancy.move_index(self.grid.index(from), self.grid.index(to));
                }
            }
            CellIndex::Side(columns) => columns.heights[usize::from(to.x)] += 1,
        }
        self.state.set_cell(block, to);
        Ok(())
    }

    fn put(&mut self, state: &State) {
        self.state = state.clone();
        self.index = Self::index_of(self.view(), self.grid, state);
    }

    #[inline]
    fn state(&self) -> State {
        self.state.clone()
    }
}
