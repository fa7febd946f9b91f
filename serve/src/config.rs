//! What a server serves: its settings ([`ServeConfig`]), the study file ([`StudyFile`]),
//! and each condition prepared once at start-up ([`Condition`]): its model loaded, its
//! world, rule and goals resolved, so that a participant's session is only a clone away.
//!
//! Without a study the command line's `--model`, `--profile` and `--goals` make the one
//! condition, every mode the model can offer, no episode limit.

use std::net::IpAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use agent::correction::{CorrectionRule, CorrectionSession, default_goals, session_world_under};
use agent::{LearnerProfile, QAgent, QParams};
use neural::AnyModel;
use serde::{Deserialize, Serialize};
use sim::{Env, EnvConfig, Goal, GoalSpec, Grid, Profile, View};

use crate::error::{Result, ServeError};
use crate::protocol::Mode;

/// The server's bounds (docs/serve.md, "Security bounds").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// Participant sessions held at once (a session with no page for `session_idle` is let
    /// go, its recording kept).
    pub max_sessions: usize,
    /// Messages a session may send per second (a bucket of this many, refilled at this rate).
    pub actions_per_second: u32,
    /// The longest text message read, in bytes; longer ones are refused with an error.
    pub max_message_bytes: usize,
    /// The largest WebSocket message or frame at all; a longer one ends the connection.
    pub max_frame_bytes: usize,
    /// A session let go after this long: one whose participant never took a step, this long
    /// after it began (it recorded nothing); one that did, this long without a page.
    pub session_idle: Duration,
    /// Joins one client address may make: a bucket of this many, refilled at this many a
    /// minute (a study's `joins_per_minute`).
    pub joins_per_minute: u32,
    /// A request whose head or body takes longer than this to arrive, or a page that does
    /// not read what it is sent for this long, is cut off.
    pub request_timeout: Duration,
    /// A connected page that answers neither a message nor the server's pings for this long
    /// is disconnected (a browser answers pings by itself, even in a background tab).
    pub socket_idle: Duration,
    /// Connections open at once; more wait to be accepted.
    pub max_connections: usize,
    /// The most states the exact solver stores to find the shortest plan of an episode's
    /// start (the page shows none when it gives up): a bound on each participant's memory
    /// and time at an episode's start.
    pub solver_budget: usize,
}

impl Default for Limits {
    /// 100 sessions, 20 messages per second, messages of 1 KiB (a frame of 64 KiB),
    /// sessions let go after 30 minutes without a step or a page, 20 joins a minute from one
    /// address, requests cut off after 10 s, pages after 90 s without an answer, 1,000
    /// connections, a million states for a shortest plan.
    fn default() -> Self {
        Limits {
            max_sessions: 100,
            actions_per_second: 20,
            max_message_bytes: 1024,
            max_frame_bytes: 64 * 1024,
            session_idle: Duration::from_secs(30 * 60),
            joins_per_minute: 20,
            request_timeout: Duration::from_secs(10),
            socket_idle: Duration::from_secs(90),
            max_connections: 1000,
            solver_budget: 1_000_000,
        }
    }
}

/// Everything `blockstack serve` is told.
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// The address listened on (loopback unless told otherwise).
    pub bind: IpAddr,
    /// The port (0: any free port).
    pub port: u16,
    /// The model watched and corrected, without a study.
    pub model: Option<PathBuf>,
    /// The profile of play and correct mode, without a study (`None`: the model's).
    pub profile: Option<Profile>,
    /// The goals, `:`-separated, without a study (`None`: the profile's default).
    pub goals: Option<String>,
    /// Where recordings go (none: nothing is recorded; a study needs one).
    pub record_dir: Option<PathBuf>,
    /// The study file.
    pub study: Option<PathBuf>,
    /// The address participants reach the server at (`http://lab.example.org:8080/`), when
    /// it is not the address bound: printed as the link, and its host name let through the
    /// `Host` check (docs/serve.md, "Security bounds").
    pub public_url: Option<String>,
    /// The seed of every episode's start, without a study (a study names its own).
    pub seed: u64,
    /// The bounds.
    pub limits: Limits,
}

impl Default for ServeConfig {
    /// Loopback, port 8080, no model, no recording, no study, seed 1.
    fn default() -> Self {
        ServeConfig {
            bind: IpAddr::from([127, 0, 0, 1]),
            port: 8080,
            model: None,
            profile: None,
            goals: None,
            record_dir: None,
            study: None,
            public_url: None,
            seed: 1,
            limits: Limits::default(),
        }
    }
}

