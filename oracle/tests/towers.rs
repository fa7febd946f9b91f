//! The block-move planners of `oracle::towers` against an independent breadth-first
//! search over every state of small worlds, on random problems, and on bad input.

use std::collections::{HashMap, VecDeque};

use oracle::OracleError;
use oracle::towers::{
    ExactMoves, Move, NearOptimal, Part, Place, Table, TowerGoal, TowerPlan, Towers, TowersError, random_goal,
    random_state,
};
use proptest::prelude::*;

/// Every state of `n` blocks reachable on `table` from all blocks on the table, with the
/// distance from each to the nearest state where `goal` holds (`None`: unreachable). The
/// block-move graph is undirected (a move is undone by moving the block back), so a
/// breadth-first search from the goal states gives the distances to them.
fn distances(n: usize, goal: &TowerGoal, table: Table) -> HashMap<Towers, Option<usize>> {
    // All states of n blocks: search from a single tower, from which every state is
    // reachable on any table of at least one column (blocks can be restacked in any order
    // given a second column; with one column only this tower is reachable).
    let seed = Towers::new(&[(0..n).collect()]).unwrap();
    let mut all = vec![seed.clone()];
    let mut seen: HashMap<Towers, Option<usize>> = HashMap::from([(seed, None)]);
    let mut i = 0;
    while i < all.len() {
        for mv in all[i].moves(Table::Unbounded) {
            let mut next = all[i].clone();
            next.apply(mv, Table::Unbounded).unwrap();
            if !seen.contains_key(&next) {
                seen.insert(next.clone(), None);
                all.push(next);
            }
        }
        i += 1;
    }
    let fits = |s: &Towers| match table {
        Table::Unbounded => true,
        Table::Columns(c) => s.tower_count() <= c,
    };
    let mut queue: VecDeque<Towers> = VecDeque::new();
    for s in &all {
        if fits(s) && goal.holds(s) {
            seen.insert(s.clone(), Some(0));
            queue.push_back(s.clone());
        }
    }
    while let Some(s) = queue.pop_front() {
        let d = seen[&s].unwrap();
        for mv in s.moves(table) {
            let mut next = s.clone();
            next.apply(mv, table).unwrap();
            if seen[&next].is_none() {
                seen.insert(next.clone(), Some(d + 1));
                queue.push_back(next);
            }
        }
    }
    seen
}

/// Replays `plan` from `start` on `table` and checks the goal holds at the end.
fn assert_reaches(plan: &TowerPlan, start: &Towers, goal: &TowerGoal, table: Table) {
    let end = plan
        .replay(start, table)
        .unwrap_or_else(|e| panic!("{start} -> {goal}: {plan}: {e}"));
    assert!(goal.holds(&end), "{start} -> {goal}: {plan} ends in {end}");
}

/// Goals for a world of `n` blocks: one, two and three towers, complete and partial.
fn goals(n: usize) -> Vec<TowerGoal> {
    let mut goals = Vec::new();
    let ids: Vec<usize> = (0..n).collect();
    let rev: Vec<usize> = (0..n).rev().collect();
    goals.push(ids.clone());
    goals.push(rev.clone());
    let mut out: Vec<Vec<Vec<usize>>> = goals.into_iter().map(|t| vec![t]).collect();
    out.push(vec![vec![1, 0], vec![3, 2]]);
    out.push(vec![vec![0], vec![2, 1, 3]]);
    out.push(vec![vec![3, 1], vec![0], vec![2]]);
    out.push(vec![vec![2, 0, 3]]);
    out.push(vec![vec![3]]);
    if n >= 5 {
        out.push(vec![vec![4, 0, 2], vec![1, 3]]);
        out.push(vec![vec![1, 4], vec![3, 0], vec![2]]);
        out.push(vec![vec![4, 2, 0, 3, 1]]);
    }
    let mut goals: Vec<TowerGoal> = out.iter().map(|t| TowerGoal::new(t).unwrap()).collect();
    for seed in 0..4 {
        let stacks = 1 + seed as usize % 3;
        goals.push(random_goal(n, stacks, n - seed as usize % 2, seed).unwrap());
    }
    goals
}

