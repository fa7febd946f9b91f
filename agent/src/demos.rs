//! Demonstration recordings: every step of a correction session as JSON Lines, written as it
//! happens, and their replay.
//!
//! # Format (`blockstack-demos`, version 2)
//!
//! ```text
//! {"type":"session","format":"blockstack-demos","version":2,"grid":[7,7],"blocks":3,"rule":{"margin":0.8,"learn_agent_steps":true},"demonstrator":"person","model":"agent.safetensors","model_id":"3f9c0a1b2d4e5f60"}
//! {"type":"episode","episode":0,"seed":123,"goal":[0,1,2],"start":{"blocks":[[1,2],[4,0],[6,6]],"held":null}}
//! {"type":"step","episode":0,"step":1,"state":{"blocks":[[1,2],[4,0],[6,6]],"held":null},"proposed":"drop","action":"pick 1","correction":true,"reward":0.0,"next":{"blocks":[[1,2],[4,0],[6,6]],"held":1},"terminated":false,"truncated":false}
//! ```
//!
//! - A *session* line opens every session; a file may hold several sessions one after the
//!   other (a recording is appended to, never overwritten). `rule` is how the agent learnt;
//!   `model` the model file the session started from, when known, and `model_id` that
//!   model's identity ([`QAgent::identity`]). Version 1 (before `model_id`) is still read.
//! - An *episode* line opens every episode: its number in the session, the seed of its
//!   start, its goal (bottom to top) and its start state.
//! - A *step* line per executed action: the state before it, the agent's proposed action,
//!   the executed action (names as `blockstack solve` prints them: `up`, `pick 2`, ...),
//!   whether a demonstrator chose it (`correction`; it may equal the proposal), the reward,
//!   and the state after it with the episode's end flags. Each step line holds all a
//!   learner needs, so any complete line can be learnt from on its own.
//!
//! Every line is written with one write and flushed at once: a session that is killed loses
//! at most the line being written, and every complete line parses. So a recording is
//! appended to in place ([`files::OutputPath::append`]), not written through a temporary
//! file as whole-file outputs are: a temporary file would lose the whole session on a kill.
//! The destination is still checked like any output (a missing folder or a directory is
//! refused before the session starts; a FIFO or `-` receives the lines as they come).
//!
//! A recording is read through a bound ([`MAX_RECORDING_BYTES`], and
//! [`MAX_LINE_BYTES`] for one line), so that a device or a huge file given as a recording
//! is refused, never read until memory runs out.
//!
//! # Replay
//!
//! [`Replay`] applies the recorded steps to an agent with the recorded rule, in file order
//! (any [`DemoLearner`]; the tabular agent is one):
//! started from the same model, it ends with the same table as the live session. A line
//! that cannot be used is an error naming its line number; the caller's [`BadLines`]
//! policy says whether to report it and go on or to stop. Such a line is:
//!
//! - not JSON, an unknown field, a line cut off by a kill;
//! - a step or episode before its session line, a step of another episode than the one
//!   just opened, a state that does not fit the world;
//! - a step that breaks the world's rules: its `next` is not what the rules
//!   ([`sim::World::act`]) make of its `state` and `action`;
//! - a step out of order: its number not above the last step's of its episode (a line
//!   written twice), its `state` not the last step's `next` (or the episode's start), or a
//!   step after one that ended the episode; an episode numbered not above the last;
//! - with [`BadLines::Fail`] only, a gap: a step or episode number more than one past the
//!   last. (Skipping a bad line leaves such a gap, so skipping accepts it.)
//!
//! Some problems end the replay whatever the policy, because nothing after them could be
//! learnt from correctly: a file that does not begin with a session line (a model file, a
//! trajectory file, an empty file), a session of another format or version, and a session
//! recorded from another model than the agent being replayed into (its `model_id` is not
//! the agent's identity at that point of the replay: sessions appended one after another
//! each started from the model the previous one left). [`learn_from_file`] refuses a file
//! from which no step was learnt.

use std::io::{BufRead, Read, Write};
use std::path::{Path, PathBuf};

use files::{Output, OutputPath};
use serde::{Deserialize, Serialize};
use sim::{Action, ActionProtocol, Cell, Goal, Grid, GridWorld, Observation, State, Step, World};

use crate::correction::{CorrectionRule, Experience};
use crate::error::{AgentError, Result};
use crate::model::MODEL_FORMAT;
use crate::qlearning::{QAgent, check_fits_table};

/// The `format` field of every session line.
pub const DEMOS_FORMAT: &str = "blockstack-demos";

/// The recording format version this build writes (it reads this one and version 1).
pub const DEMOS_VERSION: u32 = 2;

