//! The recording format (`blockstack-demos`, version 4): its record types, its writer and
//! its bounded reader. Reading a recording needs neither the tabular learner nor a network:
//! this module depends on `sim`, `serde` and `files` (and the leaf [`crate::rule`] for the
//! `rule` field), so that every reader of recordings can use it.
//!
//! ```text
//! {"type":"session","format":"blockstack-demos","version":4,"grid":[7,7],"blocks":3,"rule":{"margin":0.8,"learn_agent_steps":true},"demonstrator":"person","model":"agent.safetensors","model_id":"3f9c0a1b2d4e5f60"}
//! {"type":"episode","episode":0,"seed":123,"goal":[0,1,2],"start":{"blocks":[[1,2],[4,0],[6,6]],"held":null},"started_ms":1764800000000}
//! {"type":"step","episode":0,"step":1,"state":{"blocks":[[1,2],[4,0],[6,6]],"held":null},"proposed":"drop","action":"pick 1","correction":true,"reward":0.0,"next":{"blocks":[[1,2],[4,0],[6,6]],"held":1},"terminated":false,"truncated":false,"t_ms":2140,"received_ms":1764800002141}
//! ```
//!
//! - A *session* line opens every session; a file may hold several sessions one after the
//!   other (a recording is appended to, never overwritten). `rule` is how the agent learnt;
//!   `model` the model file the session started from, when known, and `model_id` that
//!   model's identity (`QAgent::identity`); `view` the world's view (side only);
//!   `participant` a study's participant; `first_episode` the number of its first episode
//!   when it goes on from an earlier session (a participant resumed after a restart).
//!   Versions 1 (before `model_id`) and 2 (before time) are still read.
//! - An *episode* line opens every episode: its number in the session, the seed of its
//!   start, its goal (bottom to top), its start state, and in a timed session (a person's)
//!   `started_ms`, the wall-clock time (Unix milliseconds) its first view was shown.
//! - A *step* line per executed action: the state before it, the agent's proposed action,
//!   the executed action (names as `blockstack solve` prints them: `up`, `pick 2`, ...),
//!   whether a demonstrator chose it (`correction`; it may equal the proposal), the reward,
//!   and the state after it with the episode's end flags. In a timed session also `t_ms`,
//!   the milliseconds since the episode's first view (a monotonic clock: the page's when
//!   it sent one, else the server's), and `received_ms`, the wall-clock time the step was
//!   received. Each step line holds all a learner needs, so any complete line can be
//!   learnt from on its own. A simulated demonstrator's session is not timed: its file is
//!   fixed by its seed.
//! - A *withdrawn* line (`{"type":"withdrawn","at_ms":...}`) says the participant withdrew:
//!   every export leaves the recording out.
//!
//! Every line is written with one write and flushed at once: a session that is killed loses
//! at most the line being written, and every complete line parses. So a recording is
//! appended to in place ([`files::OutputPath::append`]), not written through a temporary
//! file as whole-file outputs are: a temporary file would lose the whole session on a kill.
//! The destination is still checked like any output (a missing folder or a directory is
//! refused before the session starts; a FIFO or `-` receives the lines as they come).
//!
//! A recording is read through two bounds ([`MAX_RECORDING_BYTES`] for the file, and
//! [`MAX_LINE_BYTES`], the trajectory format's, for one line), so that a device or a huge
//! file given as a recording is refused at its first over-long line, never read until
//! memory runs out. [`open`] tells a recording from a trajectory file by its first line
//! and reads the file once, so a pipe can be given too.

use std::collections::BTreeMap;
use std::io::{BufRead, Cursor, Read, Write};
use std::path::{Path, PathBuf};

use files::{Output, OutputPath};
use serde::{Deserialize, Serialize};
use sim::trajectory::{Record, TrajectoryReader, read_bounded_line};
use sim::{Action, Cell, Goal, Grid, Observation, State, Step, View};

use crate::error::{AgentError, Result};
pub use crate::rule::CorrectionRule;

/// The `format` field of every session line.
pub const DEMOS_FORMAT: &str = "blockstack-demos";

/// The recording format version this build writes (it reads this one and versions 1 to 3).
pub const DEMOS_VERSION: u32 = 4;

/// The largest recording read: 1 GiB, some three million steps.
pub const MAX_RECORDING_BYTES: u64 = 1 << 30;

