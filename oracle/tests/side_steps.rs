//! The exact solver in the side view (fewest gripper steps to a goal of towers) against an
//! independent breadth-first search over every action of the rules from every state of
//! small worlds; its plans replayed through the Env on both backends; and its optimum
//! between 3 x the fewest block moves and the exact block-move plan carried out by the
//! gripper.

use std::collections::{HashMap, VecDeque};

use crate::common::all_states;
use oracle::towers::{MovePlanner, gripper_actions, plan_side};
use oracle::{ExactSolver, OracleError};
use sim::{Action, Backend, Env, EnvConfig, Goal, Grid, GridWorld, State, View, World};

/// Every side-view state of `blocks` blocks on `grid` (held or not, every block standing).
fn side_states(grid: Grid, blocks: usize) -> Vec<State> {
    all_states(grid, blocks)
        .into_iter()
        .filter(|s| View::Side.check_state(s).is_ok())
        .collect()
}

/// The fewest steps from `start` to every state it reaches, by breadth-first search over
/// every action (no-ops included) through `World::act` in the side view.
fn distances_from(grid: Grid, start: State) -> HashMap<State, u32> {
    let n = start.block_count();
    let mut dist = HashMap::from([(start.clone(), 0)]);
    let mut queue = VecDeque::from([start]);
    while let Some(s) = queue.pop_front() {
        let d = dist[&s];
        let world = GridWorld::new_in(View::Side, grid, s).unwrap();
        for a in Action::all(n) {
            let mut w = world.clone();
            w.act(a).unwrap();
            dist.entry(w.state_ref().clone()).or_insert_with(|| {
                queue.push_back(w.state_ref().clone());
                d + 1
            });
        }
    }
    dist
}

/// The state `actions` lead to from `start` in the side view of the grid model.
fn replay_side(grid: Grid, start: &State, actions: &[Action]) -> State {
    let mut world = GridWorld::new_in(View::Side, grid, start.clone()).unwrap();
    for &a in actions {
        world.act(a).unwrap();
    }
    world.state_ref().clone()
}

#[test]
fn side_distances_equal_breadth_first_search_on_small_worlds() {
    let goal_sets: Vec<(usize, Vec<Goal>)> = (2..=3).map(|n| (n, Goal::all_towers(n).unwrap())).collect();
    assert_eq!(
        goal_sets[1].1.len(),
        13,
        "3 blocks: 6 one-tower, 6 two-tower, 1 three-tower goals"
    );
    let mut checked = (0, 0);
    for grid in [
        Grid::new(2, 3).unwrap(),
        Grid::new(3, 3).unwrap(),
        Grid::new(4, 3).unwrap(),
    ] {
        for (n, goals) in &goal_sets {
            let solver = ExactSolver::new(grid).with_view(View::Side);
            for start in side_states(grid, *n) {
                let dist = distances_from(grid, start.clone());
                for goal in goals {
                    let best = dist
                        .iter()
                        .filter(|(s, _)| goal.holds_in(View::Side, s))
                        .map(|(_, &d)| d)
                        .min();
                    match (solver.solve(&start, goal), best) {
                        (Ok(plan), Some(d)) => {
                            assert_eq!(plan.len() as u32, d, "{grid} {start:?} goal {goal}");
                            let end = replay_side(grid, &start, &plan.actions);
                            assert!(goal.holds_in(View::Side, &end), "{grid} {start:?} goal {goal}");
                            let bound = solver.lower_bound(&start, goal).unwrap();
                            assert!(bound <= d, "{grid} {start:?} goal {goal}: bound {bound} > {d}");
                            checked.0 += 1;
                        }
                        (Err(OracleError::GoalUnreachable { .. }), None) => checked.1 += 1,
                        // More towers than columns: refused before searching.
                        (Err(OracleError::GoalUnreachable { .. }), _) if goal.tower_count() > grid.width() => {}
                        (got, want) => panic!("{grid} {start:?} goal {goal}: {got:?}, breadth-first {want:?}"),
                    }
                }
            }
        }
    }
    // Both outcomes are exercised: on 2 x 3 three blocks often cannot be rearranged.
    assert!(checked.0 > 10_000 && checked.1 > 0, "{checked:?}");
}

#[test]
fn side_heuristic_is_consistent_on_every_state_of_a_small_world() {
    let grid = Grid::new(4, 3).unwrap();
    for goal in Goal::all_towers(3).unwrap() {
        let solver = ExactSolver::new(grid).with_view(View::Side);
        for s in side_states(grid, 3) {
            let h = solver.lower_bound(&s, &goal).unwrap();
            assert_eq!(h == 0, goal.holds_in(View::Side, &s), "{s:?} goal {goal}");
            let world = GridWorld::new_in(View::Side, grid, s.clone()).unwrap();
            for a in Action::all(3) {
                let mut w = world.clone();
                w.act(a).unwrap();
                let next = solver.lower_bound(w.state_ref(), &goal).unwrap();
                assert!(h <= next + 1, "{s:?} goal {goal}: {a} takes h from {h} to {next}");
            }
        }
    }
}

