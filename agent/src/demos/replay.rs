//! Replaying recordings into a learner: [`Replay`] applies the recorded steps to any
//! [`DemoLearner`] (the tabular agent is one; `neural` collects demonstrations, the Python
//! package columns of arrays), checking every line, in file order. Started from the same
//! model, a tabular agent ends with the same table as the live session.
//!
//! A line that cannot be used is an error naming its line number; the caller's
//! [`BadLines`] policy says whether to report it and go on or to stop. Such a line is:
//!
//! - not JSON, an unknown field, a line cut off by a kill;
//! - a step or episode before its session line, a step of another episode than the one
//!   just opened, a state that does not fit the world;
//! - a step that breaks the world's rules: its `next` is not what the rules
//!   ([`sim::World::act`]) make of its `state` and `action`, in the view the session line
//!   names (the top view when it names none); in the side view also an action its rules
//!   refuse, which the world would take as a no-op;
//! - a step whose reward or `terminated` flag no reward model or termination rule gives,
//!   or not the one the session's earlier steps agree with ([`sim::trajectory::Outcomes`]);
//! - a step out of order: its number not above the last step's of its episode (a line
//!   written twice), its `state` not the last step's `next` (or the episode's start), or a
//!   step after one that ended the episode; an episode numbered not above the last;
//! - with [`BadLines::Fail`] only, a gap: a step or episode number more than one past the
//!   last. (Skipping a bad line leaves such a gap, so skipping accepts it.)
//!
//! Some problems end the replay whatever the policy, because nothing after them could be
//! learnt from correctly: a file that does not begin with a session line (a model file, a
//! trajectory file, an empty file), a line longer than the bound, a session of another
//! format or version, and a session recorded from another model than the agent being
//! replayed into (its `model_id` is not the agent's identity at that point of the replay:
//! sessions appended one after another each started from the model the previous one
//! left). [`learn_from_file`] refuses a file from which no step was learnt.

use std::io::BufRead;
use std::path::Path;

use sim::reward::Transition;
use sim::trajectory::Outcomes;
use sim::{Action, ActionProtocol, Goal, Grid, GridWorld, Observation, State, View, World};

use super::admission::{Admission, Admitted};
use super::format::{
    DEMOS_FORMAT, DEMOS_VERSION, DemoRecord, EpisodeLine, MAX_LINE_BYTES, RawLine, RecordingLines, SessionLine,
    StepLine, demos_error,
};
use crate::error::{AgentError, Result};
use crate::qlearning::{QAgent, check_fits_table};
use crate::rule::{CorrectionRule, Experience};

/// What to do with a line that cannot be used.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BadLines {
    /// Report it (in [`ReplayReport::bad_lines`]) and go on with the next line.
    #[default]
    Skip,
    /// Stop with an error naming the line.
    Fail,
}

sim::names!(BadLines { Skip = "skip", Fail = "fail" } unknown(text) -> AgentError {
    AgentError::Config(format!("unknown policy {text:?} for bad lines: choose skip or fail"))
});

/// A line that could not be used.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BadLine {
    /// Its number, from 1.
    pub line: usize,
    /// What is wrong with it.
    pub reason: String,
}

/// What a replay did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ReplayReport {
    /// Lines read, blank ones included.
    pub lines: usize,
    /// Sessions begun.
    pub sessions: usize,
    /// Of those, sessions of version 1, which name no model identity: replayed without
    /// checking that they started from the agent.
    pub unchecked_sessions: usize,
    /// Episodes begun.
    pub episodes: usize,
    /// Steps learnt from.
    pub steps: usize,
    /// Of those, corrections.
    pub corrections: usize,
    /// The lines skipped, with why (only with [`BadLines::Skip`]).
    pub bad_lines: Vec<BadLine>,
    /// The recording says its participant withdrew (a `withdrawn` line).
    pub withdrawn: bool,
}

/// Why a line cannot be used, and whether that ends the replay whatever the policy.
struct LineError {
    reason: String,
    fatal: bool,
}

impl LineError {
    fn bad(reason: impl Into<String>) -> Self {
        LineError {
            reason: reason.into(),
            fatal: false,
        }
    }

    fn fatal(reason: impl Into<String>) -> Self {
        LineError {
            reason: reason.into(),
            fatal: true,
        }
    }
}

impl From<AgentError> for LineError {
    fn from(e: AgentError) -> Self {
        LineError::bad(e.to_string())
    }
}

impl From<sim::SimError> for LineError {
    fn from(e: sim::SimError) -> Self {
        LineError::bad(e.to_string())
    }
}

/// The session being replayed.
#[derive(Clone)]
struct OpenSession {
    grid: Grid,
    /// The number its first episode must have.
    first_episode: u64,
    /// The world's view, whose rules every step keeps.
    view: View,
    rule: CorrectionRule,
    /// The number of its last episode line used.
    last_episode: Option<u64>,
    /// The reward model and termination rule its steps so far agree with.
    outcomes: Outcomes,
}

/// The episode being replayed.
#[derive(Clone)]
struct OpenEpisode {
    number: u64,
    goal: Goal,
    /// The number of its last step used (0 before the first).
    last_step: u32,
    /// Where that step left the world (the start before the first).
    state: State,
    /// That step's action (`None` before the first).
    last_action: Option<Action>,
    /// That step ended the episode.
    ended: bool,
}

