//! What an environment shows its agent: the full state as a typed struct, and views of it
//! for learners that want arrays: one-hot planes (blocks by id, or by place in the goal)
//! and the paper's 100 x 100 pixel screen.

use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::protocol::{ActionMask, ActionProtocol};
use crate::state::{BlockId, State};
use crate::view::View;

/// The full observation: grid, every block's cell, the held block, the goal, and the
/// action protocol that says which actions are legal.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Observation {
    /// The grid.
    pub grid: Grid,
    /// Where the blocks stand and which is held.
    pub state: State,
    /// The goal of the episode.
    pub goal: Goal,
    /// The environment's action protocol: a policy handed this observation chooses among
    /// [`Observation::legal_actions`].
    pub protocol: ActionProtocol,
    /// The world: seen from above or from the side (whose rules decide the legal actions).
    pub view: View,
}

impl Observation {
    /// Every block's cell, indexed by block id.
    pub fn blocks(&self) -> &[Cell] {
        self.state.cells()
    }

    /// The held block, if any.
    pub fn held_block(&self) -> Option<BlockId> {
        self.state.held_block()
    }

    /// The actions legal in this state under the environment's protocol (in the side view,
    /// by its rules).
    #[inline]
    pub fn legal_actions(&self) -> ActionMask {
        self.view.legal_actions(self.protocol, &self.state)
    }

    /// Whether the goal holds in this observation, in its view.
    #[inline]
    pub fn goal_holds(&self) -> bool {
        self.goal.holds_in(self.view, &self.state)
    }

    /// A `W x H x (N + 1)` one-hot array: plane `i < N` marks block `i`'s cell, plane `N`
    /// marks the held block's cell (all zero when nothing is held).
    pub fn planes(&self) -> Planes {
        let mut planes = self.empty_planes();
        self.write_planes(&mut planes.data);
        planes
    }

    /// Writes [`Observation::planes`]' values into `out` (laid out as [`Planes::data`]),
    /// for callers that fill buffers of their own without allocating.
    ///
    /// # Panics
    ///
    /// Unless `out` holds `W * H * (N + 1)` values.
    pub fn write_planes(&self, out: &mut [u8]) {
        let (h, n) = (self.grid.height(), self.state.block_count());
        assert_eq!(
            out.len(),
            self.grid.width() * h * (n + 1),
            "a buffer of W x H x (N + 1) values"
        );
        out.fill(0);
        self.mark_planes(out, self.blocks().iter().copied().enumerate());
    }

    /// A `W x H x (N + 1)` array of zeros, shaped for this observation's planes.
    fn empty_planes(&self) -> Planes {
        let (w, h, n) = (self.grid.width(), self.grid.height(), self.state.block_count());
        Planes {
            width: w,
            height: h,
            channels: n + 1,
            data: vec![0; w * h * (n + 1)],
        }
    }

    /// Sets to 1, in `out` (zeros laid out as [`Planes::data`]), the cell of every
    /// `(channel, cell)` of `marks` and the held block's cell in the last channel: the one
    /// layout of [`Observation::planes`] and [`Observation::role_planes`].
    fn mark_planes(&self, out: &mut [u8], marks: impl Iterator<Item = (usize, Cell)>) {
        let (h, n) = (self.grid.height(), self.state.block_count());
        let at = |c: Cell, channel: usize| (usize::from(c.x) * h + usize::from(c.y)) * (n + 1) + channel;
        for (channel, c) in marks {
            out[at(c, channel)] = 1;
        }
        if let Some(b) = self.held_block() {
            out[at(self.state.cell(b), n)] = 1;
        }
    }

    /// The rendered frame as an RGB image (see [`crate::render`]).
    pub fn rgb(&self) -> image::RgbImage {
        crate::render::frame(self, crate::render::CELL_PIXELS)
    }
}