/// A study file (TOML), as written (docs/serve.md, "Running a study").
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// The study's name, on the researcher's page.
    #[serde(default)]
    pub name: Option<String>,
    /// The seed of the starts: every participant of a condition plays the same starts.
    #[serde(default)]
    pub seed: Option<u64>,
    /// Participants admitted at most, over every run of the server on the same record
    /// folder (at least 1): those who took a step (a join that never acts takes no place).
    #[serde(default)]
    pub max_participants: Option<u64>,
    /// The consent form, Markdown (shown first; declining records nothing).
    #[serde(default)]
    pub consent: Option<String>,
    /// The consent form's Markdown file (relative to the study file), instead of `consent`.
    #[serde(default)]
    pub consent_file: Option<PathBuf>,
    /// The instructions, Markdown (shown after consent, before the first episode).
    #[serde(default)]
    pub instructions: Option<String>,
    /// The instructions' Markdown file, instead of `instructions`.
    #[serde(default)]
    pub instructions_file: Option<PathBuf>,
    /// The URL parameters a crowd-sourcing platform sends, read into the recording's
    /// header (`["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]`, `["workerId", "assignmentId"]`):
    /// the first one identifies the participant: one who took part cannot join again as
    /// new with it. (A participant resumes by the token their browser keeps, never by an
    /// id: ids are not secrets.)
    #[serde(default)]
    pub participant_ids: Vec<String>,
    /// Refuse a join that does not carry every one of `participant_ids`.
    #[serde(default)]
    pub require_ids: bool,
    /// Minutes after which a session is let go: one that never took a step this long after
    /// it began (nothing of it is on disk), one that did this long without a page (its
    /// recording kept, the participant may come back). Default 30.
    #[serde(default)]
    pub idle_minutes: Option<u64>,
    /// Joins one client address may make in a minute (a bucket of this many, refilled at
    /// this rate). Default 20; behind a proxy every participant has the proxy's address.
    #[serde(default)]
    pub joins_per_minute: Option<u32>,
    /// The code shown when every episode is done (the platform's completion code), only in
    /// that participant's last view.
    #[serde(default)]
    pub completion_code: Option<String>,
    /// Give each participant a code of their own instead of `completion_code` (listed in
    /// the researcher's CSV, so claims can be checked); `{code}` in `completion_url` is
    /// replaced by it.
    #[serde(default)]
    pub code_per_participant: bool,
    /// Give the completion code (and link) to a participant who withdraws too.
    #[serde(default)]
    pub completion_on_withdrawal: bool,
    /// Where the page sends the participant when every episode is done (the platform's
    /// completion link).
    #[serde(default)]
    pub completion_url: Option<String>,
    /// What withdrawing does to the participant's recording: `delete` it, or `mark` it
    /// withdrawn (kept, left out of every export). Without it, no withdrawal is offered.
    #[serde(default)]
    pub withdrawal: Option<String>,
    /// The conditions, handed to participants to keep them balanced.
    #[serde(rename = "condition")]
    pub conditions: Vec<ConditionFile>,
}

/// One condition of a study file.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConditionFile {
    /// Its name, in recordings' file names and on the researcher's page.
    pub name: String,
    /// The model file (relative to the study file's folder), if any.
    #[serde(default)]
    pub model: Option<PathBuf>,
    /// `spec` or `original` (default: the model's).
    #[serde(default)]
    pub profile: Option<String>,
    /// Goals separated by `:` (default: the profile's).
    #[serde(default)]
    pub goals: Option<String>,
    /// Episodes of play and correct mode each participant is asked for (0: no limit).
    #[serde(default)]
    pub episodes: u64,
    /// The modes offered (default: every mode the model can offer).
    #[serde(default)]
    pub modes: Option<Vec<String>>,
    /// `top` or `side` (default: the model's, else `top`).
    #[serde(default)]
    pub view: Option<String>,
}

