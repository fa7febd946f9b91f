//! The trajectory file format: JSON Lines, one episode header, then one line per step.
//!
//! ```text
//! {"type":"episode","episode":0,"seed":17,"grid":[7,7],"goal":[0,1,2],"horizon":1000,"start":[[1,2],[4,0],[6,6]]}
//! {"type":"step","episode":0,"step":1,"action":5,"blocks":[[1,2],[4,0],[6,6]],"held":0,"reward":0.0,"terminated":false,"truncated":false}
//! ```
//!
//! A step line holds the state *after* the action; `step` counts the actions taken in the
//! episode, 1 for the first; `action` is the index of SPEC section 2's table; `held` is a
//! block id or `null`. Other tools read this format: it is stable, and a change to it is a
//! change of the format's version in this documentation.

use std::io::Write;

use files::{Output, OutputPath};
use serde::{Deserialize, Serialize};

use crate::env::Step;
use crate::error::Result;
use crate::goal::Goal;
use crate::grid::Grid;
use crate::state::State;

/// One line of a trajectory file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Record {
    /// Written before an episode's steps.
    Episode {
        /// Episode number in the run, from 0.
        episode: u64,
        /// The seed the episode was reset with.
        seed: u64,
        /// `[W, H]`.
        grid: [usize; 2],
        /// The goal, bottom to top.
        goal: Goal,
        /// The horizon.
        horizon: u32,
        /// Every block's start cell `[x, y]`, by block id.
        start: Vec<[u8; 2]>,
    },
    /// One action and the state after it.
    Step {
        /// Episode number in the run.
        episode: u64,
        /// Actions taken in the episode so far, this one included.
        step: u32,
        /// The action's index.
        action: usize,
        /// Every block's cell `[x, y]` after the action, by block id.
        blocks: Vec<[u8; 2]>,
        /// The held block after the action.
        held: Option<u8>,
        /// The reward.
        reward: f64,
        /// The goal holds.
        terminated: bool,
        /// The horizon was reached.
        truncated: bool,
    },
}

fn cells(state: &State) -> Vec<[u8; 2]> {
    state.cells().iter().map(|c| [c.x, c.y]).collect()
}

impl Record {
    /// The header of episode `episode`.
    pub fn episode(episode: u64, seed: u64, grid: Grid, goal: Goal, horizon: u32, start: &State) -> Record {
        Record::Episode {
            episode,
            seed,
            grid: [grid.width(), grid.height()],
            goal,
            horizon,
            start: cells(start),
        }
    }

    /// The line for `step`, the result of the action with index `action`.
    pub fn step(episode: u64, action: usize, step: &Step) -> Record {
        let state = &step.observation.state;
        Record::Step {
            episode,
            step: step.info.steps,
            action,
            blocks: cells(state),
            held: state.held_block().map(|b| b.0),
            reward: step.reward,
            terminated: step.terminated,
            truncated: step.truncated,
        }
    }
}

/// Writes a trajectory file through the output helper: a regular file appears under its
/// name once complete (and not at all if the run fails or is killed); a FIFO, a device or
/// `-` (standard output) receives the lines as they come.
pub struct TrajectoryWriter {
    out: Output,
}

impl TrajectoryWriter {
    /// Starts a trajectory file at `out` (checked before the run began).
    pub fn create(out: &OutputPath) -> Result<Self> {
        Ok(Self { out: out.create()? })
    }

    /// Appends one record.
    pub fn write(&mut self, record: &Record) -> Result<()> {
        let line = serde_json::to_string(record).expect("records serialise");
        writeln!(self.out, "{line}").map_err(|e| self.out.error(&e).into())
    }

    /// Completes the file.
    pub fn finish(self) -> Result<()> {
        Ok(self.out.commit()?)
    }
}
