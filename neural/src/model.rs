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
use std::io::Read;
use std::path::Path;

use files::container::Expect;

use agent::Policy;
use serde::{Deserialize, Serialize};
use sim::seeding::SimRng;
use sim::{
    Action, ActionProtocol, Backend, EnvConfig, Goal, GoalSpec, Grid, Observation, RewardModel, ScreenGoal, StartRule,
};

use crate::config::{DemoSource, DqnConfig, Epsilon, LossKind, TargetEvery, TdLoss};
use crate::error::{NeuralError, Result};
use crate::input::ObsKind;
use crate::mask::ActionSet;
use crate::net::{NetConfig, QNet};
use crate::netfile::{self, NetFile};
use crate::optim::OptimizerKind;

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
    /// Relabelled transitions stored ([`DqnConfig::hindsight`]); absent from a file at 0,
    /// as in every file before it.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub relabelled: u64,
}

fn is_zero(v: &u64) -> bool {
    *v == 0
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
        self.config.grid()
    }

    /// The number of blocks it plays with.
    pub fn blocks(&self) -> usize {
        self.config.blocks()
    }

    /// A short name for reports: `dqn-<network>`.
    pub fn name(&self) -> String {
        format!("dqn-{}", self.config.net.kind)
    }

    /// An error unless a world of `blocks` blocks on `grid` is the network's.
    pub fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        if grid != self.config.grid() || blocks != self.config.blocks() {
            return Err(NeuralError::Mismatch(format!(
                "the network plays {} blocks on a {} grid, the world has {blocks} blocks on a {grid} grid",
                self.config.blocks(),
                self.config.grid()
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

    /// The environment observation this network plays on as it is ([`Dqn::act_on_picture`]):
    /// `paper-screen` (the paper network's, and the `conv` network's on `--screen paper`),
    /// `screen` for the `conv` network on its default screen; `None` for the networks on
    /// planes (their input is made from the state) and the `strip` screen.
    pub fn picture(&self) -> Option<ObsKind> {
        let kind = self.config.obs();
        let shown = kind == ObsKind::PaperScreen
            || (kind == ObsKind::Screen && self.net.input().screen == ScreenGoal::default());
        shown.then_some(kind)
    }

    /// The action for a picture the environment rendered (`sim::ObsKind::write`'s bytes of
    /// the kind the network reads: `paper-screen`, or `screen` for the `conv` network on
    /// its default screen), among the actions of `allowed` (action indices: the
    /// environment's legal actions; the no-op mask of [`Dqn::greedy_action`] needs the
    /// state, which a picture does not give): a random one of them with probability
    /// `epsilon` (drawn from `rng`), else the greedy one. `goal` names the blocks the
    /// network's Pick columns name by their place in the goal. An error for a network that
    /// reads planes, or a picture of another size.
    pub fn act_on_picture(
        &self,
        picture: &[u8],
        goal: &Goal,
        allowed: ActionSet,
        epsilon: f64,
        rng: &mut SimRng,
    ) -> Result<Action> {
        use rand::RngExt;
        agent::qlearning::check_epsilon(epsilon)?;
        let spec = self.net.input();
        let kind = self.config.obs();
        if self.picture().is_none() {
            let reads = match kind {
                ObsKind::Screen => format!(
                    "the screen with the goal as a {}, which no environment shows",
                    spec.screen
                ),
                kind => format!("{kind}, which it makes from the state"),
            };
            return Err(NeuralError::Mismatch(format!(
                "the {} network reads {reads}: play it on the state observation",
                self.config.net.kind
            )));
        }
        if picture.len() != spec.len() || goal.block_count() != self.blocks() {
            return Err(NeuralError::Mismatch(format!(
                "the network reads a {kind} of {} values for {} blocks, and was given {} values and a goal of {} blocks",
                spec.len(),
                self.blocks(),
                picture.len(),
                goal.block_count()
            )));
        }
        if epsilon > 0.0 && rng.random_bool(epsilon) {
            let a = allowed
                .random(rng)
                .ok_or_else(|| NeuralError::Mismatch("no action is allowed".into()))?;
            return Ok(Action::from_index(a, self.blocks())?);
        }
        let x: Vec<f32> = picture.iter().map(|&b| f32::from(b) * spec.scale()).collect();
        let q = self.net.q_values(x)?.remove(0);
        let mut columns = Vec::new();
        for a in allowed.iter() {
            columns.push(spec.column(goal, Action::from_index(a, self.blocks())?));
        }
        let columns = ActionSet::from_indices(columns);
        let column = crate::mask::masked_argmax(&q, columns)
            .ok_or_else(|| NeuralError::Mismatch("no action is allowed".into()))?;
        Ok(spec.action(goal, column))
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
        let metadata = Metadata {
            config: StoredConfig::of(&self.config),
            report: self.report,
            warnings: self.warnings.clone(),
        };
        netfile::save(path, &EXPECT, &metadata, self.net.tensors())
    }

    /// Reads a network file; an error saying what is wrong if it is missing, too large,
    /// truncated, corrupt, of another format or version, or if its tensors do not fit its
    /// config.
    pub fn load(path: &Path) -> Result<Dqn> {
        Dqn::from_file(&NetFile::open(path, &EXPECT)?)
    }

    /// Reads a network from the bytes of a network file, named `name` in errors, with the
    /// checks of [`Dqn::load`] (the fuzz target `network_file` feeds it).
    pub fn read_from(input: impl Read, name: &str) -> Result<Dqn> {
        Dqn::from_file(&NetFile::read_from(input, name, &EXPECT)?)
    }

    /// The network a file read as a container holds, checked against its config.
    fn from_file(file: &NetFile) -> Result<Dqn> {
        let Metadata {
            config,
            report,
            warnings,
        } = file.metadata()?;
        let config = config.config();
        file.config_checked(config.validate())?;
        let input = config.net.input(config.grid(), config.blocks())?;
        let mut net = QNet::new(config.net, input, &mut sim::seeding::rng(0))?;
        let expected = net.tensors().count();
        file.fill(
            &format!("its {} network", config.net.kind),
            expected,
            |name, shape, values| net.set_tensor(name, shape, values),
        )?;
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
    config: StoredConfig,
    report: TrainReport,
    /// [`Dqn::warnings`]; absent when there are none, and in files from before it was kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    warnings: Vec<String>,
}

/// A training run as network files (version 1) store it: the flat field layout those files
/// were written with, frozen here, converted explicitly from and to [`DqnConfig`] (which
/// holds the world as `sim`'s one world value). A regrouping of `DqnConfig` changes no file;
/// changing this struct is changing the format. Fields added since the first files are
/// optional and left out at their default value, so a run that does not use them writes
/// the bytes it always did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct StoredConfig {
    grid: Grid,
    blocks: usize,
    goals: Vec<Goal>,
    net: NetConfig,
    reward: RewardModel,
    horizon: u32,
    backend: Backend,
    // Absent in files written before protocols existed.
    #[serde(default)]
    protocol: ActionProtocol,
    seed: u64,
    steps: u64,
    pretrain_steps: u64,
    demos: DemoSource,
    loss: LossKind,
    td_loss: TdLoss,
    optimizer: OptimizerKind,
    lr: f64,
    lr_final: f64,
    gamma: f64,
    buffer: usize,
    batch: usize,
    train_every: u64,
    learning_starts: u64,
    target_every: TargetEvery,
    epsilon: Epsilon,
    double: bool,
    clip_norm: Option<f64>,
    n_step: usize,
    margin: f64,
    lambda_n_step: f64,
    lambda_margin: f64,
    l2: f64,
    demo_share: f64,
    mask_noops: bool,
    correct_loops: bool,
    // Optional: absent at the default (uniform starts), as in every file before it.
    #[serde(default, skip_serializing_if = "is_default")]
    start: StartRule,
    // Optional: absent at 0 (no hindsight relabelling), as in every file before it.
    #[serde(default, skip_serializing_if = "is_default")]
    hindsight: usize,
}

fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}

impl StoredConfig {
    /// The stored form of `c`.
    pub(crate) fn of(c: &DqnConfig) -> StoredConfig {
        let w = &c.world;
        StoredConfig {
            grid: w.grid,
            blocks: w.blocks,
            goals: c.goals.clone(),
            net: c.net,
            reward: w.reward,
            horizon: w.horizon,
            backend: w.backend,
            protocol: w.protocol,
            seed: c.seed,
            steps: c.steps,
            pretrain_steps: c.pretrain_steps,
            demos: c.demos.clone(),
            loss: c.loss,
            td_loss: c.td_loss,
            optimizer: c.optimizer,
            lr: c.lr,
            lr_final: c.lr_final,
            gamma: c.gamma,
            buffer: c.buffer,
            batch: c.batch,
            train_every: c.train_every,
            learning_starts: c.learning_starts,
            target_every: c.target_every,
            epsilon: c.epsilon,
            double: c.double,
            clip_norm: c.clip_norm,
            n_step: c.n_step,
            margin: c.margin,
            lambda_n_step: c.lambda_n_step,
            lambda_margin: c.lambda_margin,
            l2: c.l2,
            demo_share: c.demo_share,
            mask_noops: c.mask_noops,
            correct_loops: c.correct_loops,
            start: w.start,
            hindsight: c.hindsight,
        }
    }

    /// The config this stored form describes: games ending at the goal, the goal drawn.
    pub(crate) fn config(self) -> DqnConfig {
        DqnConfig {
            world: EnvConfig {
                grid: self.grid,
                blocks: self.blocks,
                goal: GoalSpec::Random,
                horizon: self.horizon,
                reward: self.reward,
                backend: self.backend,
                protocol: self.protocol,
                start: self.start,
                ..EnvConfig::default()
            },
            goals: self.goals,
            net: self.net,
            seed: self.seed,
            steps: self.steps,
            pretrain_steps: self.pretrain_steps,
            demos: self.demos,
            loss: self.loss,
            td_loss: self.td_loss,
            optimizer: self.optimizer,
            lr: self.lr,
            lr_final: self.lr_final,
            gamma: self.gamma,
            buffer: self.buffer,
            batch: self.batch,
            train_every: self.train_every,
            learning_starts: self.learning_starts,
            target_every: self.target_every,
            epsilon: self.epsilon,
            double: self.double,
            clip_norm: self.clip_norm,
            n_step: self.n_step,
            margin: self.margin,
            lambda_n_step: self.lambda_n_step,
            lambda_margin: self.lambda_margin,
            l2: self.l2,
            demo_share: self.demo_share,
            mask_noops: self.mask_noops,
            correct_loops: self.correct_loops,
            hindsight: self.hindsight,
        }
    }
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
            return Ok(Action::from_index(a, self.dqn.config.blocks())?);
        }
        if let Some(&a) = self.greedy.get(obs) {
            return Ok(a);
        }
        let a = self.dqn.greedy_action(obs)?;
        self.greedy.insert(obs.clone(), a);
        Ok(a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stored_config_gives_back_the_config_and_leaves_out_defaults() {
        for name in crate::preset::Preset::ALL {
            let Ok(config) = DqnConfig::preset(name, 3) else {
                assert_eq!(name, crate::preset::Preset::General, "only general trains no network");
                continue;
            };
            let json = serde_json::to_string(&StoredConfig::of(&config)).unwrap();
            // The fields added since the first files are absent at their defaults.
            assert!(!json.contains("\"start\":\""), "{name}");
            assert_eq!(json.contains("\"hindsight\""), config.hindsight > 0, "{name}");
            let back: StoredConfig = serde_json::from_str(&json).unwrap();
            assert_eq!(back.config(), config, "{name}");
        }
        let her = DqnConfig::preset(crate::preset::Preset::HerPlanes, 3).unwrap();
        let moved = DqnConfig {
            world: EnvConfig {
                start: StartRule::Paper,
                ..her.world
            },
            ..her
        };
        let json = serde_json::to_string(&StoredConfig::of(&moved)).unwrap();
        assert!(
            json.contains("\"start\":\"paper\"") && json.contains("\"hindsight\":4"),
            "{json}"
        );
        let back: StoredConfig = serde_json::from_str(&json).unwrap();
        assert_eq!(back.config(), moved);
    }
}
