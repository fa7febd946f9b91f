//! The pure occupancy-grid backend: the reference model, and what planners search over.
//!
//! In the side view it predicts where a released block comes to rest without any dynamics:
//! on the top of the column below it ([`crate::view::landing_cell`]).

use crate::action::Action;
use crate::error::Result;
use crate::grid::{Cell, Direction, Grid};
use crate::occupancy::Occupancy;
use crate::state::{BlockId, State};
use crate::view::View;
use crate::world::World;

/// Blocks on a grid, with an occupancy bit per cell deciding every move.
///
/// `Copy`, a few dozen bytes: cloning one is how a planner tries an action.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GridWorld {
    grid: Grid,
    state: State,
    occupancy: Occupancy,
    view: View,
}

impl GridWorld {
    /// A top-view world on `grid` in `state`; an error if the state does not fit the grid.
    pub fn new(grid: Grid, state: State) -> Result<Self> {
        Self::new_in(View::Top, grid, state)
    }

    /// A world of `view` on `grid` in `state`; an error if the state does not fit the grid
    /// (or, in the side view, has a block standing on nothing).
    pub fn new_in(view: View, grid: Grid, state: State) -> Result<Self> {
        state.check_fits(grid)?;
        view.check_state(&state)?;
        Ok(Self {
            grid,
            state,
            occupancy: Occupancy::of(grid, &state),
            view,
        })
    }

    /// The occupied cells.
    pub fn occupancy(&self) -> &Occupancy {
        &self.occupancy
    }

    /// Whether `cell` has a block on it.
    #[inline]
    pub fn is_occupied(&self, cell: Cell) -> bool {
        self.occupancy.contains(self.grid, cell)
    }

    /// The state as a reference, without the copy [`World::state`] makes.
    #[inline]
    pub fn state_ref(&self) -> &State {
        &self.state
    }

    /// Carries out `actions` by the rules: the states the world passes through, the current
    /// one first (`actions.len() + 1` of them). How a plan becomes the states it visits; an
    /// error for an action of a block the world does not have.
    pub fn replay(&mut self, actions: &[Action]) -> Result<Vec<State>> {
        let mut states = Vec::with_capacity(actions.len() + 1);
        states.push(self.state);
        for &action in actions {
            self.act(action)?;
            states.push(self.state);
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
        self.view
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
        self.state.set_held(held);
    }

    #[inline]
    fn try_move(&mut self, block: BlockId, dir: Direction) -> bool {
        let from = self.state.cell(block);
        match self.grid.neighbour(from, dir) {
            Some(to) => {
                // Index arithmetic once: this is the hottest path of every planner.
                let (fi, ti) = (self.grid.index(from), self.grid.index(to));
                if self.occupancy.contains_index(ti) {
                    return false;
                }
                self.occupancy.move_index(fi, ti);
                self.state.set_cell(block, to);
                true
            }
            None => false,
        }
    }

    #[inline]
    fn is_occupied(&self, cell: Cell) -> bool {
        self.occupancy.contains(self.grid, cell)
    }

    #[inline]
    fn settle(&mut self, block: BlockId) -> Result<()> {
        let from = self.state.cell(block);
        let to = self.landing_cell(from);
        if to != from {
            self.occupancy.move_index(self.grid.index(from), self.grid.index(to));
            self.state.set_cell(block, to);
        }
        Ok(())
    }

    fn put(&mut self, state: &State) {
        self.state = *state;
        self.occupancy = Occupancy::of(self.grid, state);
    }

    #[inline]
    fn state(&self) -> State {
        self.state
    }
}
