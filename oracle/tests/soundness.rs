//! The oracle reaches the goal from every state: exhaustively for 2 and 3 blocks on 7 x 7,
//! on random mid-episode states with a held block, with many blocks, and on small grids
//! against a breadth-first search of every state.

use crate::common::{BfsTable, all_placements, all_states, replay};
use oracle::{ExactSolver, Oracle, OracleError};
use rand::{Rng, RngExt};
use rayon::prelude::*;
use sim::seeding::rng;
use sim::{Action, BlockId, Goal, Grid, GridWorld, State, World};

/// Checks the oracle from `start`: its plan replays to the goal in the grid model, its
/// first action is `next_action`'s, and the plan from the state after that action is at
/// least one action shorter (so following `next_action` always ends at the goal).
fn check_oracle(oracle: &Oracle, start: &State, goal: &Goal) -> Result<usize, String> {
    let grid = oracle.grid();
    let plan = oracle
        .plan(start, goal)
        .map_err(|e| format!("{start:?} goal {goal}: {e}"))?;
    if !goal.holds(&replay(grid, start, &plan.actions)) {
        return Err(format!("{start:?} goal {goal}: plan {plan} does not reach the goal"));
    }
    if let Some(&first) = plan.actions.first() {
        let next = oracle.next_action(start, goal).unwrap();
        if next != first {
            return Err(format!("{start:?}: next_action {next} is not the plan's first {first}"));
        }
        let after = replay(grid, start, &[first]);
        let rest = oracle.plan(&after, goal).unwrap();
        if rest.len() >= plan.len() {
            return Err(format!(
                "{start:?} goal {goal}: after {first} the plan has {} actions, not fewer than {}",
                rest.len(),
                plan.len()
            ));
        }
    }
    Ok(plan.len())
}

#[test]
fn oracle_reaches_the_goal_from_every_two_block_state() {
    let grid = Grid::default();
    let oracle = Oracle::new(grid);
    let states = all_states(grid, 2);
    assert_eq!(states.len(), 49 * 48 * 3);
    for goal in Goal::all(2).unwrap() {
        for s in &states {
            check_oracle(&oracle, s, &goal).unwrap();
        }
    }
}

#[test]
fn oracle_reaches_the_goal_from_every_three_block_placement() {
    let grid = Grid::default();
    let oracle = Oracle::new(grid);
    let placements = all_placements(grid, 3);
    assert_eq!(placements.len(), 110_544);
    for goal in Goal::all(3).unwrap() {
        let failures: Vec<String> = placements
            .par_iter()
            .filter_map(|s| check_oracle(&oracle, s, &goal).err())
            .collect();
        assert!(
            failures.is_empty(),
            "{} failures, first: {}",
            failures.len(),
            failures[0]
        );
    }
}

/// A state reached by `steps` random actions from a random start, with a block held.
fn random_mid_episode(grid: Grid, blocks: usize, steps: usize, rng: &mut impl Rng) -> State {
    let cells: Vec<sim::Cell> = rand_cells(grid, blocks, rng);
    let mut world = GridWorld::new(grid, State::new(&cells, None).unwrap()).unwrap();
    for _ in 0..steps {
        let a = Action::from_index(rng.random_range(0..Action::count(blocks)), blocks).unwrap();
        world.act(a).unwrap();
    }
    let held = BlockId::of(rng.random_range(0..blocks));
    world.state_ref().with_held(Some(held)).unwrap()
}

fn rand_cells(grid: Grid, blocks: usize, rng: &mut impl Rng) -> Vec<sim::Cell> {
    let mut cells = Vec::new();
    while cells.len() < blocks {
        let c = grid.cell_at(rng.random_range(0..grid.cell_count()));
        if !cells.contains(&c) {
            cells.push(c);
        }
    }
    cells
}

#[test]
fn following_next_action_from_mid_episode_states_reaches_the_goal() {
    let grid = Grid::default();
    let oracle = Oracle::new(grid);
    let mut r = rng(11);
    for _ in 0..2000 {
        let goal = Goal::random(3, &mut r).unwrap();
        let start = random_mid_episode(grid, 3, 30, &mut r);
        let planned = oracle.plan(&start, &goal).unwrap().len();
        let mut world = GridWorld::new(grid, start.clone()).unwrap();
        let mut steps = 0;
        while !goal.holds(world.state_ref()) {
            world
                .act(oracle.next_action(world.state_ref(), &goal).unwrap())
                .unwrap();
            steps += 1;
            assert!(
                steps <= planned,
                "{start:?} goal {goal}: more than the planned {planned} steps"
            );
        }
    }
}

#[test]
fn oracle_reaches_the_goal_with_many_blocks() {
    let mut r = rng(12);
    for (grid, blocks) in [
        (Grid::default(), 4),
        (Grid::default(), 5),
        (Grid::default(), 7),
        (Grid::new(8, 8).unwrap(), 8),
    ] {
        let oracle = Oracle::new(grid);
        for _ in 0..300 {
            let goal = Goal::random(blocks, &mut r).unwrap();
            let start = random_mid_episode(grid, blocks, 50, &mut r);
            if !goal.holds(&start) {
                check_oracle(&oracle, &start, &goal).unwrap();
            }
        }
    }
}

#[test]
fn on_small_grids_both_planners_succeed_exactly_where_the_goal_can_be_reached() {
    for (w, h, blocks) in [
        (1, 3, 2),
        (1, 4, 3),
        (2, 2, 2),
        (2, 3, 3),
        (3, 2, 2),
        (3, 3, 3),
        (4, 3, 3),
    ] {
        let grid = Grid::new(w, h).unwrap();
        let (oracle, exact) = (Oracle::new(grid), ExactSolver::new(grid));
        for goal in Goal::all(blocks).unwrap() {
            let table = BfsTable::new(grid, &goal);
            for s in all_states(grid, blocks) {
                let (o, e) = (oracle.plan(&s, &goal), exact.distance(&s, &goal));
                match table.distance(&s) {
                    Some(d) => {
                        assert_eq!(e, Ok(d), "{grid} {s:?} goal {goal}");
                        let plan = o.unwrap_or_else(|err| panic!("{grid} {s:?} goal {goal}: {err}"));
                        assert!(goal.holds(&replay(grid, &s, &plan.actions)));
                        assert!(plan.len() as u32 >= d);
                    }
                    None => {
                        assert!(
                            w == 1,
                            "only one-wide grids have unreachable goals: {grid} {s:?} {goal}"
                        );
                        assert!(matches!(o, Err(OracleError::GoalUnreachable { .. })), "{o:?}");
                        assert!(matches!(e, Err(OracleError::GoalUnreachable { .. })), "{e:?}");
                    }
                }
            }
        }
    }
}
