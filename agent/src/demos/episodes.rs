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

use super::admission::{Admission, Admitted};
use super::format::{DemoFile, EpisodeLine, ParticipantLine, SessionLine, WorldLine, demos_error};
use super::replay::{BadLines, DemoLearner, StepTime, replay_reader};
use crate::error::{AgentError, Result};
use crate::rule::{CorrectionRule, Experience};

/// One step of a [`DemoEpisode`].
#[derive(Clone, Debug, PartialEq)]
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
    /// When it happened, in a timed session (a person's, recording version 3).
    pub time: StepTime,
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
    /// In a timed session: the wall-clock time (Unix milliseconds) of its first view.
    pub started_ms: Option<u64>,
    /// The study participant whose session it is, when the recording names one.
    pub participant: Option<ParticipantLine>,
    /// The session's world (reward, protocol, horizon), when the recording names it.
    pub world: Option<WorldLine>,
}

impl DemoEpisode {
    /// The states the episode passes through, `start` first (one more than the steps).
    pub fn states(&self) -> Vec<State> {
        std::iter::once(self.start.clone())
            .chain(self.steps.iter().map(|s| s.state.clone()))
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
                    state: s.state.clone(),
                    reward: s.reward,
                    terminated: s.terminated,
                    truncated: s.truncated,
                    demonstrated: true,
                    time: StepTime::default(),
                })
                .collect(),
            started_ms: None,
            participant: None,
            world: None,
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
    /// The participant the current session names.
    participant: Option<ParticipantLine>,
    /// The world the current session names.
    session_world: Option<WorldLine>,
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

    fn begin_session(&mut self, header: &SessionLine) -> Result<()> {
        self.participant = header.participant.clone();
        self.session_world = header.world.clone();
        Ok(())
    }

    fn begin_episode(&mut self, header: &EpisodeLine, start: &Observation) -> Result<()> {
        self.episodes.push(DemoEpisode {
            episode: header.episode,
            grid: start.grid,
            view: start.view,
            goal: start.goal.clone(),
            start: start.state.clone(),
            steps: Vec::new(),
            started_ms: header.started_ms,
            participant: self.participant.clone(),
            world: self.session_world.clone(),
        });
        Ok(())
    }

    fn learn(&mut self, _rule: &CorrectionRule, step: &Experience, time: StepTime) -> Result<()> {
        let episode = self.episodes.last_mut().expect("the replay begins an episode first");
        episode.steps.push(DemoStep {
            action: step.action,
            state: step.next.state.clone(),
            reward: step.reward,
            terminated: step.terminated,
            truncated: step.truncated,
            demonstrated: step.corrected,
            time,
        });
        Ok(())
    }
}

/// Everything read from a file of demonstrations ([`read_demonstrations`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Demonstrations {
    /// The episodes, in file order (one cut off by a kill is there with the steps it had).
    pub episodes: Vec<DemoEpisode>,
    /// The recording says its participant withdrew: exports leave it out.
    pub withdrawn: bool,
    /// The lines that could not be used, skipped (a line cut off by a kill, say).
    pub bad_lines: Vec<super::replay::BadLine>,
}

/// The demonstrations at `path` as the researcher's tools read them: every line checked,
/// a bad one skipped and reported (the last line of a recording a kill cut short), a file
/// with no step read as no episode's steps, and whether the participant withdrew. `world`
/// as for [`read_episodes`].
pub fn read_demonstrations(path: &Path, world: Option<(Grid, usize)>) -> Result<Demonstrations> {
    let one = OneWorld {
        world,
        given: world.is_some(),
    };
    match super::format::open(path)? {
        DemoFile::Recording(input) => {
            let mut collector = Collector {
                world: std::cell::Cell::new(one),
                episodes: Vec::new(),
                participant: None,
                session_world: None,
            };
            let mut replay = super::replay::Replay::new(&mut collector, BadLines::Skip, &path.display().to_string());
            replay.read(input)?;
            let report = replay.finish();
            Ok(Demonstrations {
                episodes: collector.episodes,
                withdrawn: report.withdrawn,
                bad_lines: report.bad_lines,
            })
        }
        file @ DemoFile::Trajectory(_) => Ok(Demonstrations {
            episodes: episodes_of(file, path, world)?,
            withdrawn: false,
            bad_lines: Vec::new(),
        }),
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
    Ok(collect_episodes(file, path, world, &Admission::default())?.0)
}

/// The episodes of `file` (named `path` in errors), as [`read_episodes`] reads them, its
/// sessions checked by `admission`; and whether the recording says its participant
/// withdrew.
pub(crate) fn collect_episodes(
    file: DemoFile,
    path: &Path,
    world: Option<(Grid, usize)>,
    admission: &Admission,
) -> Result<(Vec<DemoEpisode>, bool)> {
    let mut one = OneWorld {
        world,
        given: world.is_some(),
    };
    match file {
        DemoFile::Recording(input) => {
            let mut collector = Collector {
                world: std::cell::Cell::new(one),
                episodes: Vec::new(),
                participant: None,
                session_world: None,
            };
            let report = replay_reader(&mut collector, input, path, BadLines::Fail, admission)?;
            Ok((collector.episodes, report.withdrawn))
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
            Ok((episodes, false))
        }
    }
}

/// The episodes of the demonstrations file at `path` (a recording or a trajectory file,
/// every line checked, as `read_episodes` reads them) when `admission` takes it (module
/// docs).
pub fn read_admitted(path: &Path, admission: &Admission) -> Result<Admitted<Vec<DemoEpisode>>> {
    let world = admission.world.and_then(|w| w.grid.zip(w.blocks));
    let (episodes, withdrawn) = collect_episodes(super::format::open(path)?, path, world, admission)?;
    if let Some(run) = admission.world
        && let Some(e) = episodes.iter().find(|e| run.view.is_some_and(|v| v != e.view))
    {
        // A trajectory file names its view per episode (a recording's session was checked).
        return Err(demos_error(
            path,
            &format!(
                "episode {}: the file is of the {} view; this run is of {run}",
                e.episode, e.view
            ),
        ));
    }
    let note = admission.withdrawal(path, withdrawn)?;
    Ok(Admitted { read: episodes, note })
}
