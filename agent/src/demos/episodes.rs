//! The demonstrated episodes of a file of either kind, a `blockstack-demos` recording or a
//! trajectory file, read by the one checked reader of each ([`Replay`](super::Replay) and
//! `sim::trajectory::TrajectoryReader`). What `neural`'s `--demos-file` and the Python
//! package's `read_recording` learn from, so that both refuse the same files with the same
//! message.
//!
//! A file holds one world (grid and block count): the learner's when one is given, or
//! else the world of its first episode, which every later one must share (a learner of
//! arrays cannot mix them).

use std::path::Path;

use sim::trajectory::Episode;
use sim::{Action, Goal, Grid, Observation, State, View};

use super::format::{DemoFile, demos_error};
use super::replay::{BadLines, DemoLearner, learn_from_reader};
use crate::error::{AgentError, Result};
use crate::rule::{CorrectionRule, Experience};

/// One step of a [`DemoEpisode`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemoStep {
    /// The action taken.
    pub action: Action,
    /// The state after it.
    pub state: State,
    /// The recorded reward.
    pub reward: f64,
    /// The step ended the episode by its termination rule.
    pub terminated: bool,
    /// The step reached the horizon.
    pub truncated: bool,
    /// A demonstrator chose the action: every step of a trajectory file, the corrections
    /// of a recording.
    pub demonstrated: bool,
}

/// One episode of a demonstrations file, checked against the world's rules.
#[derive(Clone, Debug, PartialEq)]
pub struct DemoEpisode {
    /// Its number in its run or session.
    pub episode: u64,
    /// The grid.
    pub grid: Grid,
    /// The view whose rules the steps keep.
    pub view: View,
    /// The goal.
    pub goal: Goal,
    /// The start state.
    pub start: State,
    /// The steps, in order, the first from `start`.
    pub steps: Vec<DemoStep>,
}

impl DemoEpisode {
    /// The states the episode passes through, `start` first (one more than the steps).
    pub fn states(&self) -> Vec<State> {
        std::iter::once(self.start)
            .chain(self.steps.iter().map(|s| s.state))
            .collect()
    }
}

impl From<Episode> for DemoEpisode {
    fn from(e: Episode) -> Self {
        DemoEpisode {
            episode: e.episode,
            grid: e.grid,
            view: e.view,
            goal: e.goal,
            start: e.start,
            steps: e
                .steps
                .iter()
                .map(|s| DemoStep {
                    action: s.action,
                    state: s.state,
                    reward: s.reward,
                    terminated: s.terminated,
                    truncated: s.truncated,
                    demonstrated: true,
                })
                .collect(),
        }
    }
}

/// The world a file's episodes must share.
#[derive(Clone, Copy, Debug)]
struct OneWorld {
    world: Option<(Grid, usize)>,
    /// Whether the world is the learner's (given) or the file's first.
    given: bool,
}

impl OneWorld {
    /// An error unless `blocks` blocks on `grid` is the world; the first world seen is it
    /// when none was given.
    fn check(&mut self, grid: Grid, blocks: usize) -> Result<()> {
        match self.world {
            None => {
                self.world = Some((grid, blocks));
                Ok(())
            }
            Some(w) if w == (grid, blocks) => Ok(()),
            Some((g, b)) if self.given => Err(AgentError::ModelMismatch(format!(
                "the demonstrations have {blocks} blocks on a {grid} grid, the learner plays {b} blocks on a {g} grid"
            ))),
            Some((g, b)) => Err(AgentError::MixedWorlds(format!(
                "{blocks} blocks on a {grid} grid here, {b} blocks on a {g} grid in the first episode: one file holds one world"
            ))),
        }
    }
}

/// Collects a recording's steps into episodes, as the replay begins them.
struct Collector {
    world: std::cell::Cell<OneWorld>,
    episodes: Vec<DemoEpisode>,
}

impl DemoLearner for Collector {
    fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        let mut world = self.world.get();
        let checked = world.check(grid, blocks);
        self.world.set(world);
        checked
    }

    fn identity(&self) -> Option<String> {
        // Not the model a session corrected: every session's steps are demonstrations.
        None
    }

    fn begin_episode(&mut self, episode: u64, start: &Observation) -> Result<()> {
        self.episodes.push(DemoEpisode {
            episode,
            grid: start.grid,
            view: start.view,
            goal: start.goal,
            start: start.state,
            steps: Vec::new(),
        });
        Ok(())
    }

    fn learn(&mut self, _rule: &CorrectionRule, step: &Experience) -> Result<()> {
        let episode = self.episodes.last_mut().expect("the replay begins an episode first");
        episode.steps.push(DemoStep {
            action: step.action,
            state: step.next.state,
            reward: step.reward,
            terminated: step.terminated,
            truncated: step.truncated,
            demonstrated: step.corrected,
        });
        Ok(())
    }
}

/// The episodes of the demonstrations file at `path` (module docs), every line checked
/// (a bad line is an error naming it); `world`, the learner's grid and block count, when
/// the episodes must be of it. An error for a file with no step.
pub fn read_episodes(path: &Path, world: Option<(Grid, usize)>) -> Result<Vec<DemoEpisode>> {
    episodes_of(super::format::open(path)?, path, world)
}

/// The episodes of `file` (named `path` in errors), as [`read_episodes`] reads them.
pub fn episodes_of(file: DemoFile, path: &Path, world: Option<(Grid, usize)>) -> Result<Vec<DemoEpisode>> {
    let mut one = OneWorld {
        world,
        given: world.is_some(),
    };
    match file {
        DemoFile::Recording(input) => {
            let mut collector = Collector {
                world: std::cell::Cell::new(one),
                episodes: Vec::new(),
            };
            learn_from_reader(&mut collector, input, path, BadLines::Fail)?;
            Ok(collector.episodes)
        }
        DemoFile::Trajectory(reader) => {
            let mut episodes = Vec::new();
            for episode in reader {
                // Named as a recording's lines are: the same words for either format.
                let episode = episode.map_err(|e| match e {
                    sim::SimError::Trajectory { line, reason, .. } => {
                        demos_error(path, &format!("line {line}: {reason}"))
                    }
                    other => other.into(),
                })?;
                one.check(episode.grid, episode.goal.block_count())
                    .map_err(|e| demos_error(path, &format!("episode {}: {e}", episode.episode)))?;
                episodes.push(DemoEpisode::from(episode));
            }
            if episodes.iter().all(|e| e.steps.is_empty()) {
                return Err(demos_error(path, "it holds no step to learn from"));
            }
            Ok(episodes)
        }
    }
}
