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
    /// A model file that cannot be used: missing, truncated, corrupt, or of another format
    /// or version.
    #[error("cannot read model {path}: {reason}")]
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
    /// A model that cannot be saved (its table holds a value a file cannot keep).
    #[error("cannot save model {path}: {reason}")]
    ModelSave {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// A file's destination or reading failed (names the file).
    #[error(transparent)]
    Files(#[from] files::FilesError),
    /// A file of demonstrations whose episodes are of different worlds (grid or block
    /// count), read by a learner that takes one.
    #[error("the demonstrations mix worlds: {0}")]
    MixedWorlds(String),
    /// A model used with a world (or for a purpose) it was not made for.
    #[error("the model does not fit: {0}")]
    ModelMismatch(String),
    /// A learner or training configuration that cannot work (names the setting).
    #[error("invalid configuration: {0}")]
    Config(String),
    /// A demonstration recording that cannot be read or written (names the file, and the
    /// line when one is at fault).
    #[error("demonstrations {path}: {reason}")]
    Demos {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// Work stopped on the caller's word (a progress hook that saw Ctrl-C).
    #[error("interrupted")]
    Interrupted,
}

/// Shorthand for results whose error is an [`AgentError`].
pub type Result<T, E = AgentError> = std::result::Result<T, E>;