/// What a replay hands the recorded steps to: the tabular agent, or any other learner (the
/// neural crate collects them as demonstrations).
pub trait DemoLearner {
    /// An error unless a world of `blocks` blocks on `grid` is the learner's.
    fn check_world(&self, grid: Grid, blocks: usize) -> Result<()>;

    /// The identity a session's `model_id` must match ([`QAgent::identity`]), or `None`
    /// for a learner that takes any session's steps as demonstrations (it was not the
    /// model the session corrected, so there is nothing to match).
    fn identity(&self) -> Option<String>;

    /// A session line opened a session (checked: its format, version, world and model).
    /// Learners that keep who played begin a session here; the tabular agent has nothing
    /// to do.
    fn begin_session(&mut self, header: &SessionLine) -> Result<()> {
        let _ = header;
        Ok(())
    }

    /// An episode line (`header`) opened an episode at `start` (its grid, start state, goal
    /// and view), in a world checked to be the learner's: the steps [`DemoLearner::learn`]
    /// gets next are this episode's, in order, the first from `start`. Learners that keep
    /// episodes apart begin one here; the tabular agent has nothing to do.
    fn begin_episode(&mut self, header: &EpisodeLine, start: &Observation) -> Result<()> {
        let _ = (header, start);
        Ok(())
    }

    /// Learns from one recorded step, by the session's `rule`; `time` is the step's, when
    /// its session was timed.
    fn learn(&mut self, rule: &CorrectionRule, step: &Experience, time: StepTime) -> Result<()>;
}

/// When a recorded step happened, in a timed session (the format's module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTime {
    /// Milliseconds since the episode's first view.
    pub t_ms: Option<u64>,
    /// The wall-clock time (Unix milliseconds) the step was received.
    pub received_ms: Option<u64>,
}

impl DemoLearner for QAgent {
    fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        QAgent::check_world(self, grid, blocks)
    }

    fn identity(&self) -> Option<String> {
        Some(QAgent::identity(self))
    }

    fn learn(&mut self, rule: &CorrectionRule, step: &Experience, _time: StepTime) -> Result<()> {
        rule.learn(self, step).map(|_| ())
    }
}

/// Applies recorded sessions to a learner (by default a [`QAgent`]), line by line (module
/// docs).
pub struct Replay<'a, L: ?Sized = QAgent> {
    agent: &'a mut L,
    policy: BadLines,
    /// The world each session must be of ([`Admission::check_session`]).
    admission: Admission,
    name: String,
    session: Option<OpenSession>,
    episode: Option<OpenEpisode>,
    report: ReplayReport,
}

impl<'a, L: DemoLearner + ?Sized> Replay<'a, L> {
    /// A replay into `agent`; `name` (the file's) is used in errors.
    pub fn new(agent: &'a mut L, policy: BadLines, name: &str) -> Self {
        Replay {
            agent,
            policy,
            admission: Admission::default(),
            name: name.into(),
            session: None,
            episode: None,
            report: ReplayReport::default(),
        }
    }

    /// The replay taking only sessions `admission` takes (of the run's world).
    pub fn admitting(mut self, admission: Admission) -> Self {
        self.admission = admission;
        self
    }

    /// Applies every line of `input`; with [`BadLines::Fail`], stops at the first bad line.
    /// A line longer than [`MAX_LINE_BYTES`] stops the replay whatever the policy: the
    /// input is not a recording.
    pub fn read(&mut self, input: impl BufRead) -> Result<()> {
        let mut lines = RecordingLines::new(input);
        loop {
            let line = lines
                .next_line()
                .map_err(|e| demos_error(Path::new(&self.name), &format!("cannot read: {e}")))?;
            let problem = match line {
                None => return Ok(()),
                Some(RawLine::Text(text)) => {
                    self.line(text)?;
                    continue;
                }
                Some(RawLine::TooLong) => LineError::fatal(format!(
                    "the line is longer than {}, the longest a recording line can be: is this a recording?",
                    files::Bytes(MAX_LINE_BYTES)
                )),
                Some(RawLine::CutOff) => {
                    LineError::bad("the line is cut off (no newline at its end: was the session killed?)")
                }
                Some(RawLine::NotText) => LineError::bad("the line is not UTF-8 text"),
            };
            self.report.lines += 1;
            self.bad(problem)?;
        }
    }

    /// Applies one line (its trailing newline may be included).
    pub fn line(&mut self, text: &str) -> Result<()> {
        self.report.lines += 1;
        if text.trim().is_empty() {
            return Ok(());
        }
        match self.apply(text.trim()) {
            Ok(()) => Ok(()),
            Err(e) => self.bad(e),
        }
    }

    /// Reports (or fails on) a bad line, the current one. Before the first session line
    /// every bad line is fatal: the input is not a recording.
    fn bad(&mut self, e: LineError) -> Result<()> {
        let line = self.report.lines;
        if self.report.sessions == 0 && !e.fatal {
            return Err(demos_error(
                Path::new(&self.name),
                &format!(
                    "line {line}: {}; a recording begins with a session line: is this a recording?",
                    e.reason
                ),
            ));
        }
        if e.fatal || self.policy == BadLines::Fail {
            return Err(demos_error(
                Path::new(&self.name),
                &format!("line {line}: {}", e.reason),
            ));
        }
        self.report.bad_lines.push(BadLine { line, reason: e.reason });
        Ok(())
    }

