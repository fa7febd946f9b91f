//! Everything that defines a training run, and the presets.
//!
//! # Presets
//!
//! - `paper`: the paper's DQN as section III-C and the authors' code describe it: pixels, the
//!   paper network with batch normalisation, buffer 1000, batch 64, RMSprop at 1e-4, MSE
//!   loss, the sparse reward, the target network refreshed every 3 training games (the
//!   paper's "every n epochs", n = 3 or 5), epsilon 0.1 throughout and gamma 0.1 (both from
//!   the authors' `DQN.py`; the paper gives neither), every action allowed (no mask), no
//!   demonstrations.
//! - `paper-dqfd`: the same with the paper's DQfD stage: pre-training on demonstrations
//!   (here 500 of the exact solver's, where the paper had people's) with the large-margin
//!   loss, then self-play with the demonstrations kept in the buffer.
//! - `dqn-planes`: ours without demonstrations: the small network on centred planes, Adam at
//!   1e-3 falling to 1e-4, Huber loss, double DQN, gamma 0.95, the sparse reward, a
//!   100,000-step buffer, the target refreshed every 500 gradient steps, epsilon from 1 to
//!   0.05 over the first half of 50,000 steps (2 blocks) or 300,000 (more), actions that
//!   change nothing masked, gradients clipped at norm 10.
//! - `dqfd-planes` (the recommended recipe): `dqn-planes` with DQfD (Hester et al. 2018):
//!   10,000 exact-solver demonstrations, 30,000 pre-training steps with the 1-step and
//!   10-step TD losses, the large-margin loss (margin 0.8) and L2 1e-5, then 30,000 steps of
//!   self-play (90,000 of each on 3 blocks; 40,000 demonstrations and 360,000 steps of
//!   each on 4 and more) with a quarter of every batch drawn from the demonstrations,
//!   epsilon from 0.1 to 0.01, the learning rate falling from 1e-3 to 1e-4, and loops corrected: the first
//!   time a game comes back to a state it was in, the exact solver demonstrates from there
//!   (the paper's demonstrators correcting the agent, section VI-C, as DQfD data).
//! - `her-planes`: `dqn-planes` with hindsight relabelling (HER, Andrychowicz et al. 2017,
//!   [`crate::hindsight`]): no demonstrations; every step stored again with 4 goals that
//!   stood later in its game.
//! - `dqfd-pixels`: `dqfd-planes` on the paper's screen with the paper's network (batch
//!   normalisation): the paper's network and input, our learner. Its budget is a few
//!   thousand steps (a step of that network costs twenty times one of ours): 1,000
//!   demonstrations, 6,000 pre-training and 6,000 self-play steps on 2 blocks (epsilon
//!   falling over the first 2,000); 5,000 and 15,000 on more (epsilon over 7,500).
//!
//! Why each of our choices, measured, is in the E8 section of `blockstack reproduce --only
//! E8 --long`'s report.

use std::fmt;

use serde::{Deserialize, Serialize};
use sim::{ActionProtocol, Backend, EnvConfig, Goal, GoalSpec, Grid, RewardModel};

use crate::error::{NeuralError, Result};
use crate::input::ObsKind;
use crate::net::{NetConfig, NetKind};
use crate::optim::OptimizerKind;

/// Where demonstrations come from.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DemoSource {
    /// None.
    #[default]
    None,
    /// That many episodes of the exact solver (shortest plans) from seeded starts.
    Exact(u64),
    /// That many episodes of the centroid + A* oracle from seeded starts.
    Oracle(u64),
    /// A recording: `blockstack-demos` JSON Lines, or a trajectory file.
    File(String),
}

impl fmt::Display for DemoSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DemoSource::None => f.write_str("none"),
            DemoSource::Exact(k) => write!(f, "exact:{k}"),
            DemoSource::Oracle(k) => write!(f, "oracle:{k}"),
            DemoSource::File(path) => write!(f, "file:{path}"),
        }
    }
}

impl std::str::FromStr for DemoSource {
    type Err = NeuralError;

    /// Reads `none`, `exact:K` or `oracle:K`.
    fn from_str(text: &str) -> Result<DemoSource> {
        let bad = || {
            NeuralError::Config(format!(
                "unknown demonstrations {text:?}: write exact:K or oracle:K (K episodes), or none"
            ))
        };
        if text == "none" {
            return Ok(DemoSource::None);
        }
        let (kind, count) = text.split_once(':').ok_or_else(bad)?;
        let count: u64 = count.parse().map_err(|_| bad())?;
        match kind {
            "exact" => Ok(DemoSource::Exact(count)),
            "oracle" => Ok(DemoSource::Oracle(count)),
            _ => Err(bad()),
        }
    }
}

