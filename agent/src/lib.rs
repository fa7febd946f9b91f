//! Agents that act in the blockstack world.
//!
//! - [`Policy`]: what every agent offers; [`RandomPolicy`] is the paper's baseline.
//! - [`rollout`]: the episode loop every command and experiment shares, with its
//!   [`Summary`](rollout::Summary) of failures and steps to goal.

pub mod error;
pub mod planner_policy;
pub mod policy;
pub mod rollout;

pub use error::{AgentError, Result};
pub use planner_policy::{ExactPolicy, OraclePolicy};
pub use policy::{Policy, RandomPolicy};
pub use rollout::{EpisodeResult, Summary, play, play_episode};
