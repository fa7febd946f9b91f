//! What an environment shows its agent: the full state as a typed struct, and two views of
//! it for learners that want arrays.

use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::protocol::{ActionMask, ActionProtocol};
use crate::state::{BlockId, State};

/// The full observation: grid, every block's cell, the held block, the goal, and the
/// action protocol that says which actions are legal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
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

    /// The actions legal in this state under the environment's protocol.
    #[inline]
    pub fn legal_actions(&self) -> ActionMask {
        self.protocol.legal_actions(&self.state)
    }

    /// A `W x H x (N + 1)` one-hot array: plane `i < N` marks block `i`'s cell, plane `N`
    /// marks the held block's cell (all zero when nothing is held).
    pub fn planes(&self) -> Planes {
        let (w, h, n) = (self.grid.width(), self.grid.height(), self.state.block_count());
        let mut planes = Planes {
            width: w,
            height: h,
            channels: n + 1,
            data: vec![0; w * h * (n + 1)],
        };
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
        let at = |c: Cell, channel: usize| (usize::from(c.x) * h + usize::from(c.y)) * (n + 1) + channel;
        for (i, &c) in self.blocks().iter().enumerate() {
            out[at(c, i)] = 1;
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