/// Which losses train the network.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LossKind {
    /// The 1-step TD loss only; demonstrations, if any, are only data in the buffer.
    Dqn,
    /// DQfD: the 1-step and n-step TD losses, the large-margin loss on demonstrated actions,
    /// and L2 on the weights.
    Dqfd,
}

sim::names!(LossKind { Dqn = "dqn", Dqfd = "dqfd" } unknown(text) -> NeuralError {
    NeuralError::Config(format!("unknown loss {text:?}: choose dqfd or dqn"))
});

/// How a TD error is penalised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TdLoss {
    /// Huber (smooth L1, threshold 1).
    Huber,
    /// Mean squared error.
    Mse,
}

sim::names!(TdLoss { Huber = "huber", Mse = "mse" } unknown(text) -> NeuralError {
    NeuralError::Config(format!("unknown TD loss {text:?}: choose huber or mse"))
});

/// When the target network is refreshed from the online one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TargetEvery {
    /// Every that many gradient steps.
    Steps(u64),
    /// Every that many training games (the paper's "epochs").
    Games(u64),
}

/// Epsilon falls linearly from `start` to `end` over the first `steps` environment steps of
/// self-play, and stays at `end`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Epsilon {
    /// At the first step.
    pub start: f64,
    /// From `steps` on.
    pub end: f64,
    /// Length of the fall.
    pub steps: u64,
}

impl Epsilon {
    /// Epsilon after `step` environment steps.
    pub fn at(&self, step: u64) -> f64 {
        if step >= self.steps {
            self.end
        } else {
            self.start + (self.end - self.start) * step as f64 / self.steps as f64
        }
    }
}

/// A training run: the world, the network, the learner, the budget and the seed.
///
/// A network file stores it in a frozen form of its own (`crate::model`'s metadata), so
/// regrouping these fields changes no file.
#[derive(Clone, Debug, PartialEq)]
pub struct DqnConfig {
    /// The world the training games are played in: `sim`'s one world value (grid, blocks,
    /// horizon, reward, backend, protocol, start rule). Its goal is drawn (the games' goals
    /// are [`DqnConfig::goals`]) and its observation is the network's.
    pub world: EnvConfig,
    /// Goals trained on, in turn (game `k` plays `goals[k % len]`).
    pub goals: Vec<Goal>,
    /// The network (its kind says which observation it reads).
    pub net: NetConfig,
    /// Seed of the weights, starts, demonstrations and every random choice.
    pub seed: u64,
    /// Environment steps of self-play.
    pub steps: u64,
    /// Gradient steps on the demonstrations alone, before self-play.
    pub pretrain_steps: u64,
    /// Where demonstrations come from.
    pub demos: DemoSource,
    /// Which losses.
    pub loss: LossKind,
    /// How a TD error is penalised.
    pub td_loss: TdLoss,
    /// The optimiser.
    pub optimizer: OptimizerKind,
    /// Its learning rate.
    pub lr: f64,
    /// The learning rate at the end of the run: it falls linearly from `lr` over all the
    /// run's gradient steps (pre-training and self-play); equal to `lr` for a constant rate.
    pub lr_final: f64,
    /// The discount factor.
    pub gamma: f64,
    /// The agent's transitions the replay buffer holds.
    pub buffer: usize,
    /// Transitions per gradient step.
    pub batch: usize,
    /// Environment steps per gradient step in self-play.
    pub train_every: u64,
    /// The agent's transitions in the buffer before self-play learning begins.
    pub learning_starts: u64,
    /// When the target network is refreshed.
    pub target_every: TargetEvery,
    /// The exploration schedule.
    pub epsilon: Epsilon,
    /// Double DQN: the online network chooses the next action, the target values it.
    pub double: bool,
    /// Clip the gradients' global norm to this.
    pub clip_norm: Option<f64>,
    /// `n` of the n-step TD loss (DQfD).
    pub n_step: usize,
    /// The large-margin loss's margin `l(a_E, a)` for `a != a_E` (DQfD).
    pub margin: f64,
    /// Weight of the n-step TD loss (DQfD).
    pub lambda_n_step: f64,
    /// Weight of the large-margin loss (DQfD).
    pub lambda_margin: f64,
    /// Weight of the L2 penalty on the weights (DQfD).
    pub l2: f64,
    /// Share of every self-play batch drawn from the demonstrations.
    pub demo_share: f64,
    /// Leave actions that change nothing out of every choice ([`crate::mask`]).
    pub mask_noops: bool,
    /// Corrections in self-play: the first time in a game that the agent comes back to a
    /// state it was already in (it is going round in circles), a demonstrator (the planner
    /// of [`DqnConfig::demos`]; the exact solver for a recording or none) plans from there
    /// and its plan joins the demonstrations; the agent plays on.
    pub correct_loops: bool,
    /// Hindsight relabelling ([`crate::hindsight`]): every self-play step is stored again
    /// with up to this many goals that stood later in its game (HER's `future` strategy and
    /// its `k`); 0 for none.
    pub hindsight: usize,
}

