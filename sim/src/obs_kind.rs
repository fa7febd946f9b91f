//! The observation vocabulary: one name per array an agent can be shown.
//!
//! An [`Observation`] is the whole state of a step; learners outside the tabular ones see
//! it as an array. Every layer (the CLI, the networks, Python, the docs) names those arrays
//! with the words of [`ObsKind`], so that one name always means one array:
//!
//! | name | array | shape |
//! |---|---|---|
//! | `planes` | block-id planes ([`Observation::planes`]) | `W x H x (N + 1)`, 0/1 |
//! | `role-planes` | planes by goal place ([`Observation::role_planes`]) | `W x H x (N + 1)`, 0/1 |
//! | `frame` | the rendered picture ([`crate::render::frame`]) | `height x width x 3`, RGB |
//! | `paper-screen` | the paper's DQN input ([`Observation::pixels`]) | `100 x 100 x 3`, RGB |
//! | `screen` | the compact screen, blocks coloured by goal place ([`crate::screen`]) | `4H x 4W x 3`, RGB |
//! | `state` | block cells, held block and goal, as integers | (not one array) |
//!
//! Earlier releases called two of these by other names: `pixels` meant the frame in Python
//! and the paper's screen in the networks. Both spellings are refused with a message that
//! names the new ones, so that no old script silently trains on the other picture.

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::grid::Grid;
use crate::grid::MAX_CELLS;
use crate::observation::{Observation, PIXELS_SIDE};
use crate::render::{CELL_PIXELS, frame_size, picture_size};
use crate::screen::ScreenGoal;
use crate::state::MAX_BLOCKS;

/// Which array an observation is shown as (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObsKind {
    /// Block-id planes: plane `i < N` marks block `i`, plane `N` the held block.
    #[default]
    Planes,
    /// Planes by goal place: plane `p < N` marks the block at place `p` of the goal.
    RolePlanes,
    /// The rendered picture, as `blockstack render` draws it.
    Frame,
    /// The paper's 100 x 100 x 3 screen.
    PaperScreen,
    /// The compact screen of the `pixels` networks: 4 pixels a cell, every block in the
    /// colour of its place in the goal ([`crate::screen`]).
    Screen,
    /// Block cells, held block and goal, as integers (no single array).
    State,
}

crate::names!(ObsKind {
    Planes = "planes",
    RolePlanes = "role-planes",
    Frame = "frame",
    PaperScreen = "paper-screen",
    Screen = "screen",
    State = "state",
} unknown(name) -> SimError {
    SimError::Parse {
        what: "observation kind",
        text: name.to_string(),
        reason: match name {
            "pixels" => "\"pixels\" named two different pictures in earlier releases: choose frame (the rendered \
                         picture, Python's old \"pixels\") or paper-screen (the paper's 100 x 100 input, the \
                         networks' old \"pixels\")"
                .to_string(),
            _ => format!("choose one of {}", ObsKind::NAMES.join(", ")),
        },
    }
});

impl ObsKind {
    /// The shape of this kind's `u8` array in a world of `blocks` blocks on `grid`, or
    /// `None` for `state`, which is not one array.
    pub fn shape(self, grid: Grid, blocks: usize) -> Option<[usize; 3]> {
        let (w, h) = (grid.width(), grid.height());
        match self {
            ObsKind::Planes | ObsKind::RolePlanes => Some([w, h, blocks + 1]),
            ObsKind::Frame => {
                let (fw, fh) = frame_size(grid, blocks, CELL_PIXELS);
                Some([fh as usize, fw as usize, 3])
            }
            ObsKind::PaperScreen => Some([PIXELS_SIDE, PIXELS_SIDE, 3]),
            ObsKind::Screen => Some(ScreenGoal::Colours.shape(grid)),
            ObsKind::State => None,
        }
    }

