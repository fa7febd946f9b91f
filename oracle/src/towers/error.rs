//! Why a block-move problem was refused or could not be solved.
//!
//! Bad input (a block twice, a block the state does not have, an empty tower) is caught
//! before planning, so the planners never panic on what a user typed.

use std::fmt;

use thiserror::Error;

/// Which half of a problem a value belongs to, for messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Part {
    /// The state planned from.
    State,
    /// The goal planned to.
    Goal,
}

impl fmt::Display for Part {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Part::State => "state",
            Part::Goal => "goal",
        })
    }
}

/// Why a block-move state, goal, move or search was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum TowersError {
    /// A tower with no block.
    #[error("tower {tower} of the {part} is empty: every tower needs at least one block")]
    EmptyTower {
        /// The state or the goal.
        part: Part,
        /// The tower's index, from 0.
        tower: usize,
    },
    /// A block named twice.
    #[error("block {block} appears twice in the {part}")]
    DuplicateBlock {
        /// The state or the goal.
        part: Part,
        /// The block.
        block: usize,
    },
    /// A block id outside `0..blocks`.
    #[error("the {part} names block {block}, but the blocks are 0..{blocks}")]
    UnknownBlock {
        /// The state or the goal.
        part: Part,
        /// The block.
        block: usize,
        /// Number of blocks in the state.
        blocks: usize,
    },
    /// The state leaves out a block: a state of `n` blocks holds each of `0..n` once.
    #[error("the state has {blocks} blocks but leaves out block {block}")]
    MissingBlock {
        /// The first block left out.
        block: usize,
        /// Number of blocks in the state.
        blocks: usize,
    },
    /// The table holds more towers than it has columns.
    #[error("the {part} has {towers} towers but the table has {columns} columns")]
    TooManyTowers {
        /// The state or the goal.
        part: Part,
        /// Towers needed.
        towers: usize,
        /// Columns of the table.
        columns: usize,
    },
    /// A move that the rules forbid in this state.
    #[error("illegal move {mv}: {reason}")]
    IllegalMove {
        /// The move, as text.
        mv: String,
        /// Why it is illegal.
        reason: &'static str,
    },
    /// More blocks than the exact solver encodes.
    #[error("the exact block-move solver takes at most {max} blocks, not {blocks}: use the near-optimal planner")]
    TooManyBlocks {
        /// Blocks in the problem.
        blocks: usize,
        /// The most the solver takes.
        max: usize,
    },
    /// The exact search generated its budget of states without proving a shortest plan.
    #[error(
        "the exact block-move search generated its budget of {budget} states for {blocks} blocks \
         without finding a shortest plan: use the near-optimal planner, or raise the budget"
    )]
    BudgetExceeded {
        /// The budget: the most states the search may generate.
        budget: usize,
        /// Blocks in the problem.
        blocks: usize,
    },
    /// No sequence of moves reaches the goal (only possible on a table of few columns).
    #[error("the goal cannot be reached from this state on a table of {columns} columns")]
    Unreachable {
        /// Columns of the table.
        columns: usize,
    },
    /// The near-optimal planner ran out of room: every column holds a tower and no block
    /// it could park on is free.
    #[error(
        "the near-optimal planner ran out of room on a table of {columns} columns: \
         use the exact solver, or a wider table"
    )]
    TableTooNarrow {
        /// Columns of the table.
        columns: usize,
    },
    /// A plan stacks more blocks than the grid has rows.
    #[error("the plan stacks {tallest} blocks, more than the grid's {rows} rows: use a taller grid")]
    TooTall {
        /// The tallest tower the plan builds.
        tallest: usize,
        /// Rows of the grid.
        rows: usize,
    },
    /// A planner name that is not one.
    #[error("unknown block-move planner {name:?}: choose exact, near-optimal or optimal")]
    UnknownPlanner {
        /// The name given.
        name: String,
    },
    /// A planner found no plan: a learned policy that did not reach the goal within its
    /// move limit ([`super::BlockPlanner`]).
    #[error("the {planner} found no plan: {reason}")]
    NoPlan {
        /// The planner's name.
        planner: String,
        /// Why, in the planner's words.
        reason: String,
    },
    /// A random goal of this shape cannot be drawn.
    #[error("cannot draw a goal of {stacks} towers naming {named} of {blocks} blocks")]
    GoalShape {
        /// Towers asked for (at least 1, at most `named`).
        stacks: usize,
        /// Blocks to name (at most `blocks`).
        named: usize,
        /// Blocks in the world.
        blocks: usize,
    },
    /// A state of another number of blocks than a state space's.
    #[error("the state has {blocks} blocks, and the state space is of {expected}")]
    BlockCount {
        /// Blocks in the state.
        blocks: usize,
        /// Blocks of the space.
        expected: usize,
    },
    /// A state space of no block or of more than it takes.
    #[error("a state space holds 1 to {max} blocks, not {blocks}")]
    SpaceSize {
        /// Blocks asked for.
        blocks: usize,
        /// The most it takes.
        max: usize,
    },
}
