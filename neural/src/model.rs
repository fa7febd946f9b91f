//! A trained network with its training config: played through [`agent::Policy`], saved and
//! read as a network file.
//!
//! # Network files
//!
//! The project's model container (`files::container`: safetensors with blockstack's
//! metadata and a CRC-32), format [`FORMAT`] version [`VERSION`]: one `F32` tensor per
//! parameter and per batch-normalisation statistic, named as [`QNet::tensors`] names them
//! (`conv1.weight`, `linear2.bias`, `conv1.bn.running_mean`, ...; a convolution's weight is
//! `[k * k * channels in, channels out]`, a linear layer's `[in, out]`), and as metadata
//! `{"config": the DqnConfig, "report": the TrainReport}`, with `"warnings": [sentence, ...]`
//! when the run took no gradient step ([`Dqn::warnings`]; absent otherwise, and optional
//! for a reader). A reader refuses a file that is
//! missing, too large ([`MAX_NETWORK_BYTES`]), truncated, corrupt, of another format or
//! version, or whose tensors do not fit the network its config describes, each with a
//! message that says which.

use std::collections::HashMap;
use std::path::Path;

use files::container::{Container, Expect, Tensor};
use files::{FilesError, OutputPath};

use agent::Policy;
use serde::{Deserialize, Serialize};
use sim::seeding::SimRng;
use sim::{Action, Grid, Observation};

use crate::config::DqnConfig;
use crate::error::{NeuralError, Result};
use crate::mask::ActionSet;
use crate::net::QNet;

/// The format name of a network file.
pub const FORMAT: &str = "blockstack-dqn";

/// The network file version this build writes and reads.
pub const VERSION: u32 = 1;

/// The largest network file read: far above the paper network's 4 MB.
pub const MAX_NETWORK_BYTES: u64 = 1 << 30;

const EXPECT: Expect<'static> = Expect {
    format: FORMAT,
    version: VERSION,
    max_bytes: MAX_NETWORK_BYTES,
    what: "a network file",
};

/// Totals of a training run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrainReport {
    /// Demonstrated episodes loaded.
    pub demo_episodes: u64,
    /// Their transitions, kept in the buffer.
    pub demo_transitions: u64,
    /// Gradient steps of pre-training.
    pub pretrain_steps: u64,
    /// Self-play games begun.
    pub games: u64,
    /// Of those, games that reached the goal.
    pub successes: u64,
    /// Self-play environment steps.
    pub steps: u64,
    /// Gradient steps in all (pre-training included).
    pub gradient_steps: u64,
    /// Demonstrations from a loop of a self-play game ([`DqnConfig::correct_loops`]).
    pub corrections: u64,
}

/// A network and how it was trained.
pub struct Dqn {
    net: QNet,
    config: DqnConfig,
    report: TrainReport,
    warnings: Vec<String>,
}

impl Dqn {
    /// A network with its config and report (the trainer's).
    pub fn new(net: QNet, config: DqnConfig, report: TrainReport) -> Dqn {
        let warnings = training_warnings(&config, &report);
        Dqn {
            net,
            config,
            report,
            warnings,
        }
    }

    /// The network.
    pub fn net(&self) -> &QNet {
        &self.net
    }

    /// The training config.
    pub fn config(&self) -> &DqnConfig {
        &self.config
    }

    /// The training totals.
    pub fn report(&self) -> &TrainReport {
        &self.report
    }

    /// What makes this network less than its user may think (a run that took no gradient
    /// step: its weights are the seed's initial ones), one sentence each; saved in its file.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The grid it plays on.
    pub fn grid(&self) -> Grid {
        self.config.grid
    }

    /// The number of blocks it plays with.
    pub fn blocks(&self) -> usize {
        self.config.blocks
    }

    /// A short name for reports: `dqn-<network>`.
    pub fn name(&self) -> String {
        format!("dqn-{}", self.config.net.kind)
    }

