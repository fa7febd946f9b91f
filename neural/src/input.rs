//! What a network sees: an observation of `sim` turned into a vector of bytes, which a batch
//! turns into floats.
//!
//! The observations themselves come from `sim` ([`sim::Observation::pixels`],
//! [`sim::Observation::role_planes`], [`sim::Observation::screen`]); this module only lays them out for a network and adds
//! the one input transform of the small network, centring (below).
//!
//! # Output columns
//!
//! A network has one output per action. On planes, which name blocks by their place in the
//! goal, a Pick output names a place too (as the `role` table's columns do): column `5 + p`
//! picks the block at place `p` of the episode's goal, so one network serves every goal; so
//! does the compact screen that colours blocks by goal place. On the pictures that show the
//! blocks' own colours (the paper's screen, the compact screen's `strip`), column `5 + i`
//! picks block `i`. [`InputSpec::column`]
//! and [`InputSpec::action`] translate.
//!
//! # Layouts
//!
//! Every input is a `rows x columns x channels` array, channel fastest, stored as bytes
//! (pixels 0-255, planes 0/1) and scaled to `[0, 1]` floats in a batch:
//!
//! - `pixels`: the paper's 100 x 100 RGB screen, rows from the top.
//! - `screen`: the compact screen, `4H x 4W` RGB (`4H x 4(W + 1)` with the goal as a
//!   strip), rows from the top ([`sim::screen`]).
//! - `planes`: the role planes, `W x H x (N + 1)`, "rows" are grid columns `x`.
//! - centred planes (the small network's input): the role planes moved so that the bottom
//!   block of the goal sits at the centre of a `(2W - 1) x (2H - 1)` canvas, plus one plane
//!   marking the canvas cells that lie inside the grid. Every cell of the grid lands on the
//!   canvas wherever the bottom block stands. The task is nearly translation-invariant (a
//!   stack can stand anywhere); centred, two states that differ only by a shift of every
//!   block look the same except for where the walls are, so what a network learns at one
//!   place serves every place. An absolute layout makes it learn every place separately.

pub use sim::ObsKind;
use sim::observation::PIXELS_SIDE;
use sim::{Action, Goal, Grid, Observation, ScreenGoal};

use crate::error::{NeuralError, Result};
use crate::mask::ActionSet;

/// The views a network can read: the role planes, the paper's screen and the compact
/// screen, named as every layer names them ([`sim::ObsKind`]).
pub const NETWORK_OBS: [ObsKind; 3] = [ObsKind::RolePlanes, ObsKind::PaperScreen, ObsKind::Screen];

/// An error unless networks can read `kind` ([`NETWORK_OBS`]).
pub fn check_network_obs(kind: ObsKind) -> Result<()> {
    if NETWORK_OBS.contains(&kind) {
        return Ok(());
    }
    let hint = if kind == ObsKind::Planes {
        " (the networks' `planes` of earlier releases are called role-planes now)"
    } else {
        ""
    };
    Err(NeuralError::Config(format!(
        "a network reads role-planes, paper-screen or screen, not {kind}{hint}"
    )))
}

/// How observations of one world are laid out for one network.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InputSpec {
    /// The view.
    pub kind: ObsKind,
    /// Planes centred on the goal's bottom block (module docs); planes only.
    pub centred: bool,
    /// The grid.
    pub grid: Grid,
    /// Number of blocks.
    pub blocks: usize,
    /// How the compact screen shows the goal (the screen only).
    pub screen: ScreenGoal,
}

impl InputSpec {
    /// The layout; an error for centred pixels.
    pub fn new(kind: ObsKind, centred: bool, grid: Grid, blocks: usize) -> Result<InputSpec> {
        check_network_obs(kind)?;
        if centred && kind != ObsKind::RolePlanes {
            return Err(NeuralError::Config("only planes can be centred".into()));
        }
        Ok(InputSpec {
            kind,
            centred,
            grid,
            blocks,
            screen: ScreenGoal::default(),
        })
    }

    /// `(rows, columns, channels)`.
    pub fn shape(&self) -> (usize, usize, usize) {
        let (w, h, n) = (self.grid.width(), self.grid.height(), self.blocks);
        match (self.kind, self.centred) {
            (ObsKind::PaperScreen, _) => (PIXELS_SIDE, PIXELS_SIDE, 3),
            (ObsKind::Screen, _) => {
                let [rows, columns, channels] = self.screen.shape(self.grid);
                (rows, columns, channels)
            }
            // Role planes: `InputSpec::new` admits no other kind.
            (_, false) => (w, h, n + 1),
            (_, true) => (2 * w - 1, 2 * h - 1, n + 2),
        }
    }

    /// Values per input.
    pub fn len(&self) -> usize {
        let (r, c, ch) = self.shape();
        r * c * ch
    }

