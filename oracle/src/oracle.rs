//! The oracle: the paper's analytical oracle made sound. It chooses a place for the stack,
//! gives every block its target cell there, and routes the blocks one at a time with A*
//! over the occupancy grid, moving blockers out of the way.
//!
//! # The routing policy for one placement
//!
//! For a placement `P` (column and bottom row of the stack), a block is *placed* when it
//! stands on its target cell. At every state the first rule that applies gives the next
//! stretch of actions:
//!
//! 1. the held block is not placed and can reach its target: move it along a shortest
//!    route there;
//! 2. the held block stands on another block's target and can leave the stack's cells:
//!    move it to the nearest free cell outside them;
//! 3. some block not placed can reach its target: pick one and route it (rule 1 goes on
//!    with it). Which one is the policy's *order*: the one with the shortest route (then
//!    the lowest in the goal), or the lowest in the goal, or the highest. Placing the
//!    nearest block first can wall off another's straight route; another order avoids it;
//! 4. some block on another block's target can leave: pick the one with the shortest way
//!    out (rule 2 goes on with it);
//! 5. otherwise the policy is stuck at `P`.
//!
//! Placed blocks never move, so every stretch either places one more block or takes one
//! wrong block off the stack's cells without placing fewer: `(N + 1) * placed - wrong`
//! grows with every stretch, and the policy ends, at the goal or stuck, within
//! `N * (N + 2)` stretches.
//!
//! # Choosing the placement
//!
//! [`Oracle::plan`] rolls the policy out for every placement and order and keeps the
//! shortest plan; equally short plans go to the placement nearest the blocks' centroid
//! (the paper's rule). Placements are tried in order of the exact solver's lower bound, and
//! one whose bound is no shorter than the best plan so far is skipped, so usually one or
//! two rollouts are made.
//!
//! docs/world.md section 8 places the stack at the cell nearest the centroid. That cell is not
//! where a shortest plan builds in general: it ignores that a block left where it stands
//! needs no pick, and that routes bend around blocks. So the centroid only breaks ties
//! here, and plan length decides (`cargo run --release -p oracle --example
//! optimality_gap` prints how close to the optimum that comes).
//!
//! Each rule's choice depends only on the state (for a given placement and order), and a
//! stretch, cut after any of its actions, is finished by the same rule from there: the
//! held block keeps the priority, and the nearest free cell off the stack stays the
//! nearest as the block walks towards it. So the plan from the state after the
//! first action is the rest of this plan or a shorter one, and following
//! [`Oracle::next_action`] from any state reaches the goal in at most `plan(..).len()`
//! steps, wherever control is handed over.
//!
//! # Under the `paper` action protocol
//!
//! [`Oracle::with_protocol`] makes its plans legal under a protocol: each rollout is made
//! legal ([`legalize`]: under `paper` a Drop goes before each Pick taken while a block is
//! held), and the shortest *legal* plan is kept. Rollouts never move with nothing held or
//! pick the block they hold, so that is the only change; the tests replay the plans in an
//! environment that refuses illegal actions.
//!
//! If the policy is stuck at every placement (it never is with 2 or 3 blocks on 7 x 7,
//! which the tests check exhaustively), the oracle falls back on the exact solver with a
//! small budget, and reports [`OracleError::OracleStuck`] if that runs out too.

use sim::{Action, ActionProtocol, BlockId, Goal, Grid, GridWorld, State, World};

use crate::error::{OracleError, Result};
use crate::exact::ExactSolver;
use crate::placement::{Placement, check_problem};
use crate::plan::{Plan, Planner, legalize};
use crate::route;

/// The budget of the exact search the oracle falls back on when its routing is stuck.
pub const FALLBACK_NODE_BUDGET: usize = 200_000;

/// The centroid + A* planner (module docs: the rules, the placement, and why it is sound).
///
/// ```
/// use oracle::Oracle;
/// use sim::{Action, Cell, Goal, Grid, State};
///
/// let oracle = Oracle::new(Grid::default());
/// let state = State::new(&[Cell::new(0, 0), Cell::new(3, 0)], None)?;
/// let goal: Goal = "1,0".parse()?;
/// let plan = oracle.plan(&state, &goal)?;
/// assert_eq!(plan.len(), 5);
/// assert_eq!(oracle.next_action(&state, &goal)?, plan.actions[0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Oracle {
    grid: Grid,
    fallback: ExactSolver,
    protocol: ActionProtocol,
}

