//! The neural learner: deep Q-learning from the paper's pixels or from planes, and DQfD
//! (deep Q-learning from demonstrations, Hester et al. 2018): the paper's Approach 1
//! (section III-C) rebuilt, and made to learn.
//!
//! - [`input`]: what a network sees: `sim`'s pixel and plane views laid out as bytes.
//! - [`net`]: the Q-networks, the paper's convolutional one and our small one, forward and
//!   backward by hand on the [`kernels`] (matrix products on `gemm`, im2col).
//! - [`mask`]: which actions may be chosen, and the masked argmax every choice goes through.
//! - [`replay`], [`learner`], [`optim`]: experience replay with n-step returns; one gradient
//!   step of the DQN and DQfD losses; RMSprop and Adam.
//! - [`hindsight`]: hindsight relabelling (HER): a game stored again under the stacks it built.
//! - [`demos`]: demonstrations from the exact solver, the oracle, or a recording.
//! - [`config`], [`preset`], [`train`](mod@train): a run's settings, the presets and the one resolver
//!   of a preset and explicit settings ([`DqnConfig::resolve`]), and the trainer.
//! - [`checkpoint`]: a run written between two steps, and resumed bit for bit.
//! - [`model`]: a trained network ([`Dqn`]), played through [`agent::Policy`] (so
//!   `agent::play`, rollouts and evaluation serve it unchanged), saved and read as a
//!   network file in the project's model container (`files::container`).
//! - [`planning`]: the planner of a block-move task, chosen by name or by model file.
//!
//! Everything runs on the CPU; every random draw comes from the config's seed.

pub mod any;
pub mod checkpoint;
pub mod config;
pub mod demos;
pub mod error;
pub mod hindsight;
pub mod input;
pub mod kernels;
pub mod learner;
pub mod mask;
pub mod model;
pub mod net;
mod netfile;
pub mod optim;
pub mod planning;
pub mod preset;
pub mod relational;
pub mod replay;
pub mod train;

pub use any::AnyModel;
pub use config::{DemoSource, DqnConfig, Epsilon, LossKind, TargetEvery, TdLoss};
pub use error::{NeuralError, Result};
pub use input::ObsKind;
pub use model::{Dqn, DqnPolicy, TrainReport};
pub use net::{NetConfig, NetKind};
pub use optim::OptimizerKind;
pub use preset::{DqnOverrides, Preset, Recipe};
pub use train::{Phase, Progress, TrainHooks, Trainer, train};