    fn apply(&mut self, text: &str) -> std::result::Result<(), LineError> {
        let record: DemoRecord =
            serde_json::from_str(text).map_err(|e| LineError::bad(format!("not a recording line ({e})")))?;
        match record {
            DemoRecord::Session(s) => self.session(s),
            DemoRecord::Episode(e) => self.episode(e),
            DemoRecord::Step(s) => self.step(s),
            DemoRecord::Withdrawn(_) => {
                self.session
                    .as_ref()
                    .ok_or_else(|| no_header("a withdrawal", "session"))?;
                self.report.withdrawn = true;
                Ok(())
            }
        }
    }

    fn session(&mut self, s: SessionLine) -> std::result::Result<(), LineError> {
        if s.format != DEMOS_FORMAT || !(1..=DEMOS_VERSION).contains(&s.version) {
            return Err(LineError::fatal(format!(
                "it is {} version {}, and this blockstack reads {DEMOS_FORMAT} versions 1 to {DEMOS_VERSION}",
                s.format, s.version
            )));
        }
        let grid = Grid::new(s.grid[0], s.grid[1])?;
        s.rule.validate()?;
        // Nothing of a session of another world than the run's could be learnt.
        self.admission.check_session(&s).map_err(LineError::fatal)?;
        // Nothing of a session for another world could be learnt.
        self.agent
            .check_world(grid, s.blocks)
            .map_err(|e| LineError::fatal(e.to_string()))?;
        match (&s.model_id, s.version) {
            (_, 1) => self.report.unchecked_sessions += 1,
            (None, _) => return Err(LineError::fatal("the session line names no model_id")),
            (Some(_), _) if self.agent.identity().is_none() => {}
            (Some(id), _) => {
                let given = self.agent.identity().unwrap_or_default();
                if *id != given {
                    let file = s.model.as_deref().map_or(String::new(), |m| format!(" {m}"));
                    return Err(LineError::fatal(format!(
                        "the session was recorded from the model{file} with identity {id}, and the model it would be \
                         learnt into has identity {given}: give the model the session started from{}",
                        if self.report.sessions > 0 {
                            " (a session appended after another starts from the model that one left)"
                        } else {
                            ""
                        }
                    )));
                }
            }
        }
        self.agent.begin_session(&s)?;
        self.session = Some(OpenSession {
            grid,
            first_episode: s.first_episode,
            view: s.view,
            rule: s.rule,
            last_episode: None,
            outcomes: Outcomes::default(),
        });
        self.episode = None;
        self.report.sessions += 1;
        Ok(())
    }

    fn episode(&mut self, e: EpisodeLine) -> std::result::Result<(), LineError> {
        let session = self
            .session
            .as_mut()
            .ok_or_else(|| no_header("an episode", "session"))?;
        let start = e.start.state(session.grid)?;
        session.view.check_state(&start)?;
        self.agent.check_world(session.grid, e.goal.block_count())?;
        check_blocks(&start, &e.goal)?;
        match session.last_episode {
            Some(last) if e.episode <= last => {
                return Err(LineError::bad(format!(
                    "episode {} begins after episode {last}: episodes go up one by one (a line written twice?)",
                    e.episode
                )));
            }
            Some(last) if e.episode > last + 1 && self.policy == BadLines::Fail => {
                return Err(LineError::bad(format!(
                    "episode {} begins after episode {last}: the episodes between are missing",
                    e.episode
                )));
            }
            None if e.episode != session.first_episode && self.policy == BadLines::Fail => {
                return Err(LineError::bad(format!(
                    "the session's first episode is {}, not {}: episodes are missing",
                    e.episode, session.first_episode
                )));
            }
            _ => {}
        }
        let first = Observation {
            grid: session.grid,
            state: start.clone(),
            goal: e.goal.clone(),
            protocol: ActionProtocol::Free,
            view: session.view,
        };
        self.agent.begin_episode(&e, &first)?;
        session.last_episode = Some(e.episode);
        self.episode = Some(OpenEpisode {
            number: e.episode,
            goal: e.goal,
            last_step: 0,
            state: start,
            last_action: None,
            ended: false,
        });
        self.report.episodes += 1;
        Ok(())
    }

