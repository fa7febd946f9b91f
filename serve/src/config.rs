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
use serde::Deserialize;
use sim::{Env, EnvConfig, Goal, GoalSpec, Grid, Profile};

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
    /// A session with no page connected for this long is let go.
    pub session_idle: Duration,
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
    /// sessions let go after 30 minutes without a page, requests cut off after 10 s, pages
    /// after 90 s without an answer, 1,000 connections, a million states for a shortest plan.
    fn default() -> Self {
        Limits {
            max_sessions: 100,
            actions_per_second: 20,
            max_message_bytes: 1024,
            max_frame_bytes: 64 * 1024,
            session_idle: Duration::from_secs(30 * 60),
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
    /// folder (at least 1).
    #[serde(default)]
    pub max_participants: Option<u64>,
    /// The conditions, handed to participants in turn.
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
    /// cannot be corrected by the tabular rule).
    pub agent: QAgent,
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
        } = spec;
        let (name, profile, episodes, seed) = (name.as_str(), *profile, *episodes, *seed);
        let (model, goals, modes) = (model.as_deref(), goals.as_deref(), modes.as_deref());
        let loaded = model.map(AnyModel::load).transpose()?;
        let tabular = match &loaded {
            Some(AnyModel::Q(q)) => Some((**q).clone()),
            _ => None,
        };
        let agent_is_model = tabular.is_some();
        let agent = match tabular {
            Some(q) => q,
            None => {
                // An untrained stand-in of the profile, on the model's grid and blocks.
                let p = LearnerProfile::of(profile.unwrap_or(Profile::Spec));
                let (grid, blocks) = loaded.as_ref().map_or((Grid::default(), 3), |m| (m.grid(), m.blocks()));
                QAgent::with_schedule(p.repr, grid, blocks, QParams::default(), p.schedule)?
            }
        };
        let (world, profile) = session_world_under(&agent, profile);
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
        let watch_world = loaded.as_ref().map_or(world, AnyModel::world);
        let condition = Condition {
            name: name.to_string(),
            model_file: model.map(|p| p.display().to_string()),
            model: loaded.map(Arc::new),
            agent,
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
                self.world,
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
            .map(|g| GoalSpec::Fixed(*g))
            .collect();
        if goals.is_empty() {
            vec![GoalSpec::Random]
        } else {
            goals
        }
    }
}

/// What a server runs: the study's name, its conditions, and the participants it admits
/// at most (none: no cap but `--max-sessions` at once).
pub struct Plan {
    /// The study's name (`blockstack` without a study).
    pub name: String,
    /// The conditions, handed to participants to keep them balanced.
    pub conditions: Vec<Arc<Condition>>,
    /// The study's `max_participants`.
    pub max_participants: Option<u64>,
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
        })?;
        return Ok(Plan {
            name: "blockstack".into(),
            conditions: vec![Arc::new(c)],
            max_participants: None,
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
        })
        .map_err(|e| err(format!("condition {}: {e}", c.name)))?;
        conditions.push(Arc::new(prepared));
    }
    Ok(Plan {
        name: study.name.unwrap_or_else(|| "study".into()),
        conditions,
        max_participants: study.max_participants,
    })
}
