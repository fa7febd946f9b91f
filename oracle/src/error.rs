//! The errors the planners report.

use thiserror::Error;

/// Why a planner could not return a plan.
///
/// Every variant names the offending value, so a caller can show it as one clear line.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum OracleError {
    /// The state and the goal disagree on the number of blocks.
    #[error("block counts differ: the state has {state} blocks but the goal has {goal}")]
    BlockCountMismatch {
        /// Blocks in the state.
        state: usize,
        /// Blocks in the goal.
        goal: usize,
    },
    /// The state or the goal does not fit the planner's grid (a block outside it, a stack
    /// taller than it, too many blocks).
    #[error(transparent)]
    Sim(#[from] sim::SimError),
    /// A block-move problem or search of [`crate::towers`] was refused.
    #[error(transparent)]
    Towers(#[from] crate::towers::TowersError),
    /// A planner name that is not one ([`crate::PlannerKind`]).
    #[error("unknown planner {name:?}: choose one of {}", crate::PlannerKind::NAMES.join(", "))]
    UnknownPlanner {
        /// The name given.
        name: String,
    },
    /// A planner of block moves asked to plan in the top view, which has none.
    #[error("the {planner} planner plans block moves, which only the side view has")]
    PlannerNotInView {
        /// The planner's name.
        planner: &'static str,
    },
    /// A cost name that is not one ([`crate::planner_kind::Cost`]).
    #[error("unknown cost {name:?}: choose steps or moves")]
    UnknownCost {
        /// The name given.
        name: String,
    },
    /// A plan counted in block moves asked for in the top view.
    #[error("a plan counted in block moves is the side view's: the top view counts gripper steps")]
    CostNotInView,
    /// A PDDL problem or plan was refused ([`crate::pddl`]).
    #[error(transparent)]
    Pddl(#[from] crate::pddl::PddlError),
    /// The goal holds already, so there is no next action to give.
    #[error("goal {goal} already holds: there is no next action")]
    GoalAlreadyHolds {
        /// The goal, bottom to top.
        goal: String,
    },
    /// No sequence of actions reaches the goal from this state.
    #[error("goal {goal} cannot be reached from this state: {reason}")]
    GoalUnreachable {
        /// The goal, bottom to top.
        goal: String,
        /// Why.
        reason: String,
    },
    /// The oracle's routing got stuck at every placement of the stack and the exact search
    /// it falls back on ran out of its budget.
    #[error(
        "the oracle found no plan to goal {goal} for {blocks} blocks on a {grid} grid: routing was stuck at every placement and the exact fallback ran out of its budget"
    )]
    OracleStuck {
        /// The goal, bottom to top.
        goal: String,
        /// Blocks in the problem.
        blocks: usize,
        /// The grid, `WxH`.
        grid: String,
    },
    /// The exact search stored as many states as its budget allows without proving a
    /// shortest plan.
    #[error(
        "the exact search stored its budget of {budget} states for {blocks} blocks on a {grid} grid without \
         finding a shortest plan: use the oracle, or raise the budget"
    )]
    BudgetExceeded {
        /// The budget: the most states the search may store.
        budget: usize,
        /// Blocks in the problem.
        blocks: usize,
        /// The grid, `WxH`.
        grid: String,
    },
    /// A planner option given to a planner it does not apply to (a search budget to the
    /// optimal solver, a time limit to the exact one).
    #[error("the {option} is the {owner}'s: it does not apply to the {planner} planner")]
    OptionNotApplicable {
        /// The option, in words ("search budget", "time limit").
        option: &'static str,
        /// The planner it belongs to.
        owner: &'static str,
        /// The planner it was given to.
        planner: &'static str,
    },
}

/// Shorthand for results whose error is an [`OracleError`].
pub type Result<T, E = OracleError> = std::result::Result<T, E>;