/// The longest line of a recording: the trajectory format's bound, 64 KiB (a step line of
/// 16 blocks takes well under 1 KiB).
pub use sim::trajectory::MAX_LINE_BYTES;

/// A state as recorded: every block's cell `[x, y]` by block id, and the held block.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateLine {
    /// Every block's cell.
    pub blocks: Vec<[u16; 2]>,
    /// The held block's id, or `null`.
    pub held: Option<u16>,
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
    /// The identity of the model the session started from (`QAgent::identity`); always
    /// present from version 2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model_id: Option<String>,
    /// The world's view, whose rules every step keeps: written only for the side view, so
    /// a recording made before the side view existed reads back as the top view.
    #[serde(default, skip_serializing_if = "is_top")]
    pub view: View,
    /// The participant of a study whose session this is (`blockstack serve --study`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub participant: Option<ParticipantLine>,
    /// The number of the session's first episode: 0, or past the episodes of the session
    /// before it when it goes on from one (written only when not 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub first_episode: u64,
    /// The rules of the world beyond grid, blocks and view (version 3): what an exporter
    /// needs to make the environment the session was played in.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub world: Option<WorldLine>,
}

/// A session's world: its reward model, action protocol, start rule and horizon.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldLine {
    /// The reward model's name (`sparse`, `paper`, `step-cost`, ...).
    pub reward: String,
    /// The action protocol.
    pub protocol: sim::ActionProtocol,
    /// The start rule (version 4; `uniform` when a version 3 line leaves it out): with the
    /// others, the whole of a profile's world, so an exporter makes the `original` world again.
    #[serde(default)]
    pub start: sim::StartRule,
    /// Steps before an episode is cut off.
    pub horizon: u32,
}

impl WorldLine {
    /// The line of `world`.
    pub fn of(world: &sim::EnvConfig) -> WorldLine {
        WorldLine {
            reward: world.reward.name().into(),
            protocol: world.protocol,
            start: world.start,
            horizon: world.horizon,
        }
    }
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

fn is_top(view: &View) -> bool {
    *view == View::Top
}

/// Who a study's session belongs to: the server's participant number, the condition, and
/// the code the participant typed (none when none was typed).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticipantLine {
    /// The participant's number on the server, from 0 (in the recording's file name).
    pub number: u64,
    /// The study condition the participant was assigned.
    pub condition: String,
    /// The participant code typed on joining, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub code: Option<String>,
    /// The crowd-sourcing platform's ids, by the URL parameter that carried each
    /// (`PROLIFIC_PID`, `STUDY_ID`, `SESSION_ID`, `workerId`, ...).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub ids: BTreeMap<String, String>,
}

impl SessionLine {
    /// The header of a session of the model with identity `model_id` (`QAgent::identity`),
    /// playing `blocks` blocks on `grid`, loaded from the file `model` when known.
    pub fn new(
        grid: Grid,
        blocks: usize,
        model_id: String,
        rule: CorrectionRule,
        demonstrator: &str,
        model: Option<&str>,
    ) -> Self {
        SessionLine {
            format: DEMOS_FORMAT.into(),
            version: DEMOS_VERSION,
            grid: [grid.width(), grid.height()],
            blocks,
            rule,
            demonstrator: demonstrator.into(),
            model: model.map(Into::into),
            model_id: Some(model_id),
            view: View::Top,
            participant: None,
            first_episode: 0,
            world: None,
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
    /// In a timed session: the wall-clock time (Unix milliseconds) of the episode's first
    /// view.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub started_ms: Option<u64>,
}

impl EpisodeLine {
    /// The header of episode `episode`, reset with `seed`, starting at `obs` (untimed).
    pub fn new(episode: u64, seed: u64, obs: &Observation) -> Self {
        EpisodeLine {
            episode,
            seed,
            goal: obs.goal.clone(),
            start: StateLine::of(&obs.state),
            started_ms: None,
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
    /// In a timed session: milliseconds since the episode's first view (monotonic).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_ms: Option<u64>,
    /// In a timed session: the wall-clock time (Unix milliseconds) the step was received.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub received_ms: Option<u64>,
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
            t_ms: None,
            received_ms: None,
        }
    }
}

/// The line that says a study's participant withdrew.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WithdrawnLine {
    /// When (Unix milliseconds).
    pub at_ms: u64,
}

/// Milliseconds since the Unix epoch, now (0 on a clock set before 1970).
pub fn unix_ms() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as u64)
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
    /// The participant withdrew (version 3).
    Withdrawn(WithdrawnLine),
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

