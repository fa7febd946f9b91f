//! Block-move planning speed (`oracle::towers`): the near-optimal planner for 100, 1,000
//! and 10,000 blocks, and the exact solver for 8 and 10 blocks.
//!
//! `cargo bench -p oracle --bench towers`. Each figure is the mean time per plan over 20
//! seeded random problems taken in turn: in `towers_near_optimal` and `towers_exact`, a
//! uniformly random start and a random goal naming every block in one to three towers; in
//! `towers_near_optimal_ipc`, a start and a goal of the 2023 planning competition's shape
//! (`ipc_state`: about one tower per ten blocks), as its test tasks are.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use oracle::towers::{ExactMoves, NearOptimal, TowerGoal, Towers, ipc_state, random_goal, random_state};

/// Problems per size.
const PROBLEMS: u64 = 20;

/// The seeded problems of `blocks` blocks.
fn problems(blocks: usize) -> Vec<(Towers, TowerGoal)> {
    (0..PROBLEMS)
        .map(|seed| {
            let goal = random_goal(blocks, 1 + seed as usize % 3, blocks, seed ^ 0xfeed).unwrap();
            (random_state(blocks, seed), goal)
        })
        .collect()
}

fn near_optimal(c: &mut Criterion) {
    let planner = NearOptimal::new();
    let mut group = c.benchmark_group("towers_near_optimal");
    group.measurement_time(Duration::from_secs(10));
    for blocks in [100, 1_000, 10_000] {
        let problems = problems(blocks);
        let mut i = 0;
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                i = (i + 1) % problems.len();
                let (start, goal) = &problems[i];
                black_box(planner.plan(start, goal).unwrap())
            })
        });
    }
}

/// The seeded problems of `blocks` blocks in the competition's shape.
fn ipc_problems(blocks: usize) -> Vec<(Towers, TowerGoal)> {
    (0..PROBLEMS)
        .map(|seed| {
            let goal = TowerGoal::new(&ipc_state(blocks, seed ^ 0xfeed).towers()).unwrap();
            (ipc_state(blocks, seed), goal)
        })
        .collect()
}

fn near_optimal_ipc(c: &mut Criterion) {
    let planner = NearOptimal::new();
    let mut group = c.benchmark_group("towers_near_optimal_ipc");
    group.measurement_time(Duration::from_secs(10));
    for blocks in [100, 1_000, 10_000] {
        let problems = ipc_problems(blocks);
        let mut i = 0;
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                i = (i + 1) % problems.len();
                let (start, goal) = &problems[i];
                black_box(planner.plan(start, goal).unwrap())
            })
        });
    }
}

fn exact(c: &mut Criterion) {
    let solver = ExactMoves::new();
    let mut group = c.benchmark_group("towers_exact");
    group.sample_size(20).measurement_time(Duration::from_secs(10));
    for blocks in [8, 10] {
        let problems = problems(blocks);
        let mut i = 0;
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                i = (i + 1) % problems.len();
                let (start, goal) = &problems[i];
                black_box(solver.solve(start, goal).unwrap())
            })
        });
    }
}

criterion_group!(benches, near_optimal, near_optimal_ipc, exact);
criterion_main!(benches);