    /// An error if this array of a world of `blocks` blocks on `grid` is past its bound:
    /// the planes (and the paper's screen, drawn from them) are `W x H` arrays of the top
    /// view's size, at most [`MAX_CELLS`] cells and [`MAX_BLOCKS`] blocks (a side-view world
    /// of 1,000 blocks would make planes of a billion values); the frame is a picture of at
    /// most [`crate::render::MAX_PICTURE_PIXELS`]. `state` has no bound.
    pub fn check(self, grid: Grid, blocks: usize) -> Result<()> {
        match self {
            ObsKind::Planes | ObsKind::RolePlanes | ObsKind::PaperScreen
                if grid.cell_count() > MAX_CELLS || blocks > MAX_BLOCKS =>
            {
                Err(SimError::ObsTooLarge {
                    kind: self,
                    width: grid.width(),
                    height: grid.height(),
                    blocks,
                })
            }
            ObsKind::Frame => picture_size(grid, blocks, CELL_PIXELS).map(drop),
            _ => Ok(()),
        }
    }

    /// Writes `obs` as this kind's array into `out`, which holds exactly
    /// [`ObsKind::shape`]'s values; an error for `state` or a buffer of another size.
    pub fn write(self, obs: &Observation, out: &mut [u8]) -> Result<()> {
        let shape = self.shape(obs.grid, obs.state.block_count());
        let fits = shape.is_some_and(|s| s.iter().product::<usize>() == out.len());
        if !fits {
            return Err(SimError::Parse {
                what: "observation buffer",
                text: format!("{} values", out.len()),
                reason: match shape {
                    Some(s) => format!(
                        "a {} observation has {:?} = {} values",
                        self,
                        s,
                        s.iter().product::<usize>()
                    ),
                    None => "a state observation is not one array".into(),
                },
            });
        }
        match self {
            ObsKind::Planes => obs.write_planes(out),
            ObsKind::RolePlanes => out.copy_from_slice(&obs.role_planes().data),
            ObsKind::Frame => out.copy_from_slice(obs.rgb().as_raw()),
            ObsKind::PaperScreen => out.copy_from_slice(&obs.pixels().data),
            ObsKind::Screen => obs.write_screen(ScreenGoal::Colours, out),
            ObsKind::State => unreachable!("refused above: state is not one array"),
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ActionProtocol, BlockId, Cell, State};

    fn obs() -> Observation {
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
    fn every_name_parses_prints_and_serialises_as_itself() {
        for (kind, name) in ObsKind::ALL.into_iter().zip(ObsKind::NAMES) {
            assert_eq!(name.parse::<ObsKind>().unwrap(), kind);
            assert_eq!(kind.to_string(), name);
            assert_eq!(serde_json::to_string(&kind).unwrap(), format!("\"{name}\""));
        }
    }

    #[test]
    fn the_old_ambiguous_name_is_refused_naming_both_new_ones() {
        let err = "pixels".parse::<ObsKind>().unwrap_err().to_string();
        assert!(err.contains("frame") && err.contains("paper-screen"), "{err}");
        let err = "plane".parse::<ObsKind>().unwrap_err().to_string();
        assert!(err.contains("role-planes"), "{err}");
    }

    #[test]
    fn each_array_kind_writes_the_observations_own_array() {
        let o = obs();
        for kind in ObsKind::ALL {
            let Some(shape) = kind.shape(o.grid, 3) else {
                assert!(kind.write(&o, &mut []).is_err());
                continue;
            };
            let mut out = vec![7u8; shape.iter().product()];
            kind.write(&o, &mut out).unwrap();
            let expected = match kind {
                ObsKind::Planes => o.planes().data,
                ObsKind::RolePlanes => o.role_planes().data,
                ObsKind::Frame => o.rgb().into_raw(),
                ObsKind::PaperScreen => o.pixels().data,
                ObsKind::Screen => o.screen(ScreenGoal::Colours),
                ObsKind::State => unreachable!(),
            };
            assert_eq!(out, expected, "{kind}");
            assert!(kind.write(&o, &mut out[1..]).is_err(), "{kind}: a short buffer");
        }
        let frame = o.rgb();
        assert_eq!(
            ObsKind::Frame.shape(o.grid, 3),
            Some([frame.height() as usize, frame.width() as usize, 3])
        );
    }
}
