//! The trajectory file format: JSON Lines, one episode header, then one line per step.
//!
//! ```text
//! {"type":"episode","episode":0,"seed":17,"grid":[7,7],"goal":[0,1,2],"horizon":1000,"start":[[1,2],[4,0],[6,6]]}
//! {"type":"step","episode":0,"step":1,"action":5,"blocks":[[1,2],[4,0],[6,6]],"held":0,"reward":0.0,"terminated":false,"truncated":false}
//! ```
//!
//! A side-view episode's header also says `"view":"side"` (a top-view header leaves the view
//! out, so files written before the side view existed read back as the top view, and top-view
//! files are written as before), and a goal of several towers is written
//! `{"towers":[[0,1],[2]],"blocks":3}` ([`Goal`]'s JSON form).
//!
//! A step line holds the state *after* the action; `step` counts the actions taken in the
//! episode, 1 for the first; `action` is the index of docs/world.md section 2's table; `held` is a
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
//! at the latest. The reward model and the termination rule are not in the file, so
//! [`Outcomes`] keeps every one that agrees with the steps read so far and refuses a step
//! that leaves none: a reward no model gives, or an end flag no rule sets, is invented. A
//! line longer than [`MAX_LINE_BYTES`] is refused at once (the same bound as a
//! demonstration recording's). The last episode of a file cut short (a killed run writing
//! to a FIFO) is handed out as it stands: [`Episode::is_complete`] says so.

use std::io::{BufRead, Read, Write};

use files::{Output, OutputPath};
use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::env::Step;
use crate::error::{Result, SimError};
use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::grid_world::GridWorld;
use crate::protocol::ActionProtocol;
use crate::reward::{RewardModel, Transition};
use crate::state::{BlockId, State};
use crate::termination::Termination;
use crate::view::View;
use crate::world::World;

/// The longest line of a trajectory file, and of a demonstration recording (`agent`'s
/// `demos::format` shares it): 64 KiB (a step line of 16 blocks takes well under 1 KiB).
pub const MAX_LINE_BYTES: u64 = 1 << 16;

/// Reads one line of a JSON Lines file through the bound [`MAX_LINE_BYTES`] into `buf`
/// (cleared first, newline kept): the number of bytes read, 0 at the end. A line longer
/// than the bound stops after `MAX_LINE_BYTES + 1` bytes, so that a device or a binary file
/// is refused at its first line instead of read into memory; the caller refuses it.
pub fn read_bounded_line(input: &mut impl BufRead, buf: &mut Vec<u8>) -> std::io::Result<usize> {
    buf.clear();
    input.take(MAX_LINE_BYTES + 1).read_until(b'\n', buf)
}

/// The reward models and termination rules that could have produced the rewards and end
/// flags a file records (module docs). Files do not name them; every run and session uses
/// one of each, so the candidates only shrink as steps are read.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcomes {
    rewards: Vec<RewardModel>,
    terminations: Vec<Termination>,
}

impl Default for Outcomes {
    /// Every named reward model, and both termination rules.
    fn default() -> Self {
        Outcomes {
            rewards: RewardModel::NAMES
                .iter()
                .map(|n| RewardModel::from_name(n).expect("a named model"))
                .collect(),
            terminations: vec![Termination::Goal, Termination::paper_training()],
        }
    }
}

/// Whether a recorded reward is the computed one: JSON's decimal text may differ from the
/// computed float in its last digit.
fn same_reward(recorded: f64, computed: f64) -> bool {
    (recorded - computed).abs() <= 1e-9 * computed.abs().max(1.0)
}

impl Outcomes {
    /// Checks the recorded `reward` and `terminated` of the step `t` against the candidates
    /// left, and keeps those that agree; an error (why, for a message) if none does.
    pub fn check(&mut self, t: &Transition, reward: f64, terminated: bool) -> std::result::Result<(), String> {
        if !reward.is_finite() {
            return Err(format!("the reward {reward} is not a finite number"));
        }
        let fits: Vec<RewardModel> = self
            .rewards
            .iter()
            .copied()
            .filter(|m| same_reward(reward, m.reward(t)))
            .collect();
        if fits.is_empty() {
            let given: Vec<String> = self.rewards.iter().map(|m| format!("{m} {}", m.reward(t))).collect();
            return Err(format!(
                "the reward {reward} is not what {} for this step ({}): an invented reward?",
                if self.rewards.len() == RewardModel::NAMES.len() {
                    "any reward model gives"
                } else {
                    "the reward model of the earlier steps gives"
                },
                given.join(", ")
            ));
        }
        let holds = t.reaches_goal();
        let ends: Vec<Termination> = self
            .terminations
            .iter()
            .copied()
            .filter(|rule| rule.ends(reward, holds) == terminated)
            .collect();
        if ends.is_empty() {
            let (marked, goal) = if terminated { ("", "not ") } else { ("not ", "") };
            return Err(format!(
                "the step is {marked}marked terminated, though the goal does {goal}hold after it{}",
                if self.terminations.len() == 2 {
                    format!(
                        " and its reward is {}above {}",
                        if reward > Termination::PAPER_TRAINING_THRESHOLD {
                            ""
                        } else {
                            "not "
                        },
                        Termination::PAPER_TRAINING_THRESHOLD
                    )
                } else {
                    String::new()
                }
            ));
        }
        self.rewards = fits;
        self.terminations = ends;
        Ok(())
    }
}

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
        /// The goal: one tower bottom to top, or towers.
        goal: Goal,
        /// The horizon.
        horizon: u32,
        /// Every block's start cell `[x, y]`, by block id.
        start: Vec<[u16; 2]>,
        /// The world: written only for the side view.
        #[serde(default, skip_serializing_if = "is_top")]
        view: View,
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
        blocks: Vec<[u16; 2]>,
        /// The held block after the action.
        held: Option<u16>,
        /// The reward.
        reward: f64,
        /// The goal holds.
        terminated: bool,
        /// The horizon was reached.
        truncated: bool,
    },
}

