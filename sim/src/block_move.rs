//! Block moves: the actions of the Blocks World literature (`move(x, onto y)`,
//! `move(x, onto the table at column c)`), carried out by the gripper in the side view.
//!
//! Planning and learning results in the Blocks World count block moves; the gripper's world
//! counts gripper steps. A block move is expanded ([`expand`]) into the gripper actions
//! that carry it out, the fewest there are: Pick the block, lift it just high enough to
//! pass over every column between it and its destination (and the destination itself),
//! carry it across, and Drop it, to fall onto the destination. [`Env::step_block_move`]
//! takes those actions through the world's backend (the physics decides every move and
//! where the block comes to rest) and says how many gripper steps the move took.
//!
//! Moves are numbered for array-based callers (Python's `actions="moves"`): with `N` blocks
//! on a grid `W` wide, move `x * (N + W) + d` takes block `x` onto block `d` for `d < N`
//! and onto the table at column `d - N` otherwise ([`BlockMove::index`]).
//!
//! [`Env::step_block_move`]: crate::Env::step_block_move

use std::fmt;

use crate::action::Action;
use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid};
use crate::grid_world::GridWorld;
use crate::state::{BlockId, State};
use crate::view;
use crate::world::World;

/// One block move.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BlockMove {
    /// Put `block` onto `target` (both clear, distinct).
    Onto {
        /// The block moved.
        block: BlockId,
        /// The block it is put on.
        target: BlockId,
    },
    /// Put `block` on the table at column `column` (an empty column).
    ToTable {
        /// The block moved.
        block: BlockId,
        /// The column, from 0 at the left.
        column: u16,
    },
}

impl BlockMove {
    /// The number of moves of a world of `blocks` blocks on `grid`: `N * (N + W)`.
    pub const fn count(blocks: usize, grid: Grid) -> usize {
        blocks * (blocks + grid.width())
    }

    /// This move's index (module docs).
    pub fn index(self, blocks: usize, grid: Grid) -> usize {
        let per = blocks + grid.width();
        match self {
            BlockMove::Onto { block, target } => block.index() * per + target.index(),
            BlockMove::ToTable { block, column } => block.index() * per + blocks + usize::from(column),
        }
    }

    /// The move with index `index` of a world of `blocks` blocks on `grid`; an error past
    /// [`BlockMove::count`].
    pub fn from_index(index: usize, blocks: usize, grid: Grid) -> Result<BlockMove> {
        if index >= BlockMove::count(blocks, grid) {
            return Err(SimError::MoveOutOfRange {
                index,
                count: BlockMove::count(blocks, grid),
            });
        }
        let per = blocks + grid.width();
        let (block, d) = (BlockId::of(index / per), index % per);
        Ok(if d < blocks {
            BlockMove::Onto {
                block,
                target: BlockId::of(d),
            }
        } else {
            BlockMove::ToTable {
                block,
                column: (d - blocks) as u16,
            }
        })
    }

    /// The block moved.
    pub const fn block(self) -> BlockId {
        match self {
            BlockMove::Onto { block, .. } | BlockMove::ToTable { block, .. } => block,
        }
    }
}

impl fmt::Display for BlockMove {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BlockMove::Onto { block, target } => write!(f, "move {block} onto {target}"),
            BlockMove::ToTable { block, column } => write!(f, "move {block} onto the table at column {column}"),
        }
    }
}

/// How the gripper carries out a block move, the fewest actions there are (module docs):
/// Pick `block` at `from`, Up to `row`, across to column `to_x`, Drop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Carry {
    /// The block moved.
    pub block: BlockId,
    /// Where it stands before the move.
    pub from: Cell,
    /// The row it is carried across on: just over every column on the way and the
    /// destination.
    pub row: u16,
    /// The destination's column.
    pub to_x: u16,
}

impl Carry {
    /// Number of gripper actions: the Pick, the lift, the way across and the Drop.
    pub fn len(&self) -> usize {
        2 + usize::from(self.row - self.from.y) + usize::from(self.from.x.abs_diff(self.to_x))
    }

