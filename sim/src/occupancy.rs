//! A set of occupied cells: one bit per cell.

use crate::grid::{Cell, Grid, MAX_CELLS};
use crate::state::State;

/// Masks a word index into `0..MAX_CELLS / 64`.
const WORD_MASK: usize = MAX_CELLS / 64 - 1;

/// The occupied cells of a grid, one bit each, indexed by [`Grid::index`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Occupancy([u64; MAX_CELLS / 64]);

impl Occupancy {
    /// The cells the blocks of `state` stand on.
    pub fn of(grid: Grid, state: &State) -> Self {
        let mut occ = Occupancy::default();
        for &c in state.cells() {
            occ.insert(grid, c);
        }
        occ
    }

    /// Whether `cell` is occupied.
    #[inline]
    pub fn contains(&self, grid: Grid, cell: Cell) -> bool {
        let i = grid.index(cell);
        self.0[i >> 6] & (1 << (i & 63)) != 0
    }

    /// Marks `cell` occupied.
    #[inline]
    pub fn insert(&mut self, grid: Grid, cell: Cell) {
        let i = grid.index(cell);
        self.0[i >> 6] |= 1 << (i & 63);
    }

    /// Marks `cell` free.
    #[inline]
    pub fn remove(&mut self, grid: Grid, cell: Cell) {
        let i = grid.index(cell);
        self.0[i >> 6] &= !(1 << (i & 63));
    }

    /// Whether the cell with row-major index `index` is occupied.
    #[inline]
    pub fn contains_index(&self, index: usize) -> bool {
        // The mask keeps the word index in range without a bounds check (indices are
        // below MAX_CELLS by construction of the grid).
        self.0[(index >> 6) & WORD_MASK] & (1 << (index & 63)) != 0
    }

    /// Moves the mark of cell index `from` to cell index `to`.
    #[inline]
    pub fn move_index(&mut self, from: usize, to: usize) {
        self.0[(from >> 6) & WORD_MASK] &= !(1 << (from & 63));
        self.0[(to >> 6) & WORD_MASK] |= 1 << (to & 63);
    }

    /// Number of occupied cells.
    pub fn len(&self) -> usize {
        self.0.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Whether no cell is occupied.
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(|&w| w == 0)
    }
}