#[test]
fn exact_is_optimal_and_near_optimal_within_twice_on_every_start() {
    for n in [4, 5] {
        for goal in goals(n) {
            let dist = distances(n, &goal, Table::Unbounded);
            assert_eq!(dist.len(), if n == 4 { 73 } else { 501 });
            for (start, d) in &dist {
                let d = d.expect("every goal is reachable on an unbounded table");
                let exact = ExactMoves::new().solve(start, &goal).unwrap();
                assert_eq!(exact.len(), d, "{start} -> {goal}: {exact}");
                assert_reaches(&exact, start, &goal, Table::Unbounded);
                let near = NearOptimal::new().plan(start, &goal).unwrap();
                assert!(near.len() <= 2 * d, "{start} -> {goal}: {near} against {d}");
                assert_reaches(&near, start, &goal, Table::Unbounded);
            }
        }
    }
}

#[test]
fn exact_is_optimal_on_a_narrow_table() {
    let mut fitted = 0;
    for (n, columns) in [(4, 1), (4, 2), (5, 2), (5, 3)] {
        let table = Table::Columns(columns);
        for goal in goals(n) {
            let dist = distances(n, &goal, table);
            for (start, d) in dist.iter().filter(|(s, _)| s.tower_count() <= columns) {
                let solved = ExactMoves::new().with_table(table).solve(start, &goal);
                match (d, solved) {
                    (Some(d), Ok(plan)) => {
                        assert_eq!(plan.len(), *d, "{start} -> {goal} on {columns}: {plan}");
                        assert_reaches(&plan, start, &goal, table);
                    }
                    (None, Err(OracleError::Towers(TowersError::Unreachable { .. })))
                    | (None, Err(OracleError::Towers(TowersError::TooManyTowers { part: Part::Goal, .. }))) => {}
                    (d, other) => panic!("{start} -> {goal} on {columns}: distance {d:?}, solver {other:?}"),
                }
                // The near-optimal planner either fits the table, within twice the optimum
                // there, or says it ran out of room.
                match NearOptimal::new().with_table(table).plan(start, &goal) {
                    Ok(plan) => {
                        assert_reaches(&plan, start, &goal, table);
                        assert!(plan.len() <= 2 * d.unwrap(), "{start} -> {goal} on {columns}: {plan}");
                        fitted += 1;
                    }
                    Err(OracleError::Towers(
                        TowersError::TableTooNarrow { .. } | TowersError::TooManyTowers { part: Part::Goal, .. },
                    )) => {}
                    Err(e) => panic!("{start} -> {goal} on {columns}: {e}"),
                }
            }
        }
    }
    // Parking on blocks nothing must stand on lets many plans fit two or three columns.
    assert!(fitted > 1000, "{fitted}");
}

#[test]
fn near_optimal_parks_when_the_table_is_full() {
    // Three columns, all taken: 1 stands on 2, which stands where 1 must go (on 0). 1
    // parks on the free block 5, 2 on 4 (the top of the finished tower 3,4, where nothing
    // must stand), and both come home.
    let start = Towers::new(&[vec![0, 2, 1], vec![3, 4], vec![5]]).unwrap();
    let goal = TowerGoal::new(&[vec![3, 4], vec![0, 1, 2]]).unwrap();
    let table = Table::Columns(3);
    let plan = NearOptimal::new().with_table(table).plan(&start, &goal).unwrap();
    assert_eq!(plan.to_string(), "1->5, 2->4, 1->0, 2->1");
    assert_reaches(&plan, &start, &goal, table);
    assert_eq!(
        plan.len(),
        ExactMoves::new().with_table(table).solve(&start, &goal).unwrap().len()
    );
    // With one column nothing can move aside.
    let one = Towers::new(&[vec![0, 1]]).unwrap();
    let e = NearOptimal::new()
        .with_table(Table::Columns(1))
        .plan(&one, &TowerGoal::new(&[vec![1, 0]]).unwrap());
    assert_eq!(e.unwrap_err(), TowersError::TableTooNarrow { columns: 1 }.into());
}

