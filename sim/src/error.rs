//! The errors the world reports to its callers.

use thiserror::Error;

use crate::action::Action;
use crate::protocol::ActionProtocol;
use crate::start::StartRule;
use crate::state::BlockId;

/// Everything that can go wrong when building or driving a world.
///
/// Every variant names the offending value, so a caller can turn it into one clear line
/// for a user without adding context of its own.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum SimError {
    /// A top-view grid with more cells than the top view's occupancy model holds
    /// ([`crate::MAX_CELLS`]).
    #[error(
        "grid {width}x{height} is not allowed in the top view: it holds at most {max} cells (the side view takes larger grids)"
    )]
    BadGrid {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
        /// Largest number of cells supported.
        max: usize,
    },
    /// A grid with a side of zero or longer than [`crate::grid::MAX_SIDE`].
    #[error("grid {width}x{height} is not allowed: each side must be between 1 and {max}")]
    GridSide {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
        /// The longest side.
        max: usize,
    },
    /// A block count outside the range of what is asked for it (the top view, the side
    /// view, a learner).
    #[error("{count} blocks is not allowed in {what}: use between {min} and {max}")]
    BadBlockCount {
        /// Requested block count.
        count: usize,
        /// What bounds it: "the top view", "the side view", ...
        what: &'static str,
        /// Smallest supported count.
        min: usize,
        /// Largest supported count.
        max: usize,
    },
    /// More blocks than the grid can hold while leaving a cell free to move into.
    #[error("{blocks} blocks do not fit a {width}x{height} grid: at least one cell must stay free")]
    TooManyBlocks {
        /// Requested block count.
        blocks: usize,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// The goal's stack does not fit the grid's height.
    #[error("a stack of {blocks} blocks is taller than the grid ({height} rows)")]
    StackTooTall {
        /// Blocks in the stack.
        blocks: usize,
        /// Rows in the grid.
        height: usize,
    },
    /// A goal that is not a permutation of the block ids `0..count`.
    #[error("goal {goal} is not a permutation of the blocks 0..{count}: {reason}")]
    BadGoal {
        /// The goal as written.
        goal: String,
        /// How many blocks the world has.
        count: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// Text that does not parse as a goal, a cell or an action.
    #[error("cannot read {what} from {text:?}: {reason}")]
    Parse {
        /// What was being read ("goal", "cell", ...).
        what: &'static str,
        /// The text given.
        text: String,
        /// What is wrong with it.
        reason: String,
    },
    /// An action index outside `0..5 + blocks`.
    #[error("action {index} is out of range: with {blocks} blocks the actions are 0..{}", 5 + blocks)]
    ActionOutOfRange {
        /// The index given.
        index: usize,
        /// How many blocks the world has.
        blocks: usize,
    },
    /// An action the environment's action protocol forbids in the current state.
    #[error(
        "{action} is not legal under the {protocol} action protocol while {}: {}",
        held_text(*.held),
        .protocol.allowed(.held.is_some())
    )]
    IllegalAction {
        /// The action given.
        action: Action,
        /// The block held when it was given.
        held: Option<BlockId>,
        /// The protocol that forbids it.
        protocol: ActionProtocol,
    },
    /// An action the side view's rules forbid in the current state (docs/world.md, "The side
    /// view"): a pick while holding or of a block that is not clear, a move or Drop with
    /// nothing held.
    #[error("{action} is not legal in the side view: {reason}")]
    IllegalInSideView {
        /// The action given.
        action: Action,
        /// Why not.
        reason: String,
    },
    /// A side-view state with a block that is not held standing on nothing.
    #[error(
        "block {block} floats at ({x}, {y}) in the side view: a block that is not held must stand on the table or on another block"
    )]
    Floating {
        /// The block.
        block: usize,
        /// Column.
        x: u16,
        /// Row.
        y: u16,
    },
    /// Towers asked of a side-view state in which a block is held.
    #[error("block {block} is held: a state's towers are read with nothing held")]
    HeldInTowers {
        /// The held block.
        block: usize,
    },
    /// A side-view drop whose dynamics did not bring a block to rest on a cell centre.
    #[error("the physics did not bring block {block} to rest on a cell: {reason}")]
    NotAtRest {
        /// The block.
        block: usize,
        /// What was found (where it is, how fast it moves).
        reason: String,
    },
    /// A goal of several towers (or of a tower naming only some blocks) given to something
    /// that handles only a goal of one tower of every block.
    #[error("goal {goal} is not one tower of every block: {what} handles only such goals (e.g. 0,1,2)")]
    NotOneTower {
        /// The goal as written.
        goal: String,
        /// What refuses it ("the paper reward", "the exact top-view solver", ...).
        what: &'static str,
    },
    /// A side-view grid that holds fewer than [`crate::env::MIN_SIDE_FIT`] of the Blocks
    /// World states of its blocks: the uniform start would draw for long.
    #[error(
        "a {width}x{height} grid holds fewer than 1 in 1000 of the Blocks World states of {blocks} blocks, which the side view's start draws uniformly: use a wider or taller grid (without --grid the side view takes {default})"
    )]
    SideGridTooSmall {
        /// Blocks.
        blocks: usize,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
        /// The side view's default grid for these blocks.
        default: String,
    },
    /// An observation array past its bound ([`crate::ObsKind::check`]).
    #[error(
        "a {kind} observation of {blocks} blocks on a {width}x{height} grid is not allowed: it is a W x H array of at most 256 cells and 16 blocks; use obs state"
    )]
    ObsTooLarge {
        /// The array.
        kind: crate::ObsKind,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
        /// Blocks.
        blocks: usize,
    },
    /// A start rule the side view does not use.
    #[error(
        "the {rule} start rule places blocks in the air; the side view starts from random towers: use the uniform start rule"
    )]
    SideViewStart {
        /// The start rule.
        rule: StartRule,
    },
    /// A block move that cannot be carried out in the current state.
    #[error("cannot {mv}: {reason}")]
    IllegalMove {
        /// The move, in words.
        mv: String,
        /// Why not.
        reason: String,
    },
    /// A block move index past the world's moves.
    #[error("block move {index} is out of range: the moves are 0..{count}")]
    MoveOutOfRange {
        /// The index given.
        index: usize,
        /// `N * (N + W)`.
        count: usize,
    },
    /// Block moves asked of a top-view world.
    #[error("block moves are carried out in the side view only (--view side)")]
    MovesNeedSideView,
    /// A buffer for an action mask whose length is not the world's number of actions.
    #[error("an action mask needs a buffer of {expected} bytes (5 + blocks), not {found}")]
    MaskLength {
        /// `5 + N`.
        expected: usize,
        /// The buffer's length.
        found: usize,
    },
    /// A start rule whose cells cannot hold every block of the world.
    #[error(
        "the {rule} start rule places blocks on {cells} cells of the {width}x{height} grid, too few for {blocks} blocks: use a larger grid, fewer blocks or the uniform start rule"
    )]
    StartDoesNotFit {
        /// The start rule.
        rule: StartRule,
        /// Cells the rule draws from.
        cells: usize,
        /// Blocks to place.
        blocks: usize,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// A block id outside `0..blocks`.
    #[error("block {block} does not exist: the blocks are 0..{blocks}")]
    NoSuchBlock {
        /// The id given.
        block: usize,
        /// How many blocks the world has.
        blocks: usize,
    },
    /// More goals than [`crate::goal::MAX_ALL_GOALS`] asked for all at once.
    #[error(
        "{blocks} blocks have {goals} goals, more than the {max} that can be drawn all at once: name the goals to use (e.g. {example})"
    )]
    TooManyGoals {
        /// The block count.
        blocks: usize,
        /// Its number of goals (`blocks!`), written out.
        goals: String,
        /// [`crate::goal::MAX_ALL_GOALS`].
        max: usize,
        /// An example goal of that many blocks.
        example: String,
    },
    /// A cell outside the grid.
    #[error("cell ({x}, {y}) is outside the {width}x{height} grid")]
    CellOutsideGrid {
        /// Column.
        x: i64,
        /// Row.
        y: i64,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// Two blocks placed on one cell.
    #[error("blocks {first} and {second} both stand on cell ({x}, {y})")]
    CellsOverlap {
        /// One block.
        first: usize,
        /// The other block.
        second: usize,
        /// Column.
        x: u16,
        /// Row.
        y: u16,
    },
    /// Two things that must agree on the number of blocks do not.
    #[error("block counts differ: the world has {expected} blocks but {what} has {found}")]
    BlockCountMismatch {
        /// Blocks in the world (or config).
        expected: usize,
        /// What disagrees ("the goal", "the state").
        what: &'static str,
        /// Blocks it has.
        found: usize,
    },
    /// A zero horizon.
    #[error("the horizon must be at least 1 step")]
    ZeroHorizon,
    /// `step` called before the first `reset`.
    #[error("the environment has not been reset: call reset before step")]
    NotReset,
    /// `step` called after the episode ended.
    #[error("the episode has ended (terminated or truncated): call reset before step")]
    EpisodeOver,
    /// A vectorised step given a different number of actions than it has environments.
    #[error("{actions} actions given for {envs} environments: give one action per environment")]
    ActionCountMismatch {
        /// Environments.
        envs: usize,
        /// Actions given.
        actions: usize,
    },
    /// The thread pool for parallel stepping could not start.
    #[error("cannot start {threads} worker threads: {reason}")]
    ThreadPool {
        /// Threads asked for.
        threads: usize,
        /// The system's reason.
        reason: String,
    },
    /// A picture larger than [`crate::render::MAX_PICTURE_SIDE`] a side or
    /// [`crate::render::MAX_PICTURE_PIXELS`] in all.
    #[error(
        "a picture with {cell}-pixel cells would be {width}x{height} pixels, larger than {max_side} a side or {max_pixels} pixels in all: use smaller cells"
    )]
    PictureTooLarge {
        /// Pixels per cell asked for.
        cell: u32,
        /// The picture's width.
        width: u64,
        /// The picture's height.
        height: u64,
        /// The largest side allowed.
        max_side: u64,
        /// The most pixels allowed.
        max_pixels: u64,
    },
    /// A picture file whose name does not say a format blockstack writes.
    #[error("cannot write a picture to {path}: name it .png or .jpg (or .jpeg)")]
    PictureFormat {
        /// The path.
        path: String,
    },
    /// A trajectory file line that cannot be read or breaks the rules.
    #[error("{name}:{line}: {reason}")]
    Trajectory {
        /// The file's name.
        name: String,
        /// The line's number, from 1.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file (trajectory, picture) failed, or its destination cannot
    /// be written.
    #[error(transparent)]
    Files(#[from] files::FilesError),
}

/// "nothing is held" or "block 2 is held".
impl SimError {
    /// Whether this is the world's rules refusing an action that exists (the action
    /// protocol's, or the side view's): what [`Refusal::Step`](crate::Refusal::Step) takes
    /// as a step that changes nothing.
    pub fn is_refusal(&self) -> bool {
        matches!(
            self,
            SimError::IllegalAction { .. } | SimError::IllegalInSideView { .. }
        )
    }
}

fn held_text(held: Option<BlockId>) -> String {
    match held {
        None => "nothing is held".into(),
        Some(b) => format!("block {b} is held"),
    }
}

/// Shorthand for results whose error is a [`SimError`].
pub type Result<T, E = SimError> = std::result::Result<T, E>;
