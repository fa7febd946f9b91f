//! The data of a training run: what a [`TrainConfig`] holds and the checks every value
//! passes, with no behaviour attached.
//!
//! This module is a leaf of the crate (it uses `sim` and the leaf modules [`crate::assist`],
//! [`crate::repr`] and [`crate::schedule`]), so that the learner, the trainer, model files
//! and checkpoints all read one description of a run without importing each other. The
//! world a game is played in is `sim`'s one world value, [`EnvConfig`], embedded as
//! [`TrainConfig::world`]; the learner's parts sit beside it. Presets and the resolver of
//! profile, preset and explicit settings live in [`crate::preset`]; model files store a
//! frozen schema of their own ([`crate::model`]), so regrouping these fields changes no file.

use serde::{Deserialize, Serialize};
use sim::{EnvConfig, Goal, GoalSpec, Profile};

use crate::assist::{Assist, OracleKind, Oscillation};
use crate::error::{AgentError, Result};
use crate::repr::{Repr, ReprKind};
use crate::schedule::Schedule;

/// The learner's hyper-parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct QParams {
    /// Learning rate, `0 < alpha <= 1` (paper: 1).
    pub alpha: f64,
    /// Discount factor, `0 <= gamma <= 1` (paper: 0.1).
    pub gamma: f64,
    /// Probability of a uniformly random action while training, `0 <= epsilon <= 1`
    /// (paper: 0.1).
    pub epsilon: f64,
    /// The value every entry of the table starts at (paper: not stated; 0).
    pub initial_q: f64,
}

impl Default for QParams {
    /// The paper's: alpha 1, gamma 0.1, epsilon 0.1, table starting at 0.
    fn default() -> Self {
        QParams {
            alpha: 1.0,
            gamma: 0.1,
            epsilon: 0.1,
            initial_q: 0.0,
        }
    }
}

impl QParams {
    /// An error naming the first value out of its range.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: &str, v: f64, range: &str| Err(AgentError::Config(format!("{what} {v} is not in {range}")));
        if !(self.alpha > 0.0 && self.alpha <= 1.0) {
            return bad("alpha", self.alpha, "(0, 1]");
        }
        if !(0.0..=1.0).contains(&self.gamma) {
            return bad("gamma", self.gamma, "[0, 1]");
        }
        check_epsilon(self.epsilon)?;
        check_fits_table("the initial Q-value", self.initial_q)
    }
}

/// An error unless `value` is a finite number that the table's 32-bit floats hold (at most
/// `f32::MAX` in size): a value beyond it would become infinite in the table and could not
/// be saved. `what` names it in the error.
pub fn check_fits_table(what: &str, value: f64) -> Result<()> {
    if value.is_finite() && value.abs() <= f64::from(f32::MAX) {
        Ok(())
    } else {
        Err(AgentError::Config(format!(
            "{what} {value:e} does not fit the Q-table's 32-bit floats: use a finite value of at most {:e} in size",
            f32::MAX
        )))
    }
}

/// An error unless `0 <= epsilon <= 1`.
pub fn check_epsilon(epsilon: f64) -> Result<()> {
    if (0.0..=1.0).contains(&epsilon) {
        Ok(())
    } else {
        Err(AgentError::Config(format!("epsilon {epsilon} is not in [0, 1]")))
    }
}

