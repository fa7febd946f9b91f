//! Blocks and the world's logical state: where every block stands and which one is held.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid};

/// The fewest blocks a world may have: with one block every goal holds from the start.
pub const MIN_BLOCKS: usize = 2;

/// The most blocks a world may have. States are fixed-size arrays of this length, so they
/// are `Copy` and cheap for planners to clone and hash.
pub const MAX_BLOCKS: usize = 16;

/// A block's id, `0..N`; also its index in [`State::cells`] and its colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct BlockId(pub u8);

impl BlockId {
    /// The id as an index.
    #[inline]
    pub const fn index(self) -> usize {
        self.0 as usize
    }
}

impl fmt::Display for BlockId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// Where every block stands and which block, if any, is held.
///
/// This is the whole logical state of a world; both backends read and write it, and the
/// oracle and the solvers search over it. Unused slots past [`State::block_count`] are kept
/// at their default so that derived equality and hashing see only the real blocks.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct State {
    cells: [Cell; MAX_BLOCKS],
    count: u8,
    held: Option<BlockId>,
}

impl State {
    /// A state with block `i` on `cells[i]` and `held` in hand.
    ///
    /// Checks what can be checked without a grid: the block count, that no two blocks
    /// share a cell, and that the held block exists. [`State::check_fits`] checks the grid.
    pub fn new(cells: &[Cell], held: Option<BlockId>) -> Result<Self> {
        let count = cells.len();
        if !(MIN_BLOCKS..=MAX_BLOCKS).contains(&count) {
            return Err(SimError::BadBlockCount {
                count,
                min: MIN_BLOCKS,
                max: MAX_BLOCKS,
            });
        }
        for (i, a) in cells.iter().enumerate() {
            if let Some(j) = cells[..i].iter().position(|b| b == a) {
                return Err(SimError::CellsOverlap {
                    first: j,
                    second: i,
                    x: a.x,
                    y: a.y,
                });
            }
        }
        if let Some(b) = held
            && b.index() >= count
        {
            return Err(SimError::NoSuchBlock {
                block: b.index(),
                blocks: count,
            });
        }
        let mut all = [Cell::default(); MAX_BLOCKS];
        all[..count].copy_from_slice(cells);
        Ok(Self {
            cells: all,
            count: count as u8,
            held,
        })
    }

    /// Reads a state as the command line writes it: every block's cell `x,y`, block 0
    /// first, separated by `;` (e.g. `"0,0;3,0;5,2"`), and the held block, if any. Checked
    /// like [`State::new`] and against `grid` ([`State::check_fits`]); a held block is
    /// named as given, however large.
    pub fn parse(text: &str, held: Option<usize>, grid: Grid) -> Result<State> {
        let cells = text
            .split(';')
            .map(|part| {
                let coords: Vec<Option<i64>> = part.split(',').map(|v| v.trim().parse().ok()).collect();
                let [Some(x), Some(y)] = coords[..] else {
                    return Err(SimError::Parse {
                        what: "cell",
                        text: part.trim().to_string(),
                        reason: "write each block's cell as x,y, blocks separated by ';', e.g. \"0,0;3,0;5,2\"".into(),
                    });
                };
                grid.cell(x, y)
            })
            .collect::<Result<Vec<Cell>>>()?;
        let held = match held {
            Some(b) if b >= cells.len() => {
                return Err(SimError::NoSuchBlock {
                    block: b,
                    blocks: cells.len(),
                });
            }
            held => held.map(|b| BlockId(b as u8)),
        };
        let state = State::new(&cells, held)?;
        state.check_fits(grid)?;
        Ok(state)
    }

    /// An error naming the first block that stands outside `grid`.
    pub fn check_fits(&self, grid: Grid) -> Result<()> {
        for c in self.cells() {
            grid.cell(c.x.into(), c.y.into())?;
        }
        if self.block_count() >= grid.cell_count() {
            return Err(SimError::TooManyBlocks {
                blocks: self.block_count(),
                width: grid.width(),
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

    /// Every block's cell, indexed by block id.
    #[inline]
    pub fn cells(&self) -> &[Cell] {
        &self.cells[..self.count as usize]
    }

    /// The cell of `block`.
    #[inline]
    pub fn cell(&self, block: BlockId) -> Cell {
        self.cells[block.index()]
    }

    /// The held block, if any.
    #[inline]
    pub const fn held_block(&self) -> Option<BlockId> {
        self.held
    }

    /// All block ids, `0..N`.
    pub fn blocks(&self) -> impl Iterator<Item = BlockId> + use<> {
        (0..self.count).map(BlockId)
    }

    /// The block standing on `cell`, if any.
    #[inline]
    pub fn block_at(&self, cell: Cell) -> Option<BlockId> {
        self.cells().iter().position(|&c| c == cell).map(|i| BlockId(i as u8))
    }

    /// Puts `block` on `cell` without any check: the caller (a backend) has decided the
    /// move is legal.
    #[inline]
    pub(crate) fn set_cell(&mut self, block: BlockId, cell: Cell) {
        self.cells[block.index()] = cell;
    }

    /// Sets the held block without any check.
    #[inline]
    pub(crate) fn set_held(&mut self, held: Option<BlockId>) {
        self.held = held;
    }

    /// This state with `held` in hand instead (`None`: nothing held).
    pub fn with_held(mut self, held: Option<BlockId>) -> Result<Self> {
        if let Some(b) = held
            && b.index() >= self.block_count()
        {
            return Err(SimError::NoSuchBlock {
                block: b.index(),
                blocks: self.block_count(),
            });
        }
        self.held = held;
        Ok(self)
    }
}

impl fmt::Debug for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("State")
            .field("cells", &self.cells())
            .field("held", &self.held)
            .finish()
    }
}