fn is_top(view: &View) -> bool {
    *view == View::Top
}

fn cells(state: &State) -> Vec<[u16; 2]> {
    state.cells().iter().map(|c| [c.x, c.y]).collect()
}

impl Record {
    /// The header of top-view episode `episode`.
    pub fn episode(episode: u64, seed: u64, grid: Grid, goal: Goal, horizon: u32, start: &State) -> Record {
        Record::episode_in(View::Top, episode, seed, grid, goal, horizon, start)
    }

    /// The header of episode `episode` in `view`.
    pub fn episode_in(
        view: View,
        episode: u64,
        seed: u64,
        grid: Grid,
        goal: Goal,
        horizon: u32,
        start: &State,
    ) -> Record {
        Record::Episode {
            episode,
            seed,
            grid: [grid.width(), grid.height()],
            goal,
            horizon,
            start: cells(start),
            view,
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
    /// The world: seen from above or from the side.
    pub view: View,
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
#[derive(Clone, Debug, PartialEq)]
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
    /// The reward model and termination rule the steps so far agree with.
    outcomes: Outcomes,
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
            outcomes: Outcomes::default(),
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
        let n = read_bounded_line(&mut self.input, &mut buf).map_err(|e| self.error(format!("cannot read: {e}")))?;
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
            view,
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
        let world = GridWorld::new_in(view, grid, start.clone()).map_err(|e| self.error(e.to_string()))?;
        self.next_episode = episode.checked_add(1);
        let ended = self.current.replace((
            Episode {
                episode,
                seed,
                grid,
                view,
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
    fn state(&self, blocks: &[[u16; 2]], held: Option<u16>, grid: Grid, goal: &Goal) -> Result<State> {
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
        let (grid, goal, view) = (open.grid, open.goal.clone(), open.view);
        let previous_action = open.steps.last().map(|s| s.action);
        let action = Action::from_index(action, goal.block_count()).map_err(|e| self.error(e.to_string()))?;
        let state = self.state(&blocks, held, grid, &goal)?;
        let before = self.current.as_ref().expect("an open episode").1.state();
        if view == View::Side {
            // The side view's rules refuse what the world would take as a no-op.
            View::Side
                .check(ActionProtocol::Free, &before, action)
                .map_err(|e| self.error(e.to_string()))?;
        }
        let world = &mut self.current.as_mut().expect("an open episode").1;
        world.act(action).expect("an action of the world's blocks");
        if *world.state_ref() != state {
            let after = world.state();
            return Err(self.error(format!(
                "{action} from {} gives {}, not the recorded {}",
                describe(&before),
                describe(&after),
                describe(&state)
            )));
        }
        let transition = Transition {
            grid,
            view,
            goal: &goal,
            before: &before,
            action,
            previous_action,
            after: &state,
        };
        if let Err(reason) = self.outcomes.check(&transition, reward, terminated) {
            return Err(self.error(reason));
        }
        let (open, _) = self.current.as_mut().expect("an open episode");
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The trajectory files `blockstack run --trajectory` wrote at the release before this
    /// reader served the commands (testkit/fixtures/README.md).
    const FIXTURES: [&str; 4] = [
        "trajectory.jsonl",
        "trajectory-original.jsonl",
        "trajectory-paper.jsonl",
        "trajectory-dense.jsonl",
    ];

    fn fixture(name: &str) -> String {
        testkit::fixture_text(name)
    }

    fn read(text: &str) -> Result<Vec<Episode>> {
        TrajectoryReader::new(text.as_bytes(), "t.jsonl").collect()
    }

    /// The error's message for `text`, which must not read.
    fn refused(text: &str) -> String {
        read(text).expect_err("refused").to_string()
    }

    /// `text` with line `i` (from 0) edited as JSON by `edit`.
    fn edited(text: &str, i: usize, edit: impl Fn(&mut serde_json::Value)) -> String {
        text.lines()
            .enumerate()
            .map(|(k, l)| {
                if k == i {
                    let mut v: serde_json::Value = serde_json::from_str(l).unwrap();
                    edit(&mut v);
                    v.to_string() + "\n"
                } else {
                    format!("{l}\n")
                }
            })
            .collect()
    }

    #[test]
    fn files_written_by_the_previous_release_still_read() {
        for name in FIXTURES {
            let text = fixture(name);
            let episodes = read(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!episodes.is_empty(), "{name}");
            let steps: usize = episodes.iter().map(|e| e.steps.len()).sum();
            let lines = text.lines().count();
            assert_eq!(steps + episodes.len(), lines, "{name}: every line read");
            assert!(episodes.iter().all(Episode::is_complete), "{name}");
        }
    }

    #[test]
    fn an_invented_reward_or_termination_is_refused() {
        let text = fixture("trajectory.jsonl");
        // Line 2 is the first step of episode 0: no goal, reward 0.
        let reward = edited(&text, 1, |v| v["reward"] = 5.0.into());
        let err = refused(&reward);
        assert!(err.contains(":2:") && err.contains("invented reward"), "{err}");
        let ended = edited(&text, 1, |v| v["terminated"] = true.into());
        let err = refused(&ended);
        assert!(err.contains(":2:") && err.contains("marked terminated"), "{err}");
        // The last step of episode 0 reaches the goal: not marking it is refused too (as
        // an episode going on after it, since a rule of rewards above 70 would not end it).
        let last = text.lines().position(|l| l.contains("\"terminated\":true")).unwrap();
        let err = refused(&edited(&text, last, |v| v["terminated"] = false.into()));
        assert!(err.contains("before episode 0 ended"), "{err}");
        // A reward one model gives, but not the model of the earlier steps: the dense
        // reward on a file of sparse rewards.
        let dense = fixture("trajectory-dense.jsonl");
        let err = refused(&edited(&dense, 3, |v| v["reward"] = 0.0.into()));
        assert!(err.contains(":4:") && err.contains("earlier steps"), "{err}");
    }

    #[test]
    fn a_step_after_a_terminated_step_is_refused() {
        let text = fixture("trajectory.jsonl");
        let lines: Vec<&str> = text.lines().collect();
        let last = lines.iter().position(|l| l.contains("\"terminated\":true")).unwrap();
        let mut after: serde_json::Value = serde_json::from_str(lines[last]).unwrap();
        after["step"] = (after["step"].as_u64().unwrap() + 1).into();
        // Picking the held block again: the rules allow it and change nothing.
        after["action"] = 7.into();
        let broken: String = lines[..=last]
            .iter()
            .map(|l| format!("{l}\n"))
            .chain([after.to_string() + "\n"])
            .collect();
        let err = refused(&broken);
        assert!(
            err.contains(&format!(":{}:", last + 2)) && err.contains("ended"),
            "{err}"
        );
    }

    #[test]
    fn a_cell_outside_the_grid_is_refused() {
        let text = fixture("trajectory.jsonl");
        let outside = edited(&text, 1, |v| v["blocks"][0] = serde_json::json!([0, 7]));
        let err = refused(&outside);
        assert!(err.contains(":2:"), "{err}");
        let start = edited(&text, 0, |v| v["start"][1] = serde_json::json!([7, 0]));
        assert!(refused(&start).contains(":1:"));
    }

    #[test]
    fn an_over_long_line_is_refused_at_once() {
        // Valid JSON padded past the bound: refused as too long, not parsed.
        let text = fixture("trajectory.jsonl");
        let long = text.replacen("{\"type\"", &format!("{{{}\"type\"", " ".repeat(70_000)), 1);
        assert!(refused(&long).contains("longer than"));
        // An endless input without a newline: refused after the bound, not read to its end.
        let mut zeros = std::io::BufReader::new(std::io::repeat(0));
        let mut reader = TrajectoryReader::new(&mut zeros, "/dev/zero");
        let err = reader.next().unwrap().unwrap_err().to_string();
        assert!(err.contains(":1:") && err.contains("longer than"), "{err}");
    }

    #[test]
    fn a_plan_replays_into_the_states_it_visits() {
        let episode = &read(&fixture("trajectory.jsonl")).unwrap()[0];
        let actions: Vec<Action> = episode.steps.iter().map(|s| s.action).collect();
        let states = GridWorld::new(episode.grid, episode.start.clone())
            .unwrap()
            .replay(&actions)
            .unwrap();
        assert_eq!(states[0], episode.start);
        assert_eq!(
            states[1..],
            episode.steps.iter().map(|s| s.state.clone()).collect::<Vec<_>>()[..]
        );
        let mut world = GridWorld::new(episode.grid, episode.start.clone()).unwrap();
        assert!(world.replay(&[Action::Pick(BlockId(9))]).is_err());
    }
}
