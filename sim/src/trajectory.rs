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
//!
//! # Reading
//!
//! [`TrajectoryReader`] reads a file back episode by episode (memory grows with one
//! episode, never with the file) and checks it against the world's rules, so that what it
//! hands out is a trajectory that could have happened: a header's grid, goal and start fit
//! together; episodes are numbered one after the other; a step belongs to the episode
//! just opened, its number is the previous one plus one, its action exists, and its state
//! is what the rules ([`World::act`] on a [`GridWorld`]) make of the previous state and
//! the action; no step comes after the episode ended, and the episode ends at its horizon
//! at the latest; rewards are finite. The reward model and the termination rule are not in
//! the file, so rewards and end flags are checked only that far. A line longer than
//! [`MAX_LINE_BYTES`] is refused. The last episode of a file cut short (a killed run
//! writing to a FIFO) is handed out as it stands: [`Episode::is_complete`] says so.

use std::io::{BufRead, Read, Write};

use files::{Output, OutputPath};
use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::env::Step;
use crate::error::{Result, SimError};
use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::grid_world::GridWorld;
use crate::state::{BlockId, State};
use crate::world::World;

/// The longest line of a trajectory file: 64 KiB (a step line of 16 blocks takes a few
/// hundred bytes).
pub const MAX_LINE_BYTES: u64 = 1 << 16;

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

/// One episode read back from a trajectory file, checked (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Episode {
    /// Episode number in the run.
    pub episode: u64,
    /// The seed the episode was reset with.
    pub seed: u64,
    /// The grid.
    pub grid: Grid,
    /// The goal.
    pub goal: Goal,
    /// The horizon.
    pub horizon: u32,
    /// The start state (nothing held).
    pub start: State,
    /// The steps, in order.
    pub steps: Vec<EpisodeStep>,
}

impl Episode {
    /// Whether the episode ended (its last step terminated or truncated it); a file cut
    /// short may end with an episode that did not.
    pub fn is_complete(&self) -> bool {
        self.steps.last().is_some_and(|s| s.terminated || s.truncated)
    }
}

/// One step of an [`Episode`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EpisodeStep {
    /// The action taken.
    pub action: Action,
    /// The state after it.
    pub state: State,
    /// The reward.
    pub reward: f64,
    /// The episode ended by its termination rule.
    pub terminated: bool,
    /// The horizon was reached.
    pub truncated: bool,
}

/// Reads a trajectory file episode by episode, checking every line (module docs). An
/// iterator of episodes; the first error ends it.
pub struct TrajectoryReader<R> {
    input: R,
    name: String,
    line: usize,
    /// The episode being read, with the world replaying it.
    current: Option<(Episode, GridWorld)>,
    /// The number the next episode must have.
    next_episode: Option<u64>,
    failed: bool,
}

impl<R: BufRead> TrajectoryReader<R> {
    /// A reader of `input`, named `name` in errors.
    pub fn new(input: R, name: &str) -> Self {
        TrajectoryReader {
            input,
            name: name.into(),
            line: 0,
            current: None,
            next_episode: None,
            failed: false,
        }
    }

    fn error(&self, reason: impl Into<String>) -> SimError {
        SimError::Trajectory {
            name: self.name.clone(),
            line: self.line,
            reason: reason.into(),
        }
    }

    /// The next line, without its newline; `None` at the end.
    fn next_line(&mut self) -> Result<Option<String>> {
        let mut buf = Vec::new();
        let n = (&mut self.input)
            .take(MAX_LINE_BYTES + 1)
            .read_until(b'\n', &mut buf)
            .map_err(|e| self.error(format!("cannot read: {e}")))?;
        if n == 0 {
            return Ok(None);
        }
        self.line += 1;
        if n as u64 > MAX_LINE_BYTES {
            return Err(self.error(format!(
                "the line is longer than {}, the longest a trajectory line can be: is this a trajectory file?",
                files::Bytes(MAX_LINE_BYTES)
            )));
        }
        let text = String::from_utf8(buf).map_err(|_| self.error("the line is not UTF-8 text"))?;
        Ok(Some(text.trim_end_matches(['\n', '\r']).to_string()))
    }