/// A `width x height x channels` array of 0/1 values, stored `(x, y, channel)` with the
/// channel varying fastest: `data[(x * height + y) * channels + channel]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Planes {
    /// Grid width.
    pub width: usize,
    /// Grid height.
    pub height: usize,
    /// `N + 1`.
    pub channels: usize,
    /// The values, `width * height * channels` of them.
    pub data: Vec<u8>,
}

impl Planes {
    /// The value at cell `(x, y)`, channel `channel`.
    pub fn get(&self, x: usize, y: usize, channel: usize) -> u8 {
        self.data[(x * self.height + y) * self.channels + channel]
    }
}

/// Side of the square [`Observation::pixels`] image, as in the paper.
pub const PIXELS_SIDE: usize = 100;

/// Side of a cell in the paper's screen (50 px blocks on a 350 x 350 screen).
const PAPER_CELL: usize = 50;

/// The colour of the held block in [`Observation::pixels`] (the paper's: white).
pub const PIXELS_HELD: [u8; 3] = [255, 255, 255];

/// The background of the goal image in [`Observation::pixels`] (the paper's gray).
pub const PIXELS_GOAL_BACKGROUND: [u8; 3] = [50, 50, 50];

/// An RGB image stored row by row from the top, 3 bytes per pixel:
/// `data[(row * width + column) * 3 + channel]`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pixels {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The bytes, `width * height * 3` of them.
    pub data: Vec<u8>,
}

impl Pixels {
    /// The colour at `(column, row)`, row 0 at the top.
    pub fn rgb(&self, column: usize, row: usize) -> [u8; 3] {
        let i = (row * self.width + column) * 3;
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }
}

impl Observation {
    /// The planes of [`Observation::planes`] with blocks named by their place in the goal
    /// (as the `role` table does): plane `p < N` marks the cell of the block at place `p`
    /// (0 = bottom), plane `N` the held block's cell. Every goal becomes the same picture
    /// problem, so one network serves every goal.
    pub fn role_planes(&self) -> Planes {
        let mut planes = self.empty_planes();
        let by_place = self.goal.order().iter().map(|&b| self.state.cell(b)).enumerate();
        self.mark_planes(&mut planes.data, by_place);
        planes
    }

    /// The paper's DQN input (section III-C1), [`PIXELS_SIDE`] pixels square, 3 channels.
    ///
    /// The authors' screen (their `BlockWorld`): 50-pixel cells on a black background, each
    /// block a square of its colour ([`crate::render::colour`]), the held block white, and
    /// the goal as a small picture in the top-right corner: a gray square a fifth of the
    /// screen wide, drawn over the grid (a block in the top-right cell is hidden under it,
    /// as on the authors' screen), holding the goal stack in blocks a tenth of its side,
    /// centred, bottom block two block-sides above the square's bottom edge. That screen is
    /// scaled to 100 x 100 with bilinear interpolation (OpenCV's default, which the authors
    /// used), so a goal block covers about 2 x 2 pixels. A grid of another size is scaled the
    /// same way to the same square.
    pub fn pixels(&self) -> Pixels {
        let screen = PaperScreen::of(self);
        Pixels {
            width: PIXELS_SIDE,
            height: PIXELS_SIDE,
            data: bilinear(&screen, PIXELS_SIDE, PIXELS_SIDE),
        }
    }
}

/// The authors' screen (50-pixel cells), drawn one row at a time: the scaling reads two
/// rows for each row it writes, so the 350 x 350 screen is never held whole.
struct PaperScreen<'a> {
    obs: &'a Observation,
    /// Width and height in screen pixels.
    width: usize,
    height: usize,
    /// The goal picture: its left edge, side, block side, the blocks' left edge within it
    /// and the bottom block's top row.
    goal_x: usize,
    goal_side: usize,
    goal_block: usize,
    goal_left: usize,
    goal_bottom: usize,
}

