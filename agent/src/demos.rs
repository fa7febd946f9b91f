//! Demonstration recordings: every step of a correction session as JSON Lines, written as it
//! happens, and their replay.
//!
//! # Format (`blockstack-demos`, version 1)
//!
//! ```text
//! {"type":"session","format":"blockstack-demos","version":1,"grid":[7,7],"blocks":3,"rule":{"margin":0.8,"learn_agent_steps":true},"demonstrator":"person","model":"agent.json"}
//! {"type":"episode","episode":0,"seed":123,"goal":[0,1,2],"start":{"blocks":[[1,2],[4,0],[6,6]],"held":null}}
//! {"type":"step","episode":0,"step":1,"state":{"blocks":[[1,2],[4,0],[6,6]],"held":null},"proposed":"drop","action":"pick 1","correction":true,"reward":0.0,"next":{"blocks":[[1,2],[4,0],[6,6]],"held":1},"terminated":false,"truncated":false}
//! ```
//!
//! - A *session* line opens every session; a file may hold several sessions one after the
//!   other (a recording is appended to, never overwritten). `rule` is how the agent learnt.
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
//! [`Replay`] applies the recorded steps to an agent with the recorded rule, in file order:
//! started from the same model, it ends with the same table as the live session. A line
//! that cannot be used (not JSON, an unknown field, a step before any episode line, a state
//! that does not fit, a line cut off by a kill) is an error naming its line number; the
//! caller's [`BadLines`] policy says whether to report it and go on or to stop. A file of
//! another format or version is always refused.

use std::io::{BufRead, Read, Write};
use std::path::{Path, PathBuf};

use files::{Output, OutputPath};
use serde::{Deserialize, Serialize};
use sim::{Action, ActionProtocol, Cell, Goal, Grid, Observation, State, Step};

use crate::correction::{CorrectionRule, Experience};
use crate::error::{AgentError, Result};
use crate::qlearning::QAgent;

/// The `format` field of every session line.
pub const DEMOS_FORMAT: &str = "blockstack-demos";

/// The recording format version this build writes and reads.
pub const DEMOS_VERSION: u32 = 1;

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
}