impl StudyFile {
    /// Reads and checks the study at `path` (at most 1 MiB).
    pub fn read(path: &Path) -> Result<StudyFile> {
        let err = |reason: String| ServeError::Study {
            path: path.to_path_buf(),
            reason,
        };
        // A pipe or a device would block the start (a FIFO until a writer comes) or never end.
        match std::fs::metadata(path) {
            Ok(meta) if !meta.is_file() => {
                return Err(err(
                    "it is not a regular file (a folder, a pipe or a device): give a TOML file".into(),
                ));
            }
            _ => {}
        }
        let mut text = String::new();
        std::io::Read::read_to_string(&mut files::open_bounded(path, 1 << 20, "a study file")?, &mut text)
            .map_err(|e| err(format!("cannot read: {e}")))?;
        let study: StudyFile = toml::from_str(&text).map_err(|e| err(e.message().to_string()))?;
        if study.conditions.is_empty() {
            return Err(err("it lists no [[condition]]".into()));
        }
        if study.max_participants == Some(0) {
            return Err(err(
                "max_participants = 0 admits no one: give at least 1, or leave it out".into(),
            ));
        }
        if study.consent.is_some() && study.consent_file.is_some() {
            return Err(err("give consent or consent_file, not both".into()));
        }
        if study.instructions.is_some() && study.instructions_file.is_some() {
            return Err(err("give instructions or instructions_file, not both".into()));
        }
        for (i, id) in study.participant_ids.iter().enumerate() {
            check_name(id).map_err(|e| err(format!("participant_ids: {e}")))?;
            if study.participant_ids[..i].contains(id) {
                return Err(err(format!("participant_ids: {id} is listed twice")));
            }
        }
        if let Some(code) = &study.completion_code {
            check_name(code).map_err(|e| err(format!("completion_code: {e}")))?;
            if study.code_per_participant {
                return Err(err(
                    "give completion_code or code_per_participant = true, not both".into()
                ));
            }
        }
        if study.require_ids && study.participant_ids.is_empty() {
            return Err(err("require_ids = true needs participant_ids to require".into()));
        }
        if study.idle_minutes == Some(0) {
            return Err(err(
                "idle_minutes = 0 lets every session go at once: give at least 1".into()
            ));
        }
        if study.joins_per_minute == Some(0) {
            return Err(err("joins_per_minute = 0 admits no one: give at least 1".into()));
        }
        if let Some(url) = &study.completion_url
            && (!(url.starts_with("https://") || url.starts_with("http://")) || url.contains(['"', '<', '>', ' ']))
        {
            return Err(err(format!(
                "completion_url {url:?}: give an http:// or https:// address"
            )));
        }
        if let Some(w) = &study.withdrawal {
            w.parse::<Withdrawal>().map_err(|e| err(format!("withdrawal: {e}")))?;
        }
        for c in &study.conditions {
            check_name(&c.name).map_err(|e| err(format!("condition name: {e}")))?;
            if let Some(modes) = &c.modes {
                for (i, m) in modes.iter().enumerate() {
                    if modes[..i].contains(m) {
                        return Err(err(format!("condition {}: the mode {m} is listed twice", c.name)));
                    }
                }
            }
        }
        Ok(study)
    }
}

/// An error unless `name` is 1 to 32 letters, digits, `-` and `_`: names go into file
/// names, and a path must not.
pub fn check_name(name: &str) -> std::result::Result<(), String> {
    if (1..=32).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_')
    {
        Ok(())
    } else {
        Err(format!(
            "{name:?} is not a name: use 1 to 32 letters, digits, - and _ (no paths)"
        ))
    }
}

/// What a participant's withdrawal does to their recording.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Withdrawal {
    /// The recording is deleted.
    Delete,
    /// The recording is kept, a `withdrawn` line appended: every export leaves it out.
    Mark,
}

sim::names!(Withdrawal { Delete = "delete", Mark = "mark" } unknown(text) -> String {
    format!("{text:?} is not a withdrawal: delete or mark")
});

/// A study's path for its participants: consent, instructions, ids, the end. What the
/// page may show anyone (`GET /api/study`) is serialised; the completion code and link are
/// not: they go only into a finished participant's last view.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct StudyPath {
    /// The study's name.
    pub name: String,
    /// The consent form as safe HTML ([`crate::markdown`]).
    pub consent: Option<String>,
    /// The instructions as safe HTML.
    pub instructions: Option<String>,
    /// The URL parameters read as the participant's ids; the first identifies them.
    pub participant_ids: Vec<String>,
    /// The completion code.
    #[serde(skip)]
    pub completion_code: Option<String>,
    /// Each participant has a code of their own, which replaces `{code}` in the link.
    #[serde(skip)]
    pub code_per_participant: bool,
    /// The completion link.
    #[serde(skip)]
    pub completion_url: Option<String>,
    /// A participant who withdraws is given the code and link too.
    #[serde(skip)]
    pub completion_on_withdrawal: bool,
    /// A join must carry every one of `participant_ids`.
    #[serde(skip)]
    pub require_ids: bool,
    /// What withdrawing does, if it is offered.
    pub withdrawal: Option<Withdrawal>,
}

