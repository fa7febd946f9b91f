//! Everything that defines a training run.
//!
//! The presets that fill it, and the one resolver of a preset and explicit settings, are
//! [`crate::preset`]'s.

use std::fmt;

use serde::{Deserialize, Serialize};
use sim::{ActionProtocol, EnvConfig, Goal, GoalSpec, Grid, ScreenGoal};

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

impl DqnConfig {
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

    /// This config with the network `net`.
    pub fn with_net(self, net: NetConfig) -> DqnConfig {
        DqnConfig { net, ..self }
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
            NetKind::Conv if self.net.screen == ScreenGoal::Paper => format!(
                "conv network ({} channels a cell, {} x 2) on the paper's screen (goal: a picture in the corner)",
                self.net.channels, self.net.hidden
            ),
            NetKind::Conv => format!(
                "conv network ({} channels a cell, {} x 2) on the compact screen (goal: {})",
                self.net.channels, self.net.hidden, self.net.screen
            ),
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
            self.env_config(goal.clone()).validate()?;
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