#[test]
fn a_deadlock_costs_a_second_move() {
    // 2 must leave 1 before 1 can go to the table, and return onto 3 after 3 is on 1.
    let start = Towers::new(&[vec![0, 1, 2], vec![3]]).unwrap();
    let goal = TowerGoal::new(&[vec![1, 3, 2]]).unwrap();
    let plan = ExactMoves::new().solve(&start, &goal).unwrap();
    assert_eq!(plan.len(), 4);
    let near = NearOptimal::new().plan(&start, &goal).unwrap();
    assert_eq!(near.len(), 4, "{near}");
    assert_eq!(
        near.moves[0],
        Move {
            block: 2,
            to: Place::Table
        }
    );
    // A goal that holds already needs no move.
    let done = TowerGoal::new(&[vec![0, 1]]).unwrap();
    assert!(ExactMoves::new().solve(&start, &done).unwrap().is_empty());
    assert!(NearOptimal::new().plan(&start, &done).unwrap().is_empty());
}

#[test]
fn bad_input_is_an_error() {
    let err = |r: Result<Towers, OracleError>| r.unwrap_err();
    assert_eq!(
        err(Towers::new(&[vec![0, 1], vec![]])),
        TowersError::EmptyTower {
            part: Part::State,
            tower: 1
        }
        .into()
    );
    assert_eq!(
        err(Towers::new(&[vec![0, 1], vec![1]])),
        TowersError::DuplicateBlock {
            part: Part::State,
            block: 1
        }
        .into()
    );
    assert_eq!(
        err(Towers::new(&[vec![0, 5]])),
        TowersError::UnknownBlock {
            part: Part::State,
            block: 5,
            blocks: 2
        }
        .into()
    );
    assert_eq!(
        TowerGoal::new(&[vec![0], vec![]]).unwrap_err(),
        TowersError::EmptyTower {
            part: Part::Goal,
            tower: 1
        }
        .into()
    );
    assert_eq!(
        TowerGoal::new(&[vec![0, 2], vec![2]]).unwrap_err(),
        TowersError::DuplicateBlock {
            part: Part::Goal,
            block: 2
        }
        .into()
    );
    let start = Towers::new(&[vec![0, 1], vec![2]]).unwrap();
    let unknown = TowerGoal::new(&[vec![0, 7]]).unwrap();
    let want: OracleError = TowersError::UnknownBlock {
        part: Part::Goal,
        block: 7,
        blocks: 3,
    }
    .into();
    assert_eq!(ExactMoves::new().solve(&start, &unknown).unwrap_err(), want);
    assert_eq!(NearOptimal::new().plan(&start, &unknown).unwrap_err(), want);
    assert!(!unknown.holds(&start));
    // Illegal moves: a covered block, onto itself, onto a covered block, no such block,
    // to the table from the table, to a full table.
    let mut s = start.clone();
    for (mv, table) in [
        (
            Move {
                block: 0,
                to: Place::Table,
            },
            Table::Unbounded,
        ),
        (
            Move {
                block: 1,
                to: Place::On(1),
            },
            Table::Unbounded,
        ),
        (
            Move {
                block: 2,
                to: Place::On(0),
            },
            Table::Unbounded,
        ),
        (
            Move {
                block: 9,
                to: Place::Table,
            },
            Table::Unbounded,
        ),
        (
            Move {
                block: 2,
                to: Place::On(9),
            },
            Table::Unbounded,
        ),
        (
            Move {
                block: 2,
                to: Place::Table,
            },
            Table::Unbounded,
        ),
        (
            Move {
                block: 1,
                to: Place::Table,
            },
            Table::Columns(2),
        ),
    ] {
        let e = s.apply(mv, table).unwrap_err();
        assert!(
            matches!(e, OracleError::Towers(TowersError::IllegalMove { .. })),
            "{mv}: {e}"
        );
        assert!(e.to_string().starts_with(&format!("illegal move {mv}: ")), "{e}");
    }
    assert_eq!(s, start);
    // A state wider than the table, a goal of more towers than it has columns.
    let wide = ExactMoves::new()
        .with_table(Table::Columns(1))
        .solve(&start, &TowerGoal::new(&[vec![0]]).unwrap());
    assert_eq!(
        wide.unwrap_err(),
        TowersError::TooManyTowers {
            part: Part::State,
            towers: 2,
            columns: 1
        }
        .into()
    );
    let too_many = ExactMoves::new().solve(&random_state(30, 1), &TowerGoal::new(&[vec![0]]).unwrap());
    assert_eq!(
        too_many.unwrap_err(),
        TowersError::TooManyBlocks {
            blocks: 30,
            max: ExactMoves::MAX_BLOCKS
        }
        .into()
    );
    assert_eq!(
        random_goal(3, 4, 3, 0).unwrap_err(),
        TowersError::GoalShape {
            stacks: 4,
            named: 3,
            blocks: 3
        }
        .into()
    );
    assert!(random_goal(3, 1, 4, 0).is_err());
    assert!(random_goal(3, 0, 2, 0).is_err());
}