impl<'a> PaperScreen<'a> {
    fn of(obs: &'a Observation) -> PaperScreen<'a> {
        let (width, height) = (obs.grid.width() * PAPER_CELL, obs.grid.height() * PAPER_CELL);
        let side = width / 5;
        let block = (side / 10).max(1);
        PaperScreen {
            obs,
            width,
            height,
            goal_x: width - side,
            goal_side: side,
            goal_block: block,
            goal_left: (side - block) / 2,
            goal_bottom: side.saturating_sub(2 * block),
        }
    }

    /// Writes screen row `y` (0 at the top) into `row`, which is [`PaperScreen::width`] long.
    fn row(&self, y: usize, row: &mut [[u8; 3]]) {
        let fill = |row: &mut [[u8; 3]], x: usize, width: usize, rgb: [u8; 3]| {
            row[x.min(self.width)..(x + width).min(self.width)].fill(rgb);
        };
        row.fill([0, 0, 0]);
        // Screen rows grow downward, grid rows upward.
        let grid_row = self.obs.grid.height() - 1 - y / PAPER_CELL;
        for (i, &c) in self.obs.blocks().iter().enumerate() {
            if usize::from(c.y) != grid_row {
                continue;
            }
            let b = BlockId::of(i);
            let rgb = if self.obs.held_block() == Some(b) {
                PIXELS_HELD
            } else {
                crate::render::colour(b)
            };
            fill(row, usize::from(c.x) * PAPER_CELL, PAPER_CELL, rgb);
        }
        if y >= self.goal_side {
            return;
        }
        fill(row, self.goal_x, self.goal_side, PIXELS_GOAL_BACKGROUND);
        for (place, &b) in self.obs.goal.order().iter().enumerate() {
            let Some(top) = self.goal_bottom.checked_sub(self.goal_block * place) else {
                continue;
            };
            if (top..top + self.goal_block).contains(&y) {
                fill(
                    row,
                    self.goal_x + self.goal_left,
                    self.goal_block,
                    crate::render::colour(b),
                );
            }
        }
    }
}

/// `screen` resized to `dw x dh` by bilinear interpolation with OpenCV's pixel-centre
/// convention (`cv2.resize`'s default `INTER_LINEAR`), rounded to bytes.
fn bilinear(screen: &PaperScreen<'_>, dw: usize, dh: usize) -> Vec<u8> {
    let (sw, sh) = (screen.width, screen.height);
    // For each destination coordinate: the two source indices and the second's weight.
    let taps = |d: usize, s: usize| -> Vec<(usize, usize, f32)> {
        let scale = s as f32 / d as f32;
        (0..d)
            .map(|i| {
                let x = ((i as f32 + 0.5) * scale - 0.5).max(0.0);
                let x0 = (x.floor() as usize).min(s - 1);
                let x1 = (x0 + 1).min(s - 1);
                (x0, x1, x - x0 as f32)
            })
            .collect()
    };
    let (xs, ys) = (taps(dw, sw), taps(dh, sh));
    let (mut upper, mut lower) = (vec![[0u8; 3]; sw], vec![[0u8; 3]; sw]);
    let mut out = Vec::with_capacity(dw * dh * 3);
    for &(y0, y1, fy) in &ys {
        screen.row(y0, &mut upper);
        screen.row(y1, &mut lower);
        for &(x0, x1, fx) in &xs {
            let [a, b, c, d] = [upper[x0], upper[x1], lower[x0], lower[x1]];
            // Most of the screen is flat (the background, a cell's inside): there the
            // weighted sum is `a` up to a rounding error far below half a unit, so it
            // rounds to `a`.
            if a == b && a == c && a == d {
                out.extend_from_slice(&a);
                continue;
            }
            for ch in 0..3 {
                let top = f32::from(a[ch]) * (1.0 - fx) + f32::from(b[ch]) * fx;
                let low = f32::from(c[ch]) * (1.0 - fx) + f32::from(d[ch]) * fx;
                out.push((top * (1.0 - fy) + low * fy).round() as u8);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Goal 1,0,2 on 7 x 7: block 1 at (0, 0), block 0 held at (3, 3), block 2 at (6, 6),
    /// the top-right cell, under the goal picture.
    fn hand_built() -> Observation {
        let cells = [Cell::new(3, 3), Cell::new(0, 0), Cell::new(6, 6)];
        Observation {
            grid: Grid::default(),
            state: State::new(&cells, Some(BlockId(0))).unwrap(),
            goal: "1,0,2".parse().unwrap(),
            protocol: ActionProtocol::Free,
            view: crate::View::Top,
        }
    }

    #[test]
    fn role_planes_name_blocks_by_their_place_in_the_goal() {
        let p = hand_built().role_planes();
        assert_eq!((p.width, p.height, p.channels), (7, 7, 4));
        // Place 0 is block 1, place 1 block 0 (held), place 2 block 2.
        assert_eq!(p.get(0, 0, 0), 1);
        assert_eq!(p.get(3, 3, 1), 1);
        assert_eq!(p.get(6, 6, 2), 1);
        assert_eq!(p.get(3, 3, 3), 1);
        assert_eq!(p.data.iter().map(|&v| u32::from(v)).sum::<u32>(), 4);
    }

    #[test]
    fn pixels_are_the_papers_screen_scaled_to_100_by_100() {
        let obs = hand_built();
        let px = obs.pixels();
        assert_eq!((px.width, px.height, px.data.len()), (100, 100, 100 * 100 * 3));
        // 350 px scaled to 100: a cell is 100/7 pixels; sample the middle of cells.
        let centre = |x: usize, y: usize| {
            let c = |i: usize| ((i as f32 + 0.5) * 100.0 / 7.0) as usize;
            px.rgb(c(x), c(6 - y))
        };
        assert_eq!(centre(3, 3), PIXELS_HELD, "the held block is white");
        assert_eq!(centre(0, 0), crate::render::colour(BlockId(1)));
        assert_eq!(centre(5, 0), [0, 0, 0], "the background is black");
        // The goal picture: the top-right fifth of the screen (20 x 20 pixels), gray,
        // drawn over block 2's cell; its blocks are 7 screen pixels = 2 image pixels.
        assert_eq!(px.rgb(81, 1), PIXELS_GOAL_BACKGROUND);
        assert_eq!(px.rgb(98, 18), PIXELS_GOAL_BACKGROUND);
        // Goal blocks, bottom first, at screen rows 56, 49, 42 and columns 311-317.
        let goal_pixel = |place: usize| px.rgb(90, ((56 - 7 * place) as f32 + 3.5) as usize * 100 / 350);
        for (place, &b) in obs.goal.order().iter().enumerate() {
            assert_eq!(goal_pixel(place), crate::render::colour(b), "goal place {place}");
        }
        // The picture hides block 2 (the top-right cell) whole, as on the authors' screen.
        assert_eq!(centre(6, 6), PIXELS_GOAL_BACKGROUND);
        assert_eq!(centre(6, 5), [0, 0, 0]);
        // Nothing held: the block shows its own colour.
        let mut dropped = obs;
        dropped.state = dropped.state.with_held(None).unwrap();
        assert_eq!(
            dropped.pixels().rgb(50, 50),
            crate::render::colour(BlockId(0)),
            "block 0 at the centre"
        );
    }

    proptest::proptest! {
        /// The shortcut in `bilinear`: four equal neighbours give their own value, whatever
        /// the weights, exactly as the full weighted sum rounds.
        #[test]
        fn four_equal_neighbours_round_to_their_own_value(v in 0u8..=255, fx in 0.0f32..1.0, fy in 0.0f32..1.0) {
            let v32 = f32::from(v);
            let top = v32 * (1.0 - fx) + v32 * fx;
            let low = v32 * (1.0 - fx) + v32 * fx;
            proptest::prop_assert_eq!((top * (1.0 - fy) + low * fy).round() as u8, v);
        }
    }
}