impl SessionLine {
    /// The header of a session on `grid` with `blocks` blocks.
    pub fn new(grid: Grid, blocks: usize, rule: CorrectionRule, demonstrator: &str, model: Option<&str>) -> Self {
        SessionLine {
            format: DEMOS_FORMAT.into(),
            version: DEMOS_VERSION,
            grid: [grid.width(), grid.height()],
            blocks,
            rule,
            demonstrator: demonstrator.into(),
            model: model.map(Into::into),
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

impl From<AgentError> for LineError {
    fn from(e: AgentError) -> Self {
        LineError {
            reason: e.to_string(),
            fatal: false,
        }
    }
}

/// Applies recorded sessions to an agent, line by line (module docs).
pub struct Replay<'a> {
    agent: &'a mut QAgent,
    policy: BadLines,
    name: String,
    /// The current session's grid and rule.
    session: Option<(Grid, CorrectionRule)>,
    /// The current episode's number and goal.
    episode: Option<(u64, Goal)>,
    report: ReplayReport,
}

impl<'a> Replay<'a> {
    /// A replay into `agent`; `name` (the file's) is used in errors.
    pub fn new(agent: &'a mut QAgent, policy: BadLines, name: &str) -> Self {
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
            if n as u64 > MAX_LINE_BYTES {
                self.report.lines += 1;
                return self.bad(LineError {
                    reason: format!(
                        "the line is longer than {}, the longest a recording line can be: is this a recording?",
                        files::Bytes(MAX_LINE_BYTES)
                    ),
                    fatal: true,
                });
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
                        self.bad(LineError {
                            reason: "the line is cut off (no newline at its end: was the session killed?)".into(),
                            fatal: false,
                        })?;
                    }
                }
                Err(_) => {
                    self.report.lines += 1;
                    self.bad(LineError {
                        reason: "the line is not UTF-8 text".into(),
                        fatal: false,
                    })?;
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

    /// Reports (or fails on) a bad line, the current one.
    fn bad(&mut self, e: LineError) -> Result<()> {
        let line = self.report.lines;
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
        let record: DemoRecord = serde_json::from_str(text).map_err(|e| LineError {
            reason: format!("not a recording line ({e})"),
            fatal: false,
        })?;
        match record {
            DemoRecord::Session(s) => {
                if s.format != DEMOS_FORMAT || s.version != DEMOS_VERSION {
                    return Err(LineError {
                        reason: format!(
                            "it is {} version {}, and this blockstack reads {DEMOS_FORMAT} version {DEMOS_VERSION}",
                            s.format, s.version
                        ),
                        fatal: true,
                    });
                }
                let grid = Grid::new(s.grid[0], s.grid[1]).map_err(AgentError::from)?;
                s.rule.validate()?;
                self.agent.check_world(grid, s.blocks)?;
                self.session = Some((grid, s.rule));
                self.episode = None;
                self.report.sessions += 1;
            }
            DemoRecord::Episode(e) => {
                let (grid, _) = self.session.ok_or_else(|| no_header("an episode", "session"))?;
                e.start.state(grid)?;
                self.agent.check_world(grid, e.goal.block_count())?;
                self.episode = Some((e.episode, e.goal));
                self.report.episodes += 1;
            }
            DemoRecord::Step(s) => {
                let (grid, rule) = self.session.ok_or_else(|| no_header("a step", "session"))?;
                let goal = match self.episode {
                    Some((k, goal)) if k == s.episode => goal,
                    _ => return Err(no_header(&format!("a step of episode {}", s.episode), "episode")),
                };
                let blocks = self.agent.blocks();
                let obs = Observation {
                    grid,
                    state: s.state.state(grid)?,
                    goal,
                    protocol: ActionProtocol::Free,
                };
                let next = Observation {
                    state: s.next.state(grid)?,
                    ..obs
                };
                let action = Action::parse(&s.action, blocks).map_err(AgentError::from)?;
                Action::parse(&s.proposed, blocks).map_err(AgentError::from)?;
                if !s.reward.is_finite() {
                    return Err(LineError {
                        reason: format!("the reward {} is not a finite number", s.reward),
                        fatal: false,
                    });
                }
                rule.learn(
                    self.agent,
                    &Experience {
                        obs,
                        action,
                        reward: s.reward,
                        next,
                        terminated: s.terminated,
                        corrected: s.correction,
                    },
                )?;
                self.report.steps += 1;
                self.report.corrections += usize::from(s.correction);
            }
        }
        Ok(())
    }

    /// What the replay did.
    pub fn finish(self) -> ReplayReport {
        self.report
    }
}

fn no_header(what: &str, header: &str) -> LineError {
    LineError {
        reason: format!("{what} before its {header} line"),
        fatal: false,
    }
}

/// Replays the recording at `path` into `agent` (module docs), reading at most
/// [`MAX_RECORDING_BYTES`].
pub fn learn_from_file(agent: &mut QAgent, path: &Path, policy: BadLines) -> Result<ReplayReport> {
    let file = files::open_bounded(path, MAX_RECORDING_BYTES, "a recording")?;
    let mut replay = Replay::new(agent, policy, &path.display().to_string());
    replay.read(std::io::BufReader::new(file))?;
    Ok(replay.finish())
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
    use crate::correction::{CorrectionConfig, correct};
    use crate::demonstrator::DemonstratorProfile;
    use crate::qlearning::QParams;
    use crate::repr::ReprKind;
    use crate::train::{TrainConfig, train};

    fn trained() -> QAgent {
        let goals: Vec<Goal> = ["0,1,2", "1,0,2"].iter().map(|g| g.parse().unwrap()).collect();
        let config = TrainConfig {
            games: 300,
            backend: sim::Backend::Grid,
            ..TrainConfig::paper(goals)
        };
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
            Grid::default(),
            3,
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
        let other = session.replace("\"version\":1", "\"version\":2");
        let mut replay = Replay::new(&mut agent, BadLines::Skip, "x.jsonl");
        let err = replay.read(other.as_bytes()).unwrap_err().to_string();
        assert!(err.contains("version 2"), "{err}");
    }
}