    /// Whether it takes no action (never: a move is at least a Pick, a step across and a
    /// Drop).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The cell the block is carried to, from which the Drop lets it fall.
    pub fn release_cell(&self) -> Cell {
        Cell::new(self.to_x, self.row)
    }

    /// The step across: Left or Right.
    pub fn across(&self) -> Action {
        if self.to_x > self.from.x {
            Action::Right
        } else {
            Action::Left
        }
    }

    /// The gripper actions, in order.
    pub fn actions(&self) -> impl Iterator<Item = Action> + use<> {
        let (lift, across) = (
            usize::from(self.row - self.from.y),
            usize::from(self.from.x.abs_diff(self.to_x)),
        );
        std::iter::once(Action::Pick(self.block))
            .chain(std::iter::repeat_n(Action::Up, lift))
            .chain(std::iter::repeat_n(self.across(), across))
            .chain(std::iter::once(Action::Drop))
    }
}

/// What a route needs to know of a world: the blocks' cells, whether a block is clear, what
/// stands on it, and how tall the columns stand (the moved block left out). The state itself
/// answers by scanning its blocks (O(N) each); the grid backend's side view answers from its
/// column heights.
trait Layout {
    fn state(&self) -> &State;
    /// The block standing on `block` (`None`: it is clear).
    fn block_on(&self, block: BlockId) -> Option<BlockId>;
    /// The height of column `x`, not counting `except`.
    fn height(&self, x: u16, except: BlockId) -> u16;
    /// The row to carry `from`'s block across on to column `to_x`: the tallest column
    /// strictly between them or at `to_x` (the block's own column stands below it).
    fn carry_row(&self, from: Cell, to_x: u16, block: BlockId) -> u16 {
        let (lo, hi) = (from.x.min(to_x), from.x.max(to_x));
        (lo..=hi)
            .filter(|&x| x != from.x)
            .map(|x| self.height(x, block))
            .max()
            .unwrap_or(0)
            .max(from.y)
    }
}

/// A state seen through scans of its blocks; column heights computed once.
struct Scanned<'a> {
    state: &'a State,
    heights: Vec<u16>,
    block: BlockId,
}

impl<'a> Scanned<'a> {
    fn new(state: &'a State, grid: Grid, block: BlockId) -> Self {
        let mut heights = vec![0u16; grid.width()];
        for b in state.blocks().filter(|&b| b != block) {
            let c = state.cell(b);
            let x = usize::from(c.x);
            heights[x] = heights[x].max(c.y + 1);
        }
        Scanned { state, heights, block }
    }
}

impl Layout for Scanned<'_> {
    fn state(&self) -> &State {
        self.state
    }

    fn block_on(&self, block: BlockId) -> Option<BlockId> {
        view::block_on(self.state, block)
    }

    fn height(&self, x: u16, except: BlockId) -> u16 {
        debug_assert_eq!(except, self.block);
        self.heights[usize::from(x)]
    }
}

impl Layout for GridWorld {
    fn state(&self) -> &State {
        self.state_ref()
    }

    fn block_on(&self, block: BlockId) -> Option<BlockId> {
        let c = self.cell_of(block);
        if usize::from(c.y) + 1 >= self.grid().height() {
            return None;
        }
        self.block_at(Cell::new(c.x, c.y + 1))
    }

    fn height(&self, x: u16, except: BlockId) -> u16 {
        let h = self.columns().expect("a side-view world").height(x);
        // A clear block stands on the top of its column: leaving it out lowers it by one.
        if self.cell_of(except).x == x { h - 1 } else { h }
    }
}

/// `Ok` if `mv` can be carried out in the side-view state `state` on `grid`: nothing held,
/// the block (and the target) exist and are clear, the target is another block, the column
/// exists and is empty, and the grid has a free row to carry the block over what lies
/// between. Otherwise [`SimError::IllegalMove`] (or [`SimError::NoSuchBlock`]) naming why.
pub fn check(state: &State, grid: Grid, mv: BlockMove) -> Result<()> {
    route(state, grid, mv).map(drop)
}

/// The gripper actions that carry out `mv` from the side-view state `state` on `grid`, the
/// fewest there are (module docs); an error, as [`check`] says, if it cannot be done.
pub fn expand(state: &State, grid: Grid, mv: BlockMove) -> Result<Vec<Action>> {
    Ok(route(state, grid, mv)?.actions().collect())
}

