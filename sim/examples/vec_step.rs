//! A fixed amount of batched stepping, for `perf stat` and `perf record`: the criterion
//! bench (`cargo bench -p sim --bench vec_env`) times a batch for as long as it takes,
//! this runs a given number of batches, so counts such as instructions per env-step can
//! be compared between commits on a machine that is not quiet.
//!
//! `cargo run --release -p sim --example vec_step [envs] [threads] [batches] [physics|grid]`
//! (4096 envs, 1 thread, 200 batches, physics by default). Every result is written into
//! flat `planes` buffers on the thread that stepped it, as the Python vector env does;
//! prints env-steps per second of wall time.

use std::time::Instant;

use rand::RngExt;
use sim::{Action, Backend, EnvConfig, ObsKind, VecEnv};

fn main() -> Result<(), sim::SimError> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, default: usize| args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default);
    let (envs, threads, batches) = (arg(1, 4096), arg(2, 1), arg(3, 200));
    let backend = match args.get(4).map(String::as_str) {
        Some("grid") => Backend::Grid,
        _ => Backend::Physics,
    };
    let config = EnvConfig {
        backend,
        ..EnvConfig::default()
    };
    let blocks = config.blocks;
    let obs_len: usize = ObsKind::Planes
        .shape(config.grid, blocks)
        .map_or(0, |s| s.iter().product());
    let mut rng = sim::seeding::rng(42);
    let actions: Vec<Vec<Action>> = (0..16)
        .map(|_| {
            (0..envs)
                .map(|_| Action::from_index(rng.random_range(0..Action::count(blocks)), blocks))
                .collect()
        })
        .collect::<Result<_, _>>()?;
    let mut obs = vec![0u8; envs * obs_len];
    let mut slots: Vec<&mut [u8]> = obs.chunks_mut(obs_len).collect();
    let mut v = VecEnv::new(config, envs, threads)?;
    v.reset(0);
    let start = Instant::now();
    for i in 0..batches {
        v.step_with(&actions[i % actions.len()], &mut slots, |result, slot| {
            ObsKind::Planes
                .write(result.observation, slot)
                .expect("the buffer has the planes' shape");
        })?;
    }
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{envs} {backend} envs, {threads} thread(s), {batches} batches: {:.0} env-steps/s",
        (envs * batches) as f64 / seconds
    );
    Ok(())
}
