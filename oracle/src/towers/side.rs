//! The side view's problems as the planners' towers: the one place a side-view state and
//! goal (`sim::view`, docs/world.md section 12) become a block-move plan, for `blockstack
//! solve --view side`, Python's `solve` and the agents that play the side view.
//!
//! The table is as wide as the grid (a move to the table needs an empty column), and a plan
//! that would stack more blocks than the grid has rows is refused, since the planners do
//! not know the grid's height.

use sim::{Goal, Grid, State};

use super::{ExactMoves, NearOptimal, Table, TowerGoal, TowerPlan, Towers, TowersError};
use crate::error::{OracleError, Result};

/// Which block-move planner.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MovePlanner {
    /// [`ExactMoves`]: the fewest block moves.
    Exact,
    /// [`NearOptimal`]: at most twice the fewest, for any number of blocks.
    NearOptimal,
}

sim::names!(MovePlanner { Exact = "exact", NearOptimal = "near-optimal" } unknown(text) -> OracleError {
    TowersError::UnknownPlanner { name: text.to_string() }.into()
});

/// `planner`'s block-move plan from the side-view `state` (nothing held, every block
/// standing) to `goal`, on a table as wide as `grid`; an error if the towers do not fit the
/// grid, the goal cannot be reached, or the plan would stack higher than the grid.
pub fn plan_side(planner: MovePlanner, grid: Grid, state: &State, goal: &Goal) -> Result<TowerPlan> {
    let start = Towers::new(&sim::view::towers(state)?)?;
    let towers = TowerGoal::new(&goal.tower_lists())?;
    towers.check_blocks(start.blocks())?;
    let table = Table::Columns(grid.width());
    let plan = match planner {
        MovePlanner::Exact => ExactMoves::new().with_table(table).solve(&start, &towers)?,
        MovePlanner::NearOptimal => NearOptimal::new().with_table(table).plan(&start, &towers)?,
    };
    let mut now = start;
    for &mv in &plan.moves {
        now.apply(mv, table)?;
        let tallest = now.towers().iter().map(Vec::len).max().unwrap_or(0);
        if tallest > grid.height() {
            return Err(TowersError::TooTall {
                tallest,
                rows: grid.height(),
            }
            .into());
        }
    }
    Ok(plan)
}
