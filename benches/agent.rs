//! The Q-learner's speed: one table update, and training games per second of our `role`
//! learner against the physics world and the grid world.
//!
//! `cargo bench --bench agent`. `train_games/<backend>/fresh` plays the first 100 games of
//! a new agent (every value optimistic: long, exploring games); `.../trained` plays games
//! of an agent already trained for the recipe's 100,000 games (short games), the regime
//! most of a training run's games are played in. Both include the recipe's backward replay
//! and the writes to the replay memory; the final replay is not timed here.
//!
//! `train_original/<backend>` plays the first 5 games of the paper's learner as its
//! authors coded it (`TrainConfig::original`: `chasing-code` keys in a hashed table, the
//! `paper-code` reward and schedule, games of up to 5000 steps), steps per second.

use std::hint::black_box;

use agent::{QAgent, QParams, ReprKind, TrainConfig, Trainer};
use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use sim::{Action, ActionProtocol, Backend, BlockId, Cell, Grid, Observation, State};

fn q_update(c: &mut Criterion) {
    let grid = Grid::default();
    let goal = "1,0,2".parse().unwrap();
    let params = QParams {
        alpha: 0.5,
        ..QParams::default()
    };
    let mut q = QAgent::new(ReprKind::Role, grid, 3, params).unwrap();
    let obs = |cells: [Cell; 3], held| Observation {
        grid,
        state: State::new(&cells, held).unwrap(),
        goal,
        protocol: ActionProtocol::Free,
        view: sim::View::Top,
    };
    let before = obs.clone()([Cell::new(1, 1), Cell::new(4, 0), Cell::new(6, 6)], Some(BlockId(2)));
    let after = obs([Cell::new(1, 1), Cell::new(4, 0), Cell::new(5, 6)], Some(BlockId(2)));
    c.bench_function("q_update", |b| {
        b.iter(|| {
            black_box(
                q.update(black_box(&before), Action::Left, -1.0, black_box(&after), false)
                    .unwrap(),
            )
        })
    });
}

fn train_games(c: &mut Criterion) {
    let mut group = c.benchmark_group("train_games");
    let config = |backend| TrainConfig::role_step_cost(vec!["0,1,2".parse().unwrap()]).with_backend(backend);
    for backend in [Backend::Physics, Backend::Grid] {
        let fresh_games = 100;
        group.throughput(Throughput::Elements(fresh_games));
        group.sample_size(10);
        group.bench_function(BenchmarkId::new(backend.to_string(), "fresh"), |b| {
            b.iter_batched(
                || Trainer::new(config(backend)).unwrap(),
                |mut trainer| {
                    trainer.play_games(fresh_games, None).unwrap();
                    trainer
                },
                BatchSize::PerIteration,
            )
        });
        let mut trainer = Trainer::new(config(backend)).unwrap();
        trainer.play_games(100_000, None).unwrap();
        let games = 1000;
        group.throughput(Throughput::Elements(games));
        group.sample_size(20);
        group.bench_function(BenchmarkId::new(backend.to_string(), "trained"), |b| {
            b.iter(|| trainer.play_games(games, None).unwrap())
        });
    }
    group.finish();
}

fn train_original(c: &mut Criterion) {
    let mut group = c.benchmark_group("train_original");
    let goals = sim::Goal::all(3).unwrap();
    for backend in [Backend::Physics, Backend::Grid] {
        let config = TrainConfig::original(goals.clone()).with_backend(backend);
        // The steps the first 5 games take, the same in every iteration (seeded).
        let mut probe = Trainer::new(config.clone()).unwrap();
        probe.play_games(5, None).unwrap();
        group.throughput(Throughput::Elements(probe.report().steps));
        group.sample_size(10);
        group.bench_function(BenchmarkId::from_parameter(backend), |b| {
            b.iter_batched(
                || Trainer::new(config.clone()).unwrap(),
                |mut trainer| {
                    trainer.play_games(5, None).unwrap();
                    trainer
                },
                BatchSize::PerIteration,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, q_update, train_games, train_original);
criterion_main!(benches);