/// How the gripper carries out `mv` from the side-view `state` on `grid` ([`Carry`]); an
/// error, as [`check`] says, if it cannot be done. O(N + W).
pub fn route(state: &State, grid: Grid, mv: BlockMove) -> Result<Carry> {
    if mv.block().index() >= state.block_count() {
        return Err(SimError::NoSuchBlock {
            block: mv.block().index(),
            blocks: state.block_count(),
        });
    }
    route_over(&Scanned::new(state, grid, mv.block()), grid, mv)
}

/// [`route`] in a side-view grid world, from its column heights: O(1) but for the way
/// across (O(W)) and the error messages.
pub fn route_in(world: &GridWorld, mv: BlockMove) -> Result<Carry> {
    if world.view() != view::View::Side {
        return Err(SimError::MovesNeedSideView);
    }
    route_over(world, world.grid(), mv)
}

fn route_over(layout: &impl Layout, grid: Grid, mv: BlockMove) -> Result<Carry> {
    let state = layout.state();
    let n = state.block_count();
    let block = mv.block();
    let illegal = |reason: String| SimError::IllegalMove {
        mv: mv.to_string(),
        reason,
    };
    for b in [
        Some(block),
        if let BlockMove::Onto { target, .. } = mv {
            Some(target)
        } else {
            None
        },
    ]
    .into_iter()
    .flatten()
    {
        if b.index() >= n {
            return Err(SimError::NoSuchBlock {
                block: b.index(),
                blocks: n,
            });
        }
        if let Some(top) = layout.block_on(b) {
            return Err(illegal(format!("block {top} stands on block {b}")));
        }
    }
    if let Some(h) = state.held_block() {
        return Err(illegal(format!("block {h} is held; drop it first")));
    }
    let from = state.cell(block);
    let to_x = match mv {
        BlockMove::Onto { target, .. } if target == block => {
            return Err(illegal("a block cannot be put onto itself".into()));
        }
        BlockMove::Onto { target, .. } => state.cell(target).x,
        BlockMove::ToTable { column, .. } if usize::from(column) >= grid.width() => {
            return Err(illegal(format!("the grid has columns 0..{}", grid.width())));
        }
        BlockMove::ToTable { column, .. } if layout.height(column, block) > 0 => {
            return Err(illegal(format!("column {column} is not empty")));
        }
        BlockMove::ToTable { column, .. } => column,
    };
    if to_x == from.x {
        return Err(illegal("the block is already there".into()));
    }
    let row = layout.carry_row(from, to_x, block);
    if usize::from(row) >= grid.height() {
        return Err(illegal(format!(
            "no free row to carry it over: the grid has {} rows",
            grid.height()
        )));
    }
    Ok(Carry { block, from, row, to_x })
}

