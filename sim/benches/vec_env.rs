//! `VecEnv::step_with` (each result lent in place, a `VecStepRef`) as the Python vector env drives it: 64, 1,024 and 4,096 environments
//! of the SPEC world (3 blocks), on 1 and 2 threads, physics and grid backends, each
//! environment's result written into its slot of flat buffers (the `planes` observation,
//! reward, flags, goal pairs in place and action mask) on the thread that stepped it, as
//! `python/src/vector.rs` does.
//!
//! `cargo bench -p sim --bench vec_env`; the throughput is in environment steps. Actions are
//! drawn up front from a seeded generator, so the timing is of the batch, not of the
//! generator.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::RngExt;
use sim::{Action, Backend, EnvConfig, ObsKind, VecEnv, VecStepRef};

/// One environment's part of the buffers.
struct Slot<'a> {
    obs: &'a mut [u8],
    reward: &'a mut f64,
    done: &'a mut bool,
    pairs: &'a mut usize,
    mask: &'a mut [bool],
}

/// Writes one environment's result into its slot.
fn write(result: &VecStepRef<'_>, slot: &mut Slot<'_>) {
    let obs = result.observation;
    ObsKind::Planes
        .write(obs, slot.obs)
        .expect("the buffer has the planes' shape");
    (*slot.reward, *slot.done) = result
        .outcome
        .map_or((0.0, false), |o| (o.reward, o.terminated || o.truncated));
    *slot.pairs = result.pairs_in_place();
    for (i, m) in slot.mask.iter_mut().enumerate() {
        *m = result.action_mask.contains_index(i);
    }
}

fn step_with(c: &mut Criterion) {
    const BLOCKS: usize = 3;
    let actions = Action::count(BLOCKS);
    for backend in [Backend::Physics, Backend::Grid] {
        let mut group = c.benchmark_group(format!("vec_step_with_{backend}"));
        for envs in [64, 1024, 4096] {
            group.throughput(Throughput::Elements(envs as u64));
            let mut rng = sim::seeding::rng(42);
            let batches: Vec<Vec<Action>> = (0..16)
                .map(|_| {
                    (0..envs)
                        .map(|_| Action::from_index(rng.random_range(0..actions), BLOCKS).unwrap())
                        .collect()
                })
                .collect();
            let config = EnvConfig {
                backend,
                blocks: BLOCKS,
                ..EnvConfig::default()
            };
            let shape = ObsKind::Planes.shape(config.grid, BLOCKS).unwrap();
            let obs_len: usize = shape.iter().product();
            let mut obs = vec![0u8; envs * obs_len];
            let mut rewards = vec![0.0; envs];
            let mut done = vec![false; envs];
            let mut pairs = vec![0; envs];
            let mut masks = vec![false; envs * actions];
            for threads in [1, 2] {
                let mut v = VecEnv::new(config.clone(), envs, threads).unwrap();
                v.reset(0);
                let mut slots: Vec<Slot<'_>> = obs
                    .chunks_mut(obs_len)
                    .zip(rewards.iter_mut())
                    .zip(done.iter_mut())
                    .zip(pairs.iter_mut())
                    .zip(masks.chunks_mut(actions))
                    .map(|((((obs, reward), done), pairs), mask)| Slot {
                        obs,
                        reward,
                        done,
                        pairs,
                        mask,
                    })
                    .collect();
                let mut i = 0;
                group.bench_function(BenchmarkId::new(format!("{envs}_envs_threads"), threads), |b| {
                    b.iter(|| {
                        i = (i + 1) % batches.len();
                        v.step_with(&batches[i], &mut slots, write).unwrap();
                    })
                });
                black_box(&slots);
            }
        }
        group.finish();
    }
}

criterion_group!(benches, step_with);
criterion_main!(benches);
