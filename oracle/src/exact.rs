//! The exact solver: A* over the joint state (every block's cell and the held block) with
//! an admissible, consistent heuristic, so the plan it returns is a shortest one.
//!
//! These docs are the top view's (the paper's world, the default). In the side view
//! ([`ExactSolver::with_view`]) the same search finds the fewest gripper steps to a goal of
//! towers, with the side view's successors and its own heuristic: [`side`] says which and
//! proves it.
//!
//! # The heuristic and why it is admissible and consistent
//!
//! For a placement `P` of the stack (its column and bottom row), let `D` be the blocks not
//! on their cell of `P`, `d_b` the Manhattan distance from block `b` to its cell, and
//! `h_P = sum over b in D of (d_b + [b is not held])`. The heuristic is
//! `h = min over P of h_P`.
//!
//! - *Admissible.* A state where the goal holds is the stack at some placement `P*`. To
//!   get there every block of `D(P*)` moves at least `d_b` times (a move shifts one block
//!   by one cell), and every block of `D(P*)` other than the one held now must be picked
//!   at least once (only the held block moves, and only a pick changes which block is
//!   held). Moves and picks are different actions, so at least `h_P*` actions are needed,
//!   and `h <= h_P*`.
//! - *Consistent.* One action lowers each `h_P` by at most 1: a move changes one `d_b` by
//!   one (when the block reaches its cell its term was `1 + 0`, the held block paying no
//!   pick; when it leaves, the term grows), a pick lowers the pick count by at most one,
//!   and a drop never lowers it. A minimum of functions that each fall by at most 1 per
//!   action falls by at most 1 too, so `h(s) <= 1 + h(s')` for every action `s -> s'`.
//!
//! # Actions searched
//!
//! Successors come from [`sim::World::act`] on a [`GridWorld`], among the actions the
//! solver's [`ActionProtocol`] allows ([`ExactSolver::with_protocol`]; `free` by default),
//! so a plan is a shortest one *under that protocol*.
//!
//! - `free`: only moves that move and picks of another block are searched: an action that
//!   changes nothing never shortens a plan, and a shortest plan never drops. Proof: a drop
//!   cannot be the last action (the goal does not depend on the held block, so it held one
//!   action earlier), and the next useful action after it is a pick, which reaches the
//!   same state with or without the drop; removing the drop gives a shorter plan.
//! - `paper` (nothing held: only picks; holding: only the moves and Drop): every pick with
//!   nothing held, and, holding, the moves that move and Drop. Changing blocks costs a
//!   Drop and a Pick.
//!
//! The heuristic stays admissible and consistent under `paper`: a plan legal under `paper`
//! is a plan under `free` too (the same actions do the same there), so it is no shorter
//! than the `free` optimum the heuristic bounds; and a Drop lowers no `h_P`.
//!
//! # How far it scales
//!
//! One search stores at most its budget of states ([`DEFAULT_NODE_BUDGET`] by default),
//! and past it returns [`OracleError::BudgetExceeded`] instead of growing, so no search can
//! run the machine out of memory; [`ExactSolver::with_node_budget`] sets another budget.
//! A search that used up the default budget peaked under half a gigabyte here.
//!
//! What fits in the default budget depends on how much the blocks get in each other's way,
//! not on the size of the whole state space: the heuristic is exact when no block stands in
//! another's way, and A* then walks straight down a shortest plan. On 7 x 7, 2 and 3 blocks are
//! solved from any state (the tests compare every 2-block state and random 3-block states
//! with a breadth-first search of the whole space) in tens of microseconds on average, and
//! 4 blocks from random starts in about a millisecond at most. Random starts of up to 7 blocks
//! on 7 x 7, 8 on 8 x 8, and 6 on 16 x 16 stayed inside the default budget when measured;
//! with 8 blocks on 16 x 16 some starts ran out of it. The figures, for this machine:
//! `cargo run --release -p oracle --example exact_scaling`. Past the budget, use the
//! [`Oracle`](crate::Oracle), which plans any size in microseconds.

use std::cell::Cell as Counter;

use pathfinding::directed::astar::astar;
use sim::{Action, ActionProtocol, Effect, Goal, Grid, GridWorld, State, View, World};

use crate::error::{OracleError, Result};
use crate::placement::{self, check_problem};
use crate::plan::{Plan, Planner};

pub mod side;

/// The default budget of the exact search: the most states it may store.
pub const DEFAULT_NODE_BUDGET: usize = 4_000_000;

/// What one exact search did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SearchStats {
    /// States taken off the open list and expanded.
    pub expanded: usize,
    /// Successor states generated (stored at most once each); bounded by the budget.
    pub generated: usize,
}