    /// Whether the input is empty (never: every layout has cells).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The factor that turns a byte into the network's float.
    pub fn scale(&self) -> f32 {
        match self.kind {
            ObsKind::PaperScreen | ObsKind::Screen => 1.0 / 255.0,
            _ => 1.0,
        }
    }

    /// An error unless `obs` is of this layout's world.
    pub fn check(&self, obs: &Observation) -> Result<()> {
        if obs.grid != self.grid || obs.state.block_count() != self.blocks || obs.goal.block_count() != self.blocks {
            return Err(NeuralError::Mismatch(format!(
                "the network plays {} blocks on a {} grid, the world has {} blocks on a {} grid",
                self.blocks,
                self.grid,
                obs.state.block_count(),
                obs.grid
            )));
        }
        Ok(())
    }

    /// Appends the input of `obs` (of this layout's world) to `out`.
    pub fn encode(&self, obs: &Observation, out: &mut Vec<u8>) {
        match (self.kind, self.centred) {
            (ObsKind::PaperScreen, _) => out.extend_from_slice(&obs.pixels().data),
            (ObsKind::Screen, _) => {
                let start = out.len();
                out.resize(start + self.len(), 0);
                obs.write_screen(self.screen, &mut out[start..]);
            }
            // Role planes: `InputSpec::new` admits no other kind.
            (_, false) => out.extend_from_slice(&obs.role_planes().data),
            (_, true) => self.encode_centred(obs, out),
        }
    }

    fn encode_centred(&self, obs: &Observation, out: &mut Vec<u8>) {
        let (w, h) = (self.grid.width() as i64, self.grid.height() as i64);
        let (rows, cols, channels) = self.shape();
        let start = out.len();
        out.resize(start + rows * cols * channels, 0);
        let canvas = &mut out[start..];
        let anchor = obs.state.cell(obs.goal.block_at_place(0));
        // Canvas coordinates of grid cell (x, y): shifted so the anchor is at (w-1, h-1).
        let (dx, dy) = (w - 1 - i64::from(anchor.x), h - 1 - i64::from(anchor.y));
        let at = |x: i64, y: i64, ch: usize| (((x + dx) * (2 * h - 1) + (y + dy)) as usize) * channels + ch;
        let planes = obs.role_planes();
        for x in 0..w {
            for y in 0..h {
                for ch in 0..planes.channels {
                    canvas[at(x, y, ch)] = planes.get(x as usize, y as usize, ch);
                }
                canvas[at(x, y, channels - 1)] = 1;
            }
        }
    }

    /// Whether Pick columns name goal places (the role planes, and the compact screen that
    /// colours blocks by goal place) rather than block ids (the other pictures).
    fn by_place(&self) -> bool {
        match self.kind {
            ObsKind::RolePlanes => true,
            ObsKind::Screen => self.screen == ScreenGoal::Colours,
            _ => false,
        }
    }

    /// The output column of `action` under `goal` (module docs).
    pub fn column(&self, goal: &Goal, action: Action) -> usize {
        match action {
            Action::Pick(b) if self.by_place() => 5 + goal.place_of(b),
            a => a.index(),
        }
    }

    /// The action of output column `column` (below `5 + N`) under `goal`.
    pub fn action(&self, goal: &Goal, column: usize) -> Action {
        match Action::from_index(column, self.blocks).expect("a column of this network") {
            Action::Pick(_) if self.by_place() => Action::Pick(goal.block_at_place(column - 5)),
            a => a,
        }
    }

    /// The output columns of the actions allowed in `obs` ([`ActionSet::allowed`]).
    pub fn allowed_columns(&self, obs: &Observation, mask_noops: bool) -> ActionSet {
        let allowed = ActionSet::allowed(obs, mask_noops);
        if !self.by_place() {
            return allowed;
        }
        ActionSet::from_indices(allowed.iter().map(|a| {
            self.column(
                &obs.goal,
                Action::from_index(a, self.blocks).expect("an allowed action"),
            )
        }))
    }