impl Oracle {
    /// An oracle planning on `grid`.
    pub fn new(grid: Grid) -> Self {
        Self {
            grid,
            fallback: ExactSolver::new(grid).with_node_budget(FALLBACK_NODE_BUDGET),
            protocol: ActionProtocol::Free,
        }
    }

    /// This oracle with plans legal under `protocol` (module docs).
    pub fn with_protocol(self, protocol: ActionProtocol) -> Self {
        Self {
            fallback: self.fallback.with_protocol(protocol),
            protocol,
            ..self
        }
    }

    /// The action protocol its plans obey.
    pub fn protocol(&self) -> ActionProtocol {
        self.protocol
    }

    /// The grid it plans on.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The first action of [`Oracle::plan`]; an error if the goal holds already.
    pub fn next_action(&self, state: &State, goal: &Goal) -> Result<Action> {
        Planner::next_action(self, state, goal)
    }

    /// A plan from `state`, which may hold a block, to `goal` (empty if the goal holds).
    pub fn plan(&self, state: &State, goal: &Goal) -> Result<Plan> {
        check_problem(self.grid, state, goal)?;
        if goal.holds(state) {
            return Ok(Plan::default());
        }
        match self.routed_plan(state, goal)? {
            Some(plan) => Ok(plan),
            None => self.fallback.solve(state, goal).map_err(|e| match e {
                OracleError::BudgetExceeded { .. } => OracleError::OracleStuck {
                    goal: goal.to_string(),
                    blocks: goal.block_count(),
                    grid: self.grid.to_string(),
                },
                other => other,
            }),
        }
    }

    /// The shortest routing-policy plan over every placement and block order, `None` if the
    /// policy is stuck at all of them; `state` and `goal` have been checked.
    fn routed_plan(&self, state: &State, goal: &Goal) -> Result<Option<Plan>> {
        let world = GridWorld::new(self.grid, *state)?;
        let mut placements: Vec<(u32, u64, Placement)> = Placement::all(self.grid, goal.block_count())
            .map(|p| (p.lower_bound(state, goal), p.centroid_distance(state, goal), p))
            .collect();
        placements.sort_unstable_by_key(|&(bound, centroid, p)| (bound, centroid, p.bottom, p.column));
        let mut best: Option<Vec<Action>> = None;
        for (bound, _, placement) in placements {
            for order in Order::ALL {
                if best.as_ref().is_some_and(|b| bound as usize >= b.len()) {
                    break;
                }
                if let Some(actions) = rollout(world, goal, placement, order) {
                    let actions = legalize(&actions, state.held_block(), self.protocol);
                    if best.as_ref().is_none_or(|b| actions.len() < b.len()) {
                        best = Some(actions);
                    }
                }
            }
        }
        Ok(best.map(|actions| Plan { actions }))
    }
}

impl Planner for Oracle {
    fn name(&self) -> &'static str {
        "oracle"
    }

    fn plan(&self, state: &State, goal: &Goal) -> Result<Plan> {
        Oracle::plan(self, state, goal)
    }

    fn protocol(&self) -> ActionProtocol {
        self.protocol
    }

    fn with_protocol(self, protocol: ActionProtocol) -> Self {
        Oracle::with_protocol(self, protocol)
    }
}

/// Which block rule 3 of the routing policy places first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Order {
    /// The one with the shortest route (then the lowest in the goal).
    Nearest,
    /// The lowest in the goal.
    BottomUp,
    /// The highest in the goal.
    TopDown,
}

impl Order {
    /// Every order, in the order the oracle tries them.
    const ALL: [Order; 3] = [Order::Nearest, Order::BottomUp, Order::TopDown];
}

/// The routing policy's actions from `world` to the goal at `placement`, placing blocks in
/// `order`, or `None` if it gets stuck.
fn rollout(mut world: GridWorld, goal: &Goal, placement: Placement, order: Order) -> Option<Vec<Action>> {
    let mut actions = Vec::new();
    while !goal.holds(world.state_ref()) {
        let stretch = next_stretch(&world, goal, placement, order)?;
        for &a in &stretch {
            world.act(a).expect("planned actions name existing blocks");
        }
        actions.extend(stretch);
    }
    Some(actions)
}

