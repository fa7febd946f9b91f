//! Agents that act in the blockstack world.
//!
//! - [`Policy`]: what every agent offers; [`RandomPolicy`] is the paper's baseline. Every
//!   policy chooses among the legal actions of its observation (the world's action
//!   protocol): the planners ([`planner_policy`]) plan under it, the Q-learners mask it.
//! - [`PolicyKind`] ([`policy_kind`]): an agent chosen by name (the random agent, a planner,
//!   a trained model), built from the world it plays and its model.
//! - [`rollout`]: the episode loop every command and experiment shares, with its
//!   [`Summary`] of failures and steps to goal.
//! - [`QAgent`]: tabular Q-learning over one of the [`repr`] state representations, trained
//!   by [`train`](train::train) / [`Trainer`] as a [`TrainConfig`] ([`config`]) says, which
//!   [`TrainConfig::resolve`] ([`preset`]) makes from a profile, a preset and explicit
//!   settings, on a [`schedule`], assisted by an oracle as
//!   [`assist`] says, saved and loaded as [`model`] files; a run stopped and resumed
//!   through a [`checkpoint`] ends as if it had not stopped.
//! - [`optimality`]: steps taken against the exact solver's shortest plans; [`eval`]: a
//!   policy evaluated on seeded starts, per goal and overall, as `blockstack eval` reports it.
//! - [`correction`]: learning from a demonstrator's corrections, and simulated
//!   [`demonstrator`]s; [`demos`]: recordings ([`demos::format`], needing no learner) and
//!   their replay into one; [`rule`]: the data both share.
//! - [`profile`]: the learner-level parts of `sim::Profile`: ours (`spec`), or the paper's
//!   learner, oracle and corrections as its authors coded them (`original`).

pub mod assist;
pub mod checkpoint;
pub mod config;
pub mod correction;
pub mod demonstrator;
pub mod demos;
pub mod error;
pub mod eval;
pub mod memory;
pub mod model;
pub mod optimality;
pub mod planner_policy;
pub mod policy;
pub mod policy_kind;
pub mod preset;
pub mod profile;
pub mod qlearning;
pub mod qtable;
pub mod repr;
pub mod rollout;
pub mod rule;
pub mod run;
pub mod schedule;
pub mod towers_policy;
pub mod train;

pub use assist::{Assist, OracleKind, Oscillation};
pub use config::{QParams, TrainConfig};
pub use correction::{Corrected, CorrectionConfig, CorrectionRule, CorrectionSession, correct};
pub use demonstrator::{Demonstrator, DemonstratorProfile};
pub use demos::{BadLines, DemoRecord, DemoSink, DemoWriter};
pub use error::{AgentError, Result};
pub use planner_policy::{ExactPolicy, OraclePolicy, PaperOraclePolicy, PlannerPolicy};
pub use policy::{Policy, RandomPolicy};
pub use policy_kind::{PlayingModel, PolicyKind, PolicyOptions};
pub use preset::{Preset, TrainOverrides};
pub use profile::LearnerProfile;
pub use qlearning::{QAgent, QPolicy};
pub use qtable::QTable;
pub use repr::{Repr, ReprKind, Representation};
pub use rollout::{EpisodeObserver, EpisodeResult, EpisodeStart, Summary, play, play_episode, play_episode_from};
pub use run::{Checkpoints, RunHooks};
pub use schedule::Schedule;
pub use towers_policy::TowersPolicy;
pub use train::{Progress, TrainReport, Trained, Trainer, train};