/// A condition ready to hand to participants.
pub struct Condition {
    /// Its name.
    pub name: String,
    /// The model watched, if any.
    pub model: Option<Arc<AnyModel>>,
    /// The model file as given, for the recording's session line.
    pub model_file: Option<String>,
    /// The agent that proposes in correct mode and learns from play and correct mode: the
    /// tabular model, or an untrained agent of the profile when there is none (a network
    /// cannot be corrected by the tabular rule). Shared by every participant's session
    /// until their first lesson copies it.
    pub agent: Arc<QAgent>,
    /// Whether `agent` is the condition's model (else an untrained stand-in).
    pub agent_is_model: bool,
    /// The world of play and correct mode.
    pub world: EnvConfig,
    /// The world of watch mode: the model's own.
    pub watch_world: EnvConfig,
    /// How the agent learns.
    pub rule: CorrectionRule,
    /// The goals, played in turn.
    pub goals: Vec<Goal>,
    /// Episodes asked for (0: no limit).
    pub episodes: u64,
    /// The modes offered, the first one the mode a participant starts in.
    pub modes: Vec<Mode>,
    /// The seed of the starts.
    pub seed: u64,
    /// The most states a shortest plan's search stores ([`Limits::solver_budget`]).
    pub solver_budget: usize,
}

/// What a condition is made of, typed: from a study file's `[[condition]]` or the command
/// line's flags.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConditionSpec {
    /// Its name.
    pub name: String,
    /// The model file (a tabular model or a network), if any.
    pub model: Option<PathBuf>,
    /// The profile of play and correct mode (`None`: the model's).
    pub profile: Option<Profile>,
    /// The goals, `:`-separated (`None`: the profile's default).
    pub goals: Option<String>,
    /// Episodes asked for (0: no limit).
    pub episodes: u64,
    /// The modes offered (`None`: every mode the model can offer).
    pub modes: Option<Vec<Mode>>,
    /// The seed of the starts.
    pub seed: u64,
    /// The most states a shortest plan's search stores.
    pub solver_budget: usize,
    /// The view (`None`: the model's, else the top view).
    pub view: Option<View>,
}

impl Condition {
    /// Loads and resolves a condition: its model (a tabular or network file), profile,
    /// goals and modes; then checks that it runs (every goal's world can be made, an
    /// episode begun), so that a condition that cannot run is refused before anyone joins.
    pub fn prepare(spec: &ConditionSpec) -> Result<Condition> {
        let ConditionSpec {
            name,
            model,
            profile,
            goals,
            episodes,
            modes,
            seed,
            solver_budget,
            view,
        } = spec;
        let (name, profile, episodes, seed) = (name.as_str(), *profile, *episodes, *seed);
        let (model, goals, modes) = (model.as_deref(), goals.as_deref(), modes.as_deref());
        let loaded = model.map(AnyModel::load).transpose()?;
        let tabular = match &loaded {
            Some(AnyModel::Q(q)) => Some((**q).clone()),
            _ => None,
        };
        let agent_is_model = tabular.is_some();
        let model_view = loaded.as_ref().map(|m| m.world().view);
        let view = match (*view, model_view) {
            (Some(asked), Some(own)) if asked != own => {
                return Err(ServeError::Config(format!(
                    "condition {name}: its view is {asked}, and its model plays the {own} view"
                )));
            }
            (asked, own) => asked.or(own).unwrap_or(View::Top),
        };
        let (agent, world, profile) = match tabular {
            Some(q) => {
                let (world, profile) = session_world_under(&q, profile);
                (q, world, profile)
            }
            None => stand_in(loaded.as_ref(), profile, view)?,
        };
        let goals = match goals {
            Some(text) => Goal::parse_list(text, agent.blocks())?,
            None => default_goals(&world, profile)?,
        };
        let offered: Vec<Mode> = Mode::ALL
            .into_iter()
            .filter(|m| match m {
                Mode::Play => true,
                Mode::Watch => loaded.is_some(),
                Mode::Correct => agent_is_model,
            })
            .collect();
        let modes = match modes {
            None => offered,
            Some(asked) => {
                if asked.is_empty() {
                    return Err(ServeError::Config(format!("condition {name}: no modes offered")));
                }
                for m in asked {
                    if !offered.contains(m) {
                        let why = match m {
                            Mode::Watch => "it needs a model",
                            _ => "it needs a tabular model (blockstack train): a network is not corrected",
                        };
                        return Err(ServeError::Config(format!(
                            "condition {name}: the {} mode cannot be offered: {why}",
                            m.name()
                        )));
                    }
                }
                asked.to_vec()
            }
        };
        let watch_world = loaded.as_ref().map_or(world.clone(), AnyModel::world);
        let condition = Condition {
            name: name.to_string(),
            model_file: model.map(|p| p.display().to_string()),
            model: loaded.map(Arc::new),
            agent: Arc::new(agent),
            agent_is_model,
            world,
            watch_world,
            rule: CorrectionRule::for_profile(profile),
            goals,
            episodes,
            modes,
            seed,
            solver_budget: *solver_budget,
        };
        condition
            .check_runs()
            .map_err(|e| ServeError::Config(format!("condition {name}: {e}")))?;
        Ok(condition)
    }

