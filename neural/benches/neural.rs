//! The neural learner's speed: one gradient step (batch 64) of each network, one greedy
//! action, and self-play throughput.
//!
//! `cargo bench -p neural`. Run it as the binary runs the networks: `CANDLE_NUM_THREADS=1`
//! (`blockstack` sets it; see `src/main.rs`). `train_step/<net>` is one DQfD gradient step
//! on 64 demonstrated transitions (targets, forward, backward, optimiser); `greedy/<net>`
//! encodes one observation and takes the masked argmax; `self_play/small` is 100
//! environment steps of the `dqfd-planes` recipe with a gradient step each.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use neural::{DemoSource, DqnConfig, Trainer};
use sim::Env;

fn config(preset: &str) -> DqnConfig {
    DqnConfig {
        demos: DemoSource::Exact(50),
        pretrain_steps: 1,
        learning_starts: 64,
        ..DqnConfig::preset(preset, 3).unwrap()
    }
}

fn train_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("train_step");
    group.sample_size(10);
    for (name, preset) in [("small", "dqfd-planes"), ("paper", "paper-dqfd")] {
        let mut trainer = Trainer::new(config(preset)).unwrap();
        group.bench_function(name, |b| {
            b.iter(|| trainer.pretrain(1, &mut |_: &neural::Progress| {}).unwrap())
        });
    }
    group.finish();
}

fn greedy(c: &mut Criterion) {
    let mut group = c.benchmark_group("greedy");
    for (name, preset) in [("small", "dqfd-planes"), ("paper", "paper-dqfd")] {
        let config = config(preset);
        let dqn = Trainer::new(config.clone()).unwrap().finish().unwrap();
        let mut env = Env::new(config.env_config(config.goals[0])).unwrap();
        let obs = env.reset(3);
        group.bench_function(name, |b| {
            b.iter(|| black_box(dqn.greedy_action(black_box(&obs)).unwrap()))
        });
    }
    group.finish();
}

fn self_play(c: &mut Criterion) {
    let mut group = c.benchmark_group("self_play");
    group.sample_size(10);
    group.throughput(Throughput::Elements(100));
    group.bench_function("small", |b| {
        b.iter_batched(
            || {
                let mut t = Trainer::new(config("dqfd-planes")).unwrap();
                t.play(64, &mut |_: &neural::Progress| {}).unwrap();
                t
            },
            |mut t| t.play(100, &mut |_: &neural::Progress| {}).unwrap(),
            BatchSize::PerIteration,
        )
    });
    group.finish();
}

criterion_group!(benches, train_step, greedy, self_play);
criterion_main!(benches);
