//! The errors of the server library; the binary prints them as one line.

use std::path::PathBuf;

/// What can go wrong starting or running the server.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// A setting that cannot work (a mode a model cannot offer, a bad goal list, ...).
    #[error("{0}")]
    Config(String),
    /// The study file cannot be read or says something wrong.
    #[error("the study {path}: {reason}")]
    Study {
        /// The study file.
        path: PathBuf,
        /// What is wrong, naming the field.
        reason: String,
    },
    /// The address cannot be listened on.
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        /// The address asked for.
        addr: String,
        /// Why not.
        source: std::io::Error,
    },
    /// Another input/output failure of the server (the runtime, the listener).
    #[error("{0}")]
    Io(#[from] std::io::Error),
    /// A model, session or recording error.
    #[error(transparent)]
    Agent(#[from] agent::AgentError),
    /// A network model's error.
    #[error(transparent)]
    Neural(#[from] neural::NeuralError),
    /// A world error.
    #[error(transparent)]
    Sim(#[from] sim::SimError),
    /// An output path error (the recording folder).
    #[error(transparent)]
    Files(#[from] files::FilesError),
}

/// The result of the server library.
pub type Result<T> = std::result::Result<T, ServeError>;
