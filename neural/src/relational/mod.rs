//! A learned block-move policy for the classic Blocks World at any number of blocks.

pub mod graph;
pub mod model;
pub mod net;
pub mod train;

/// The most moves a game of `blocks` blocks may take before it counts as failed: four per
/// block. The near-optimal planner never needs more than two per block.
pub fn move_limit(blocks: usize) -> usize {
    4 * blocks
}

pub use model::{Game, MovePolicy, RelationalModel, RelationalPolicy};
pub use net::{RelationalNet, Shape};
pub use train::{IterationReport, RelationalConfig};