/// The largest recording read: 1 GiB, some three million steps.
pub const MAX_RECORDING_BYTES: u64 = 1 << 30;

/// The longest line of a recording: 64 KiB (a step line of 16 blocks takes well under
/// 1 KiB).
pub const MAX_LINE_BYTES: u64 = 1 << 16;

/// A state as recorded: every block's cell `[x, y]` by block id, and the held block.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateLine {
    /// Every block's cell.
    pub blocks: Vec<[u8; 2]>,
    /// The held block's id, or `null`.
    pub held: Option<u8>,
}

impl StateLine {
    /// The record of `state`.
    pub fn of(state: &State) -> StateLine {
        StateLine {
            blocks: state.cells().iter().map(|c| [c.x, c.y]).collect(),
            held: state.held_block().map(|b| b.0),
        }
    }

    /// The state, checked against `grid`.
    pub fn state(&self, grid: Grid) -> Result<State> {
        let cells: Vec<Cell> = self.blocks.iter().map(|&[x, y]| Cell::new(x, y)).collect();
        let state = State::new(&cells, self.held.map(sim::BlockId))?;
        state.check_fits(grid)?;
        Ok(state)
    }
}

/// The line that opens a session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SessionLine {
    /// Always [`DEMOS_FORMAT`].
    pub format: String,
    /// Always [`DEMOS_VERSION`] for files this build writes.
    pub version: u32,
    /// `[W, H]`.
    pub grid: [usize; 2],
    /// Number of blocks.
    pub blocks: usize,
    /// How the agent learnt in this session.
    pub rule: CorrectionRule,
    /// Who corrected: `person`, or a simulated demonstrator's name.
    pub demonstrator: String,
    /// The model file the session started from, when known.
    pub model: Option<String>,
    /// The identity of the model the session started from ([`QAgent::identity`]); always
    /// present from version 2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_id: Option<String>,
}

impl SessionLine {
    /// The header of a session of `agent` (its grid, blocks and identity), loaded from the
    /// file `model` when known.
    pub fn new(agent: &QAgent, rule: CorrectionRule, demonstrator: &str, model: Option<&str>) -> Self {
        let grid = agent.grid();
        SessionLine {
            format: DEMOS_FORMAT.into(),
            version: DEMOS_VERSION,
            grid: [grid.width(), grid.height()],
            blocks: agent.blocks(),
            rule,
            demonstrator: demonstrator.into(),
            model: model.map(Into::into),
            model_id: Some(agent.identity()),
        }
    }
}

/// The line that opens an episode.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EpisodeLine {
    /// The episode's number in the session, from 0.
    pub episode: u64,
    /// The seed its start was drawn with.
    pub seed: u64,
    /// The goal, bottom to top.
    pub goal: Goal,
    /// The start state.
    pub start: StateLine,
}

impl EpisodeLine {
    /// The header of episode `episode`, reset with `seed`, starting at `obs`.
    pub fn new(episode: u64, seed: u64, obs: &Observation) -> Self {
        EpisodeLine {
            episode,
            seed,
            goal: obs.goal,
            start: StateLine::of(&obs.state),
        }
    }
}

/// One executed step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepLine {
    /// The episode's number.
    pub episode: u64,
    /// Actions taken in the episode, this one included.
    pub step: u32,
    /// The state before the action.
    pub state: StateLine,
    /// The agent's proposed action.
    pub proposed: String,
    /// The executed action.
    pub action: String,
    /// Whether a demonstrator chose the executed action.
    pub correction: bool,
    /// The reward.
    pub reward: f64,
    /// The state after the action.
    pub next: StateLine,
    /// The goal holds after the action.
    pub terminated: bool,
    /// The horizon was reached without the goal.
    pub truncated: bool,
}

impl StepLine {
    /// The line of `step`, the outcome of `action` (proposed: `proposed`) taken in `obs`
    /// in episode `episode`.
    pub fn new(
        episode: u64,
        obs: &Observation,
        proposed: Action,
        action: Action,
        correction: bool,
        step: &Step,
    ) -> Self {
        StepLine {
            episode,
            step: step.info.steps,
            state: StateLine::of(&obs.state),
            proposed: proposed.to_string(),
            action: action.to_string(),
            correction,
            reward: step.reward,
            next: StateLine::of(&step.observation.state),
            terminated: step.terminated,
            truncated: step.truncated,
        }
    }
}

/// One line of a recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum DemoRecord {
    /// Opens a session.
    Session(SessionLine),
    /// Opens an episode.
    Episode(EpisodeLine),
    /// One executed step.
    Step(StepLine),
}

/// Where a session's lines go, as they happen.
pub trait DemoSink {
    /// Takes one line.
    fn record(&mut self, line: &DemoRecord) -> Result<()>;
}