    fn step(&mut self, s: StepLine) -> std::result::Result<(), LineError> {
        let session = self.session.as_mut().ok_or_else(|| no_header("a step", "session"))?;
        let episode = match self.episode.clone() {
            Some(e) if e.number == s.episode => e,
            _ => return Err(no_header(&format!("a step of episode {}", s.episode), "episode")),
        };
        if episode.ended {
            return Err(LineError::bad(format!(
                "step {} comes after step {}, which ended episode {}",
                s.step, episode.last_step, episode.number
            )));
        }
        if s.step <= episode.last_step {
            return Err(LineError::bad(format!(
                "step {} comes after step {} of episode {}: steps go up one by one (a line written twice?)",
                s.step, episode.last_step, episode.number
            )));
        }
        let follows = s.step == episode.last_step + 1;
        if !follows && self.policy == BadLines::Fail {
            return Err(LineError::bad(format!(
                "step {} comes after step {} of episode {}: the steps between are missing",
                s.step, episode.last_step, episode.number
            )));
        }
        let blocks = episode.goal.block_count();
        let obs = Observation {
            grid: session.grid,
            state: s.state.state(session.grid)?,
            goal: episode.goal.clone(),
            protocol: ActionProtocol::Free,
            view: session.view,
        };
        let next = Observation {
            state: s.next.state(session.grid)?,
            ..obs.clone()
        };
        check_blocks(&obs.state, &episode.goal)?;
        check_blocks(&next.state, &episode.goal)?;
        if follows && obs.state != episode.state {
            return Err(LineError::bad(format!(
                "the step's state is not the one the {} left",
                if episode.last_step == 0 {
                    "episode's start"
                } else {
                    "previous step"
                }
            )));
        }
        let action = Action::parse(&s.action, blocks)?;
        Action::parse(&s.proposed, blocks)?;
        if session.view == View::Side {
            // The side view's rules refuse what the world would take as a no-op (as the
            // trajectory reader does): a session in that view never records one.
            View::Side.check(ActionProtocol::Free, &obs.state, action)?;
        }
        let mut world = GridWorld::new_in(session.view, session.grid, obs.state.clone())?;
        world.act(action)?;
        if world.state() != next.state {
            return Err(LineError::bad(format!(
                "the step breaks the world's rules: {action} does not lead from its state to its next state"
            )));
        }
        check_fits_table("the reward", s.reward)?;
        if follows {
            // The previous action is known only on a step that follows the last one used.
            let transition = Transition {
                grid: session.grid,
                view: obs.view,
                goal: &episode.goal,
                before: &obs.state,
                action,
                previous_action: episode.last_action,
                after: &next.state,
            };
            session
                .outcomes
                .check(&transition, s.reward, s.terminated)
                .map_err(LineError::bad)?;
        }
        self.agent.learn(
            &session.rule,
            &Experience {
                obs,
                action,
                reward: s.reward,
                next: next.clone(),
                terminated: s.terminated,
                truncated: s.truncated,
                corrected: s.correction,
            },
            StepTime {
                t_ms: s.t_ms,
                received_ms: s.received_ms,
            },
        )?;
        self.episode = Some(OpenEpisode {
            last_step: s.step,
            state: next.state,
            last_action: Some(action),
            ended: s.terminated || s.truncated,
            ..episode
        });
        self.report.steps += 1;
        self.report.corrections += usize::from(s.correction);
        Ok(())
    }

    /// What the replay did.
    pub fn finish(self) -> ReplayReport {
        self.report
    }
}

/// An error unless `state` has the goal's block count.
fn check_blocks(state: &State, goal: &Goal) -> std::result::Result<(), LineError> {
    if state.block_count() == goal.block_count() {
        Ok(())
    } else {
        Err(AgentError::from(sim::SimError::BlockCountMismatch {
            expected: goal.block_count(),
            what: "a recorded state",
            found: state.block_count(),
        })
        .into())
    }
}

fn no_header(what: &str, header: &str) -> LineError {
    LineError::bad(format!("{what} before its {header} line"))
}

/// Replays the recording at `path` into `agent` (module docs), reading at most
/// [`MAX_RECORDING_BYTES`](super::format::MAX_RECORDING_BYTES). An error if no step could
/// be learnt from it (an empty file, a file of sessions without steps, or one whose every
/// step was skipped), or if it is a model file.
pub fn learn_from_file<L: DemoLearner + ?Sized>(agent: &mut L, path: &Path, policy: BadLines) -> Result<ReplayReport> {
    super::format::refuse_model_file(path)?;
    let file = files::open_bounded(path, super::format::MAX_RECORDING_BYTES, "a recording")?;
    learn_from_reader(agent, std::io::BufReader::new(file), path, policy)
}

/// Replays the recording read from `input` (named `path` in errors) into `agent`, as
/// [`learn_from_file`] does.
pub fn learn_from_reader<L: DemoLearner + ?Sized>(
    agent: &mut L,
    input: impl BufRead,
    path: &Path,
    policy: BadLines,
) -> Result<ReplayReport> {
    replay_reader(agent, input, path, policy, &Admission::default())
}

/// [`learn_from_reader`], taking only sessions `admission` takes.
pub(crate) fn replay_reader<L: DemoLearner + ?Sized>(
    agent: &mut L,
    input: impl BufRead,
    path: &Path,
    policy: BadLines,
    admission: &Admission,
) -> Result<ReplayReport> {
    let mut replay = Replay::new(agent, policy, &path.display().to_string()).admitting(*admission);
    replay.read(input)?;
    let report = replay.finish();
    if report.steps == 0 {
        let reason = match (report.sessions, report.bad_lines.len()) {
            (0, _) => "it is empty: a recording holds a session line, then episodes and steps".to_string(),
            (_, 0) => "it holds no step to learn from".to_string(),
            (_, bad) => format!("none of its steps could be used ({bad} lines skipped)"),
        };
        return Err(demos_error(path, &reason));
    }
    Ok(report)
}

/// Replays recorded lines into `agent` (the lines of a `Vec<DemoRecord>` sink, say).
pub fn learn_from_records(agent: &mut QAgent, records: &[DemoRecord]) -> Result<ReplayReport> {
    let mut replay = Replay::new(agent, BadLines::Fail, "the records");
    for record in records {
        replay.line(&serde_json::to_string(record).expect("records serialise"))?;
    }
    Ok(replay.finish())
}

