//! Agents that act in the blockstack world.
//!
//! - [`Policy`]: what every agent offers; [`RandomPolicy`] is the paper's baseline.
//! - [`rollout`]: the episode loop every command and experiment shares, with its
//!   [`Summary`](rollout::Summary) of failures and steps to goal.
//! - [`QAgent`]: tabular Q-learning over one of the [`repr`] state representations, trained
//!   by [`train`](train::train) / [`Trainer`], saved and loaded as [`model`] files.
//! - [`optimality`]: steps taken against the exact solver's shortest plans.

pub mod error;
pub mod model;
pub mod optimality;
pub mod planner_policy;
pub mod policy;
pub mod qlearning;
pub mod qtable;
pub mod repr;
pub mod rollout;
pub mod train;

pub use error::{AgentError, Result};
pub use planner_policy::{ExactPolicy, OraclePolicy};
pub use policy::{Policy, RandomPolicy};
pub use qlearning::{QAgent, QParams, QPolicy};
pub use qtable::QTable;
pub use repr::{Repr, ReprKind, Representation};
pub use rollout::{EpisodeResult, Summary, play, play_episode};
pub use train::{Assist, Progress, TrainConfig, TrainReport, Trained, Trainer, train};
