//! Model files as the commands that play them see them: a file says what it holds (a
//! tabular Q-agent, or a network), and `eval` and `run` dispatch on it.

use std::path::Path;

use agent::{Policy, QAgent};
use anyhow::Result;
use neural::Dqn;
use sim::{Grid, Profile, RewardModel};

use super::profile::Rules;

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

    /// The reward it was trained with, when the file says.
    pub fn training_reward(&self) -> Option<RewardModel> {
        match self {
            Model::Q(q) => q.training().map(|t| t.world.reward),
            Model::Dqn(d) => Some(d.config().reward),
        }
    }

    /// The rules of the world it was trained in: a tabular model's
    /// ([`Rules::of_model`]); a network's protocol and reward in the `spec` profile's world
    /// (`blockstack dqn` trains there, from uniform starts).
    pub fn rules(&self) -> Rules {
        match self {
            Model::Q(q) => Rules::of_model(q),
            Model::Dqn(d) => Rules {
                protocol: d.config().protocol,
                reward: d.config().reward,
                ..Rules::of(Profile::Spec)
            },
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