/// The most input values one batch may hold (a batch's inputs are made in memory at every
/// gradient step): 256 MiB of floats, over 2,000 paper screens or 79,000 centred 7 x 7
/// planes of 3 blocks, where the presets draw 64.
pub const MAX_BATCH_VALUES: usize = 1 << 26;

/// The most memory the agent's transitions in the replay buffer may take: 8 GiB.
pub const MAX_BUFFER_BYTES: u64 = 8 << 30;

/// The most episodes a planner may demonstrate (all are kept in memory): 100 times the
/// recommended recipe's 10,000.
pub const MAX_DEMO_EPISODES: u64 = 1_000_000;

/// The preset names, in the order the CLI lists them.
pub const PRESETS: [&str; 6] = [
    "paper",
    "paper-dqfd",
    "dqn-planes",
    "dqfd-planes",
    "her-planes",
    "dqfd-pixels",
];

impl DqnConfig {
    /// The paper's DQN (module docs) on `blocks` blocks, every goal.
    pub fn paper(blocks: usize) -> Result<DqnConfig> {
        let net = NetConfig::paper();
        Ok(DqnConfig {
            world: EnvConfig {
                grid: Grid::default(),
                blocks,
                goal: GoalSpec::Random,
                horizon: sim::DEFAULT_HORIZON,
                reward: RewardModel::from_name("sparse")?,
                backend: Backend::Grid,
                protocol: ActionProtocol::Free,
                obs: net.obs(),
                ..EnvConfig::default()
            },
            goals: Goal::all(blocks)?,
            net,
            seed: 1,
            // A gradient step of the paper network costs about 100 ms here: 5,000 steps
            // are minutes, where the paper trained for 2-8 hours.
            steps: 5_000,
            pretrain_steps: 0,
            demos: DemoSource::None,
            loss: LossKind::Dqn,
            td_loss: TdLoss::Mse,
            optimizer: OptimizerKind::Rmsprop,
            lr: 1e-4,
            lr_final: 1e-4,
            gamma: 0.1,
            buffer: 1000,
            batch: 64,
            train_every: 1,
            learning_starts: 64,
            target_every: TargetEvery::Games(3),
            epsilon: Epsilon {
                start: 0.1,
                end: 0.1,
                steps: 0,
            },
            double: false,
            clip_norm: None,
            n_step: 10,
            margin: agent::correction::DEFAULT_MARGIN,
            lambda_n_step: 1.0,
            lambda_margin: 1.0,
            l2: 1e-5,
            demo_share: 0.25,
            mask_noops: false,
            correct_loops: false,
            hindsight: 0,
        })
    }

    /// A preset by name ([`PRESETS`]) for `blocks` blocks.
    pub fn preset(name: &str, blocks: usize) -> Result<DqnConfig> {
        let paper = DqnConfig::paper(blocks)?;
        match name {
            "paper" => Ok(paper),
            "paper-dqfd" => Ok(DqnConfig {
                demos: DemoSource::Exact(500),
                loss: LossKind::Dqfd,
                pretrain_steps: 2_000,
                steps: 3_000,
                ..paper
            }),
            "dqn-planes" => Ok(DqnConfig::dqn_planes(paper)),
            "dqfd-planes" => Ok(DqnConfig::dqfd_planes(paper)),
            "her-planes" => Ok(DqnConfig::her_planes(paper)),
            "dqfd-pixels" => Ok(DqnConfig::dqfd_pixels(paper)),
            _ => Err(NeuralError::Config(format!(
                "unknown preset {name:?}: choose {}",
                PRESETS.join(", ")
            ))),
        }
    }

