//! The relational policy's speed (`dqn --preset general`): one choice of a block move (the
//! relations read, one forward pass, the best legal move) at 50 and 500 blocks, and a whole
//! greedy game of 500 blocks.
//!
//! `cargo bench -p neural --bench relational`. The network is the preset's shape with seeded
//! weights (a pass costs the same whatever the weights); each figure is the mean over 20
//! seeded problems taken in turn: a uniformly random start and a uniformly random goal naming
//! every block. A game is played to the goal or the move limit with the weights of a short
//! training run, so that it ends as a trained policy's games do.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use neural::relational::{MovePolicy, RelationalConfig, RelationalModel, RelationalNet};
use oracle::towers::{Table, TowerGoal, Towers, random_state};

/// Problems per size.
const PROBLEMS: u64 = 20;

fn problems(blocks: usize) -> Vec<(Towers, TowerGoal)> {
    (0..PROBLEMS)
        .map(|seed| {
            let goal = TowerGoal::new(&random_state(blocks, seed ^ 0xfeed).towers()).unwrap();
            (random_state(blocks, seed), goal)
        })
        .collect()
}

fn forward_pass(c: &mut Criterion) {
    let net = RelationalNet::new(RelationalConfig::general().shape, &mut sim::seeding::rng(1)).unwrap();
    let mut policy = MovePolicy::new(&net);
    let mut group = c.benchmark_group("relational_choice");
    group.measurement_time(Duration::from_secs(10));
    for blocks in [50, 500] {
        let problems = problems(blocks);
        let mut i = 0;
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                i = (i + 1) % problems.len();
                let (state, goal) = &problems[i];
                black_box(policy.choose(state, goal, Table::Unbounded))
            })
        });
    }
}

fn game(c: &mut Criterion) {
    let config = RelationalConfig {
        iterations: 3,
        steps: 1_000,
        rollouts: 300,
        problems: 10_000,
        ..RelationalConfig::general()
    };
    let model = RelationalModel::train(&config, &mut |_| {}).unwrap();
    let problems = problems(500);
    let mut group = c.benchmark_group("relational_game");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    let mut i = 0;
    group.bench_function(BenchmarkId::from_parameter(500), |b| {
        b.iter(|| {
            i = (i + 1) % problems.len();
            let (state, goal) = &problems[i];
            black_box(model.play(state, goal).unwrap())
        })
    });
}

criterion_group!(benches, forward_pass, game);
criterion_main!(benches);
