//! The errors agents report.

use thiserror::Error;

/// What can go wrong while an agent acts, learns, or reads and writes its files.
#[derive(Debug, Error)]
pub enum AgentError {
    /// The world refused something (bad config, action, state).
    #[error(transparent)]
    Sim(#[from] sim::SimError),
    /// A planner (the oracle or the exact solver) could not plan.
    #[error(transparent)]
    Oracle(#[from] oracle::OracleError),
}

/// Shorthand for results whose error is an [`AgentError`].
pub type Result<T, E = AgentError> = std::result::Result<T, E>;