    fn dqfd_planes(paper: DqnConfig) -> DqnConfig {
        // Greedy failures are loops that fade with gradient steps (measured on 3,000 test
        // games of 3 blocks: 1.9 % at 30,000 + 30,000 steps, 0.8 % at three times that,
        // 0.4 % at four; on 12,000 of 4 blocks: 14.9 % at 90,000 + 90,000 with 10,000
        // demonstrations, 9.7 % at twice both, 3.1 % at four times): 3 blocks get three times
        // 2 blocks' steps, 4 blocks and more four times 3 blocks' steps and demonstrations.
        let (steps, demos) = match paper.world.blocks {
            ..=2 => (30_000, 10_000),
            3 => (90_000, 10_000),
            _ => (360_000, 40_000),
        };
        DqnConfig {
            steps,
            pretrain_steps: steps,
            demos: DemoSource::Exact(demos),
            loss: LossKind::Dqfd,
            learning_starts: 1_000,
            epsilon: Epsilon {
                start: 0.1,
                end: 0.01,
                steps: 15_000,
            },
            correct_loops: true,
            ..DqnConfig::dqn_planes(paper)
        }
    }

    fn dqfd_pixels(paper: DqnConfig) -> DqnConfig {
        let blocks = paper.world.blocks;
        // A DQfD step of the paper network costs about 40 ms here, a step of the small one
        // 2 ms: a budget of minutes buys a few thousand steps, so the demonstrations carry
        // most of the learning and the budget grows with the blocks. On 2 blocks, 4,000 steps
        // of each left one goal at 94.6 %; 6,000 reach 95 % on every goal (epsilon falling
        // over the first 2,000 self-play steps, as it did at 4,000).
        let (demos, steps, fall) = if blocks <= 2 {
            (1_000, 6_000, 2_000)
        } else {
            (5_000, 15_000, 7_500)
        };
        let net = paper.net;
        DqnConfig {
            demos: DemoSource::Exact(demos),
            pretrain_steps: steps,
            steps,
            learning_starts: 500,
            epsilon: Epsilon {
                start: 0.1,
                end: 0.01,
                steps: fall,
            },
            ..DqnConfig::dqfd_planes(paper).with_net(net)
        }
    }

    fn her_planes(paper: DqnConfig) -> DqnConfig {
        let planes = DqnConfig::dqn_planes(paper);
        DqnConfig { hindsight: 4, ..planes }
    }

    fn dqn_planes(paper: DqnConfig) -> DqnConfig {
        // Exploration alone must find the goal: far longer on 3 blocks than on 2.
        let steps = if paper.world.blocks <= 2 { 50_000 } else { 300_000 };
        let net = NetConfig::small();
        DqnConfig {
            world: EnvConfig {
                obs: net.obs(),
                ..paper.world
            },
            net,
            steps,
            td_loss: TdLoss::Huber,
            optimizer: OptimizerKind::Adam,
            lr: 1e-3,
            lr_final: 1e-4,
            gamma: 0.95,
            buffer: 100_000,
            learning_starts: 5_000,
            target_every: TargetEvery::Steps(500),
            epsilon: Epsilon {
                start: 1.0,
                end: 0.05,
                steps: steps / 2,
            },
            double: true,
            clip_norm: Some(10.0),
            mask_noops: true,
            ..paper
        }
    }

    /// The observation the network reads.
    pub fn obs(&self) -> ObsKind {
        self.net.obs()
    }

    /// The grid.
    pub fn grid(&self) -> Grid {
        self.world.grid
    }

    /// Number of blocks.
    pub fn blocks(&self) -> usize {
        self.world.blocks
    }

    /// This config with the network `net`, the world's observation made the one it reads.
    pub fn with_net(self, net: NetConfig) -> DqnConfig {
        DqnConfig {
            world: EnvConfig {
                obs: net.obs(),
                ..self.world
            },
            net,
            ..self
        }
    }

    /// The environment a game on `goal` is played in: [`DqnConfig::world`] with that goal.
    pub fn env_config(&self, goal: Goal) -> EnvConfig {
        EnvConfig {
            goal: GoalSpec::Fixed(goal),
            ..self.world
        }
    }