    /// An error unless every mode offered can begin an episode on every goal: the session
    /// of play and correct mode is begun once here (recording nothing), and watch mode's
    /// world is made for each of the model's goals, so that a condition that cannot run is
    /// refused at start-up, not at each participant's join.
    fn check_runs(&self) -> Result<()> {
        if self.modes.iter().any(|m| *m != Mode::Watch) {
            let mut session = CorrectionSession::new(
                self.agent.clone(),
                self.rule,
                self.world.clone(),
                self.goals.clone(),
                self.seed,
                0.0,
                "person",
                None,
                (),
            )?;
            // Every goal's world was checked by the session; one episode checks the start.
            session.next_episode()?;
        }
        if let (true, Some(model)) = (self.modes.contains(&Mode::Watch), &self.model) {
            for goal in self.watch_goals(model) {
                let mut env = Env::new(EnvConfig {
                    goal,
                    ..self.watch_world
                })?;
                env.reset(self.seed);
            }
        }
        Ok(())
    }

    /// The goals watch mode plays in turn: those of the condition with the model's block
    /// count, or drawn ones when there are none.
    pub fn watch_goals(&self, model: &AnyModel) -> Vec<GoalSpec> {
        let goals: Vec<GoalSpec> = self
            .goals
            .iter()
            .filter(|g| g.block_count() == model.blocks())
            .map(|g| GoalSpec::Fixed(g.clone()))
            .collect();
        if goals.is_empty() {
            vec![GoalSpec::Random]
        } else {
            goals
        }
    }
}

/// What a server runs: the study's path, its conditions, and the participants it admits
/// at most (none: no cap but `--max-sessions` at once).
pub struct Plan {
    /// The study's path for its participants (its name `blockstack` without a study).
    pub path: StudyPath,
    /// The conditions, handed to participants to keep them balanced.
    pub conditions: Vec<Arc<Condition>>,
    /// The study's `max_participants`.
    pub max_participants: Option<u64>,
    /// The study's `idle_minutes`, as a time.
    pub idle: Option<Duration>,
    /// The study's `joins_per_minute`.
    pub joins_per_minute: Option<u32>,
}

/// The agent that proposes and learns in a condition without a tabular model (a network
/// is not corrected by the tabular rule), untrained, on the model's grid and blocks (the
/// default world's without a model); its world and the profile whose rule applies. In the
/// side view the learner `train --view side` makes, in that world.
fn stand_in(model: Option<&AnyModel>, profile: Option<Profile>, view: View) -> Result<(QAgent, EnvConfig, Profile)> {
    let (grid, blocks) = model.map_or((Grid::default(), 3), |m| (m.grid(), m.blocks()));
    let profile = profile.unwrap_or(Profile::Spec);
    if view == View::Side {
        let config = agent::TrainConfig::resolve(&agent::TrainOverrides {
            view: Some(View::Side),
            profile: Some(profile),
            grid: Some(grid),
            blocks: Some(blocks),
            ..agent::TrainOverrides::default()
        })?;
        let agent = QAgent::with_schedule(config.repr, grid, blocks, config.params, config.schedule)?;
        let world = EnvConfig {
            goal: GoalSpec::Random,
            horizon: sim::DEFAULT_HORIZON,
            termination: sim::Termination::Goal,
            ..config.world
        };
        return Ok((agent, world, profile));
    }
    let p = LearnerProfile::of(profile);
    let agent = QAgent::with_schedule(p.repr, grid, blocks, QParams::default(), p.schedule)?;
    let (world, profile) = session_world_under(&agent, Some(profile));
    Ok((agent, world, profile))
}

