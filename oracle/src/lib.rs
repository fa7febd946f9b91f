//! Planners for the blockstack world (docs/world.md section 8).
//!
//! - [`Oracle`]: the paper's analytical oracle made sound. It places the stack, routes the
//!   blocks one at a time with A* around the others, and moves blockers out of the way;
//!   it plans from any state, a held block included, so learners and demonstrators can
//!   hand control to it mid-episode ([`Oracle::next_action`]).
//! - [`ExactSolver`]: A* over the joint state with an admissible, consistent heuristic; its
//!   plans are provably shortest, the yardstick for every "steps to goal" figure. In the
//!   side view ([`ExactSolver::with_view`]) it finds the fewest gripper steps to a goal of
//!   towers.
//! - [`CentroidWalker`]: the paper's oracle as its authors coded it, a greedy walker
//!   towards a stack laid around the blocks' centroid, with a random block when nothing is
//!   held. It plans nothing and can get stuck; Table I of the paper assisted its learner
//!   with it.
//! - [`PlannerKind`]: a planner chosen by name, with one meaning in both views (the one
//!   table the command line, Python and the experiments share).
//! - [`pddl`]: the planning competitions' Blocks World problems and plans, read and written.
//! - [`towers`]: block-move planners for the classic Blocks World seen from the side (an
//!   exact A* solver and a near-optimal planner that scales to thousands of blocks).
//!
//! Both planners plan under an action protocol ([`Planner::protocol`]; `free` unless
//! [`ExactSolver::with_protocol`] / [`Oracle::with_protocol`] say otherwise): under `paper`
//! their plans change blocks by a Drop and a Pick, and the exact solver's are the shortest
//! such plans.
//!
//! How far each goes: the oracle plans 3 blocks in a few microseconds and 8 in tens, from
//! any state; it is never shorter than the exact plan and is within a fraction of a percent
//! of it on average (the [`gap`] module measures it; `cargo run --release -p oracle
//! --example optimality_gap` prints it). The exact solver's reach and its memory budget are
//! in the docs of [`exact`].
//!
//! Both search over [`sim::GridWorld`] and take every step with [`sim::World::act`]: the
//! rules of the world live in `sim` only. Both are `Copy`, `Send` and `Sync`, keep no
//! state between calls, and take `&self`, so threads can share one.
//!
//! # When a goal can be reached
//!
//! On a grid at least two cells wide every goal can be reached from every state: moving a
//! held block one cell into a free neighbour is pebble motion on the grid graph, which is
//! 2-connected and (apart from 2 x 2, where two blocks always stand in the one cyclic
//! order) not a cycle, and a stack of `N <= H` blocks leaves at least `W * H - N >= 2`
//! free cells; with two free cells every arrangement of the pebbles is reachable
//! (Kornhauser, Miller and Spirakis, 1984). On a grid one cell wide blocks cannot pass each
//! other, so only the goal that lists them in the order they stand can be reached; both
//! planners report any other as [`OracleError::GoalUnreachable`]. The tests check this
//! against a breadth-first search of every state on small grids.
//!
//! # Example
//!
//! ```
//! use oracle::{ExactSolver, Oracle};
//! use sim::{Goal, Grid, GridWorld, World};
//!
//! let grid = Grid::default();
//! let goal: Goal = "1,0,2".parse()?;
//! let mut env = sim::Env::new(sim::EnvConfig::with_goal(goal.clone()))?;
//! let start = env.reset(7).state;
//! let plan = Oracle::new(grid).plan(&start, &goal)?;
//! let shortest = ExactSolver::new(grid).distance(&start, &goal)?;
//! assert!(plan.len() as u32 >= shortest);
//! let mut world = GridWorld::new(grid, start)?;
//! for &a in &plan.actions {
//!     world.act(a)?;
//! }
//! assert!(goal.holds(world.state_ref()));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod centroid_walker;
pub mod error;
pub mod exact;
pub mod gap;
pub mod oracle;
pub mod pddl;
mod placement;
pub mod plan;
pub mod planner_kind;
mod route;
pub mod towers;

pub use centroid_walker::{CentroidWalker, SweepOrder};
pub use error::{OracleError, Result};
pub use exact::{DEFAULT_NODE_BUDGET, ExactSolver, SearchStats};
pub use oracle::{FALLBACK_NODE_BUDGET, Oracle};
pub use plan::{Plan, Planner, legalize};
pub use planner_kind::{Cost, CountedPlan, PlanOptions, PlannerKind};