#[test]
fn the_budget_stops_the_search() {
    let start = random_state(12, 3);
    let goal = random_goal(12, 2, 12, 3).unwrap();
    let e = ExactMoves::new().with_budget(100).solve(&start, &goal).unwrap_err();
    assert_eq!(
        e,
        TowersError::BudgetExceeded {
            budget: 100,
            blocks: 12
        }
        .into()
    );
}

#[test]
fn random_states_are_seeded_and_uniform() {
    assert_eq!(random_state(40, 9), random_state(40, 9));
    assert_ne!(random_state(40, 9), random_state(40, 10));
    assert_eq!(random_goal(40, 3, 30, 9).unwrap(), random_goal(40, 3, 30, 9).unwrap());
    // The 13 states of 3 blocks, 13,000 draws: each about 1,000 times.
    let mut counts: HashMap<Towers, usize> = HashMap::new();
    for seed in 0..13_000 {
        *counts.entry(random_state(3, seed)).or_default() += 1;
    }
    assert_eq!(counts.len(), 13);
    for (s, c) in &counts {
        assert!((850..1150).contains(c), "{s}: {c}");
    }
    let goal = random_goal(10, 3, 7, 4).unwrap();
    assert_eq!(goal.towers().len(), 3);
    assert_eq!(goal.towers().iter().map(Vec::len).sum::<usize>(), 7);
}

#[test]
fn near_optimal_scales() {
    for (n, seed) in [(100, 1), (1000, 2), (3000, 3)] {
        let start = random_state(n, seed);
        let goal = random_goal(n, 1 + seed as usize, n, seed).unwrap();
        let plan = NearOptimal::new().plan(&start, &goal).unwrap();
        assert_reaches(&plan, &start, &goal, Table::Unbounded);
        // Never more than two moves per block.
        assert!(plan.len() <= 2 * n, "{n}: {}", plan.len());
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn near_optimal_within_twice_the_exact_optimum(
        n in 6usize..=10, stacks in 1usize..=3, free in 0usize..=2, seed in any::<u64>(),
    ) {
        let start = random_state(n, seed);
        let goal = random_goal(n, stacks, n - free, seed ^ 0x5eed).unwrap();
        let exact = ExactMoves::new().solve(&start, &goal).unwrap();
        let near = NearOptimal::new().plan(&start, &goal).unwrap();
        assert_reaches(&exact, &start, &goal, Table::Unbounded);
        assert_reaches(&near, &start, &goal, Table::Unbounded);
        prop_assert!(exact.len() <= near.len());
        prop_assert!(near.len() <= 2 * exact.len(), "{} -> {}: {} against {}", start, goal, near, exact);
    }
}
