//! Model files as the commands that play them see them: a file says what it holds (a
//! tabular Q-agent, or a network), and `eval` and `run` dispatch on it.

use std::path::Path;

use agent::{Policy, QAgent};
use anyhow::Result;
use neural::Dqn;
use sim::{Grid, RewardModel};

/// A trained agent read from a model file.
pub enum Model {
    /// A tabular Q-agent (`blockstack train`).
    Q(Box<QAgent>),
    /// A network (`blockstack dqn`).
    Dqn(Box<Dqn>),
}

impl Model {
    /// Reads the model file at `path`, whichever kind it is: the container names its
    /// format in its header; anything that is not a network file is read as a tabular model
    /// (whose reader says what is wrong with a file that is neither).
    pub fn load(path: &Path) -> Result<Model> {
        match files::container::format_of(path, neural::model::MAX_NETWORK_BYTES) {
            Some(format) if format == neural::model::FORMAT => Ok(Model::Dqn(Box::new(Dqn::load(path)?))),
            _ => Ok(Model::Q(Box::new(QAgent::load(path)?))),
        }
    }

    /// The grid it plays on.
    pub fn grid(&self) -> Grid {
        match self {
            Model::Q(q) => q.grid(),
            Model::Dqn(d) => d.grid(),
        }
    }

    /// The number of blocks it plays with.
    pub fn blocks(&self) -> usize {
        match self {
            Model::Q(q) => q.blocks(),
            Model::Dqn(d) => d.blocks(),
        }
    }

    /// Its name in reports.
    pub fn name(&self) -> String {
        match self {
            Model::Q(q) => q.name(),
            Model::Dqn(d) => d.name(),
        }
    }

    /// The reward it was trained with (sparse when the file does not say).
    pub fn reward(&self) -> RewardModel {
        match self {
            Model::Q(q) => q.training().map_or_else(
                || RewardModel::from_name("sparse").expect("a known model"),
                |t| t.reward,
            ),
            Model::Dqn(d) => d.config().reward,
        }
    }

    /// An error unless a world of `blocks` blocks on `grid` is the model's.
    pub fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        match self {
            Model::Q(q) => q.check_world(grid, blocks)?,
            Model::Dqn(d) => d.check_world(grid, blocks)?,
        }
        Ok(())
    }

    /// The model playing with a random action with probability `epsilon`.
    pub fn policy(&self, epsilon: f64) -> Result<Box<dyn Policy + '_>> {
        Ok(match self {
            Model::Q(q) => Box::new(q.policy(epsilon)?),
            Model::Dqn(d) => Box::new(d.policy(epsilon)?),
        })
    }
}
