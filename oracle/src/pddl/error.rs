//! Why a PDDL problem or plan was refused: one line naming the file, the line and the
//! problem.

use thiserror::Error;

/// Why a problem file or a plan was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum PddlError {
    /// The file cannot be read: missing, a directory, larger than
    /// [`MAX_PROBLEM_BYTES`](super::MAX_PROBLEM_BYTES), not UTF-8.
    #[error(transparent)]
    File(#[from] files::FilesError),
    /// The text is not a 4-operator Blocks World problem this reader takes, or says
    /// something about the blocks that cannot be (a block placed twice, a cycle of `on`).
    #[error("{file}, line {line}: {reason}")]
    Invalid {
        /// The file's path, or `the problem` for text given directly.
        file: String,
        /// The line, from 1.
        line: usize,
        /// What is wrong, and where it helps what to write instead.
        reason: String,
    },
    /// A problem built from towers that a file cannot hold (a name PDDL cannot spell).
    #[error("cannot write the problem: {0}")]
    Unwritable(String),
    /// A plan's action that is not one of the domain's, or names an unknown block.
    #[error("plan line {line}: {reason}")]
    PlanSyntax {
        /// The line of the plan, from 1.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A plan's action whose precondition does not hold when it is taken.
    #[error("plan step {step}, {action}: {reason}")]
    NotApplicable {
        /// The step, from 1.
        step: usize,
        /// The action, as PDDL.
        action: String,
        /// The precondition that fails.
        reason: String,
    },
    /// A file of best known costs that is not a JSON object from task paths to costs.
    #[error("{file}: {reason}; expected a JSON object from task paths to costs, e.g. {{\"easy/p01.pddl\": 10}}")]
    Bounds {
        /// The file's path.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// A folder of tasks that holds none.
    #[error("{folder} holds no .pddl problem (domain.pddl is not one)")]
    NoTasks {
        /// The folder's path.
        folder: String,
    },
    /// A task to play whose start already meets its goal (an empty goal included): its
    /// plan is empty, but an episode cannot begin over (`run --pddl`, `BlocksWorld-v0`).
    #[error(
        "the task's start already meets its goal{}, so there is no episode to play (its plan is empty, as solve --pddl prints it)",
        if *empty_goal { " (which places no block)" } else { "" }
    )]
    NothingToPlay {
        /// Whether the goal places no block at all.
        empty_goal: bool,
    },
    /// A plan after which a fact of the goal does not hold.
    #[error("after the plan's {steps} steps the goal's {fact} does not hold")]
    GoalNotReached {
        /// The plan's length.
        steps: usize,
        /// The first goal fact that fails, as PDDL.
        fact: String,
    },
}
