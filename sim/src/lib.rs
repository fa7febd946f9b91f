//! The blockstack world: blocks on a grid, picked, moved and dropped until they stand in
//! the goal's order.
//!
//! - [`Grid`], [`Cell`], [`BlockId`], [`Action`], [`Goal`], [`State`]: the vocabulary.
//! - [`World`]: the rules (docs/world.md section 2), written once in [`World::act`], over two
//!   backends: [`GridWorld`], a pure occupancy model that planners search over, and
//!   [`PhysicsWorld`], rapier2d rigid bodies moved by a controller that asks rapier's
//!   collision detection whether each move is free.
//! - [`Env`]: a Gymnasium-style environment (`reset`, `step`) over either backend, with the
//!   reward models of [`reward`]; [`VecEnv`] steps many in parallel, with either of
//!   Gymnasium's autoreset modes.
//! - [`render`] draws the world as text or pictures; [`trajectory`] writes episodes as
//!   JSON Lines. Both write their files through the `files` crate's output helper.
//!
//! # Two worlds: `spec` and `original`
//!
//! Our world is the one docs/world.md sections 1-9 describe. The paper's experiments ran in the world its authors coded
//! (docs/world.md section 10, with file:line citations of their repository), which differs
//! in rules that an [`EnvConfig`] can switch one by one, or all at once with a [`Profile`]
//! ([`ProfileParts::apply`], [`Profile::world`]):
//!
//! - [`ActionProtocol`] ([`protocol`]): `free` (SPEC, every action legal) or `paper` (nothing
//!   held: only Pick; holding: only the moves and Drop). The legal actions are an
//!   [`ActionMask`]: [`Env::legal_actions`], `info.action_mask`,
//!   [`Observation::legal_actions`]. An illegal action is an error that changes nothing.
//! - [`StartRule`] ([`start`]): `uniform` (SPEC) or `paper` (the 6 x 6 corner leaving out
//!   the right column and the bottom row, a start meeting the goal kept).
//! - [`Termination`] ([`termination`]): at the goal (SPEC), or at a step reward above a
//!   threshold (the authors' training games: above 70).
//! - The reward `paper-code` ([`reward::PaperCode`]), computed from the authors' state
//!   tuple [`CodedState`] ([`coded_state`]), beside `paper`, our reading of the paper's
//!   prose.
//!
//! The defaults are the SPEC's: a config that names none of these is the SPEC world, and
//! its seeded runs are the same as before these rules existed.
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
pub mod block_move;
pub mod coded_state;
pub mod env;
pub mod error;
pub mod goal;
pub mod grid;
pub mod grid_world;
pub mod inline_vec;
pub mod names;
pub mod obs_kind;
pub mod observation;
pub mod occupancy;
pub mod physics_world;
pub mod profile;
pub mod protocol;
pub mod render;
pub mod reward;
pub mod screen;
pub mod seeding;
pub mod start;
pub mod state;
pub mod team;
pub mod termination;
pub mod trajectory;
pub mod uniform;
pub mod vec_env;
pub mod view;
pub mod world;

pub use action::Action;
pub use block_move::BlockMove;
pub use coded_state::CodedState;
pub use env::{
    Backend, DEFAULT_HORIZON, Env, EnvConfig, GoalSpec, Info, MIN_SIDE_FIT, MoveStep, Outcome, Refusal, Step,
};
pub use error::{Result, SimError};
pub use goal::Goal;
pub use grid::{Cell, Direction, Grid, MAX_CELLS, MAX_SIDE};
pub use grid_world::{Columns, GridWorld};
pub use inline_vec::InlineVec;
pub use obs_kind::ObsKind;
pub use observation::{Observation, Pixels, Planes};
pub use occupancy::Occupancy;
pub use physics_world::PhysicsWorld;
pub use profile::{Profile, ProfileParts};
pub use protocol::{ActionMask, ActionProtocol};
pub use reward::RewardModel;
pub use screen::{SCREEN_CELL, ScreenGoal};
pub use start::StartRule;
pub use state::{BlockId, Cells, MAX_BLOCKS, MAX_SIDE_BLOCKS, MIN_BLOCKS, MIN_SIDE_BLOCKS, State};
pub use termination::Termination;
pub use uniform::UniformStates;
pub use vec_env::{Autoreset, PARALLEL_FROM_ENVS, VecEnv, VecStep, VecStepRef};
pub use view::View;
pub use world::{Effect, World};
