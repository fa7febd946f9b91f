//! The compact screen: the world drawn for a pixel network at a few pixels a cell.
//!
//! The paper's screen ([`Observation::pixels`]) draws the goal as a picture of 2 x 2-pixel
//! blocks in a corner, and a network must tell six goals apart from it before it learns
//! anything else (docs/dqn.md measures what that costs). This screen draws the same state
//! at [`SCREEN_CELL`] pixels a cell, every cell of the grid one square of the picture, and
//! shows the goal in one of two ways ([`ScreenGoal`]):
//!
//! - `colours`: every block in the colour of its *place in the goal* (the bottom block red,
//!   the next green, then blue, ..., [`crate::render::PALETTE`]): the goal is read off the
//!   blocks themselves, and every goal is the same picture problem, as the role planes make
//!   it for the planes networks;
//! - `strip`: every block in its own colour (block 0 red, ...), and the goal stack drawn in
//!   a column of cells of its own to the right of the grid, bottom block at the bottom, at
//!   the picture's own scale: the paper's goal picture, made legible.
//!
//! Either way the background is black and the held block is drawn in its colour inside a
//! white ring. A third choice, `paper`, is no compact screen but the paper's own
//! ([`Observation::pixels`]: 100 x 100, blocks in their own colours, the goal a picture of
//! 2 x 2-pixel blocks in the corner), so that the network that reads these screens can be
//! put on the paper's and what the goal's presentation costs be measured (docs/dqn.md). A cell is a `SCREEN_CELL x SCREEN_CELL` square, so that a convolution whose
//! kernel and stride are one cell reads each cell once. Rows run from the top (the grid's
//! top row first), as in any image; 3 bytes (RGB) a pixel.

use serde::{Deserialize, Serialize};

use crate::grid::Grid;
use crate::observation::{Observation, PIXELS_HELD, PIXELS_SIDE};
use crate::render::PALETTE;
use crate::state::{BlockId, MAX_BLOCKS};

/// Side of a cell on the compact screen, in pixels.
pub const SCREEN_CELL: usize = 4;

/// How the compact screen shows the goal (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScreenGoal {
    /// Every block in the colour of its place in the goal.
    #[default]
    Colours,
    /// Every block in its own colour, the goal stack in a column of its own.
    Strip,
    /// The paper's screen ([`Observation::pixels`]), goal picture in the corner and all.
    Paper,
}

crate::names!(ScreenGoal { Colours = "colours", Strip = "strip", Paper = "paper" } unknown(name) -> crate::SimError {
    crate::SimError::Parse {
        what: "screen goal",
        text: name.to_string(),
        reason: format!("choose one of {}", ScreenGoal::NAMES.join(", ")),
    }
});

impl ScreenGoal {
    /// `(rows, columns, 3)` of the screen of a `grid`.
    pub fn shape(self, grid: Grid) -> [usize; 3] {
        let columns = match self {
            ScreenGoal::Colours => grid.width(),
            ScreenGoal::Strip => grid.width() + 1,
            ScreenGoal::Paper => return [PIXELS_SIDE, PIXELS_SIDE, 3],
        };
        [grid.height() * SCREEN_CELL, columns * SCREEN_CELL, 3]
    }
}

impl Observation {
    /// The compact screen (module docs) with the goal shown as `goal` says.
    pub fn screen(&self, goal: ScreenGoal) -> Vec<u8> {
        let mut out = vec![0; goal.shape(self.grid).iter().product()];
        self.write_screen(goal, &mut out);
        out
    }

