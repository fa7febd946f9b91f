//! A learned block-move policy for the classic Blocks World at any number of blocks.
//!
//! One network, trained on problems of at most 6 blocks, plays problems of hundreds: its
//! input is only the domain's raw relations (`on`, `on-table`, `clear`, and the goal's `on`
//! and `on-table`), and one forward pass chooses one block move, greedily, with no search.
//!
//! Why this shape ([`net`]): what a move should do depends on facts that reach arbitrarily
//! far along a tower (whether everything below a block stands as the goal wants; where a
//! block the goal wants here is buried). A fixed number of message-passing rounds sees a
//! fixed distance, so the network passes messages along the towers, bottom to top and top
//! to bottom, one step per block with the same weights (as a recurrent network does), then
//! across the goal, and repeats that a few rounds: one round reaches every block of a
//! tower however tall, so the same weights serve any size. How it learns is in [`train`]
//! (imitation of the optimum with DAgger); the file it is saved in, in [`model`]; why and
//! what it reaches, in docs/dqn.md ("The general policy").
//!
//! A game does not pass over every block for every move: [`incremental`] keeps one pass up
//! to date, recomputing after a move only the values whose inputs it changed, with the same
//! bits as a full pass, so the policy plays thousands of blocks (docs/dqn.md, "Playing
//! 10,000 blocks").

pub mod graph;
pub mod incremental;
pub mod model;
pub mod move_policy;
pub mod net;
pub mod train;

/// The most moves a game of `blocks` blocks may take before it counts as failed: four per
/// block. The near-optimal planner never needs more than two per block.
pub fn move_limit(blocks: usize) -> usize {
    4 * blocks
}

pub use incremental::LivePass;
pub use model::{Game, RelationalModel, RelationalPolicy};
pub use move_policy::MovePolicy;
pub use net::{RelationalNet, Shape};
pub use train::{IterationReport, RelationalConfig};