    /// Opens an episode from its header.
    fn header(&mut self, record: Record) -> Result<Option<Episode>> {
        let Record::Episode {
            episode,
            seed,
            grid,
            goal,
            horizon,
            start,
        } = record
        else {
            unreachable!("called with a header");
        };
        if let Some((open, _)) = self.current.as_ref().filter(|(e, _)| !e.is_complete()) {
            return Err(self.error(format!(
                "episode {episode} begins before episode {} ended",
                open.episode
            )));
        }
        if let Some(expected) = self.next_episode.filter(|&e| e != episode) {
            return Err(self.error(format!("episode {episode} follows episode {}", expected - 1)));
        }
        let grid = Grid::new(grid[0], grid[1]).map_err(|e| self.error(e.to_string()))?;
        goal.check_fits(grid).map_err(|e| self.error(e.to_string()))?;
        if horizon == 0 {
            return Err(self.error(SimError::ZeroHorizon.to_string()));
        }
        let start = self.state(&start, None, grid, &goal)?;
        let world = GridWorld::new(grid, start).map_err(|e| self.error(e.to_string()))?;
        self.next_episode = episode.checked_add(1);
        let ended = self.current.replace((
            Episode {
                episode,
                seed,
                grid,
                goal,
                horizon,
                start,
                steps: Vec::new(),
            },
            world,
        ));
        Ok(ended.map(|(e, _)| e))
    }

    /// A recorded state, checked against the grid and the goal's block count.
    fn state(&self, blocks: &[[u8; 2]], held: Option<u8>, grid: Grid, goal: &Goal) -> Result<State> {
        if blocks.len() != goal.block_count() {
            return Err(self.error(format!(
                "the state has {} blocks and the goal {}",
                blocks.len(),
                goal.block_count()
            )));
        }
        let cells: Vec<Cell> = blocks.iter().map(|&[x, y]| Cell::new(x, y)).collect();
        let state = State::new(&cells, held.map(BlockId)).map_err(|e| self.error(e.to_string()))?;
        state.check_fits(grid).map_err(|e| self.error(e.to_string()))?;
        Ok(state)
    }

    /// Adds a step to the open episode, checked against the rules.
    fn step(&mut self, record: Record) -> Result<()> {
        let Record::Step {
            episode,
            step,
            action,
            blocks,
            held,
            reward,
            terminated,
            truncated,
        } = record
        else {
            unreachable!("called with a step");
        };
        let Some((open, _)) = &self.current else {
            return Err(self.error("a step before any episode line"));
        };
        if open.episode != episode {
            return Err(self.error(format!("a step of episode {episode} in episode {}", open.episode)));
        }
        if open.is_complete() {
            return Err(self.error(format!("a step after episode {episode} ended")));
        }
        let expected = open.steps.len() as u64 + 1;
        if u64::from(step) != expected {
            return Err(self.error(format!("step {step} where step {expected} comes")));
        }
        if step > open.horizon {
            return Err(self.error(format!("step {step} is past the horizon, {}", open.horizon)));
        }
        if step == open.horizon && !(terminated || truncated) {
            return Err(self.error(format!("the episode goes on past its horizon, {}", open.horizon)));
        }
        if truncated && (terminated || step != open.horizon) {
            return Err(self.error(format!(
                "step {step} is marked truncated, which only the last step before the horizon ({}) can be without terminating",
                open.horizon
            )));
        }
        if !reward.is_finite() {
            return Err(self.error(format!("the reward {reward} is not a finite number")));
        }
        let (grid, goal) = (open.grid, open.goal);
        let action = Action::from_index(action, goal.block_count()).map_err(|e| self.error(e.to_string()))?;
        let state = self.state(&blocks, held, grid, &goal)?;
        let (open, world) = self.current.as_mut().expect("an open episode");
        let before = world.state();
        world.act(action).expect("an action of the world's blocks");
        if world.state() != state {
            let after = world.state();
            return Err(self.error(format!(
                "{action} from {} gives {}, not the recorded {}",
                describe(&before),
                describe(&after),
                describe(&state)
            )));
        }
        open.steps.push(EpisodeStep {
            action,
            state,
            reward,
            terminated,
            truncated,
        });
        Ok(())
    }

    fn next_episode(&mut self) -> Result<Option<Episode>> {
        while let Some(text) = self.next_line()? {
            if text.trim().is_empty() {
                continue;
            }
            let record: Record =
                serde_json::from_str(&text).map_err(|e| self.error(format!("not a trajectory line ({e})")))?;
            match record {
                Record::Episode { .. } => {
                    if let Some(ended) = self.header(record)? {
                        return Ok(Some(ended));
                    }
                }
                Record::Step { .. } => self.step(record)?,
            }
        }
        Ok(self.current.take().map(|(e, _)| e))
    }
}

/// `[[x, y], ...] held h` for messages.
fn describe(state: &State) -> String {
    let cells: Vec<String> = state.cells().iter().map(|c| format!("[{},{}]", c.x, c.y)).collect();
    let held = state.held_block().map_or("none".to_string(), |b| b.to_string());
    format!("[{}] held {held}", cells.join(","))
}

impl<R: BufRead> Iterator for TrajectoryReader<R> {
    type Item = Result<Episode>;

    fn next(&mut self) -> Option<Result<Episode>> {
        if self.failed {
            return None;
        }
        let next = self.next_episode();
        self.failed = next.is_err();
        next.transpose()
    }
}
