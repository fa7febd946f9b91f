//! The errors the neural learner reports.

use thiserror::Error;

/// What can go wrong while a network is built, trained, played, saved or read.
#[derive(Debug, Error)]
pub enum NeuralError {
    /// An agent-layer piece (rollout, demonstrations reader) refused something.
    #[error(transparent)]
    Agent(#[from] agent::AgentError),
    /// The world refused something (bad config, action, state).
    #[error(transparent)]
    Sim(#[from] sim::SimError),
    /// A file could not be written (or a destination is refused).
    #[error(transparent)]
    Files(#[from] files::FilesError),
    /// A planner could not plan a demonstration.
    #[error(transparent)]
    Oracle(#[from] oracle::OracleError),
    /// A learner configuration that cannot work (names the setting).
    #[error("invalid configuration: {0}")]
    Config(String),
    /// A network file that cannot be used: missing, truncated, corrupt, or of another format
    /// or version.
    #[error("cannot read network {path}: {reason}")]
    Model {
        /// The file.
        path: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A training checkpoint that cannot be read or written.
    #[error("checkpoint {path}: {reason}")]
    Checkpoint {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// A network used with a world it was not made for.
    #[error("the network does not fit: {0}")]
    Mismatch(String),
    /// A setting the `general` preset (the relational policy) does not take, by its name in
    /// [`crate::DqnOverrides`]; `blockstack dqn` names the flag instead.
    #[error(
        "{setting} does not apply to the general preset (a relational policy learnt from the optimum): it takes {}",
        crate::preset::GENERAL_SETTINGS.join(", ")
    )]
    NotForGeneral {
        /// The setting given.
        setting: &'static str,
    },
    /// A demonstration file that cannot be used (names the file and the line).
    #[error("demonstrations {path}: {reason}")]
    Demos {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
}

/// Shorthand for results whose error is a [`NeuralError`].
pub type Result<T, E = NeuralError> = std::result::Result<T, E>;

impl From<NeuralError> for agent::AgentError {
    /// For the [`agent::Policy`] interface: a network that cannot act is a model that does
    /// not fit.
    fn from(e: NeuralError) -> Self {
        match e {
            NeuralError::Agent(e) => e,
            NeuralError::Sim(e) => agent::AgentError::Sim(e),
            NeuralError::Oracle(e) => agent::AgentError::Oracle(e),
            other => agent::AgentError::ModelMismatch(other.to_string()),
        }
    }
}