/// Replays the recording at `path` into `agent` (as `learn_from_file` does) when
/// `admission` takes it (module docs). A withdrawn recording refused has been replayed
/// into `agent` already: the caller keeps nothing of it.
pub fn learn_admitted<L: DemoLearner + ?Sized>(
    agent: &mut L,
    path: &Path,
    policy: BadLines,
    admission: &Admission,
) -> Result<Admitted<ReplayReport>> {
    super::format::refuse_model_file(path)?;
    let file = files::open_bounded(path, super::format::MAX_RECORDING_BYTES, "a recording")?;
    let report = replay_reader(agent, std::io::BufReader::new(file), path, policy, admission)?;
    let note = admission.withdrawal(path, report.withdrawn)?;
    Ok(Admitted { read: report, note })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::TrainConfig;
    use crate::correction::{CorrectionConfig, correct};
    use crate::demonstrator::DemonstratorProfile;
    use crate::demos::format::DemoWriter;
    use crate::qlearning::QParams;
    use crate::repr::ReprKind;
    use crate::train::train;

    fn trained() -> QAgent {
        let goals: Vec<Goal> = ["0,1,2", "1,0,2"].iter().map(|g| g.parse().unwrap()).collect();
        let config = TrainConfig {
            games: 300,
            ..TrainConfig::paper(goals)
        }
        .with_backend(sim::Backend::Grid);
        train(&config, None).unwrap().agent
    }

    fn session(agent: &QAgent, preset: u8, demos: u64, seed: u64) -> (QAgent, Vec<u8>) {
        let goals: Vec<Goal> = ["0,1,2", "2,1,0"].iter().map(|g| g.parse().unwrap()).collect();
        let config = CorrectionConfig::new(DemonstratorProfile::preset(preset).unwrap(), goals, demos, seed);
        let out = correct(agent.clone(), &config, DemoWriter::new(Vec::new(), "memory")).unwrap();
        (out.agent, out.sink.into_inner())
    }

    #[test]
    fn replaying_a_recording_gives_the_live_sessions_table() {
        let base = trained();
        for preset in 1..=3 {
            let (live, bytes) = session(&base, preset, 4, 3);
            assert_ne!(live, base, "the session learnt something");
            let mut replayed = base.clone();
            let mut replay = Replay::new(&mut replayed, BadLines::Fail, "memory");
            replay.read(&bytes[..]).unwrap();
            let report = replay.finish();
            assert_eq!(report.sessions, 1);
            assert_eq!(report.episodes, 4);
            assert!(report.corrections > 0);
            assert_eq!(replayed, live);
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_session_and_another_seed_another() {
        let base = trained();
        let (a, bytes_a) = session(&base, 2, 3, 5);
        let (b, bytes_b) = session(&base, 2, 3, 5);
        assert_eq!(a, b);
        assert_eq!(bytes_a, bytes_b);
        let (_, bytes_c) = session(&base, 2, 3, 6);
        assert_ne!(bytes_a, bytes_c);
    }

    #[test]
    fn in_memory_records_replay_like_the_file() {
        let base = trained();
        let goals: Vec<Goal> = vec!["1,2,0".parse().unwrap()];
        let config = CorrectionConfig::new(DemonstratorProfile::preset(3).unwrap(), goals, 2, 8);
        let out = correct(base.clone(), &config, Vec::<DemoRecord>::new()).unwrap();
        let mut replayed = base;
        let report = learn_from_records(&mut replayed, &out.sink).unwrap();
        assert_eq!(report.steps as u64, out.report.steps);
        assert_eq!(replayed, out.agent);
    }

    #[test]
    fn bad_lines_are_reported_by_number_or_stop_the_replay() {
        let base = trained();
        let (live, bytes) = session(&base, 1, 2, 4);
        let text = String::from_utf8(bytes).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        // Corrupt line 3 (a step) and cut the last line short.
        let mut broken = String::new();
        for (i, line) in lines.iter().enumerate() {
            if i == 2 {
                broken.push_str("{\"type\":\"step\",\"episode\":0,oops\n");
            } else if i == lines.len() - 1 {
                broken.push_str(&line[..line.len() / 2]);
            } else {
                broken.push_str(line);
                broken.push('\n');
            }
        }
        let mut skipped = base.clone();
        let mut replay = Replay::new(&mut skipped, BadLines::Skip, "broken.jsonl");
        replay.read(broken.as_bytes()).unwrap();
        let report = replay.finish();
        assert_eq!(
            report.bad_lines.iter().map(|b| b.line).collect::<Vec<_>>(),
            vec![3, lines.len()]
        );
        assert!(report.bad_lines[1].reason.contains("cut off"));
        assert_eq!(report.steps, lines.len() - 1 - 2 - 2, "every other step was used");
        assert_ne!(skipped, base);
        let _ = live;

        let mut failed = base.clone();
        let mut replay = Replay::new(&mut failed, BadLines::Fail, "broken.jsonl");
        let err = replay.read(broken.as_bytes()).unwrap_err().to_string();
        assert!(err.contains("broken.jsonl") && err.contains("line 3"), "{err}");
    }

    #[test]
    fn semantic_errors_name_the_line() {
        let mut agent = QAgent::new(ReprKind::Chasing, Grid::default(), 3, QParams::default()).unwrap();
        let session = serde_json::to_string(&DemoRecord::Session(SessionLine::new(
            agent.grid(),
            agent.blocks(),
            agent.identity(),
            CorrectionRule::default(),
            "person",
            None,
        )))
        .unwrap();
        let cases = [
            // A step before any episode line.
            format!(
                "{session}\n{{\"type\":\"step\",\"episode\":0,\"step\":1,\"state\":{{\"blocks\":[[0,0],[1,0],[2,0]],\"held\":null}},\"proposed\":\"up\",\"action\":\"up\",\"correction\":true,\"reward\":0.0,\"next\":{{\"blocks\":[[0,0],[1,0],[2,0]],\"held\":null}},\"terminated\":false,\"truncated\":false}}\n"
            ),
            // A start off the grid.
            format!(
                "{session}\n{{\"type\":\"episode\",\"episode\":0,\"seed\":1,\"goal\":[0,1,2],\"start\":{{\"blocks\":[[9,0],[1,0],[2,0]],\"held\":null}}}}\n"
            ),
            // A four-block goal in a three-block session.
            format!(
                "{session}\n{{\"type\":\"episode\",\"episode\":0,\"seed\":1,\"goal\":[0,1,2,3],\"start\":{{\"blocks\":[[0,0],[1,0],[2,0]],\"held\":null}}}}\n"
            ),
        ];
        for case in cases {
            let mut replay = Replay::new(&mut agent, BadLines::Fail, "x.jsonl");
            let err = replay.read(case.as_bytes()).unwrap_err().to_string();
            assert!(err.contains("line 2"), "{err}");
        }
        // Another version is refused even when skipping bad lines.
        let newer = DEMOS_VERSION + 1;
        let other = session.replace(&format!("\"version\":{DEMOS_VERSION}"), &format!("\"version\":{newer}"));
        let mut replay = Replay::new(&mut agent, BadLines::Skip, "x.jsonl");
        let err = replay.read(other.as_bytes()).unwrap_err().to_string();
        assert!(err.contains(&format!("version {newer}")), "{err}");
    }

    /// A recording's lines, and the same lines with `edit` applied to line `i` (from 0).
    fn edited(bytes: &[u8], i: usize, edit: impl Fn(&str) -> String) -> String {
        let text = String::from_utf8(bytes.to_vec()).unwrap();
        text.lines()
            .enumerate()
            .map(|(k, l)| if k == i { edit(l) } else { l.to_string() } + "\n")
            .collect()
    }

    /// The replay of `text` into `base` with `policy`: the agent, or the error.
    fn replay(base: &QAgent, text: &str, policy: BadLines) -> std::result::Result<(QAgent, ReplayReport), String> {
        let mut agent = base.clone();
        let mut replay = Replay::new(&mut agent, policy, "r.jsonl");
        replay.read(text.as_bytes()).map_err(|e| e.to_string())?;
        let report = replay.finish();
        Ok((agent, report))
    }

    #[test]
    fn a_recording_of_another_model_is_refused_whatever_the_policy() {
        let base = trained();
        let (_, bytes) = session(&base, 1, 2, 4);
        let other = QAgent::new(ReprKind::Chasing, Grid::default(), 3, QParams::default()).unwrap();
        assert_ne!(other.identity(), base.identity());
        for policy in [BadLines::Skip, BadLines::Fail] {
            let err = replay(&other, std::str::from_utf8(&bytes).unwrap(), policy).unwrap_err();
            assert!(err.contains("line 1") && err.contains(&base.identity()), "{err}");
            assert!(err.contains(&other.identity()), "{err}");
        }
        // The same model saved and loaded keeps its identity, and the recording replays.
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let file = dir.join("m.safetensors");
        base.save(&file).unwrap();
        let loaded = QAgent::load(&file).unwrap();
        assert_eq!(loaded.identity(), base.identity());
        assert!(replay(&loaded, std::str::from_utf8(&bytes).unwrap(), BadLines::Fail).is_ok());
    }

    #[test]
    fn a_second_session_must_start_from_the_model_the_first_left() {
        let base = trained();
        let (after_first, first) = session(&base, 1, 2, 4);
        // Appended: a second session from the corrected model replays; one from the base
        // model again does not (its live session started elsewhere).
        let (live, second) = session(&after_first, 2, 2, 5);
        let (replayed, report) = replay(
            &base,
            &String::from_utf8([first.clone(), second].concat()).unwrap(),
            BadLines::Fail,
        )
        .unwrap();
        assert_eq!(report.sessions, 2);
        assert_eq!(replayed, live);
        let (_, again) = session(&base, 2, 2, 5);
        let err = replay(
            &base,
            &String::from_utf8([first, again].concat()).unwrap(),
            BadLines::Skip,
        )
        .unwrap_err();
        assert!(err.contains("appended"), "{err}");
    }

    #[test]
    fn steps_that_break_the_rules_or_the_order_are_bad_lines() {
        let base = trained();
        let (live, bytes) = session(&base, 1, 2, 4);
        let text = std::str::from_utf8(&bytes).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        // Line 3 is the first step; line 4 the second.
        let step = |i: usize| serde_json::from_str::<DemoRecord>(lines[i]).unwrap();
        let DemoRecord::Step(first) = step(2) else {
            panic!("line 3 is a step")
        };
        let moved = |l: &str| {
            let DemoRecord::Step(mut s) = serde_json::from_str::<DemoRecord>(l).unwrap() else {
                unreachable!()
            };
            // A next state the rules cannot give: a block jumps to a free far cell.
            let free = (0..7u16)
                .flat_map(|x| (0..7u16).map(move |y| [x, y]))
                .find(|c| !s.next.blocks.contains(c) && !s.state.blocks.contains(c))
                .unwrap();
            s.next.blocks[0] = free;
            serde_json::to_string(&DemoRecord::Step(s)).unwrap()
        };
        let cases: Vec<(String, &str)> = vec![
            (edited(&bytes, 2, moved), "breaks the world's rules"),
            // Line 3 written twice.
            (
                lines[..3].iter().chain(&lines[2..]).map(|l| format!("{l}\n")).collect(),
                "written twice",
            ),
            // The first step left out: a gap.
            (
                lines[..2].iter().chain(&lines[3..]).map(|l| format!("{l}\n")).collect(),
                "missing",
            ),
            // A state that is not where the last step left the world.
            (
                edited(&bytes, 3, |l| {
                    let DemoRecord::Step(mut s) = serde_json::from_str::<DemoRecord>(l).unwrap() else {
                        unreachable!()
                    };
                    s.state = first.state.clone();
                    s.state.held = Some((first.state.held.unwrap_or(0) + 1) % 3);
                    serde_json::to_string(&DemoRecord::Step(s)).unwrap()
                }),
                "previous step",
            ),
        ];
        for (text, needle) in &cases {
            let err = replay(&base, text, BadLines::Fail).unwrap_err();
            assert!(err.contains(needle), "{needle}: {err}");
        }
        // Skipping: the line written twice is skipped and the rest gives the live table.
        let (skipped, report) = replay(&base, &cases[1].0, BadLines::Skip).unwrap();
        assert_eq!(report.bad_lines.iter().map(|b| b.line).collect::<Vec<_>>(), [4]);
        assert_eq!(skipped, live);
        // A gap is accepted when skipping (a skipped line leaves one).
        assert!(replay(&base, &cases[2].0, BadLines::Skip).is_ok());
    }

    #[test]
    fn a_reward_beyond_the_tables_floats_is_a_bad_line() {
        let base = trained();
        let (_, bytes) = session(&base, 1, 1, 4);
        let text = edited(&bytes, 2, |l| {
            let DemoRecord::Step(mut s) = serde_json::from_str::<DemoRecord>(l).unwrap() else {
                unreachable!()
            };
            s.reward = 1e39;
            serde_json::to_string(&DemoRecord::Step(s)).unwrap()
        });
        let err = replay(&base, &text, BadLines::Fail).unwrap_err();
        assert!(err.contains("line 3") && err.contains("32-bit"), "{err}");
    }

    #[test]
    fn what_is_not_a_recording_is_refused_at_its_first_line() {
        let base = trained();
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let model = dir.join("m.safetensors");
        base.save(&model).unwrap();
        let trajectory = "{\"type\":\"episode\",\"episode\":0,\"seed\":1,\"grid\":[7,7],\"goal\":[0,1,2],\"horizon\":9,\"start\":[[0,0],[1,0],[2,0]]}\n";
        let empty = dir.join("empty.jsonl");
        std::fs::write(&empty, "").unwrap();
        let traj = dir.join("t.jsonl");
        std::fs::write(&traj, trajectory).unwrap();
        for (path, needle) in [
            (&model, "model file"),
            (&traj, "begins with a session line"),
            (&empty, "empty"),
        ] {
            for policy in [BadLines::Skip, BadLines::Fail] {
                let mut agent = base.clone();
                let err = learn_from_file(&mut agent, path, policy).unwrap_err().to_string();
                assert!(err.contains(needle), "{}: {err}", path.display());
            }
        }
        // Sessions without a step teach nothing: refused too.
        let (_, bytes) = session(&base, 1, 1, 4);
        let header: String = String::from_utf8(bytes)
            .unwrap()
            .lines()
            .take(2)
            .map(|l| format!("{l}\n"))
            .collect();
        let no_steps = dir.join("no-steps.jsonl");
        std::fs::write(&no_steps, header).unwrap();
        let mut agent = base.clone();
        let err = learn_from_file(&mut agent, &no_steps, BadLines::Skip)
            .unwrap_err()
            .to_string();
        assert!(err.contains("no step"), "{err}");
    }

    #[test]
    fn a_version_1_session_is_replayed_unchecked() {
        let base = trained();
        let (live, bytes) = session(&base, 1, 2, 4);
        let v1 = edited(&bytes, 0, |l| {
            let DemoRecord::Session(mut s) = serde_json::from_str::<DemoRecord>(l).unwrap() else {
                unreachable!()
            };
            s.version = 1;
            s.model_id = None;
            serde_json::to_string(&DemoRecord::Session(s)).unwrap()
        });
        assert!(!v1.contains("model_id"));
        let (replayed, report) = replay(&base, &v1, BadLines::Fail).unwrap();
        assert_eq!(report.unchecked_sessions, 1);
        assert_eq!(replayed, live);
    }

    fn fixture(name: &str) -> std::path::PathBuf {
        testkit::fixture(name)
    }

    #[test]
    fn recordings_written_by_the_previous_release_still_replay() {
        let mut agent = QAgent::load(&fixture("model.safetensors")).unwrap();
        let before = agent.clone();
        let report = learn_from_file(&mut agent, &fixture("recording-v2.jsonl"), BadLines::Fail).unwrap();
        assert_eq!((report.sessions, report.episodes, report.steps), (1, 2, 21));
        assert!(report.bad_lines.is_empty());
        assert_ne!(agent, before, "learnt");
        // The original profile's session (paper-code rewards, their termination rule),
        // into a learner that takes any session.
        let episodes = super::super::read_episodes(&fixture("recording-original-v2.jsonl"), None).unwrap();
        assert_eq!(episodes.len(), 2);
        assert_eq!(episodes.iter().map(|e| e.steps.len()).sum::<usize>(), 32 - 3);
    }

    #[test]
    fn an_invented_reward_or_termination_is_a_bad_line() {
        let path = fixture("recording-v2.jsonl");
        let base = QAgent::load(&fixture("model.safetensors")).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // Line 3 is the first step: a pick, reward 0, the goal far.
        for (edit, needle) in [
            (
                Box::new(|s: &mut StepLine| s.reward = 5.0) as Box<dyn Fn(&mut StepLine)>,
                "invented reward",
            ),
            (Box::new(|s: &mut StepLine| s.terminated = true), "marked terminated"),
        ] {
            let text = edited(&bytes, 2, |l| {
                let DemoRecord::Step(mut s) = serde_json::from_str::<DemoRecord>(l).unwrap() else {
                    unreachable!()
                };
                edit(&mut s);
                serde_json::to_string(&DemoRecord::Step(s)).unwrap()
            });
            let err = replay(&base, &text, BadLines::Fail).unwrap_err();
            assert!(err.contains("line 3") && err.contains(needle), "{err}");
        }
    }

    #[test]
    fn episodes_are_begun_in_the_learner_before_their_steps() {
        /// Records what the replay hands it.
        #[derive(Default)]
        struct Log(Vec<String>);
        impl DemoLearner for Log {
            fn check_world(&self, _grid: Grid, _blocks: usize) -> Result<()> {
                Ok(())
            }
            fn identity(&self) -> Option<String> {
                None
            }
            fn begin_episode(&mut self, header: &EpisodeLine, start: &Observation) -> Result<()> {
                let (episode, start) = (header.episode, start.state.clone());
                self.0.push(format!("episode {episode} {start:?}"));
                Ok(())
            }
            fn learn(&mut self, _rule: &CorrectionRule, step: &Experience, _time: StepTime) -> Result<()> {
                self.0.push(format!("step {:?}", step.obs.state));
                Ok(())
            }
        }
        let mut log = Log::default();
        let report = learn_from_file(&mut log, &fixture("recording-v2.jsonl"), BadLines::Fail).unwrap();
        let begun: Vec<usize> = log
            .0
            .iter()
            .enumerate()
            .filter(|(_, l)| l.starts_with("episode"))
            .map(|(k, _)| k)
            .collect();
        assert_eq!(begun.len(), report.episodes);
        assert_eq!(log.0.len(), report.episodes + report.steps);
        for &k in &begun {
            // The first step of each episode starts from the start just begun.
            let start = log.0[k].splitn(3, ' ').nth(2).unwrap();
            assert_eq!(log.0[k + 1], format!("step {start}"));
        }
    }

    #[test]
    fn a_side_view_session_replays_under_the_side_views_rules() {
        use crate::correction::{CorrectionSession, PersonRole, session_world};
        // A person plays a side-view episode to the goal: picks of clear blocks, moves,
        // drops that fall onto towers.
        let agent = QAgent::new(ReprKind::RoleTowers, Grid::default(), 3, QParams::default()).unwrap();
        let world = sim::EnvConfig {
            view: View::Side,
            reward: "step-cost".parse().unwrap(),
            ..session_world(&agent)
        };
        let goal: Goal = "0,1/2".parse().unwrap();
        let mut session = CorrectionSession::new(
            agent.clone(),
            CorrectionRule::default(),
            world.clone(),
            vec![goal],
            3,
            0.0,
            "person",
            None,
            DemoWriter::new(Vec::new(), "memory"),
        )
        .unwrap();
        let obs = session.next_episode().unwrap();
        let plan = oracle::ExactSolver::for_world(&world)
            .solve(&obs.state, &obs.goal)
            .unwrap();
        for &a in &plan.actions {
            session.person(a, PersonRole::Player).unwrap();
        }
        assert!(session.episode_end().unwrap().reached);
        let (live, sink, _) = session.finish();
        let bytes = sink.into_inner();
        let text = String::from_utf8(bytes.clone()).unwrap();
        assert!(
            text.lines().next().unwrap().contains("\"view\":\"side\""),
            "the recording names its view"
        );
        let mut replayed = agent.clone();
        let mut replay = Replay::new(&mut replayed, BadLines::Fail, "side.jsonl");
        replay.read(&bytes[..]).unwrap();
        assert_eq!(replay.finish().steps, plan.len());
        assert_eq!(replayed, live);
        // Read as the top view (a file without its view: what every reader did before the
        // side view was recorded), valid lines are refused (a drop that falls, or its
        // reward, taken for an invented one).
        let top = text.replacen(",\"view\":\"side\"", "", 1);
        let mut as_top = agent.clone();
        let err = Replay::new(&mut as_top, BadLines::Fail, "top.jsonl")
            .read(top.as_bytes())
            .unwrap_err()
            .to_string();
        assert!(err.contains("top.jsonl: line"), "{err}");
    }
}