/// Finds provably shortest plans by A* over the joint state (module docs: the heuristic,
/// its proofs, and how far it scales).
///
/// ```
/// use oracle::ExactSolver;
/// use sim::{Cell, Goal, Grid, State};
///
/// let solver = ExactSolver::new(Grid::default());
/// let state = State::new(&[Cell::new(0, 0), Cell::new(3, 0)], None)?;
/// let goal: Goal = "1,0".parse()?;
/// // Pick block 0 and take it four cells to the cell above block 1.
/// assert_eq!(solver.distance(&state, &goal)?, 5);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExactSolver {
    grid: Grid,
    budget: usize,
    protocol: ActionProtocol,
    view: View,
}

impl ExactSolver {
    /// A solver on `grid` with the default budget.
    pub fn new(grid: Grid) -> Self {
        Self {
            grid,
            budget: DEFAULT_NODE_BUDGET,
            protocol: ActionProtocol::Free,
            view: View::Top,
        }
    }

    /// This solver planning in `view`: in the side view it finds the fewest gripper steps
    /// (Pick, moves, Drop) from a side-view state to any goal (towers included) as
    /// [`Goal::holds_in`] the side view checks it ([`side`]: the actions searched, the
    /// heuristic and its proofs). The top view is the default.
    ///
    /// ```
    /// use oracle::ExactSolver;
    /// use sim::{Cell, Goal, Grid, State, View};
    ///
    /// let solver = ExactSolver::new(Grid::default()).with_view(View::Side);
    /// // Blocks 0 and 1 on the table, two columns apart; the goal puts 1 on 0.
    /// let state = State::new(&[Cell::new(0, 0), Cell::new(2, 0)], None)?;
    /// let goal: Goal = "0,1".parse()?;
    /// // Pick 1, up, left twice, Drop: it falls onto 0.
    /// assert_eq!(solver.distance(&state, &goal)?, 5);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_view(mut self, view: View) -> Self {
        self.view = view;
        self
    }

    /// The solver of `world`'s grid, protocol and view: the yardstick of an evaluation
    /// played in that world.
    pub fn for_world(world: &sim::EnvConfig) -> Self {
        ExactSolver::new(world.grid)
            .with_protocol(world.protocol)
            .with_view(world.view)
    }

    /// The world it plans in.
    pub fn view(&self) -> View {
        self.view
    }

    /// This solver planning under `protocol`: its plans take only actions the protocol
    /// allows, and are shortest among such plans (module docs).
    pub fn with_protocol(mut self, protocol: ActionProtocol) -> Self {
        self.protocol = protocol;
        self
    }

    /// The action protocol its plans obey.
    pub fn protocol(&self) -> ActionProtocol {
        self.protocol
    }

    /// This solver with a budget of `states`: the most states one search may store before
    /// it gives up with [`OracleError::BudgetExceeded`].
    pub fn with_node_budget(mut self, states: usize) -> Self {
        self.budget = states;
        self
    }

    /// The grid it plans on.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The most states one search may store.
    pub fn node_budget(&self) -> usize {
        self.budget
    }

    /// A shortest plan from `state` to `goal` (empty if the goal holds).
    pub fn solve(&self, state: &State, goal: &Goal) -> Result<Plan> {
        self.solve_with_stats(state, goal).map(|(plan, _)| plan)
    }

    /// The length of a shortest plan: `solve(..).len()`.
    pub fn distance(&self, state: &State, goal: &Goal) -> Result<u32> {
        self.solve(state, goal).map(|plan| plan.len() as u32)
    }

    /// The heuristic's value: a lower bound on [`ExactSolver::distance`] (module docs).
    pub fn lower_bound(&self, state: &State, goal: &Goal) -> Result<u32> {
        match self.view {
            View::Top => {
                check_problem(self.grid, state, goal)?;
                Ok(placement::lower_bound(self.grid, state, goal))
            }
            View::Side => Ok(side::SideProblem::new(self.grid, state, goal)?.lower_bound(state)),
        }
    }

    /// A shortest plan and what the search did to find it.
    pub fn solve_with_stats(&self, state: &State, goal: &Goal) -> Result<(Plan, SearchStats)> {
        let (grid, protocol) = (self.grid, self.protocol);
        match self.view {
            View::Top => {
                check_problem(grid, state, goal)?;
                self.search(
                    state,
                    goal,
                    |s| successors(grid, protocol, s),
                    |s| placement::lower_bound(grid, s, goal),
                    |s| goal.holds(s),
                )
            }
            View::Side => {
                let problem = side::SideProblem::new(grid, state, goal)?;
                self.search(
                    state,
                    goal,
                    |s| side::successors(grid, s),
                    |s| problem.lower_bound(s),
                    |s| goal.holds_in(View::Side, s),
                )
            }
        }
    }

    /// A* from `state` over `successors` with the heuristic `bound` to a state where `done`
    /// holds, within the budget; the plan is read back from the path's states.
    fn search(
        &self,
        state: &State,
        goal: &Goal,
        successors: impl Fn(&State) -> Vec<(Action, State)>,
        bound: impl Fn(&State) -> u32,
        done: impl Fn(&State) -> bool,
    ) -> Result<(Plan, SearchStats)> {
        let expanded = Counter::new(0usize);
        let generated = Counter::new(0usize);
        let over_budget = || generated.get() > self.budget;
        let found = astar(
            state,
            |s: &State| {
                if over_budget() {
                    // Starve the search: it drains its open list and reports no path.
                    return Vec::new();
                }
                expanded.set(expanded.get() + 1);
                let next = successors(s);
                generated.set(generated.get() + next.len());
                next.into_iter().map(|(_, t)| (t, 1u32)).collect()
            },
            |s| bound(s),
            |s| done(s),
        );
        let stats = SearchStats {
            expanded: expanded.get(),
            generated: generated.get(),
        };
        if over_budget() {
            // Even a path found after the budget ran out is not proved shortest.
            return Err(OracleError::BudgetExceeded {
                budget: self.budget,
                blocks: state.block_count(),
                grid: self.grid.to_string(),
            });
        }
        let Some((path, _)) = found else {
            return Err(OracleError::GoalUnreachable {
                goal: goal.to_string(),
                reason: "the exact search tried every reachable state".into(),
            });
        };
        let actions = path
            .windows(2)
            .map(|w| {
                successors(&w[0])
                    .into_iter()
                    .find(|(_, t)| *t == w[1])
                    .map(|(a, _)| a)
                    .expect("consecutive states of a path are one action apart")
            })
            .collect();
        Ok((Plan { actions }, stats))
    }
}