/// The next stretch of actions of the routing policy (module docs), or `None` if stuck.
fn next_stretch(world: &GridWorld, goal: &Goal, placement: Placement, order: Order) -> Option<Vec<Action>> {
    let state = world.state_ref();
    let target = |b: BlockId| placement.target(goal, b);
    let unplaced = |b: &BlockId| state.cell(*b) != target(*b);
    let off_stack = |c| !placement.contains(goal, c);
    let in_stack = |b: &BlockId| placement.contains(goal, state.cell(*b));
    // Rules 1 and 2: go on with the held block.
    if let Some(h) = state.held_block().filter(unplaced) {
        if let Some(path) = route::route(world, h, target(h)) {
            return Some(path);
        }
        if in_stack(&h)
            && let Some(path) = route::to_nearest(world, h, off_stack)
        {
            return Some(path);
        }
    }
    // Rule 3: place a block that can reach its target, chosen as `order` says.
    let mut candidates: Vec<BlockId> = state
        .blocks()
        .filter(unplaced)
        .filter(|&b| !world.is_occupied(target(b)))
        .collect();
    let mut best: Option<(BlockId, Vec<Action>)> = None;
    match order {
        Order::Nearest => {
            // A block's Manhattan distance bounds its route from below, so blocks farther
            // than the best route so far are not routed.
            candidates.sort_by_key(|&b| (state.cell(b).manhattan(target(b)), goal.place_of(b)));
            for b in candidates {
                if best
                    .as_ref()
                    .is_some_and(|(_, path)| state.cell(b).manhattan(target(b)) as usize > path.len())
                {
                    break;
                }
                if let Some(path) = route::route(world, b, target(b)) {
                    let better = best
                        .as_ref()
                        .is_none_or(|(c, p)| (path.len(), goal.place_of(b)) < (p.len(), goal.place_of(*c)));
                    if better {
                        best = Some((b, path));
                    }
                }
            }
        }
        Order::BottomUp | Order::TopDown => {
            candidates.sort_by_key(|&b| goal.place_of(b));
            if order == Order::TopDown {
                candidates.reverse();
            }
            best = candidates
                .into_iter()
                .find_map(|b| route::route(world, b, target(b)).map(|path| (b, path)));
        }
    }
    // Rule 4: take a wrong block off the stack's cells.
    if best.is_none() {
        best = state
            .blocks()
            .filter(|b| unplaced(b) && in_stack(b))
            .filter_map(|b| route::to_nearest(world, b, off_stack).map(|path| (b, path)))
            .min_by_key(|(b, path)| (path.len(), goal.place_of(*b)));
    }
    best.map(|(b, path)| {
        let mut stretch = Vec::with_capacity(path.len() + 1);
        if state.held_block() != Some(b) {
            stretch.push(Action::Pick(b));
        }
        stretch.extend(path);
        stretch
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;
    use sim::Cell;

    /// Every placement of `blocks` blocks on `grid`, nothing held.
    fn placements(grid: Grid, blocks: usize) -> Vec<State> {
        let cells: Vec<Cell> = grid.cells().collect();
        let mut out = Vec::new();
        let mut pick = vec![0usize; blocks];
        'next: loop {
            let chosen: Vec<Cell> = pick.iter().map(|&i| cells[i]).collect();
            if let Ok(s) = State::new(&chosen, None) {
                out.push(s);
            }
            for k in (0..blocks).rev() {
                pick[k] += 1;
                if pick[k] < cells.len() {
                    continue 'next;
                }
                pick[k] = 0;
            }
            return out;
        }
    }

    #[test]
    fn routing_alone_plans_every_two_and_three_block_start_on_7x7() {
        // The fallback on the exact solver is never needed here (the module docs say so).
        let grid = Grid::default();
        let oracle = Oracle::new(grid);
        for blocks in [2, 3] {
            let starts = placements(grid, blocks);
            for goal in Goal::all(blocks).unwrap() {
                let stuck = starts
                    .par_iter()
                    .flat_map_iter(|s| (0..=blocks).map(move |h| (s, h)))
                    .filter(|&(s, h)| {
                        let held = (h < blocks).then_some(BlockId(h as u8));
                        let s = s.with_held(held).unwrap();
                        !goal.holds(&s) && oracle.routed_plan(&s, &goal).unwrap().is_none()
                    })
                    .count();
                assert_eq!(stuck, 0, "{blocks} blocks, goal {goal}");
            }
        }
    }
}