/// What `config` runs: its study's conditions, or the one the command line describes.
pub fn plan(config: &ServeConfig) -> Result<Plan> {
    if config.limits.max_sessions == 0 {
        return Err(ServeError::Config(
            "--max-sessions 0 holds no session: give at least 1".into(),
        ));
    }
    let Some(path) = config.study.clone() else {
        let c = Condition::prepare(&ConditionSpec {
            name: "default".into(),
            model: config.model.clone(),
            profile: config.profile,
            goals: config.goals.clone(),
            episodes: 0,
            modes: None,
            seed: config.seed,
            solver_budget: config.limits.solver_budget,
            view: None,
        })?;
        return Ok(Plan {
            path: StudyPath {
                name: "blockstack".into(),
                ..StudyPath::default()
            },
            conditions: vec![Arc::new(c)],
            max_participants: None,
            idle: None,
            joins_per_minute: None,
        });
    };
    if config.model.is_some() || config.profile.is_some() || config.goals.is_some() {
        return Err(ServeError::Config(
            "with --study the study file names each condition's model, profile and goals: give them there".into(),
        ));
    }
    if config.record_dir.is_none() {
        return Err(ServeError::Config(
            "a study writes one recording per participant: give --record-dir".into(),
        ));
    }
    let study = StudyFile::read(&path)?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let err = |reason: String| ServeError::Study {
        path: path.clone(),
        reason,
    };
    let seed = study.seed.unwrap_or(config.seed);
    let mut conditions = Vec::new();
    for c in &study.conditions {
        if conditions.iter().any(|d: &Arc<Condition>| d.name == c.name) {
            return Err(err(format!("two conditions are named {}", c.name)));
        }
        let profile = c
            .profile
            .as_deref()
            .map(str::parse::<Profile>)
            .transpose()
            .map_err(|e| err(format!("condition {}: {e}", c.name)))?;
        let modes = c
            .modes
            .as_ref()
            .map(|ms| {
                ms.iter()
                    .map(|m| m.parse::<Mode>())
                    .collect::<std::result::Result<Vec<_>, _>>()
            })
            .transpose()
            .map_err(|e| err(format!("condition {}: {e}", c.name)))?;
        let prepared = Condition::prepare(&ConditionSpec {
            name: c.name.clone(),
            model: c.model.as_ref().map(|m| folder.join(m)),
            profile,
            goals: c.goals.clone(),
            episodes: c.episodes,
            modes,
            seed,
            solver_budget: config.limits.solver_budget,
            view: c
                .view
                .as_deref()
                .map(str::parse::<View>)
                .transpose()
                .map_err(|e| err(format!("condition {}: {e}", c.name)))?,
        })
        .map_err(|e| match e {
            // Condition::prepare's own lines name the condition already (P22: not twice).
            ServeError::Config(line) => err(line),
            other => err(format!("condition {}: {other}", c.name)),
        })?;
        conditions.push(Arc::new(prepared));
    }
    let text = |inline: &Option<String>, file: &Option<PathBuf>, what: &str| -> Result<Option<String>> {
        let markdown = match (inline, file) {
            (Some(text), _) => Some(text.clone()),
            (None, Some(file)) => {
                let file = folder.join(file);
                let mut text = String::new();
                std::io::Read::read_to_string(&mut files::open_bounded(&file, 1 << 20, "a Markdown text")?, &mut text)
                    .map_err(|e| err(format!("{what} {}: {e}", file.display())))?;
                Some(text)
            }
            (None, None) => None,
        };
        Ok(markdown.as_deref().map(crate::markdown::render))
    };
    let path_of_study = StudyPath {
        name: study.name.clone().unwrap_or_else(|| "study".into()),
        consent: text(&study.consent, &study.consent_file, "consent_file")?,
        instructions: text(&study.instructions, &study.instructions_file, "instructions_file")?,
        participant_ids: study.participant_ids.clone(),
        completion_code: study.completion_code.clone(),
        code_per_participant: study.code_per_participant,
        completion_url: study.completion_url.clone(),
        completion_on_withdrawal: study.completion_on_withdrawal,
        require_ids: study.require_ids,
        withdrawal: study
            .withdrawal
            .as_deref()
            .map(|w| w.parse().expect("checked on reading")),
    };
    Ok(Plan {
        path: path_of_study,
        conditions,
        max_participants: study.max_participants,
        idle: study.idle_minutes.map(|m| Duration::from_secs(m.saturating_mul(60))),
        joins_per_minute: study.joins_per_minute,
    })
}
