//! The blockstack world: blocks on a grid, picked, moved and dropped until they stand in
//! the goal's order.
//!
//! - [`Grid`], [`Cell`], [`BlockId`], [`Action`], [`Goal`], [`State`]: the vocabulary.
//! - [`World`]: the rules (SPEC section 2), written once in [`World::act`], over two
//!   backends: [`GridWorld`], a pure occupancy model that planners search over, and
//!   [`PhysicsWorld`], rapier2d rigid bodies moved by a controller that asks rapier's
//!   collision detection whether each move is free.
//! - [`Env`]: a Gymnasium-style environment (`reset`, `step`) over either backend, with the
//!   reward models of [`reward`]; [`VecEnv`] steps many in parallel, with either of
//!   Gymnasium's autoreset modes.
//! - [`render`] draws the world as text or pictures; [`trajectory`] writes episodes as
//!   JSON Lines.
//!
//! ```
//! use sim::{Action, Backend, Env, EnvConfig, Goal};
//!
//! let goal: Goal = "1,0,2".parse()?;
//! let mut env = Env::new(EnvConfig { backend: Backend::Physics, ..EnvConfig::with_goal(goal) })?;
//! let obs = env.reset(7);
//! assert_eq!(obs.blocks().len(), 3);
//! let step = env.step(Action::Pick(sim::BlockId(0)))?;
//! assert_eq!(step.observation.held_block(), Some(sim::BlockId(0)));
//! # Ok::<(), sim::SimError>(())
//! ```

pub mod action;
pub mod env;
pub mod error;
pub mod files;
pub mod goal;
pub mod grid;
pub mod grid_world;
pub mod observation;
pub mod occupancy;
pub mod physics_world;
pub mod render;
pub mod reward;
pub mod seeding;
pub mod state;
pub mod trajectory;
pub mod vec_env;
pub mod world;

pub use action::Action;
pub use env::{Backend, DEFAULT_HORIZON, Env, EnvConfig, GoalSpec, Info, Step};
pub use error::{Result, SimError};
pub use goal::Goal;
pub use grid::{Cell, Direction, Grid, MAX_CELLS};
pub use grid_world::GridWorld;
pub use observation::{Observation, Planes};
pub use occupancy::Occupancy;
pub use physics_world::PhysicsWorld;
pub use reward::RewardModel;
pub use state::{BlockId, MAX_BLOCKS, MIN_BLOCKS, State};
pub use vec_env::{Autoreset, VecEnv, VecStep};
pub use world::{Effect, World};
