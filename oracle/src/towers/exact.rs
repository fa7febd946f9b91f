//! The exact block-move solver: A* over whole states with an admissible heuristic.
//!
//! The heuristic is the deadlock bound (the `deadlock` module): one move per misplaced block
//! plus one per vertex-disjoint cycle of "moves before" constraints. Both parts are lower
//! bounds on what any plan from the state still needs, so A* returns a shortest plan
//! (`pathfinding`'s A* reopens a state reached again more cheaply, so the bound need not
//! be consistent).

use pathfinding::directed::astar::astar;

use crate::error::Result;

use super::deadlock::lower_bound;
use super::error::{Part, TowersError};
use super::goal::TowerGoal;
use super::plan::TowerPlan;
use super::state::{Move, NONE, Place, Table, Towers};

/// Bits per block in a packed state.
const BITS: usize = 5;
/// The packed code of "on the table".
const TABLE_CODE: u128 = (1 << BITS) - 1;

/// The most states [`ExactMoves`] generates by default before giving up: about 100 MB.
pub const DEFAULT_MOVE_BUDGET: usize = 2_000_000;

/// The exact block-move solver: a shortest plan in block moves, by A*.
///
/// Optimal plans of up to 10 blocks take milliseconds to a few seconds (the tests and the
/// `towers` example measure it); the search stops with
/// [`TowersError::BudgetExceeded`] after generating its budget of states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExactMoves {
    /// The table the plan is made on.
    table: Table,
    /// The most states the search may generate.
    budget: usize,
}

impl Default for ExactMoves {
    fn default() -> Self {
        ExactMoves {
            table: Table::Unbounded,
            budget: DEFAULT_MOVE_BUDGET,
        }
    }
}

impl ExactMoves {
    /// The most blocks the solver takes (a state is packed into 128 bits).
    pub const MAX_BLOCKS: usize = 128 / BITS;

    /// The solver on an unbounded table with the default budget.
    pub fn new() -> Self {
        Self::default()
    }

    /// This solver, planning on `table`: on a table of `c` columns a move to the table
    /// needs one of them free.
    pub fn with_table(self, table: Table) -> Self {
        ExactMoves { table, ..self }
    }

    /// This solver, generating at most `budget` states.
    pub fn with_budget(self, budget: usize) -> Self {
        ExactMoves { budget, ..self }
    }

    /// A shortest plan from `start` to `goal`.
    ///
    /// Errors: a goal naming a block the state lacks, more towers than the table's
    /// columns, more than [`ExactMoves::MAX_BLOCKS`] blocks, a goal no plan reaches (on a
    /// narrow table), or the budget spent.
    pub fn solve(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        let n = start.blocks();
        goal.check_blocks(n)?;
        self.table.check(Part::State, start.tower_count())?;
        self.table.check(Part::Goal, goal.towers().len())?;
        if n > Self::MAX_BLOCKS {
            return Err(TowersError::TooManyBlocks {
                blocks: n,
                max: Self::MAX_BLOCKS,
            }
            .into());
        }
        // The goal holds when the named blocks' fields equal their goal supports.
        let (mut mask, mut want) = (0u128, 0u128);
        for &b in goal.towers().iter().flatten() {
            mask |= TABLE_CODE << (BITS * b);
            want |= code_of(goal.below_of(b)) << (BITS * b);
        }
        let mut generated = 0usize;
        let mut over = false;
        let table = self.table;
        let budget = self.budget;
        let found = astar(
            &encode(start.below()),
            |&code| {
                let state = decode(code, n);
                if over || generated >= budget {
                    over = true;
                    return Vec::new();
                }
                let next: Vec<(u128, u32)> = state
                    .moves(table)
                    .into_iter()
                    .map(|mv| (with_move(code, mv), 1))
                    .collect();
                generated += next.len();
                next
            },
            |&code| {
                let state = decode(code, n);
                lower_bound(state.below(), state.above(), goal)
            },
            |&code| code & mask == want,
        );
        match found {
            _ if over => Err(TowersError::BudgetExceeded { budget, blocks: n }.into()),
            Some((path, _)) => Ok(TowerPlan {
                moves: path.windows(2).map(|w| moved(w[0], w[1], n)).collect(),
            }),
            None => Err(TowersError::Unreachable {
                columns: match table {
                    Table::Columns(c) => c,
                    Table::Unbounded => n,
                },
            }
            .into()),
        }
    }
}

/// The packed code of a support.
fn code_of(support: usize) -> u128 {
    if support == NONE { TABLE_CODE } else { support as u128 }
}

/// A support array packed into 128 bits, [`BITS`] per block.
fn encode(below: &[usize]) -> u128 {
    below
        .iter()
        .enumerate()
        .fold(0, |acc, (b, &s)| acc | code_of(s) << (BITS * b))
}

/// The support of block `b` in a packed state.
fn field(code: u128, b: usize) -> usize {
    match (code >> (BITS * b)) & TABLE_CODE {
        TABLE_CODE => NONE,
        s => s as usize,
    }
}

/// The state of `n` blocks a code packs.
fn decode(code: u128, n: usize) -> Towers {
    Towers::from_below((0..n).map(|b| field(code, b)).collect())
}

/// The code after a legal move.
fn with_move(code: u128, mv: Move) -> u128 {
    let to = match mv.to {
        Place::Table => TABLE_CODE,
        Place::On(y) => y as u128,
    };
    let shift = BITS * mv.block;
    (code & !(TABLE_CODE << shift)) | to << shift
}

/// The move that leads from one packed state to the next (they differ in one field).
fn moved(from: u128, to: u128, n: usize) -> Move {
    let block = (0..n).find(|&b| field(from, b) != field(to, b)).unwrap_or(0);
    Move {
        block,
        to: Place::from_support(field(to, block)),
    }
}