    /// A one-line description for reports: network, losses, demonstrations, budget.
    pub fn describe(&self) -> String {
        let net = match self.net.kind {
            NetKind::Paper => format!(
                "paper network on pixels{}",
                if self.net.batch_norm { "" } else { " without batch norm" }
            ),
            NetKind::Small => format!("small network ({} x 2) on centred planes", self.net.hidden),
            NetKind::Mlp => format!("MLP ({} x 2) on absolute planes", self.net.hidden),
        };
        format!(
            "{net}; {} loss, {} reward, gamma {}, {} lr {}{}, buffer {}, batch {}; demonstrations {}{}; {} self-play steps{}",
            self.loss,
            self.world.reward,
            self.gamma,
            self.optimizer,
            self.lr,
            if self.lr_final == self.lr {
                String::new()
            } else {
                format!(" to {}", self.lr_final)
            },
            self.buffer,
            self.batch,
            self.demos,
            if self.pretrain_steps > 0 {
                format!(", {} pre-training steps", self.pretrain_steps)
            } else {
                String::new()
            },
            self.steps,
            if self.mask_noops { "; no-op actions masked" } else { "" },
        ) + &if self.hindsight > 0 {
            format!("; hindsight relabelling (future, k = {})", self.hindsight)
        } else {
            String::new()
        } + if self.correct_loops {
            "; loops corrected by the demonstrator"
        } else {
            ""
        }
    }

