//! Step throughput of the two backends, environment resets, and the vectorised env.
//!
//! `cargo bench --bench sim`. Actions are drawn up front from a seeded generator so the
//! timing is of the world, not of the generator. `env_step` is the SPEC world;
//! `env_step_original` the `original` profile (paper protocol, `paper-code` reward), whose
//! actions are chosen among the legal ones of each step's mask. `side_*` is the side view
//! (docs/world.md, "The side view"): a gripper step, a drop (on the physics backend, rapier's
//! dynamics to rest), and random play among the legal actions, on both backends. `side_reset`
//! and `side_task_by_block_moves` are the side view at 50 to 10,000 blocks.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::RngExt;
use sim::{
    Action, Backend, BlockId, Cell, Env, EnvConfig, Grid, GridWorld, PhysicsWorld, Profile, State, VecEnv, View, World,
};

/// Random actions of a world with `blocks` blocks.
fn random_actions(blocks: usize, count: usize) -> Vec<Action> {
    let mut rng = sim::seeding::rng(42);
    (0..count)
        .map(|_| Action::from_index(rng.random_range(0..Action::count(blocks)), blocks).unwrap())
        .collect()
}

/// A start state of `blocks` blocks on `grid`.
fn start(grid: Grid, blocks: usize) -> sim::State {
    let config = EnvConfig {
        grid,
        blocks,
        backend: Backend::Grid,
        ..EnvConfig::default()
    };
    Env::new(config).unwrap().reset(1).state
}

fn world_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("step");
    group.throughput(Throughput::Elements(1));
    // Eight blocks need eight rows for their stack; the world itself would not mind.
    for (blocks, grid) in [(3, Grid::default()), (8, Grid::new(8, 8).unwrap())] {
        let actions = random_actions(blocks, 1 << 16);
        let mut grid_world = GridWorld::new(grid, start(grid, blocks)).unwrap();
        let mut i = 0;
        group.bench_function(BenchmarkId::new("grid", blocks), |b| {
            b.iter(|| {
                i = (i + 1) & 0xFFFF;
                black_box(grid_world.act(actions[i]).unwrap())
            })
        });
        let mut physics = PhysicsWorld::new(grid, start(grid, blocks)).unwrap();
        group.bench_function(BenchmarkId::new("physics", blocks), |b| {
            b.iter(|| {
                i = (i + 1) & 0xFFFF;
                black_box(physics.act(actions[i]).unwrap())
            })
        });
    }
    group.finish();
}

fn env_step(c: &mut Criterion) {
    // The whole Env step: action, state read-back, reward, goal check, autoreset on end.
    let mut group = c.benchmark_group("env_step");
    group.throughput(Throughput::Elements(1));
    for (blocks, grid) in [(3, Grid::default()), (8, Grid::new(8, 8).unwrap())] {
        let actions = random_actions(blocks, 1 << 16);
        for backend in [Backend::Grid, Backend::Physics] {
            let mut env = Env::new(EnvConfig {
                grid,
                blocks,
                backend,
                ..EnvConfig::default()
            })
            .unwrap();
            env.reset(1);
            let mut i = 0;
            group.bench_function(BenchmarkId::new(backend.to_string(), blocks), |b| {
                b.iter(|| {
                    i = (i + 1) & 0xFFFF;
                    let step = env.step(actions[i]).unwrap();
                    if step.terminated || step.truncated {
                        env.reset(None);
                    }
                    black_box(step.reward)
                })
            });
        }
    }
    group.finish();
}

fn env_step_original(c: &mut Criterion) {
    // The step of the paper's world: the legality check, the mask, and the reward computed
    // from the authors' state tuple before and after.
    let mut group = c.benchmark_group("env_step_original");
    group.throughput(Throughput::Elements(1));
    let mut rng = sim::seeding::rng(42);
    // Draws below 15, a multiple of both 3 (picks) and 5 (moves and drop): uniform choices.
    let draws: Vec<usize> = (0..1 << 16).map(|_| rng.random_range(0..15)).collect();
    for backend in [Backend::Grid, Backend::Physics] {
        let mut env = Env::new(EnvConfig {
            backend,
            ..Profile::Original.world()
        })
        .unwrap();
        let mut legal = env.reset(1).legal_actions();
        let mut i = 0;
        group.bench_function(BenchmarkId::new(backend.to_string(), 3), |b| {
            b.iter(|| {
                i = (i + 1) & 0xFFFF;
                let action = legal.nth(draws[i] % legal.count()).unwrap();
                let step = env.step(action).unwrap();
                legal = step.info.action_mask;
                if step.terminated || step.truncated {
                    legal = env.reset(None).legal_actions();
                }
                black_box(step.reward)
            })
        });
    }
    group.finish();
}

fn reset(c: &mut Criterion) {
    let mut group = c.benchmark_group("reset");
    for backend in [Backend::Grid, Backend::Physics] {
        let mut env = Env::new(EnvConfig {
            backend,
            ..EnvConfig::default()
        })
        .unwrap();
        let mut seed = 0;
        group.bench_function(backend.to_string(), |b| {
            b.iter(|| {
                seed += 1;
                black_box(env.reset(seed))
            })
        });
    }
    group.finish();
}

