//! Blocks and the world's logical state: where every block stands and which one is held.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid};
use crate::inline_vec::InlineVec;

/// The fewest blocks of a top-view world: with one block every goal holds from the start.
/// (The side view takes one block: [`MIN_SIDE_BLOCKS`].)
pub const MIN_BLOCKS: usize = 2;

/// The most blocks of a top-view world, and of the learners whose tables and networks are
/// sized by the block count. Up to this many blocks a state (and a goal, and an action mask)
/// is kept inline, without allocation, so planners clone and hash them cheaply; the side
/// view goes further ([`MAX_SIDE_BLOCKS`]), on the heap.
pub const MAX_BLOCKS: usize = 16;

/// The fewest blocks of a side-view world: one block, whose goal (on the table) holds in
/// every state, so its task is solved by the empty plan.
pub const MIN_SIDE_BLOCKS: usize = 1;

/// The most blocks of a side-view world (docs/world.md, "The side view at any size"): a
/// state costs O(N) memory, and the grid backend, the uniform start and the near-optimal
/// planner were measured at this size.
pub const MAX_SIDE_BLOCKS: usize = 10_000;

/// A block's id, `0..N`; also its index in [`State::cells`] and its colour.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct BlockId(pub u16);

impl BlockId {
    /// The block with index `index` (below [`MAX_SIDE_BLOCKS`], as every block is).
    #[inline]
    pub const fn of(index: usize) -> BlockId {
        BlockId(index as u16)
    }
}

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

/// Every block's cell, indexed by block id: inline up to [`MAX_BLOCKS`] blocks, on the heap
/// beyond ([`InlineVec`]).
pub type Cells = InlineVec<Cell, MAX_BLOCKS>;

/// Where every block stands and which block, if any, is held.
///
/// This is the whole logical state of a world; both backends read and write it, and the
/// oracle and the solvers search over it. It costs O(N) memory: up to [`MAX_BLOCKS`] blocks
/// it is kept inline (a clone allocates nothing), beyond on the heap.
#[derive(Clone, PartialEq, Eq, Hash)]
pub struct State {
    cells: Cells,
    held: Option<BlockId>,
}

impl State {
    /// A state with block `i` on `cells[i]` and `held` in hand.
    ///
    /// Checks what can be checked without a grid or a view: the block count (1 to
    /// [`MAX_SIDE_BLOCKS`]; a view may bound it further, [`View::check_world`]), that no two
    /// blocks share a cell, and that the held block exists. [`State::check_fits`] checks the
    /// grid.
    ///
    /// [`View::check_world`]: crate::View::check_world
    pub fn new(cells: &[Cell], held: Option<BlockId>) -> Result<Self> {
        let count = cells.len();
        if !(MIN_SIDE_BLOCKS..=MAX_SIDE_BLOCKS).contains(&count) {
            return Err(SimError::BadBlockCount {
                count,
                what: "any world",
                min: MIN_SIDE_BLOCKS,
                max: MAX_SIDE_BLOCKS,
            });
        }
        if let Some((first, second)) = first_overlap(cells) {
            let a = cells[second];
            return Err(SimError::CellsOverlap {
                first,
                second,
                x: a.x,
                y: a.y,
            });
        }
        if let Some(b) = held
            && b.index() >= count
        {
            return Err(SimError::NoSuchBlock {
                block: b.index(),
                blocks: count,
            });
        }
        Ok(Self {
            cells: Cells::from_slice(cells),
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
            held => held.map(BlockId::of),
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
    pub fn block_count(&self) -> usize {
        self.cells.len()
    }

    /// Every block's cell, indexed by block id.
    #[inline]
    pub fn cells(&self) -> &[Cell] {
        &self.cells
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
        (0..self.block_count() as u16).map(BlockId)
    }

    /// The block standing on `cell`, if any (a scan of the blocks; the grid backend's side
    /// view answers from its columns instead).
    #[inline]
    pub fn block_at(&self, cell: Cell) -> Option<BlockId> {
        self.cells().iter().position(|&c| c == cell).map(BlockId::of)
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
    pub fn with_held(&self, held: Option<BlockId>) -> Result<Self> {
        if let Some(b) = held
            && b.index() >= self.block_count()
        {
            return Err(SimError::NoSuchBlock {
                block: b.index(),
                blocks: self.block_count(),
            });
        }
        Ok(Self {
            cells: self.cells.clone(),
            held,
        })
    }
}

/// The first pair of blocks on one cell, `(first, second)` with `second` the smallest index
/// standing where an earlier block stands and `first` the earliest such block; `None` if the
/// cells are distinct. Quadratic up to [`MAX_BLOCKS`] (no allocation), by sorting beyond.
fn first_overlap(cells: &[Cell]) -> Option<(usize, usize)> {
    if cells.len() <= MAX_BLOCKS {
        return cells
            .iter()
            .enumerate()
            .find_map(|(i, a)| cells[..i].iter().position(|b| b == a).map(|j| (j, i)));
    }
    let mut order: Vec<u32> = (0..cells.len() as u32).collect();
    order.sort_unstable_by_key(|&i| (cells[i as usize], i));
    // Sorted by cell, then index: a run of equal cells starts with its earliest block, and
    // its second entry is the next block standing there.
    order
        .chunk_by(|&a, &b| cells[a as usize] == cells[b as usize])
        .filter(|run| run.len() > 1)
        .map(|run| (run[0] as usize, run[1] as usize))
        .min_by_key(|&(_, second)| second)
}

impl fmt::Debug for State {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("State")
            .field("cells", &self.cells())
            .field("held", &self.held)
            .finish()
    }
}