    /// An error unless a world of `blocks` blocks on `grid` is the network's.
    pub fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        if grid != self.config.grid || blocks != self.config.blocks {
            return Err(NeuralError::Mismatch(format!(
                "the network plays {} blocks on a {} grid, the world has {blocks} blocks on a {grid} grid",
                self.config.blocks, self.config.grid
            )));
        }
        Ok(())
    }

    /// Q-values of `obs`, by output column ([`crate::input`]: Pick columns name goal
    /// places on planes).
    pub fn q_values(&self, obs: &Observation) -> Result<Vec<f32>> {
        let spec = self.net.input();
        spec.check(obs)?;
        Ok(self.net.q_values(spec.batch(&[obs]))?.remove(0))
    }

    /// The allowed action (masked as in training) with the highest Q-value.
    pub fn greedy_action(&self, obs: &Observation) -> Result<Action> {
        self.net.input().check(obs)?;
        self.net.greedy_action(obs, self.config.mask_noops)
    }

    /// The network as a [`Policy`]: a uniformly random allowed action with probability
    /// `epsilon`, the greedy one otherwise.
    pub fn policy(&self, epsilon: f64) -> Result<DqnPolicy<'_>> {
        agent::qlearning::check_epsilon(epsilon)?;
        Ok(DqnPolicy {
            dqn: self,
            epsilon,
            greedy: HashMap::new(),
        })
    }

    /// Writes the network file (module docs) through the project's output helper:
    /// atomically for a regular file.
    pub fn save(&self, path: &Path) -> Result<()> {
        let out = OutputPath::check(path)?;
        let tensors: Vec<(&str, Tensor<'_>)> = self
            .net
            .tensors()
            .map(|t| {
                let tensor = Tensor::from_values(t.shape, t.values).expect("a tensor's shape fits its values");
                (t.name, tensor)
            })
            .collect();
        let metadata = Metadata {
            config: self.config.clone(),
            report: self.report,
            warnings: self.warnings.clone(),
        };
        files::container::write(&out, FORMAT, VERSION, &metadata, &tensors)?;
        Ok(())
    }

    /// Reads a network file; an error saying what is wrong if it is missing, too large,
    /// truncated, corrupt, of another format or version, or if its tensors do not fit its
    /// config.
    pub fn load(path: &Path) -> Result<Dqn> {
        let fail = |reason: String| NeuralError::Model {
            path: path.display().to_string(),
            reason,
        };
        let container = Container::read(path, &EXPECT).map_err(|e| match e {
            FilesError::Read { problem, .. } => fail(problem.to_string()),
            other => fail(other.to_string()),
        })?;
        let Metadata {
            config,
            report,
            warnings,
        } = container
            .metadata()
            .map_err(|e| fail(format!("the file is corrupt: its metadata does not read ({e})")))?;
        config
            .validate()
            .map_err(|e| fail(format!("its training config is not valid: {e}")))?;
        let input = config.net.input(config.grid, config.blocks)?;
        let mut net = QNet::new(config.net, input, &mut sim::seeding::rng(0))?;
        let names = container.names();
        let expected = net.tensors().count();
        if names.len() != expected {
            return Err(fail(format!(
                "it holds {} tensors, and its {} network has {expected}",
                names.len(),
                config.net.kind
            )));
        }
        for name in names {
            let tensor = container.tensor(&name).expect("a name of the container");
            let values = tensor
                .values::<f32>()
                .ok_or_else(|| fail(format!("tensor {name} is {:?}, not F32", tensor.dtype())))?;
            net.set_tensor(&name, tensor.shape(), &values)
                .map_err(|e| fail(e.to_string()))?;
        }
        Ok(Dqn {
            net,
            config,
            report,
            warnings,
        })
    }
}

/// The warnings of [`Dqn::warnings`] for a run of `config` that ended with `report`. A run
/// that pre-trained but learned nothing in self-play is not warned about: pre-training alone
/// is a way to train.
fn training_warnings(config: &DqnConfig, report: &TrainReport) -> Vec<String> {
    if report.gradient_steps > 0 {
        return Vec::new();
    }
    vec![format!(
        "the network is untrained: no gradient step was taken (no pre-training, {} self-play steps, \
         and self-play learns only once the buffer holds {} of the agent's transitions)",
        report.steps,
        config.learning_starts.max(1)
    )]
}

/// The JSON metadata of a network file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Metadata {
    config: DqnConfig,
    report: TrainReport,
    /// [`Dqn::warnings`]; absent when there are none, and in files from before it was kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    warnings: Vec<String>,
}

/// A trained network playing without learning. Borrows the network.
///
/// The greedy choice of each observation is remembered for the episode: the network is
/// fixed and the argmax deterministic, so a state seen again gets the same action without a
/// second forward pass. A greedy policy caught in a loop (the world is deterministic too)
/// then costs a table look-up a step, not a network evaluation, until the horizon.
pub struct DqnPolicy<'a> {
    dqn: &'a Dqn,
    epsilon: f64,
    greedy: HashMap<Observation, Action>,
}

impl Policy for DqnPolicy<'_> {
    fn name(&self) -> String {
        self.dqn.name()
    }

    fn begin_episode(&mut self, _obs: &Observation) {
        self.greedy.clear();
    }

    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> agent::Result<Action> {
        use rand::RngExt;
        if self.epsilon > 0.0 && rng.random_bool(self.epsilon) {
            let allowed = ActionSet::allowed(obs, self.dqn.config.mask_noops);
            let a = allowed.random(rng).expect("some action is always allowed");
            return Ok(Action::from_index(a, self.dqn.config.blocks)?);
        }
        if let Some(&a) = self.greedy.get(obs) {
            return Ok(a);
        }
        let a = self.dqn.greedy_action(obs)?;
        self.greedy.insert(*obs, a);
        Ok(a)
    }
}