/// An error about the recording `path`.
pub(crate) fn demos_error(path: &Path, reason: &str) -> AgentError {
    AgentError::Demos {
        path: path.display().to_string(),
        reason: reason.into(),
    }
}

/// One line of a recording as the bounded reader gives it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RawLine<'a> {
    /// A line of text, its newline included when it had one.
    Text(&'a str),
    /// The last line, without its newline and not a whole record: what a kill mid-write
    /// leaves.
    CutOff,
    /// A line that is not UTF-8.
    NotText,
    /// A line longer than [`MAX_LINE_BYTES`] (only its first bytes were read).
    TooLong,
}

/// Reads a recording line by line through [`MAX_LINE_BYTES`].
pub struct RecordingLines<R> {
    input: R,
    buf: Vec<u8>,
}

impl<R: BufRead> RecordingLines<R> {
    /// The lines of `input`.
    pub fn new(input: R) -> Self {
        RecordingLines { input, buf: Vec::new() }
    }

    /// The next line; `None` at the end.
    pub fn next_line(&mut self) -> std::io::Result<Option<RawLine<'_>>> {
        let n = read_bounded_line(&mut self.input, &mut self.buf)?;
        if n == 0 {
            return Ok(None);
        }
        if n as u64 > MAX_LINE_BYTES {
            return Ok(Some(RawLine::TooLong));
        }
        let complete = self.buf.last() == Some(&b'\n');
        Ok(Some(match std::str::from_utf8(&self.buf) {
            Ok(text) if complete || text.trim().is_empty() => RawLine::Text(text),
            // A last line without its newline is used if it happens to be whole.
            Ok(text) if serde_json::from_str::<DemoRecord>(text.trim()).is_ok() => RawLine::Text(text),
            Ok(_) => RawLine::CutOff,
            Err(_) => RawLine::NotText,
        }))
    }
}

/// An error if `path` is a model file (any format of `files::container`), naming its format.
/// Only a regular file is looked at: a pipe would lose what was read.
pub fn refuse_model_file(path: &Path) -> Result<()> {
    if std::fs::metadata(path).is_ok_and(|m| m.is_file())
        && let Some(format) = files::container::format_of(path, MAX_RECORDING_BYTES)
    {
        return Err(demos_error(
            path,
            &format!(
                "line 1: it is a model file ({format}), not a recording: give the recording first and the model with --model"
            ),
        ));
    }
    Ok(())
}

/// A file of demonstrations, told by its first line.
pub enum DemoFile {
    /// A `blockstack-demos` recording, to replay ([`crate::demos::Replay`]).
    Recording(Box<dyn BufRead + Send>),
    /// A trajectory file (`blockstack run --trajectory`), read by `sim`'s checked reader.
    Trajectory(Box<TrajectoryReader<Box<dyn BufRead + Send>>>),
}

/// Opens the demonstrations at `path` through [`MAX_RECORDING_BYTES`]: a trajectory file
/// if its first line is a trajectory's episode line, a recording otherwise (whose replay
/// says what is wrong with a file that is neither). A model file given here is refused,
/// naming its format. The file is read once: a pipe works as well as a file.
pub fn open(path: &Path) -> Result<DemoFile> {
    refuse_model_file(path)?;
    let file = files::open_bounded(path, MAX_RECORDING_BYTES, "a recording")?;
    read(Box::new(std::io::BufReader::new(file)), path)
}

/// The demonstrations read from `input` (named `path` in errors), told by the first line
/// as [`open`] tells them.
pub fn read(mut input: Box<dyn BufRead + Send>, path: &Path) -> Result<DemoFile> {
    let mut first = Vec::new();
    read_bounded_line(&mut input, &mut first).map_err(|e| demos_error(path, &format!("cannot read: {e}")))?;
    let trajectory = std::str::from_utf8(&first)
        .ok()
        .and_then(|text| serde_json::from_str::<Record>(text.trim()).ok())
        .is_some_and(|r| matches!(r, Record::Episode { .. }));
    let whole: Box<dyn BufRead + Send> = Box::new(Cursor::new(first).chain(input));
    Ok(if trajectory {
        DemoFile::Trajectory(Box::new(TrajectoryReader::new(whole, &path.display().to_string())))
    } else {
        DemoFile::Recording(whole)
    })
}