    /// The inputs of `observations` as floats, one row each.
    pub fn batch(&self, observations: &[&Observation]) -> Vec<f32> {
        let mut bytes = Vec::with_capacity(observations.len() * self.len());
        for obs in observations {
            self.encode(obs, &mut bytes);
        }
        let scale = self.scale();
        bytes.into_iter().map(|b| f32::from(b) * scale).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{BlockId, Cell, State};

    fn obs(cells: [Cell; 3], held: Option<u16>) -> Observation {
        Observation {
            grid: Grid::default(),
            state: State::new(&cells, held.map(BlockId)).unwrap(),
            protocol: sim::ActionProtocol::Free,
            goal: "2,0,1".parse().unwrap(),
            view: sim::View::Top,
        }
    }

    #[test]
    fn centred_planes_are_the_same_for_shifted_states_but_for_the_walls() {
        let spec = InputSpec::new(ObsKind::RolePlanes, true, Grid::default(), 3).unwrap();
        assert_eq!(spec.shape(), (13, 13, 5));
        let a = obs([Cell::new(1, 2), Cell::new(3, 3), Cell::new(1, 1)], Some(0));
        let b = obs([Cell::new(2, 3), Cell::new(4, 4), Cell::new(2, 2)], Some(0));
        let (mut ea, mut eb) = (Vec::new(), Vec::new());
        spec.encode(&a, &mut ea);
        spec.encode(&b, &mut eb);
        assert_eq!(ea.len(), spec.len());
        let blocks_only = |e: &[u8]| e.chunks(5).map(|c| c[..4].to_vec()).collect::<Vec<_>>();
        assert_eq!(blocks_only(&ea), blocks_only(&eb), "the blocks look the same");
        assert_ne!(ea, eb, "the walls do not");
        // The bottom block of the goal (block 2) is at the canvas centre, on plane 0.
        assert_eq!(ea[(6 * 13 + 6) * 5], 1);
        // 49 canvas cells are inside the grid.
        assert_eq!(ea.chunks(5).filter(|c| c[4] == 1).count(), 49);
    }

    #[test]
    fn pick_columns_name_goal_places_on_planes_and_blocks_on_pixels() {
        let planes = InputSpec::new(ObsKind::RolePlanes, true, Grid::default(), 3).unwrap();
        let pixels = InputSpec::new(ObsKind::PaperScreen, false, Grid::default(), 3).unwrap();
        let o = obs([Cell::new(1, 2), Cell::new(3, 3), Cell::new(1, 1)], Some(2));
        // Goal 2,0,1: block 2 at place 0, block 0 at place 1, block 1 at place 2.
        for (block, place) in [(2u16, 0usize), (0, 1), (1, 2)] {
            let pick = sim::Action::Pick(BlockId(block));
            assert_eq!(planes.column(&o.goal, pick), 5 + place);
            assert_eq!(planes.action(&o.goal, 5 + place), pick);
            assert_eq!(pixels.column(&o.goal, pick), 5 + usize::from(block));
        }
        assert_eq!(planes.column(&o.goal, sim::Action::Left), 2);
        // Holding block 2 (place 0): the pick of place 0 changes nothing.
        let cols: Vec<usize> = planes.allowed_columns(&o, true).iter().collect();
        assert!(!cols.contains(&5) && cols.contains(&6) && cols.contains(&7), "{cols:?}");
        let acts: Vec<usize> = pixels.allowed_columns(&o, true).iter().collect();
        assert!(!acts.contains(&7) && acts.contains(&5), "{acts:?}");
    }

    #[test]
    fn the_compact_screen_is_the_states_picture_and_names_picks_as_it_colours_them() {
        let o = obs([Cell::new(1, 2), Cell::new(3, 3), Cell::new(1, 1)], Some(2));
        for (screen, shape, by_place) in [
            (ScreenGoal::Colours, (28, 28, 3), true),
            (ScreenGoal::Strip, (28, 32, 3), false),
        ] {
            let spec = InputSpec {
                screen,
                ..InputSpec::new(ObsKind::Screen, false, Grid::default(), 3).unwrap()
            };
            assert_eq!(spec.shape(), shape);
            let mut bytes = Vec::new();
            spec.encode(&o, &mut bytes);
            assert_eq!(bytes, o.screen(screen), "{screen}");
            assert_eq!(bytes.len(), spec.len());
            // Goal 2,0,1: block 0 is at place 1.
            let pick = sim::Action::Pick(BlockId(0));
            assert_eq!(spec.column(&o.goal, pick), if by_place { 6 } else { 5 }, "{screen}");
            assert_eq!(spec.action(&o.goal, spec.column(&o.goal, pick)), pick);
        }
        assert!(InputSpec::new(ObsKind::Screen, true, Grid::default(), 3).is_err());
    }

    #[test]
    fn pixels_cannot_be_centred_and_batches_scale_to_unit_floats() {
        assert!(InputSpec::new(ObsKind::PaperScreen, true, Grid::default(), 3).is_err());
        let spec = InputSpec::new(ObsKind::PaperScreen, false, Grid::default(), 3).unwrap();
        let o = obs([Cell::new(1, 2), Cell::new(3, 3), Cell::new(1, 1)], None);
        let batch = spec.batch(&[&o, &o]);
        assert_eq!(batch.len(), 2 * 30_000);
        assert!(batch.iter().all(|v| (0.0..=1.0).contains(v)));
    }
}
