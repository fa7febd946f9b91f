//! The grid: its size, its cells and the four directions between them.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};

/// The largest number of cells of a top-view grid (16 x 16, or any other shape of at most
/// this many cells): the top view's occupancy model keeps one bit per cell in a fixed-size
/// set, and its planes and pictures are `W x H` arrays. Checked where a top-view world is
/// built ([`View::check_world`](crate::View::check_world)), not by [`Grid`] itself: the side
/// view keeps no `W x H` structure and takes any grid whose sides fit [`MAX_SIDE`].
pub const MAX_CELLS: usize = 256;

/// The longest side of any grid: coordinates are `u16`.
pub const MAX_SIDE: usize = u16::MAX as usize;

/// A cell `(x, y)` of the grid: `x` grows to the right, `y` grows upward.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Cell {
    /// Column, from 0 at the left.
    pub x: u16,
    /// Row, from 0 at the bottom.
    pub y: u16,
}

impl Cell {
    /// The cell at column `x`, row `y`.
    pub const fn new(x: u16, y: u16) -> Self {
        Self { x, y }
    }

    /// Manhattan distance to `other`.
    pub fn manhattan(self, other: Cell) -> u32 {
        u32::from(self.x.abs_diff(other.x)) + u32::from(self.y.abs_diff(other.y))
    }

    /// The cell directly above (`y + 1`), if it is inside `grid`.
    pub fn above(self, grid: Grid) -> Option<Cell> {
        grid.neighbour(self, Direction::Up)
    }

    /// The cell directly below (`y - 1`), if it is inside `grid`.
    pub fn below(self, grid: Grid) -> Option<Cell> {
        grid.neighbour(self, Direction::Down)
    }
}

impl fmt::Display for Cell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.x, self.y)
    }
}

/// One of the four directions a held block can move in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Direction {
    /// `y + 1`.
    Up,
    /// `y - 1`.
    Down,
    /// `x - 1`.
    Left,
    /// `x + 1`.
    Right,
}

impl Direction {
    /// All four, in action-index order.
    pub const ALL: [Direction; 4] = [Direction::Up, Direction::Down, Direction::Left, Direction::Right];

    /// The unit step `(dx, dy)` of this direction.
    pub const fn delta(self) -> (i32, i32) {
        match self {
            Direction::Up => (0, 1),
            Direction::Down => (0, -1),
            Direction::Left => (-1, 0),
            Direction::Right => (1, 0),
        }
    }
}

/// The size of the world: `width x height` cells of one world unit each.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Grid {
    width: u16,
    height: u16,
}

impl Default for Grid {
    /// The paper's 7 x 7 grid.
    fn default() -> Self {
        Self { width: 7, height: 7 }
    }
}

impl Grid {
    /// A `width x height` grid; both sides from 1 to [`MAX_SIDE`]. (A top-view world also
    /// needs at most [`MAX_CELLS`] cells: [`View::check_world`](crate::View::check_world).)
    pub fn new(width: usize, height: usize) -> Result<Self> {
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return Err(SimError::GridSide {
                width,
                height,
                max: MAX_SIDE,
            });
        }
        Ok(Self {
            width: width as u16,
            height: height as u16,
        })
    }

    /// The side view's grid for `blocks` blocks when none is given (docs/world.md, "The side
    /// view at any size"): the paper's 7 x 7 up to 7 blocks (it holds every state and every
    /// goal of 7 blocks), and beyond, `N` columns (a table as wide as the widest state, all
    /// blocks on the table) and `N + 1` rows (a tower of every block, and a row above it), as
    /// E9's grid. A grid this size holds every state of `N` blocks and leaves a row to carry
    /// any block over any tower, so every block move can be carried out.
    pub fn side_default(blocks: usize) -> Grid {
        // More blocks than a side holds are refused where the world is built; their grid is
        // the largest.
        let n = blocks.min(MAX_SIDE - 1);
        if n <= 7 {
            Grid::default()
        } else {
            Grid::new(n, n + 1).expect("sides of at most MAX_SIDE")
        }
    }

    /// Columns.
    pub const fn width(self) -> usize {
        self.width as usize
    }

    /// Rows.
    pub const fn height(self) -> usize {
        self.height as usize
    }

    /// Number of cells.
    pub const fn cell_count(self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether `(x, y)` lies inside the grid.
    pub fn contains(self, x: i64, y: i64) -> bool {
        (0..self.width as i64).contains(&x) && (0..self.height as i64).contains(&y)
    }

    /// The cell at `(x, y)`, or an error naming it if it lies outside the grid.
    pub fn cell(self, x: i64, y: i64) -> Result<Cell> {
        if self.contains(x, y) {
            Ok(Cell::new(x as u16, y as u16))
        } else {
            Err(SimError::CellOutsideGrid {
                x,
                y,
                width: self.width(),
                height: self.height(),
            })
        }
    }

    /// The neighbour of `cell` in direction `dir`, if it is inside the grid.
    #[inline]
    pub fn neighbour(self, cell: Cell, dir: Direction) -> Option<Cell> {
        match dir {
            Direction::Up => (cell.y + 1 < self.height).then(|| Cell::new(cell.x, cell.y + 1)),
            Direction::Down => cell.y.checked_sub(1).map(|y| Cell::new(cell.x, y)),
            Direction::Left => cell.x.checked_sub(1).map(|x| Cell::new(x, cell.y)),
            Direction::Right => (cell.x + 1 < self.width).then(|| Cell::new(cell.x + 1, cell.y)),
        }
    }

    /// The cell's index in row-major order (`y * width + x`), in `0..cell_count()`.
    #[inline]
    pub const fn index(self, cell: Cell) -> usize {
        cell.y as usize * self.width as usize + cell.x as usize
    }

    /// The cell with row-major index `index`.
    #[inline]
    pub const fn cell_at(self, index: usize) -> Cell {
        Cell::new(
            (index % self.width as usize) as u16,
            (index / self.width as usize) as u16,
        )
    }

    /// Every cell, in row-major order.
    pub fn cells(self) -> impl Iterator<Item = Cell> {
        (0..self.cell_count()).map(move |i| self.cell_at(i))
    }
}

impl fmt::Display for Grid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

impl std::str::FromStr for Grid {
    type Err = SimError;

    /// Reads `"WxH"`, e.g. `"7x7"`.
    fn from_str(text: &str) -> Result<Self> {
        let parse_err = |reason: &str| SimError::Parse {
            what: "grid",
            text: text.to_string(),
            reason: reason.to_string(),
        };
        let (w, h) = text
            .split_once(['x', 'X'])
            .ok_or_else(|| parse_err("write it as WxH, e.g. 7x7"))?;
        let w = w
            .trim()
            .parse::<usize>()
            .map_err(|_| parse_err("the width is not a whole number"))?;
        let h = h
            .trim()
            .parse::<usize>()
            .map_err(|_| parse_err("the height is not a whole number"))?;
        Grid::new(w, h)
    }
}
