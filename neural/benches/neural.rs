//! The neural learner's speed: one gradient step (batch 64) of each network, one greedy
//! action, and self-play throughput, on 1 and 2 threads.
//!
//! `cargo bench -p neural`. `<net>` is `small` (the `dqfd-planes` recipe), `paper`
//! (`paper-dqfd`) or `conv` (`pixels`: one convolution of a cell on the compact screen),
//! each on 3 blocks; `<threads>` a rayon pool's size (the networks split
//! large layers into two fixed halves, so it changes the time, never the result). The
//! steps run as the trainer's loop does, with the pool's other threads kept awake
//! (`neural::kernels::on_pool_awake`).
//!
//! - `network/<net>/<threads>`: the arithmetic of one DQfD step on inputs already encoded
//!   (target and choosing passes on 128 next observations, training pass and backward pass
//!   on 64, optimiser).
//! - `train_step/<net>/<threads>`: one whole DQfD gradient step on 64 demonstrated
//!   transitions (sampling, encoding, the above). With 50 demonstrations every screen is
//!   soon in the learner's cache of rendered screens: the paper network's figure leaves out
//!   rendering (about 0.12 ms a screen, `greedy/paper` includes one).
//! - `greedy/<net>`: one observation encoded, its masked argmax (one thread).
//! - `self_play/<net>/<threads>`: 100 environment steps of the recipe, a gradient step each.

use std::hint::black_box;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use neural::{DemoSource, DqnConfig, Preset, Trainer};
use sim::Env;

const NETS: [(&str, Preset); 3] = [
    ("small", Preset::DqfdPlanes),
    ("paper", Preset::PaperDqfd),
    ("conv", Preset::DqfdScreen),
];

fn config(preset: Preset) -> DqnConfig {
    DqnConfig {
        demos: DemoSource::Exact(50),
        pretrain_steps: 1,
        learning_starts: 64,
        batch: 64,
        ..DqnConfig::preset(preset, 3).unwrap()
    }
}

/// `f` as the trainer runs its loop: on a pool thread, the others awake
/// (`Trainer::run_until_on_pool`).
fn awake<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    neural::kernels::on_pool_awake(f)
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap()
}

fn train_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("train_step");
    group.sample_size(10);
    for (name, preset) in NETS {
        let mut trainer = Trainer::new(config(preset)).unwrap();
        for threads in [1, 2] {
            let pool = pool(threads);
            group.bench_function(format!("{name}/{threads}"), |b| {
                pool.install(|| awake(|| b.iter(|| trainer.pretrain(1, &mut |_: &neural::Progress| {}).unwrap())))
            });
        }
    }
    group.finish();
}

/// The networks' arithmetic alone, as one DQfD step of each recipe does it on inputs
/// already encoded: the target network (and with double DQN the online one) on 128 next
/// observations, the online network's training pass and backward pass on 64, and the
/// optimiser.
fn network(c: &mut Criterion) {
    let mut group = c.benchmark_group("network");
    group.sample_size(10);
    for (name, preset) in NETS {
        let config = config(preset);
        let trainer = Trainer::new(config.clone()).unwrap();
        let mut online = trainer.net().try_clone().unwrap();
        let target = online.try_clone().unwrap();
        let spec = *online.input();
        let mut env = Env::new(config.env_config(config.goals[0].clone())).unwrap();
        let observations: Vec<sim::Observation> = (0..128).map(|i| env.reset(i)).collect();
        let refs: Vec<&sim::Observation> = observations.iter().collect();
        let next = spec.batch(&refs);
        let x = spec.batch(&refs[..64]);
        let mut optimizer = neural::optim::Optimizer::new(config.optimizer, config.lr, online.parameter_count());
        let (mut train, mut eval) = (neural::net::Workspace::new(), neural::net::Workspace::new());
        let dq: Vec<f32> = (0..64 * online.actions())
            .map(|i| ((i % 7) as f32 - 3.0) * 0.01)
            .collect();
        let mut grad = vec![0.0; online.parameter_count()];
        for threads in [1, 2] {
            let pool = pool(threads);
            group.bench_function(format!("{name}/{threads}"), |b| {
                pool.install(|| {
                    awake(|| {
                        b.iter(|| {
                            black_box(target.forward(&next, &mut eval));
                            if config.double {
                                black_box(online.forward(&next, &mut eval));
                            }
                            online.forward_train(&x, &mut train);
                            online.backward(&x, &mut train, &dq, &mut grad);
                            optimizer.step(online.params_mut(), &mut grad, config.l2, config.clip_norm)
                        })
                    })
                })
            });
        }
    }
    group.finish();
}

fn greedy(c: &mut Criterion) {
    let mut group = c.benchmark_group("greedy");
    for (name, preset) in NETS {
        let config = config(preset);
        let dqn = Trainer::new(config.clone()).unwrap().finish().unwrap();
        let mut env = Env::new(config.env_config(config.goals[0].clone())).unwrap();
        let obs = env.reset(3);
        let pool = pool(1);
        group.bench_function(name, |b| {
            pool.install(|| b.iter(|| black_box(dqn.greedy_action(black_box(&obs)).unwrap())))
        });
    }
    group.finish();
}

fn self_play(c: &mut Criterion) {
    let mut group = c.benchmark_group("self_play");
    group.sample_size(10);
    group.throughput(Throughput::Elements(100));
    for (name, preset) in NETS {
        for threads in [1, 2] {
            let pool = pool(threads);
            group.bench_function(format!("{name}/{threads}"), |b| {
                pool.install(|| {
                    awake(|| {
                        b.iter_batched(
                            || {
                                let mut t = Trainer::new(config(preset)).unwrap();
                                t.play(64, &mut |_: &neural::Progress| {}).unwrap();
                                t
                            },
                            |mut t| t.play(100, &mut |_: &neural::Progress| {}).unwrap(),
                            BatchSize::PerIteration,
                        )
                    })
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, network, train_step, greedy, self_play);
criterion_main!(benches);
