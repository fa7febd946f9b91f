//! The side view's problems as the planners' towers: the one place a side-view state and
//! goal (`sim::view`, docs/world.md section 12) become a block-move plan, for `blockstack
//! solve --view side`, Python's `solve` and the agents that play the side view.
//!
//! The table is as wide as the grid (a move to the table needs an empty column), and a plan
//! that would stack more blocks than the grid has rows is refused, since the planners do
//! not know the grid's height.
//!
//! [`gripper_actions`] carries a block-move plan out as gripper actions (a move to the table
//! going to the leftmost empty column), for the plans counted in gripper steps.

use sim::block_move::{self, BlockMove};
use sim::{Action, BlockId, Goal, Grid, GridWorld, State, View, World};

use super::{
    Certificate, CertifiedPlan, ExactMoves, Move, NearOptimal, OptimalMoves, Place, Table, TowerGoal, TowerPlan,
    Towers, TowersError,
};
use crate::error::{OracleError, Result};

/// Which block-move planner.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MovePlanner {
    /// [`ExactMoves`]: the fewest block moves.
    Exact,
    /// [`NearOptimal`]: at most twice the fewest, for any number of blocks.
    NearOptimal,
    /// [`OptimalMoves`]: the fewest, with its proof, at any size the side view holds (its
    /// plan, made on an unbounded table, is refused if it needs more columns than the grid
    /// has).
    Optimal,
}

sim::names!(MovePlanner { Exact = "exact", NearOptimal = "near-optimal", Optimal = "optimal" } unknown(text) -> OracleError {
    TowersError::UnknownPlanner { name: text.to_string() }.into()
});

/// `planner`'s block-move plan from the side-view `state` (nothing held, every block
/// standing) to `goal`, on a table as wide as `grid`; an error if the towers do not fit the
/// grid, the goal cannot be reached, or the plan would stack higher than the grid.
pub fn plan_side(planner: MovePlanner, grid: Grid, state: &State, goal: &Goal) -> Result<TowerPlan> {
    Ok(plan_side_certified(planner, grid, state, goal)?.plan)
}

/// [`plan_side`]'s plan with the lower bound it is measured against: the exact solver's
/// plan is proven shortest, the optimal solver's comes with its certificate, the
/// near-optimal planner's with the bound that takes no search ([`Certificate::quick`]).
/// A bound of the unbounded table holds on the grid's too.
pub fn plan_side_certified(planner: MovePlanner, grid: Grid, state: &State, goal: &Goal) -> Result<CertifiedPlan> {
    let start = Towers::new(&sim::view::towers(state)?)?;
    let towers = TowerGoal::new(&goal.tower_lists())?;
    towers.check_blocks(start.blocks())?;
    let table = Table::Columns(grid.width());
    let certified = match planner {
        MovePlanner::Exact => CertifiedPlan::proven(
            ExactMoves::new().with_table(table).solve(&start, &towers)?,
            Certificate::quick(&start, &towers)?,
        ),
        MovePlanner::NearOptimal => CertifiedPlan::new(
            NearOptimal::new().with_table(table).plan(&start, &towers)?,
            Certificate::quick(&start, &towers)?,
        ),
        MovePlanner::Optimal => OptimalMoves::new().solve(&start, &towers)?,
    };
    // Each block's height in its tower, kept per move (only a clear block moves, so no
    // other block's changes): checking the whole towers after every move made a plan of
    // N blocks cost O(N^2).
    let mut height = vec![0usize; start.blocks()];
    for tower in start.towers() {
        for (y, &b) in tower.iter().enumerate() {
            height[b] = y + 1;
        }
    }
    let mut tallest = height.iter().copied().max().unwrap_or(0);
    let mut now = start;
    for &mv in &certified.plan.moves {
        now.apply(mv, table)?;
        height[mv.block] = match mv.to {
            Place::On(target) => height[target] + 1,
            Place::Table => 1,
        };
        tallest = tallest.max(height[mv.block]);
        if tallest > grid.height() {
            return Err(TowersError::TooTall {
                tallest,
                rows: grid.height(),
            }
            .into());
        }
    }
    Ok(certified)
}

/// The first block move of `planner`'s plan from the side-view `state` to `goal` on `grid`
/// ([`plan_side`]), as the world's block move ([`block_move_of`]: a move to the table goes
/// to the leftmost empty column): the expert's next action where the actions are block
/// moves. An error if the goal holds already, or as [`plan_side`] says.
pub fn next_block_move(planner: MovePlanner, grid: Grid, state: &State, goal: &Goal) -> Result<BlockMove> {
    let plan = plan_side(planner, grid, state, goal)?;
    let first = plan
        .moves
        .first()
        .ok_or_else(|| OracleError::GoalAlreadyHolds { goal: goal.to_string() })?;
    block_move_of(state, grid, *first)
}

/// The gripper actions that carry out `plan` from the side-view `state` on `grid`, move
/// after move: each is expanded by [`sim::block_move::expand`] (the fewest gripper actions
/// for it) from the state the moves before it lead to, and a move to the table goes to the
/// leftmost empty column. An error if a move cannot be carried out there (no empty column,
/// no free row to carry the block over).
pub fn gripper_actions(grid: Grid, state: &State, plan: &TowerPlan) -> Result<Vec<Action>> {
    let mut world = GridWorld::new_in(View::Side, grid, state.clone())?;
    let mut actions = Vec::new();
    for m in &plan.moves {
        let mv = block_move_of(world.state_ref(), grid, *m)?;
        let start = actions.len();
        actions.extend(block_move::route_in(&world, mv)?.actions());
        for &a in &actions[start..] {
            world.act(a)?;
        }
    }
    Ok(actions)
}

/// The world's block move that carries out the plan's move `m` from `state` on `grid`: a
/// move to the table goes to the leftmost empty column (an error if there is none).
pub fn block_move_of(state: &State, grid: Grid, m: Move) -> Result<BlockMove> {
    let block = BlockId::of(m.block);
    Ok(match m.to {
        Place::On(target) => BlockMove::Onto {
            block,
            target: BlockId::of(target),
        },
        Place::Table => BlockMove::ToTable {
            block,
            column: empty_column(state, grid).ok_or_else(|| TowersError::IllegalMove {
                mv: m.to_string(),
                reason: "no column of the grid is empty",
            })?,
        },
    })
}

/// The leftmost column with no block on the table, if any. O(N + W).
pub fn empty_column(state: &State, grid: Grid) -> Option<u16> {
    let mut used = vec![false; grid.width()];
    for c in state.cells().iter().filter(|c| c.y == 0) {
        used[usize::from(c.x)] = true;
    }
    used.iter().position(|&u| !u).map(|x| x as u16)
}