impl Planner for ExactSolver {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn plan(&self, state: &State, goal: &Goal) -> Result<Plan> {
        self.solve(state, goal)
    }

    fn protocol(&self) -> ActionProtocol {
        self.protocol
    }

    fn with_protocol(self, protocol: ActionProtocol) -> Self {
        ExactSolver::with_protocol(self, protocol)
    }
}

/// The searched successors of `state` under `protocol` (module docs), each with the action
/// that leads there: under `free`, moves of the held block that move it and picks of every
/// other block; under `paper`, those of them the protocol allows, and Drop.
fn successors(grid: Grid, protocol: ActionProtocol, state: &State) -> Vec<(Action, State)> {
    let world = GridWorld::new(grid, state.clone()).expect("states reached by act fit the grid");
    let held = state.held_block();
    let moves = [Action::Up, Action::Down, Action::Left, Action::Right]
        .into_iter()
        .filter(|_| held.is_some());
    let picks = state.blocks().filter(|&b| Some(b) != held).map(Action::Pick);
    let drop = (protocol == ActionProtocol::Paper && held.is_some()).then_some(Action::Drop);
    let legal = protocol.legal_actions(state);
    moves
        .chain(picks)
        .chain(drop)
        .filter(|&a| legal.contains(a))
        .filter_map(|a| {
            let mut w = world.clone();
            match w.act(a) {
                Ok(Effect::Moved | Effect::Picked | Effect::Dropped) => Some((a, w.into_state())),
                _ => None,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::Cell;

    fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
        let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
        State::new(&cells, held.map(sim::BlockId)).unwrap()
    }

    #[test]
    fn goal_already_holding_gives_an_empty_plan() {
        let s = state(&[(2, 2), (2, 3)], None);
        let plan = ExactSolver::new(Grid::default())
            .solve(&s, &Goal::identity(2).unwrap())
            .unwrap();
        assert!(plan.is_empty());
    }

    #[test]
    fn a_held_block_saves_its_pick() {
        let goal = Goal::identity(2).unwrap();
        let solver = ExactSolver::new(Grid::default());
        // Block 1 two cells right of the cell above block 0.
        let free = state(&[(0, 0), (2, 1)], None);
        let held = state(&[(0, 0), (2, 1)], Some(1));
        assert_eq!(solver.distance(&free, &goal).unwrap(), 3);
        assert_eq!(solver.distance(&held, &goal).unwrap(), 2);
    }

    #[test]
    fn a_tiny_budget_is_reported_not_overrun() {
        let s = state(&[(0, 0), (6, 6), (3, 0)], None);
        let err = ExactSolver::new(Grid::default())
            .with_node_budget(10)
            .solve(&s, &Goal::identity(3).unwrap())
            .unwrap_err();
        assert!(
            matches!(
                err,
                OracleError::BudgetExceeded {
                    budget: 10,
                    blocks: 3,
                    ..
                }
            ),
            "{err}"
        );
    }
}