/// Records nothing.
impl DemoSink for () {
    fn record(&mut self, _line: &DemoRecord) -> Result<()> {
        Ok(())
    }
}

/// Keeps every line in memory.
impl DemoSink for Vec<DemoRecord> {
    fn record(&mut self, line: &DemoRecord) -> Result<()> {
        self.push(line.clone());
        Ok(())
    }
}

/// Records to the sink when there is one.
impl<S: DemoSink> DemoSink for Option<S> {
    fn record(&mut self, line: &DemoRecord) -> Result<()> {
        self.as_mut().map_or(Ok(()), |s| s.record(line))
    }
}

/// Writes a recording as JSON Lines, one write and one flush per line.
#[derive(Debug)]
pub struct DemoWriter<W: Write = Output> {
    out: W,
    path: PathBuf,
}

impl DemoWriter<Output> {
    /// Opens `out` to append to (a regular file is created if missing; an earlier
    /// recording is kept), in place (module docs).
    pub fn append(out: &OutputPath) -> Result<Self> {
        Ok(DemoWriter {
            out: out.append()?,
            path: out.path().to_path_buf(),
        })
    }
}

impl<W: Write> DemoWriter<W> {
    /// A writer to `out` (named `name` in errors).
    pub fn new(out: W, name: &str) -> Self {
        DemoWriter {
            out,
            path: PathBuf::from(name),
        }
    }

    /// The underlying writer.
    pub fn into_inner(self) -> W {
        self.out
    }
}

impl<W: Write> DemoSink for DemoWriter<W> {
    fn record(&mut self, line: &DemoRecord) -> Result<()> {
        let mut text = serde_json::to_string(line).expect("records serialise");
        text.push('\n');
        // One write per line: a kill between two lines leaves only whole lines.
        self.out
            .write_all(text.as_bytes())
            .and_then(|()| self.out.flush())
            .map_err(|e| files::FilesError::write(&self.path, &e).into())
    }
}

fn demos_error(path: &Path, reason: &str) -> AgentError {
    AgentError::Demos {
        path: path.display().to_string(),
        reason: reason.into(),
    }
}

/// What to do with a line that cannot be used.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BadLines {
    /// Report it (in [`ReplayReport::bad_lines`]) and go on with the next line.
    #[default]
    Skip,
    /// Stop with an error naming the line.
    Fail,
}

impl std::str::FromStr for BadLines {
    type Err = AgentError;

    /// Reads `skip` or `fail`.
    fn from_str(text: &str) -> Result<BadLines> {
        match text {
            "skip" => Ok(BadLines::Skip),
            "fail" => Ok(BadLines::Fail),
            _ => Err(AgentError::Config(format!(
                "unknown policy {text:?} for bad lines: choose skip or fail"
            ))),
        }
    }
}

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
#[derive(Clone, Copy)]
struct OpenSession {
    grid: Grid,
    rule: CorrectionRule,
    /// The number of its last episode line used.
    last_episode: Option<u64>,
}

/// The episode being replayed.
#[derive(Clone, Copy)]
struct OpenEpisode {
    number: u64,
    goal: Goal,
    /// The number of its last step used (0 before the first).
    last_step: u32,
    /// Where that step left the world (the start before the first).
    state: State,
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

    /// Learns from one recorded step, by the session's `rule`.
    fn learn(&mut self, rule: &CorrectionRule, step: &Experience) -> Result<()>;
}

impl DemoLearner for QAgent {
    fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        QAgent::check_world(self, grid, blocks)
    }

    fn identity(&self) -> Option<String> {
        Some(QAgent::identity(self))
    }

    fn learn(&mut self, rule: &CorrectionRule, step: &Experience) -> Result<()> {
        rule.learn(self, step).map(|_| ())
    }
}