    /// Writes [`Observation::screen`] into `out`, without allocating.
    ///
    /// # Panics
    ///
    /// Unless `out` holds [`ScreenGoal::shape`]'s values.
    pub fn write_screen(&self, goal: ScreenGoal, out: &mut [u8]) {
        let [rows, columns, _] = goal.shape(self.grid);
        assert_eq!(out.len(), rows * columns * 3, "a buffer of the screen's size");
        if goal == ScreenGoal::Paper {
            out.copy_from_slice(&self.pixels().data);
            return;
        }
        out.fill(0);
        let height = self.grid.height();
        // Grid rows grow upward, screen rows downward.
        let mut square = |x: usize, y: usize, rgb: [u8; 3], held: bool| {
            let top = (height - 1 - y) * SCREEN_CELL;
            for r in 0..SCREEN_CELL {
                for c in 0..SCREEN_CELL {
                    let ring = r == 0 || c == 0 || r == SCREEN_CELL - 1 || c == SCREEN_CELL - 1;
                    let at = ((top + r) * columns + x * SCREEN_CELL + c) * 3;
                    out[at..at + 3].copy_from_slice(if held && ring { &PIXELS_HELD } else { &rgb });
                }
            }
        };
        let place_colour = |place: usize| PALETTE[place % MAX_BLOCKS];
        for (i, &cell) in self.blocks().iter().enumerate() {
            let block = BlockId::of(i);
            let rgb = match goal {
                ScreenGoal::Colours => place_colour(self.goal.place_of(block)),
                ScreenGoal::Strip | ScreenGoal::Paper => crate::render::colour(block),
            };
            let held = self.held_block() == Some(block);
            square(usize::from(cell.x), usize::from(cell.y), rgb, held);
        }
        if goal == ScreenGoal::Strip {
            for (place, &block) in self.goal.order().iter().enumerate().take(height) {
                square(self.grid.width(), place, crate::render::colour(block), false);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::ActionProtocol;
    use crate::{Cell, State, View};

    fn obs(held: Option<u16>) -> Observation {
        // Goal 2,0,1: block 2 at the bottom, then 0, then 1.
        let cells = [Cell::new(0, 0), Cell::new(6, 6), Cell::new(3, 2)];
        Observation {
            grid: Grid::default(),
            state: State::new(&cells, held.map(BlockId)).unwrap(),
            goal: "2,0,1".parse().unwrap(),
            protocol: ActionProtocol::Free,
            view: View::Top,
        }
    }

    /// The colour at the centre of grid cell `(x, y)`.
    fn at(screen: &[u8], goal: ScreenGoal, x: usize, y: usize) -> [u8; 3] {
        let [rows, columns, _] = goal.shape(Grid::default());
        let (r, c) = (
            rows - 1 - y * SCREEN_CELL - SCREEN_CELL / 2,
            x * SCREEN_CELL + SCREEN_CELL / 2,
        );
        let i = (r * columns + c) * 3;
        [screen[i], screen[i + 1], screen[i + 2]]
    }

    #[test]
    fn colours_name_each_block_by_its_place_in_the_goal() {
        let goal = ScreenGoal::Colours;
        let s = obs(None).screen(goal);
        assert_eq!(goal.shape(Grid::default()), [28, 28, 3]);
        assert_eq!(s.len(), 28 * 28 * 3);
        assert_eq!(at(&s, goal, 3, 2), PALETTE[0], "block 2 is the goal's bottom block");
        assert_eq!(at(&s, goal, 0, 0), PALETTE[1]);
        assert_eq!(at(&s, goal, 6, 6), PALETTE[2]);
        assert_eq!(at(&s, goal, 5, 5), [0, 0, 0]);
        // Three blocks of 16 pixels, the rest black.
        let lit = s.chunks(3).filter(|p| *p != [0, 0, 0]).count();
        assert_eq!(lit, 3 * SCREEN_CELL * SCREEN_CELL);
        // The top-left pixel of the screen is the top row's first cell.
        assert_eq!(s[..3], [0, 0, 0]);
        let corner = 27 * 28 * 3;
        assert_eq!(s[corner..corner + 3], PALETTE[1], "cell (0, 0) is at the bottom left");
    }

    #[test]
    fn the_held_block_keeps_its_colour_inside_a_white_ring() {
        let goal = ScreenGoal::Colours;
        let s = obs(Some(0)).screen(goal);
        assert_eq!(at(&s, goal, 0, 0), PALETTE[1], "the inside");
        assert_eq!(s[(27 * 28) * 3..(27 * 28) * 3 + 3], PIXELS_HELD, "the ring");
    }

    #[test]
    fn the_strip_shows_the_goal_stack_beside_blocks_in_their_own_colours() {
        let goal = ScreenGoal::Strip;
        let o = obs(None);
        let s = o.screen(goal);
        assert_eq!(goal.shape(Grid::default()), [28, 32, 3]);
        assert_eq!(at(&s, goal, 3, 2), PALETTE[2], "block 2 in its own colour");
        for (place, &block) in o.goal.order().iter().enumerate() {
            assert_eq!(at(&s, goal, 7, place), crate::render::colour(block));
        }
        assert_eq!(at(&s, goal, 7, 3), [0, 0, 0]);
        // The same state under another goal differs only in the strip.
        let mut other = o;
        other.goal = "0,1,2".parse().unwrap();
        let t = other.screen(goal);
        let grid_part = |v: &[u8]| v.chunks(32 * 3).map(|row| row[..28 * 3].to_vec()).collect::<Vec<_>>();
        assert_eq!(grid_part(&s), grid_part(&t));
        assert_ne!(s, t);
    }

    #[test]
    fn paper_is_the_papers_own_screen() {
        let o = obs(Some(0));
        assert_eq!(ScreenGoal::Paper.shape(Grid::new(5, 9).unwrap()), [100, 100, 3]);
        assert_eq!(o.screen(ScreenGoal::Paper), o.pixels().data);
    }

    #[test]
    fn names_read_and_print() {
        for name in ScreenGoal::NAMES {
            assert_eq!(name.parse::<ScreenGoal>().unwrap().to_string(), name);
        }
        assert!("corner".parse::<ScreenGoal>().is_err());
    }
}
