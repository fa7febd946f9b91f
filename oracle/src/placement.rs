//! Where the stack may stand, what each block's target cell is there, and the lower bound
//! on the actions needed to build it.

use sim::{BlockId, Cell, Goal, Grid, State};

use crate::error::{OracleError, Result};

/// A place for the goal's stack: its column and the row of its bottom block.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct Placement {
    pub column: u16,
    pub bottom: u16,
}

impl Placement {
    /// Every placement of a stack of `blocks` blocks that fits `grid`, row-major by bottom cell.
    pub fn all(grid: Grid, blocks: usize) -> impl Iterator<Item = Placement> {
        let rows = (grid.height() + 1).saturating_sub(blocks);
        (0..rows).flat_map(move |bottom| {
            (0..grid.width()).map(move |column| Placement {
                column: column as u16,
                bottom: bottom as u16,
            })
        })
    }

    /// The cell `block` stands on in this placement's stack.
    #[inline]
    pub fn target(self, goal: &Goal, block: BlockId) -> Cell {
        Cell::new(self.column, self.bottom + goal.place_of(block) as u16)
    }

    /// Whether `cell` is one of the stack's cells.
    #[inline]
    pub fn contains(self, goal: &Goal, cell: Cell) -> bool {
        cell.x == self.column && cell.y >= self.bottom && usize::from(cell.y - self.bottom) < goal.block_count()
    }

    /// A lower bound on the actions that put every block of `state` on its cell of this
    /// placement: every block off its cell moves at least its Manhattan distance, one cell
    /// per action, and every such block other than the held one needs a pick first.
    #[inline]
    pub fn lower_bound(self, state: &State, goal: &Goal) -> u32 {
        let held = state.held_block();
        let mut bound = 0;
        for (i, &cell) in state.cells().iter().enumerate() {
            let block = BlockId::of(i);
            let distance = cell.manhattan(self.target(goal, block));
            if distance > 0 {
                bound += distance + u32::from(held != Some(block));
            }
        }
        bound
    }

    /// Squared distance, in doubled cell units so it stays an integer, between the middle
    /// of this placement's stack and the centroid of the blocks: the paper's measure of a
    /// good place, used to break ties between equally short plans.
    pub fn centroid_distance(self, state: &State, goal: &Goal) -> u64 {
        let n = state.block_count() as i64;
        // Centres are (x + 0.5, y + 0.5); times 2n the centroid is an integer.
        let (sx, sy) = state.cells().iter().fold((0i64, 0i64), |(sx, sy), c| {
            (sx + 2 * i64::from(c.x) + 1, sy + 2 * i64::from(c.y) + 1)
        });
        let mx = n * (2 * i64::from(self.column) + 1);
        let my = n * (2 * i64::from(self.bottom)) + n * goal.block_count() as i64;
        ((sx - mx).pow(2) + (sy - my).pow(2)) as u64
    }
}

/// The exact solver's heuristic: the smallest [`Placement::lower_bound`] over every
/// placement of the stack.
pub(crate) fn lower_bound(grid: Grid, state: &State, goal: &Goal) -> u32 {
    Placement::all(grid, goal.block_count())
        .map(|p| p.lower_bound(state, goal))
        .min()
        .unwrap_or(u32::MAX)
}

/// Checks that `state` and `goal` make a problem on `grid` that has a solution: the same
/// block count, the state inside the grid, the stack no taller than it, and the goal
/// reachable ([`Goal::can_be_reached`]: on a grid one cell wide blocks cannot pass each
/// other, so there the goal must list them in the order they stand; on any wider grid every
/// goal can be reached from every state, see the crate docs).
pub(crate) fn check_problem(grid: Grid, state: &State, goal: &Goal) -> Result<()> {
    if state.block_count() != goal.block_count() {
        return Err(OracleError::BlockCountMismatch {
            state: state.block_count(),
            goal: goal.block_count(),
        });
    }
    state.check_fits(grid)?;
    goal.check_fits(grid)?;
    goal.one_tower("a top-view planner (the oracle, the exact solver)")?;
    if !goal.can_be_reached(grid, state) {
        let mut standing: Vec<BlockId> = state.blocks().collect();
        standing.sort_by_key(|&b| state.cell(b).y);
        if standing != goal.order() {
            let order: Vec<String> = standing.iter().map(|b| b.to_string()).collect();
            return Err(OracleError::GoalUnreachable {
                goal: goal.to_string(),
                reason: format!(
                    "on a grid one cell wide blocks cannot pass each other, and they stand {} bottom to top",
                    order.join(",")
                ),
            });
        }
    }
    Ok(())
}
