//! Planning speed: the oracle's `plan` and `next_action` for 3 blocks (7 x 7) and 8 blocks
//! (8 x 8, the smallest square grid an 8-block stack fits), and the exact solver for 2, 3
//! and 4 blocks on 7 x 7.
//!
//! `cargo bench --bench oracle`. Each `.../N` figure is the mean time per call over 100
//! seeded starts (`Env::reset` with the episode seeds of base seed 0), taken in turn; the
//! `exact_solve_median_start/N` figures time the one start whose search expands the median
//! number of states among them, so they are the median start's solve time.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use oracle::gap::seeded_starts;
use oracle::{ExactSolver, Oracle};
use sim::{Goal, Grid, State};

const STARTS: u64 = 100;

/// A fixed goal of `blocks` blocks that is not the identity, and its seeded starts.
fn problem(grid: Grid, blocks: usize) -> (Goal, Vec<State>) {
    let order: Vec<usize> = (0..blocks).map(|i| (i * 2 + 1) % blocks).collect();
    let goal = Goal::from_indices(&order).unwrap_or_else(|_| Goal::identity(blocks).unwrap());
    (goal.clone(), seeded_starts(grid, &goal, STARTS, 0).unwrap())
}

fn oracle(c: &mut Criterion) {
    for (blocks, grid) in [(3, Grid::default()), (8, Grid::new(8, 8).unwrap())] {
        let oracle = Oracle::new(grid);
        let (goal, starts) = problem(grid, blocks);
        let mut i = 0;
        c.benchmark_group("oracle_plan")
            .bench_function(BenchmarkId::from_parameter(blocks), |b| {
                b.iter(|| {
                    i = (i + 1) % starts.len();
                    black_box(oracle.plan(&starts[i], &goal).unwrap())
                })
            });
        c.benchmark_group("oracle_next_action")
            .bench_function(BenchmarkId::from_parameter(blocks), |b| {
                b.iter(|| {
                    i = (i + 1) % starts.len();
                    black_box(oracle.next_action(&starts[i], &goal).unwrap())
                })
            });
    }
}

fn exact(c: &mut Criterion) {
    let grid = Grid::default();
    let solver = ExactSolver::new(grid);
    for blocks in [2, 3, 4] {
        let (goal, starts) = problem(grid, blocks);
        let mut group = c.benchmark_group("exact_solve");
        if blocks == 4 {
            group.sample_size(10).measurement_time(Duration::from_secs(30));
        }
        let mut i = 0;
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                i = (i + 1) % starts.len();
                black_box(solver.solve(&starts[i], &goal).unwrap())
            })
        });
        group.finish();
        if blocks >= 3 {
            let mut by_effort: Vec<(usize, State)> = starts
                .iter()
                .map(|s| (solver.solve_with_stats(s, &goal).unwrap().1.expanded, s.clone()))
                .collect();
            by_effort.sort_by_key(|&(expanded, _)| expanded);
            let median = by_effort[by_effort.len() / 2].1.clone();
            let mut group = c.benchmark_group("exact_solve_median_start");
            if blocks == 4 {
                group.sample_size(20);
            }
            group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
                b.iter(|| black_box(solver.solve(&median, &goal).unwrap()))
            });
            group.finish();
        }
    }
}

criterion_group!(benches, oracle, exact);
criterion_main!(benches);
