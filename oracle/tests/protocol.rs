//! The planners under the `paper` action protocol: the exact solver's plans are the
//! shortest legal ones (against a breadth-first search over legal actions), and every plan
//! of either planner replays in an environment that refuses illegal actions.

use crate::common::{BfsTable, all_placements, all_states};
use oracle::{ExactSolver, Oracle, Planner};
use rand::RngExt;
use rayon::prelude::*;
use sim::seeding::rng;
use sim::{ActionProtocol, Backend, Env, EnvConfig, Goal, Grid, GridWorld, State, World};

const PAPER: ActionProtocol = ActionProtocol::Paper;

/// Replays `plan` from `start` in a grid environment under the `paper` protocol (which
/// refuses an illegal action) and returns whether the goal holds at its end.
fn replays_legally(grid: Grid, start: &State, goal: &Goal, plan: &oracle::Plan) -> Result<bool, String> {
    let mut env = Env::new(EnvConfig {
        grid,
        backend: Backend::Grid,
        protocol: PAPER,
        horizon: 10_000,
        ..EnvConfig::with_goal(goal.clone())
    })
    .unwrap();
    env.reset_to(start.clone(), goal.clone()).unwrap();
    for &a in &plan.actions {
        env.step(a)
            .map_err(|e| format!("{start:?} goal {goal}: plan {plan}: {e}"))?;
    }
    Ok(goal.holds(&env.state()))
}

#[test]
fn exact_paper_plans_are_the_shortest_legal_ones_for_every_two_block_state() {
    let grid = Grid::default();
    let solver = ExactSolver::new(grid).with_protocol(PAPER);
    assert_eq!(solver.protocol(), PAPER);
    for goal in Goal::all(2).unwrap() {
        let table = BfsTable::under(grid, &goal, PAPER);
        let free = BfsTable::new(grid, &goal);
        for s in all_states(grid, 2) {
            let plan = solver.solve(&s, &goal).unwrap();
            assert_eq!(Some(plan.len() as u32), table.distance(&s), "{s:?} goal {goal}");
            assert!(replays_legally(grid, &s, &goal, &plan).unwrap(), "{s:?} goal {goal}");
            assert!(table.distance(&s) >= free.distance(&s));
        }
    }
}

#[test]
fn exact_paper_plans_are_the_shortest_legal_ones_for_every_three_block_state_on_4x4() {
    let grid = Grid::new(4, 4).unwrap();
    let solver = ExactSolver::new(grid).with_protocol(PAPER);
    let goal: Goal = "2,0,1".parse().unwrap();
    let table = BfsTable::under(grid, &goal, PAPER);
    let states = all_states(grid, 3);
    let wrong: Vec<String> = states
        .par_iter()
        .filter_map(|s| {
            let plan = solver.solve(s, &goal).unwrap();
            (Some(plan.len() as u32) != table.distance(s) || !replays_legally(grid, s, &goal, &plan).unwrap())
                .then(|| format!("{s:?}: {plan}"))
        })
        .collect();
    assert!(wrong.is_empty(), "{} wrong, first {}", wrong.len(), wrong[0]);
}

#[test]
fn exact_paper_plans_match_breadth_first_search_on_random_three_block_states() {
    let grid = Grid::default();
    let goal: Goal = "1,0,2".parse().unwrap();
    let table = BfsTable::under(grid, &goal, PAPER);
    let solver = ExactSolver::new(grid).with_protocol(PAPER);
    let states = all_states(grid, 3);
    let mut r = rng(31);
    let mut longer = 0;
    for _ in 0..300 {
        let s = states[r.random_range(0..states.len())].clone();
        let plan = solver.solve(&s, &goal).unwrap();
        assert_eq!(Some(plan.len() as u32), table.distance(&s), "{s:?}");
        assert!(replays_legally(grid, &s, &goal, &plan).unwrap(), "{s:?}");
        longer += usize::from(plan.len() > ExactSolver::new(grid).solve(&s, &goal).unwrap().len());
    }
    assert!(longer > 0, "changing blocks costs a Drop under paper");
}

#[test]
fn oracle_paper_plans_replay_legally_from_every_two_block_state() {
    let grid = Grid::default();
    let oracle = Oracle::new(grid).with_protocol(PAPER);
    let exact = ExactSolver::new(grid).with_protocol(PAPER);
    for goal in Goal::all(2).unwrap() {
        for s in all_states(grid, 2) {
            let plan = oracle.plan(&s, &goal).unwrap();
            assert!(replays_legally(grid, &s, &goal, &plan).unwrap(), "{s:?} goal {goal}");
            assert!(plan.len() >= exact.solve(&s, &goal).unwrap().len());
        }
    }
}

#[test]
fn oracle_paper_plans_replay_legally_from_three_block_starts() {
    let grid = Grid::default();
    let oracle = Oracle::new(grid).with_protocol(PAPER);
    let placements = all_placements(grid, 3);
    for goal in Goal::all(3).unwrap() {
        let failures: Vec<String> = placements
            .par_iter()
            .step_by(7)
            .flat_map_iter(|s| (0..4).map(move |h| s.with_held((h < 3).then_some(sim::BlockId::of(h))).unwrap()))
            .filter_map(|s| {
                let plan = oracle.plan(&s, &goal).map_err(|e| e.to_string()).ok()?;
                match replays_legally(grid, &s, &goal, &plan) {
                    Ok(true) => None,
                    Ok(false) => Some(format!("{s:?}: {plan} misses the goal")),
                    Err(e) => Some(e),
                }
            })
            .collect();
        assert!(
            failures.is_empty(),
            "{} failures, first {}",
            failures.len(),
            failures[0]
        );
    }
}

#[test]
fn following_the_paper_oracle_step_by_step_reaches_the_goal_within_its_plan() {
    let grid = Grid::default();
    let oracle = Oracle::new(grid).with_protocol(PAPER);
    let mut r = rng(13);
    let states = all_states(grid, 3);
    for _ in 0..2000 {
        let goal = Goal::random(3, &mut r).unwrap();
        let start = states[r.random_range(0..states.len())].clone();
        if goal.holds(&start) {
            continue;
        }
        let planned = oracle.plan(&start, &goal).unwrap().len();
        let mut world = GridWorld::new(grid, start.clone()).unwrap();
        let mut steps = 0;
        while !goal.holds(world.state_ref()) {
            let a = oracle.next_action(world.state_ref(), &goal).unwrap();
            PAPER.check(world.state_ref(), a).unwrap();
            world.act(a).unwrap();
            steps += 1;
            assert!(
                steps <= planned,
                "{start:?} goal {goal}: more than the planned {planned} steps"
            );
        }
    }
}

#[test]
fn planners_take_a_protocol_through_the_trait() {
    fn under<P: Planner>(p: P) -> ActionProtocol {
        p.with_protocol(PAPER).protocol()
    }
    let grid = Grid::default();
    assert_eq!(under(Oracle::new(grid)), PAPER);
    assert_eq!(under(ExactSolver::new(grid)), PAPER);
    assert_eq!(Oracle::new(grid).protocol(), ActionProtocol::Free);
}