/// Seeded side-view starts of `blocks` blocks on 7 x 7 with a goal of 1-3 towers naming
/// every block, or fewer.
fn random_problems(blocks: usize, count: u64) -> Vec<(State, Goal)> {
    let goals = ["0,1,2,3", "3,1/0,2", "2/1,0/3", "1,3/", "0,1,2", "2,0/1", "1/0,2"];
    let mut out = Vec::new();
    for seed in 0..count {
        let text = goals[(seed as usize) % goals.len()];
        let Ok(goal) = Goal::parse(text, Some(blocks)) else {
            continue;
        };
        let mut env = Env::new(EnvConfig {
            view: View::Side,
            blocks,
            ..EnvConfig::with_goal(goal.clone())
        })
        .unwrap();
        out.push((env.reset(seed).state, goal));
    }
    out
}

#[test]
fn side_plans_replay_through_the_env_on_both_backends() {
    let grid = Grid::default();
    let solver = ExactSolver::new(grid).with_view(View::Side);
    for blocks in [3, 4] {
        for (start, goal) in random_problems(blocks, 12) {
            let plan = solver.solve(&start, &goal).unwrap();
            for backend in [Backend::Grid, Backend::Physics] {
                let mut env = Env::new(EnvConfig {
                    view: View::Side,
                    backend,
                    blocks,
                    ..EnvConfig::with_goal(goal.clone())
                })
                .unwrap();
                env.reset_to(start.clone(), goal.clone()).unwrap();
                let mut last = None;
                for &a in &plan.actions {
                    assert!(last.is_none_or(|s: sim::Step| !s.terminated), "{goal}: ended early");
                    last = Some(env.step(a).unwrap());
                }
                assert!(last.is_some_and(|s| s.terminated), "{backend:?} {start:?} goal {goal}");
                assert!(goal.holds_in(View::Side, &env.state()));
            }
        }
    }
}

#[test]
fn side_steps_lie_between_three_times_the_fewest_moves_and_the_expanded_exact_plan() {
    let mut compared = 0;
    let mut problems: Vec<(Grid, State, Goal)> = Vec::new();
    let small = Grid::new(4, 3).unwrap();
    for goal in Goal::all_towers(3).unwrap() {
        for s in side_states(small, 3).into_iter().filter(|s| s.held_block().is_none()) {
            problems.push((small, s, goal.clone()));
        }
    }
    for blocks in [3, 4] {
        for (s, goal) in random_problems(blocks, 14) {
            problems.push((Grid::default(), s, goal));
        }
    }
    for (grid, start, goal) in problems {
        let steps = ExactSolver::new(grid)
            .with_view(View::Side)
            .distance(&start, &goal)
            .unwrap() as usize;
        let Ok(moves) = plan_side(MovePlanner::Exact, grid, &start, &goal) else {
            continue;
        };
        assert!(
            steps >= 3 * moves.len(),
            "{grid} {start:?} goal {goal}: {steps} steps, {} moves",
            moves.len()
        );
        if let Ok(expanded) = gripper_actions(grid, &start, &moves) {
            assert!(steps <= expanded.len(), "{grid} {start:?} goal {goal}");
            assert!(goal.holds_in(View::Side, &replay_side(grid, &start, &expanded)));
            compared += 1;
        }
    }
    assert!(compared > 500, "{compared}");
}

#[test]
fn side_bad_input_is_an_error() {
    let grid = Grid::default();
    let solver = ExactSolver::new(grid).with_view(View::Side);
    let floating = State::new(&[sim::Cell::new(0, 0), sim::Cell::new(2, 3)], None).unwrap();
    let goal: Goal = "0,1".parse().unwrap();
    assert!(matches!(solver.solve(&floating, &goal), Err(OracleError::Sim(_))));
    let narrow = ExactSolver::new(Grid::new(2, 3).unwrap()).with_view(View::Side);
    let start = State::new(
        &[sim::Cell::new(0, 0), sim::Cell::new(0, 1), sim::Cell::new(1, 0)],
        None,
    )
    .unwrap();
    let three = Goal::parse("0/1/2", Some(3)).unwrap();
    let err = narrow.solve(&start, &three).unwrap_err();
    assert!(matches!(err, OracleError::GoalUnreachable { .. }), "{err}");
    let tiny = solver.with_node_budget(3);
    let (start, goal) = random_problems(4, 1)[0].clone();
    assert!(matches!(
        tiny.solve(&start, &goal),
        Err(OracleError::BudgetExceeded { .. })
    ));
}
