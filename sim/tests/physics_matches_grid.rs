//! SPEC section 4's invariants: the physics world and the occupancy model agree step for
//! step, and every body sits on its cell centre after every step.

use proptest::prelude::*;
use sim::{Action, Backend, Env, EnvConfig, Goal, GoalSpec, Grid, GridWorld, PhysicsWorld, RewardModel, World};

/// Tolerance on a body's distance from its cell centre.
const CENTRE_TOLERANCE: f32 = 1e-4;

fn config(width: usize, height: usize, blocks: usize, reward: &str, backend: Backend) -> EnvConfig {
    EnvConfig {
        grid: Grid::new(width, height).unwrap(),
        blocks,
        goal: GoalSpec::Random,
        horizon: 60,
        reward: RewardModel::from_name(reward).unwrap(),
        backend,
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random grids, block counts, reward models and action sequences (every action,
    /// blocked moves included, across episode boundaries): the two backends give the same
    /// observations, rewards, effects and episode ends.
    #[test]
    fn envs_agree_step_for_step(
        width in 2usize..=9,
        height in 2usize..=9,
        blocks in 2usize..=8,
        reward in prop::sample::select(RewardModel::NAMES.to_vec()),
        seed in any::<u64>(),
        actions in prop::collection::vec(0usize..13, 1..300),
    ) {
        prop_assume!(blocks < width * height && blocks <= height);
        let mut physics = Env::new(config(width, height, blocks, reward, Backend::Physics)).unwrap();
        let mut grid = Env::new(config(width, height, blocks, reward, Backend::Grid)).unwrap();
        prop_assert_eq!(physics.reset(seed), grid.reset(seed));
        for &a in &actions {
            let a = a % Action::count(blocks);
            let p = physics.step_index(a).unwrap();
            let g = grid.step_index(a).unwrap();
            prop_assert_eq!(p, g);
            if p.terminated || p.truncated {
                prop_assert_eq!(physics.reset(None), grid.reset(None));
            }
        }
    }

    /// The worlds themselves, driven with held blocks from arbitrary states: same states
    /// and effects, and every body (and its collider) on its cell centre after every step.
    #[test]
    fn worlds_agree_and_bodies_stay_on_centres(
        blocks in 2usize..=7,
        seed in any::<u64>(),
        actions in prop::collection::vec(0usize..13, 1..400),
    ) {
        let grid = Grid::default();
        let mut env = Env::new(EnvConfig { goal: GoalSpec::Fixed(Goal::identity(blocks).unwrap()), blocks, ..EnvConfig::default() }).unwrap();
        let start = env.reset(seed).state;
        let mut physics = PhysicsWorld::new(grid, start).unwrap();
        let mut occupancy = GridWorld::new(grid, start).unwrap();
        for &a in &actions {
            let action = Action::from_index(a % Action::count(blocks), blocks).unwrap();
            prop_assert_eq!(physics.act(action).unwrap(), occupancy.act(action).unwrap());
            prop_assert_eq!(physics.state(), occupancy.state());
            prop_assert!(physics.max_centre_error() < CENTRE_TOLERANCE, "error {}", physics.max_centre_error());
        }
    }
}

/// 10^6 physics steps of random actions, checked against the occupancy model at every
/// step (about a third of a second in release).
#[test]
fn a_million_physics_steps_agree_with_the_grid() {
    use rand::RngExt;
    let blocks = 5;
    let mut rng = sim::seeding::rng(2026);
    let mut physics = Env::new(EnvConfig {
        backend: Backend::Physics,
        blocks,
        ..EnvConfig::default()
    })
    .unwrap();
    let mut grid = Env::new(EnvConfig {
        backend: Backend::Grid,
        blocks,
        ..EnvConfig::default()
    })
    .unwrap();
    assert_eq!(physics.reset(1), grid.reset(1));
    let (mut steps, mut moves) = (0u64, 0u64);
    while steps < 1_000_000 {
        let a = rng.random_range(0..Action::count(blocks));
        let p = physics.step_index(a).unwrap();
        assert_eq!(p, grid.step_index(a).unwrap(), "step {steps}");
        moves += u64::from(p.info.effect == sim::Effect::Moved);
        if p.terminated || p.truncated {
            assert_eq!(physics.reset(None), grid.reset(None));
        }
        steps += 1;
    }
    // The run must actually have exercised the physics.
    assert!(moves > 100_000, "only {moves} moves");
}