fn vec_step(c: &mut Criterion) {
    const ENVS: usize = 64;
    let mut group = c.benchmark_group("vec_step");
    group.throughput(Throughput::Elements(ENVS as u64));
    let batches: Vec<Vec<Action>> = random_actions(3, 64 * ENVS)
        .chunks(ENVS)
        .map(<[Action]>::to_vec)
        .collect();
    for threads in [1, 2] {
        let mut v = VecEnv::new(EnvConfig::default(), ENVS, threads).unwrap();
        v.reset(0);
        let mut i = 0;
        group.bench_function(BenchmarkId::new("physics_64_envs_threads", threads), |b| {
            b.iter(|| {
                i = (i + 1) % batches.len();
                black_box(v.step(&batches[i]).unwrap().len())
            })
        });
    }
    group.finish();
}

fn side_view(c: &mut Criterion) {
    let grid = Grid::default();
    // Block 0 on the table at column 0, block 1 on it, block 2 held on the top row.
    let held_high = State::new(&[Cell::new(0, 0), Cell::new(0, 1), Cell::new(4, 6)], Some(BlockId(2))).unwrap();
    let worlds = |state: State| -> [(Backend, Box<dyn World>); 2] {
        [
            (
                Backend::Grid,
                Box::new(GridWorld::new_in(View::Side, grid, state.clone()).unwrap()),
            ),
            (
                Backend::Physics,
                Box::new(PhysicsWorld::new_in(View::Side, grid, state).unwrap()),
            ),
        ]
    };
    let mut group = c.benchmark_group("side_step");
    group.throughput(Throughput::Elements(1));
    for (backend, mut world) in worlds(held_high.clone()) {
        // A gripper step: the held block carried left and right along the top row.
        let mut k = 0u32;
        group.bench_function(backend.to_string(), |b| {
            b.iter(|| {
                k += 1;
                black_box(
                    world
                        .act(if k & 1 == 0 { Action::Left } else { Action::Right })
                        .unwrap(),
                )
            })
        });
    }
    group.finish();
    let mut group = c.benchmark_group("side_drop");
    group.throughput(Throughput::Elements(1));
    for (backend, mut world) in worlds(held_high.clone()) {
        // A fall of six rows to the table (the state put back first, which costs little).
        group.bench_function(backend.to_string(), |b| {
            b.iter(|| {
                world.place(&held_high).unwrap();
                black_box(world.act(Action::Drop).unwrap())
            })
        });
    }
    group.finish();
    let mut group = c.benchmark_group("side_random_play");
    group.throughput(Throughput::Elements(1));
    let mut rng = sim::seeding::rng(42);
    // Draws below 5 * 7 * 9 * 11 * 13 * 16: uniform over the legal actions of any mask.
    let draws: Vec<usize> = (0..1 << 16).map(|_| rng.random_range(0..720_720)).collect();
    for blocks in [3, 5] {
        for backend in [Backend::Grid, Backend::Physics] {
            let mut env = Env::new(EnvConfig {
                blocks,
                backend,
                view: View::Side,
                ..EnvConfig::default()
            })
            .unwrap();
            let mut legal = env.reset(1).legal_actions();
            let mut i = 0;
            group.bench_function(BenchmarkId::new(backend.to_string(), blocks), |b| {
                b.iter(|| {
                    i = (i + 1) & 0xFFFF;
                    let action = legal.nth(draws[i] % legal.count()).unwrap();
                    let step = env.step(action).unwrap();
                    legal = step.info.action_mask;
                    if step.terminated || step.truncated {
                        legal = env.reset(None).legal_actions();
                    }
                    black_box(step.reward)
                })
            });
        }
    }
    group.finish();
}

fn side_at_scale(c: &mut Criterion) {
    // The side view at the field's sizes (docs/world.md, "The side view at any size"): a
    // reset (a uniform Blocks World state on the default grid), and a whole task played by
    // block moves on the grid backend, the near-optimal planner's moves planned beforehand.
    let mut group = c.benchmark_group("side_reset");
    group.sample_size(10);
    for blocks in [100, 1_000, 10_000] {
        let mut env = Env::new(EnvConfig {
            blocks,
            grid: Grid::side_default(blocks),
            backend: Backend::Grid,
            view: View::Side,
            ..EnvConfig::default()
        })
        .unwrap();
        let mut seed = 0;
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                seed += 1;
                black_box(env.reset(seed).state.block_count())
            })
        });
    }
    group.finish();
    let mut group = c.benchmark_group("side_task_by_block_moves");
    group.sample_size(10);
    for blocks in [50, 500, 5_000] {
        let grid = Grid::side_default(blocks);
        let mut env = Env::new(EnvConfig {
            blocks,
            grid,
            backend: Backend::Grid,
            view: View::Side,
            horizon: u32::MAX,
            ..EnvConfig::default()
        })
        .unwrap();
        let goal = sim::Goal::uniform(blocks, &mut sim::seeding::rng(7)).unwrap();
        let start = env.reset(1).state;
        let plan = oracle::towers::plan_side(oracle::towers::MovePlanner::NearOptimal, grid, &start, &goal).unwrap();
        group.bench_function(BenchmarkId::from_parameter(blocks), |b| {
            b.iter(|| {
                env.reset_to(&start, &goal).unwrap();
                for &m in &plan.moves {
                    let mv = oracle::towers::block_move_of(&env.state(), grid, m).unwrap();
                    env.step_block_move(mv).unwrap();
                }
                assert!(env.is_over());
                black_box(env.steps())
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    world_step,
    env_step,
    env_step_original,
    reset,
    vec_step,
    side_view,
    side_at_scale
);
criterion_main!(benches);