/// Applies recorded sessions to a learner (by default a [`QAgent`]), line by line (module
/// docs).
pub struct Replay<'a, L: ?Sized = QAgent> {
    agent: &'a mut L,
    policy: BadLines,
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
            name: name.into(),
            session: None,
            episode: None,
            report: ReplayReport::default(),
        }
    }

    /// Applies every line of `input`; with [`BadLines::Fail`], stops at the first bad line.
    /// A line longer than [`MAX_LINE_BYTES`] stops the replay whatever the policy: the
    /// input is not a recording.
    pub fn read(&mut self, input: impl BufRead) -> Result<()> {
        let mut input = input;
        let mut buf = Vec::new();
        loop {
            buf.clear();
            let n = (&mut input)
                .take(MAX_LINE_BYTES + 1)
                .read_until(b'\n', &mut buf)
                .map_err(|e| demos_error(Path::new(&self.name), &format!("cannot read: {e}")))?;
            if n == 0 {
                return Ok(());
            }
            if self.report.lines == 0 && contains(&buf, MODEL_FORMAT.as_bytes()) {
                self.report.lines += 1;
                return self.bad(LineError::fatal(format!(
                    "it is a model file ({MODEL_FORMAT}), not a recording: give the recording first and the model with --model"
                )));
            }
            if n as u64 > MAX_LINE_BYTES {
                self.report.lines += 1;
                return self.bad(LineError::fatal(format!(
                    "the line is longer than {}, the longest a recording line can be: is this a recording?",
                    files::Bytes(MAX_LINE_BYTES)
                )));
            }
            let complete = buf.last() == Some(&b'\n');
            match std::str::from_utf8(&buf) {
                Ok(text) if complete || text.trim().is_empty() => self.line(text)?,
                Ok(text) => {
                    // A last line without its newline: what a kill mid-write leaves. It is
                    // used if it happens to be whole, reported otherwise.
                    if serde_json::from_str::<DemoRecord>(text.trim()).is_ok() {
                        self.line(text)?;
                    } else {
                        self.report.lines += 1;
                        self.bad(LineError::bad(
                            "the line is cut off (no newline at its end: was the session killed?)",
                        ))?;
                    }
                }
                Err(_) => {
                    self.report.lines += 1;
                    self.bad(LineError::bad("the line is not UTF-8 text"))?;
                }
            }
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
        self.session = Some(OpenSession {
            grid,
            rule: s.rule,
            last_episode: None,
        });
        self.episode = None;
        self.report.sessions += 1;
        Ok(())
    }

    fn episode(&mut self, e: EpisodeLine) -> std::result::Result<(), LineError> {
        let session = self.session.ok_or_else(|| no_header("an episode", "session"))?;
        let start = e.start.state(session.grid)?;
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
            None if e.episode != 0 && self.policy == BadLines::Fail => {
                return Err(LineError::bad(format!(
                    "the session's first episode is {}, not 0: episodes are missing",
                    e.episode
                )));
            }
            _ => {}
        }
        self.session = Some(OpenSession {
            last_episode: Some(e.episode),
            ..session
        });
        self.episode = Some(OpenEpisode {
            number: e.episode,
            goal: e.goal,
            last_step: 0,
            state: start,
            ended: false,
        });
        self.report.episodes += 1;
        Ok(())
    }

    fn step(&mut self, s: StepLine) -> std::result::Result<(), LineError> {
        let session = self.session.ok_or_else(|| no_header("a step", "session"))?;
        let episode = match self.episode {
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
            goal: episode.goal,
            protocol: ActionProtocol::Free,
        };
        let next = Observation {
            state: s.next.state(session.grid)?,
            ..obs
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
        let mut world = GridWorld::new(session.grid, obs.state)?;
        world.act(action)?;
        if world.state() != next.state {
            return Err(LineError::bad(format!(
                "the step breaks the world's rules: {action} does not lead from its state to its next state"
            )));
        }
        check_fits_table("the reward", s.reward)?;
        self.agent.learn(
            &session.rule,
            &Experience {
                obs,
                action,
                reward: s.reward,
                next,
                terminated: s.terminated,
                corrected: s.correction,
            },
        )?;
        self.episode = Some(OpenEpisode {
            last_step: s.step,
            state: next.state,
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

/// Whether `needle` occurs in `haystack`.
fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

fn no_header(what: &str, header: &str) -> LineError {
    LineError::bad(format!("{what} before its {header} line"))
}

/// Replays the recording at `path` into `agent` (module docs), reading at most
/// [`MAX_RECORDING_BYTES`]. An error if no step could be learnt from it (an empty file, a
/// file of sessions without steps, or one whose every step was skipped).
pub fn learn_from_file<L: DemoLearner + ?Sized>(agent: &mut L, path: &Path, policy: BadLines) -> Result<ReplayReport> {
    let file = files::open_bounded(path, MAX_RECORDING_BYTES, "a recording")?;
    let mut replay = Replay::new(agent, policy, &path.display().to_string());
    replay.read(std::io::BufReader::new(file))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::TrainConfig;
    use crate::correction::{CorrectionConfig, correct};
    use crate::demonstrator::DemonstratorProfile;
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
            &agent,
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
        let other = session.replace("\"version\":2", "\"version\":3");
        let mut replay = Replay::new(&mut agent, BadLines::Skip, "x.jsonl");
        let err = replay.read(other.as_bytes()).unwrap_err().to_string();
        assert!(err.contains("version 3"), "{err}");
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
            let free = (0..7u8)
                .flat_map(|x| (0..7u8).map(move |y| [x, y]))
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
}