/// Every legal block move in the side-view state `state` on `grid`, by index: `true` at
/// [`BlockMove::index`] of each move [`check`] allows. O(N (N + W)), the size of the answer.
pub fn legal_moves(state: &State, grid: Grid) -> Vec<bool> {
    let n = state.block_count();
    let (w, h) = (grid.width(), grid.height());
    let mut legal = vec![false; BlockMove::count(n, grid)];
    if state.held_block().is_some() {
        return legal;
    }
    let mut heights = vec![0u16; w];
    for c in state.cells() {
        let x = usize::from(c.x);
        heights[x] = heights[x].max(c.y + 1);
    }
    let clear: Vec<BlockId> = state
        .blocks()
        .filter(|&b| state.cell(b).y + 1 == heights[usize::from(state.cell(b).x)])
        .collect();
    // For each clear block: the row it is carried on to each column (the tallest column on
    // the way there, its own left out), from a sweep outwards in each direction.
    let mut row = vec![0u16; w];
    for &b in &clear {
        let from = state.cell(b);
        let fx = usize::from(from.x);
        let mut tallest = from.y;
        for x in (0..fx).rev() {
            tallest = tallest.max(heights[x]);
            row[x] = tallest;
        }
        tallest = from.y;
        for x in fx + 1..w {
            tallest = tallest.max(heights[x]);
            row[x] = tallest;
        }
        let base = b.index() * (n + w);
        for &t in &clear {
            let x = usize::from(state.cell(t).x);
            legal[base + t.index()] = t != b && usize::from(row[x]) < h;
        }
        for x in (0..w).filter(|&x| x != fx && heights[x] == 0) {
            legal[base + n + x] = usize::from(row[x]) < h;
        }
    }
    legal
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Cell;

    fn state(cells: &[(u16, u16)]) -> State {
        let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
        State::new(&cells, None).unwrap()
    }

    #[test]
    fn a_move_lifts_the_block_just_over_what_lies_between() {
        let grid = Grid::new(5, 4).unwrap();
        // 0 alone at column 0; 1 under 2 at column 2; 3 alone at column 4.
        let s = state(&[(0, 0), (2, 0), (2, 1), (4, 0)]);
        let mv = BlockMove::Onto {
            block: BlockId(0),
            target: BlockId(3),
        };
        // Over the tower of two at column 2: two rows up, four columns right.
        assert_eq!(
            expand(&s, grid, mv).unwrap(),
            [
                Action::Pick(BlockId(0)),
                Action::Up,
                Action::Up,
                Action::Right,
                Action::Right,
                Action::Right,
                Action::Right,
                Action::Drop
            ]
        );
        let to_table = BlockMove::ToTable {
            block: BlockId(2),
            column: 1,
        };
        assert_eq!(
            expand(&s, grid, to_table).unwrap(),
            [Action::Pick(BlockId(2)), Action::Left, Action::Drop]
        );
    }

    #[test]
    fn illegal_moves_say_why() {
        let grid = Grid::new(3, 3).unwrap();
        let s = state(&[(0, 0), (0, 1), (2, 0)]);
        let err = |mv| check(&s, grid, mv).unwrap_err().to_string();
        let onto = |block, target| BlockMove::Onto {
            block: BlockId(block),
            target: BlockId(target),
        };
        assert_eq!(err(onto(0, 2)), "cannot move 0 onto 2: block 1 stands on block 0");
        assert_eq!(err(onto(2, 0)), "cannot move 2 onto 0: block 1 stands on block 0");
        assert_eq!(
            err(onto(1, 1)),
            "cannot move 1 onto 1: a block cannot be put onto itself"
        );
        let table = |block, column| BlockMove::ToTable {
            block: BlockId(block),
            column,
        };
        assert!(err(table(1, 2)).contains("column 2 is not empty"));
        assert!(err(table(1, 3)).contains("columns 0..3"));
        assert!(check(&s, grid, table(1, 1)).is_ok());
        // On a grid two rows high the tower of two leaves no row to carry 2 over it.
        let low = Grid::new(3, 2).unwrap();
        let t = state(&[(1, 0), (1, 1), (2, 0)]);
        assert!(
            check(
                &t,
                low,
                BlockMove::ToTable {
                    block: BlockId(2),
                    column: 0
                }
            )
            .unwrap_err()
            .to_string()
            .contains("no free row")
        );
    }

    #[test]
    fn moves_are_numbered_both_ways() {
        let grid = Grid::new(4, 4).unwrap();
        for i in 0..BlockMove::count(3, grid) {
            let mv = BlockMove::from_index(i, 3, grid).unwrap();
            assert_eq!(mv.index(3, grid), i);
        }
        assert!(BlockMove::from_index(21, 3, grid).is_err());
        let legal = legal_moves(&state(&[(0, 0), (0, 1), (2, 0)]), grid);
        // Block 1 onto 2, onto the table at columns 1 and 3; block 2 onto 1, table 1, 3.
        let names: Vec<String> = (0..legal.len())
            .filter(|&i| legal[i])
            .map(|i| BlockMove::from_index(i, 3, grid).unwrap().to_string())
            .collect();
        assert_eq!(
            names,
            [
                "move 1 onto 2",
                "move 1 onto the table at column 1",
                "move 1 onto the table at column 3",
                "move 2 onto 1",
                "move 2 onto the table at column 1",
                "move 2 onto the table at column 3"
            ]
        );
    }
}
