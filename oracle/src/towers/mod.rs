//! Block-move planning in the classic Blocks World, over an abstract state: towers of
//! blocks on a table, seen from the side.
//!
//! # The count
//!
//! A move takes a clear block (nothing on it) and puts it on the table or on another
//! clear block; a plan's length is its number of moves, the count the planning literature
//! reports. The table is unbounded by default (a move to the table is always possible);
//! [`Table::Columns`] bounds how many towers stand at once, as a grid's width does: the
//! exact solver plans within it, the near-optimal planner parks blocks instead of moving them
//! to a full table and gives up when it finds no room ([`near_optimal`] says how). Tower
//! heights are not bounded (the side view's grid height is the caller's to check).
//!
//! A goal ([`TowerGoal`]) is a list of towers, each bottom to top; it holds when each
//! stands from the table up in that order, whatever it carries on top. Blocks it does not
//! name are free.
//!
//! # The planners
//!
//! - [`ExactMoves`]: A* with an admissible heuristic, so its plans are shortest. The
//!   heuristic counts the misplaced blocks (a block is well placed when it and everything
//!   below it stand as the goal wants; every other block moves at least once, since it
//!   stands where the goal forbids or above a block that must move, and only clear blocks
//!   move) and adds one per vertex-disjoint deadlock cycle (a set of misplaced blocks that
//!   cannot all move only once: see the `deadlock` module; each disjoint cycle costs at
//!   least one extra move of one of its own blocks). Optimal plans for 10 blocks take a few
//!   milliseconds on average.
//! - [`NearOptimal`]: constructive moves first (a block straight to where it ends), else a
//!   misplaced block to the table chosen to break a deadlock. Each block moves at most
//!   twice and every plan moves each misplaced block at least once, so its plans are at
//!   most twice the optimum (Gupta & Nau, "On the complexity of blocks-world planning",
//!   Artificial Intelligence 56, 1992; the US and GN1 algorithms of Slaney & Thiebaux,
//!   "Blocks World revisited", Artificial Intelligence 125, 2001). Its moves take constant
//!   time each and its searches for deadlocks are near-linear in practice: a thousand
//!   blocks in well under a millisecond ([`near_optimal`] gives the figures).
//!
//! Both implement [`BlockPlanner`], the one trait through which a task is planned by
//! whichever planner is given (the learned relational policy of `neural` implements it too).
//!
//! Bad input (an empty tower, a block named twice, a goal naming a block the state lacks)
//! is an [`OracleError::Towers`](crate::OracleError::Towers) error, never a panic.
//!
//! # Example
//!
//! ```
//! use oracle::towers::{ExactMoves, NearOptimal, Table, TowerGoal, Towers};
//!
//! // 1 on 0, 2 on 1; 3 alone. The goal: 1 on the table, 3 on 1, 2 on 3 (0 is free).
//! // 2 must leave 1 before 1 moves, and come back after 3: one block moves twice.
//! let start = Towers::new(&[vec![0, 1, 2], vec![3]])?;
//! let goal = TowerGoal::new(&[vec![1, 3, 2]])?;
//! let exact = ExactMoves::new().solve(&start, &goal)?;
//! let near = NearOptimal::new().plan(&start, &goal)?;
//! assert_eq!(exact.len(), 4);
//! assert!(near.len() <= 2 * exact.len());
//! assert!(goal.holds(&near.replay(&start, Table::Unbounded)?));
//! # Ok::<(), oracle::OracleError>(())
//! ```

mod bitset;
mod deadlock;
pub mod error;
pub mod exact;
mod fvs;
pub mod goal;
pub mod near_optimal;
pub mod optimal;
pub mod optimal_set;
pub mod plan;
pub mod planner;
pub mod random;
pub mod side;
pub mod space;
pub mod state;

pub use error::{Part, TowersError};
pub use exact::{DEFAULT_MOVE_BUDGET, ExactMoves};
pub use goal::TowerGoal;
pub use near_optimal::NearOptimal;
pub use optimal::{Certificate, CertifiedPlan, OptimalMoves};
pub use optimal_set::optimal_first_moves;
pub use plan::TowerPlan;
pub use planner::BlockPlanner;
pub use random::{ipc_state, nlm_state, random_goal, random_state};
pub use side::{MovePlanner, block_move_of, gripper_actions, next_block_move, plan_side, plan_side_certified};
pub use space::{Distances, StateSpace};
pub use state::{Move, Place, Table, Towers};