/// Everything that defines a training run: the world, the goals, the learner, the budget
/// and the seed.
#[derive(Clone, Debug, PartialEq)]
pub struct TrainConfig {
    /// The world the training games are played in: grid, blocks, horizon, reward (the one
    /// the learner maximises), backend, action protocol, start rule, and what ends a game
    /// (always the schedule's, [`Schedule::training_termination`]). Its `goal` is
    /// [`GoalSpec::Random`]: each game's goal comes from [`TrainConfig::goals`].
    pub world: EnvConfig,
    /// The goals trained on, played in turn.
    pub goals: Vec<Goal>,
    /// The state representation.
    pub repr: ReprKind,
    /// Learning rate, discount, exploration, initial values.
    pub params: QParams,
    /// Games to play.
    pub games: u64,
    /// The seed every start and every random choice derives from.
    pub seed: u64,
    /// Exploring starts: begin each game holding a block drawn at random (or none, with
    /// equal chance), so that states with any block held are tried from the first step.
    /// Starts with nothing held, as the paper's, when false.
    pub exploring_starts: bool,
    /// Backward replay: after each game, apply the game's updates once more, last step
    /// first, so that what the last steps learnt reaches the first ones within the game
    /// (with alpha 1 in this deterministic world, the whole path gets the values of its
    /// end). Off in the paper's learner.
    pub backward_replay: bool,
    /// Experience replay at the end of training: remember the last transition seen from
    /// every state-action, and after the last game apply the Q-update to every remembered
    /// transition, sweep after sweep, until no value changes (at most
    /// [`crate::train::MAX_REPLAY_SWEEPS`]). The table then agrees with everything the agent
    /// has seen, with no value left behind by a later change of its successors' (a stale
    /// value is how a greedy agent gets stuck, e.g. picking the block it already holds).
    /// Off in the paper's learner.
    pub final_replay: bool,
    /// When the oracle chooses the action instead of the learner.
    pub assist: Assist,
    /// The profile the config was made from; the world's and the learner's parts may each
    /// have been set otherwise (what a model file remembers).
    pub profile: Profile,
    /// How games are laid out and the table updated (the [`schedule`](crate::schedule)
    /// module).
    pub schedule: Schedule,
    /// Which oracle assists.
    pub oracle: OracleKind,
    /// How oscillation is spotted for [`Assist::Oscillation`].
    pub oscillation: Oscillation,
}

impl TrainConfig {
    /// Number of blocks (the world's).
    pub fn blocks(&self) -> usize {
        self.world.blocks
    }

    /// This config with `schedule`, and the world's termination that schedule's.
    pub fn with_schedule(self, schedule: Schedule) -> TrainConfig {
        TrainConfig {
            world: EnvConfig {
                termination: schedule.training_termination(),
                ..self.world
            },
            schedule,
            ..self
        }
    }

    /// This config with the world's backend `backend`.
    pub fn with_backend(self, backend: sim::Backend) -> TrainConfig {
        TrainConfig {
            world: EnvConfig { backend, ..self.world },
            ..self
        }
    }

    /// An error naming the first thing in the config that cannot train.
    pub fn validate(&self) -> Result<()> {
        self.params.validate()?;
        self.assist.validate()?;
        if self.schedule != Schedule::Spec && (self.backward_replay || self.final_replay) {
            return Err(AgentError::Config(format!(
                "backward and final replay belong to the spec schedule, not to {}",
                self.schedule
            )));
        }
        if self.world.goal != GoalSpec::Random {
            return Err(AgentError::Config(
                "a training config names its goals in `goals`: its world's goal must be random".into(),
            ));
        }
        if self.world.termination != self.schedule.training_termination() {
            return Err(AgentError::Config(format!(
                "the {} schedule ends training games {}, not {}",
                self.schedule,
                self.schedule.training_termination(),
                self.world.termination
            )));
        }
        if self.goals.is_empty() {
            return Err(AgentError::Config("no goals to train on".into()));
        }
        if !self.repr.takes_towers() {
            for goal in &self.goals {
                goal.one_tower(
                    "the tabular learner's representation (train with --repr role-towers for goals of towers)",
                )?;
            }
        }
        if self.world.view == sim::View::Side && self.assist != Assist::None {
            return Err(AgentError::Config(
                "the assisting oracles plan the top view: train the side view with --assist none".into(),
            ));
        }
        for goal in &self.goals {
            self.env_config(goal.clone()).validate()?;
        }
        Repr::new(self.repr, self.world.grid, self.world.blocks).map(|_| ())
    }

    /// The environment a training game on `goal` is played in: the world, with that goal.
    pub fn env_config(&self, goal: Goal) -> EnvConfig {
        EnvConfig {
            goal: GoalSpec::Fixed(goal),
            ..self.world.clone()
        }
    }

    /// The environment the trained agent is tested in on `goal`: the training world (its
    /// protocol, start rule, reward, backend), but games end at the goal, after at most
    /// `horizon` steps (the paper's tests: 1000).
    pub fn test_env_config(&self, goal: Goal, horizon: u32) -> EnvConfig {
        EnvConfig {
            horizon,
            termination: sim::Termination::Goal,
            ..self.env_config(goal)
        }
    }
}