    /// An error naming the first setting that cannot work.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(NeuralError::Config(what));
        self.net.validate(self.obs())?;
        if self.world.obs != self.obs() {
            return bad(format!(
                "the world shows {} and the {} network reads {}",
                self.world.obs,
                self.net.kind,
                self.obs()
            ));
        }
        if self.world.goal != GoalSpec::Random {
            return bad("a training config names its goals in `goals`: its world's goal must be drawn".into());
        }
        if self.world.termination != sim::Termination::default() {
            return bad(format!(
                "training games end at the goal, not by the {} termination",
                self.world.termination
            ));
        }
        if self.goals.is_empty() {
            return bad("no goals to train on".into());
        }
        for goal in &self.goals {
            self.env_config(*goal).validate()?;
        }
        if self.batch == 0 {
            return bad("the batch must hold at least 1 transition".into());
        }
        if self.buffer == 0 {
            return bad("the buffer must hold at least 1 transition".into());
        }
        if self.batch > self.buffer {
            return bad(format!(
                "the batch (--batch {}) is larger than the buffer (--buffer {}): it cannot be drawn from it",
                self.batch, self.buffer
            ));
        }
        // Checked before anything is allocated: a batch's inputs, the buffer and the planned
        // demonstrations are all made in memory, and a size too large to allocate would abort.
        let values = self
            .batch
            .saturating_mul(self.net.input(self.world.grid, self.world.blocks)?.len());
        if values > MAX_BATCH_VALUES {
            return bad(format!(
                "the batch (--batch {}) needs {values} input values, more than the {MAX_BATCH_VALUES} allowed: \
                 choose a smaller batch",
                self.batch
            ));
        }
        let held = (self.buffer as u64).min(self.steps);
        let bytes = held.saturating_mul(std::mem::size_of::<crate::replay::Transition>() as u64);
        if bytes > MAX_BUFFER_BYTES {
            return bad(format!(
                "the buffer (--buffer {}) would grow to {} MiB over {} steps, more than the {} MiB allowed",
                self.buffer,
                bytes >> 20,
                self.steps,
                MAX_BUFFER_BYTES >> 20
            ));
        }
        if let DemoSource::Exact(k) | DemoSource::Oracle(k) = self.demos
            && k > MAX_DEMO_EPISODES
        {
            return bad(format!(
                "{k} demonstrated episodes (--demos {}) are more than the {MAX_DEMO_EPISODES} allowed",
                self.demos
            ));
        }
        if self.train_every == 0 {
            return bad("train-every must be at least 1 step".into());
        }
        for lr in [self.lr, self.lr_final] {
            if !(lr > 0.0 && lr.is_finite()) {
                return bad(format!("the learning rate {lr} is not a positive number"));
            }
        }
        if !(0.0..=1.0).contains(&self.gamma) {
            return bad(format!("gamma {} is not in [0, 1]", self.gamma));
        }
        for (name, e) in [("start", self.epsilon.start), ("end", self.epsilon.end)] {
            if !(0.0..=1.0).contains(&e) {
                return bad(format!("epsilon {name} {e} is not in [0, 1]"));
            }
        }
        if !(0.0..=1.0).contains(&self.demo_share) {
            return bad(format!("the demonstration share {} is not in [0, 1]", self.demo_share));
        }
        if !(self.margin.is_finite() && self.margin >= 0.0) {
            return bad(format!("the margin {} is not a finite number at least 0", self.margin));
        }
        for (name, v) in [
            ("the n-step weight", self.lambda_n_step),
            ("the margin weight", self.lambda_margin),
            ("the L2 weight", self.l2),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} {v} is not a finite number at least 0"));
            }
        }
        if self.n_step == 0 {
            return bad("n-step must be at least 1".into());
        }
        if let Some(c) = self.clip_norm
            && !(c > 0.0 && c.is_finite())
        {
            return bad(format!("the gradient clip {c} is not a positive number"));
        }
        match self.target_every {
            TargetEvery::Steps(0) | TargetEvery::Games(0) => {
                bad("the target network must be refreshed every 1 or more".into())
            }
            _ => Ok(()),
        }?;
        if self.world.protocol != ActionProtocol::Free
            && (self.correct_loops || matches!(self.demos, DemoSource::Exact(_) | DemoSource::Oracle(_)))
        {
            return bad(format!(
                "the planners demonstrate in the free protocol (a pick may switch blocks), not the {} one: \
                 drop their demonstrations and corrections, or choose the free protocol",
                self.world.protocol
            ));
        }
        if self.pretrain_steps > 0 && self.demos == DemoSource::None {
            return bad("pre-training needs demonstrations (--demos or --demos-file)".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_is_valid_and_the_paper_is_the_papers() {
        for name in PRESETS {
            DqnConfig::preset(name, 3).unwrap().validate().unwrap();
        }
        let p = DqnConfig::preset("paper", 3).unwrap();
        assert_eq!(
            (p.buffer, p.batch, p.lr, p.obs()),
            (1000, 64, 1e-4, ObsKind::PaperScreen)
        );
        assert_eq!(p.optimizer, OptimizerKind::Rmsprop);
        assert_eq!(p.world.reward.name(), "sparse");
        assert!(DqnConfig::preset("nope", 3).is_err());
    }

    #[test]
    fn dqfd_planes_budget_grows_with_the_blocks_and_pixels_keep_their_own() {
        let budget = |preset: &str, blocks| {
            let c = DqnConfig::preset(preset, blocks).unwrap();
            (c.demos, c.pretrain_steps, c.steps)
        };
        assert_eq!(budget("dqfd-planes", 2), (DemoSource::Exact(10_000), 30_000, 30_000));
        assert_eq!(budget("dqfd-planes", 3), (DemoSource::Exact(10_000), 90_000, 90_000));
        for blocks in [4, 5] {
            assert_eq!(
                budget("dqfd-planes", blocks),
                (DemoSource::Exact(40_000), 360_000, 360_000)
            );
            assert_eq!(
                budget("dqfd-pixels", blocks),
                (DemoSource::Exact(5_000), 15_000, 15_000)
            );
        }
    }

    #[test]
    fn sizes_that_cannot_be_allocated_are_refused_up_front() {
        let base = || DqnConfig::preset("dqn-planes", 3).unwrap();
        let refused = |c: DqnConfig, words: &str| {
            let e = c.validate().unwrap_err().to_string();
            assert!(e.contains(words), "{e}");
        };
        refused(
            DqnConfig {
                batch: 1_000_000_000_000,
                ..base()
            },
            "--batch 1000000000000",
        );
        refused(
            DqnConfig {
                batch: 1_000_000,
                buffer: 1_000_000,
                ..base()
            },
            "--batch 1000000",
        );
        refused(
            DqnConfig {
                batch: 2_000,
                buffer: 1_000,
                ..base()
            },
            "larger than the buffer",
        );
        refused(
            DqnConfig {
                demos: DemoSource::Exact(1_000_000_000),
                ..base()
            },
            "--demos exact:1000000000",
        );
        refused(
            DqnConfig {
                buffer: usize::MAX,
                steps: u64::MAX,
                ..base()
            },
            "--buffer",
        );
        // A large buffer is fine when the run is too short to fill it.
        DqnConfig {
            buffer: usize::MAX,
            ..base()
        }
        .validate()
        .unwrap();
    }

    #[test]
    fn demonstration_sources_read_and_print() {
        for text in ["none", "exact:10", "oracle:3"] {
            assert_eq!(text.parse::<DemoSource>().unwrap().to_string(), text);
        }
        for bad in ["exact", "exact:x", "people:3"] {
            assert!(bad.parse::<DemoSource>().is_err(), "{bad}");
        }
    }

    #[test]
    fn epsilon_falls_linearly_then_stays() {
        let e = Epsilon {
            start: 1.0,
            end: 0.1,
            steps: 10,
        };
        assert_eq!((e.at(0), e.at(5), e.at(10), e.at(99)), (1.0, 0.55, 0.1, 0.1));
    }
}
