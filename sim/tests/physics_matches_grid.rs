//! docs/world.md section 4's invariants: the physics world and the occupancy model agree step for
//! step, every body sits on its cell centre after every step, and what a step reads back is
//! the whole state.

use proptest::prelude::*;
use sim::{
    Action, ActionProtocol, Backend, Env, EnvConfig, Goal, GoalSpec, Grid, GridWorld, PhysicsWorld, RewardModel,
    StartRule, Termination, World,
};

/// Tolerance on a body's distance from its cell centre.
const CENTRE_TOLERANCE: f32 = 1e-4;

/// The rules an environment of the proptest plays by.
#[derive(Clone, Copy, Debug)]
struct Rules {
    reward: &'static str,
    protocol: ActionProtocol,
    start: StartRule,
    termination: Termination,
}

fn config(width: usize, height: usize, blocks: usize, rules: Rules, backend: Backend) -> EnvConfig {
    EnvConfig {
        grid: Grid::new(width, height).unwrap(),
        blocks,
        goal: GoalSpec::Random,
        horizon: 60,
        reward: RewardModel::from_name(rules.reward).unwrap(),
        backend,
        protocol: rules.protocol,
        start: rules.start,
        termination: rules.termination,
        ..EnvConfig::default()
    }
}

fn rules() -> impl Strategy<Value = Rules> {
    (
        prop::sample::select(RewardModel::NAMES.to_vec()),
        prop::sample::select(vec![ActionProtocol::Free, ActionProtocol::Paper]),
        prop::sample::select(vec![StartRule::Uniform, StartRule::Paper]),
        prop::sample::select(vec![Termination::Goal, Termination::paper_training()]),
    )
        .prop_map(|(reward, protocol, start, termination)| Rules {
            reward,
            protocol,
            start,
            termination,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random grids, block counts, rules (reward model, action protocol, start rule,
    /// termination) and action sequences (blocked moves included, across episode
    /// boundaries): the two backends give the same observations, rewards, effects, masks
    /// and episode ends. Each drawn number picks among the *legal* actions of the state, so
    /// under `free` it is every action and under `paper` the protocol's.
    #[test]
    fn envs_agree_step_for_step(
        width in 2usize..=9,
        height in 2usize..=9,
        blocks in 2usize..=8,
        rules in rules(),
        seed in any::<u64>(),
        actions in prop::collection::vec(0usize..13, 1..300),
    ) {
        prop_assume!(blocks < width * height && blocks <= height);
        prop_assume!(rules.start.check_fits(Grid::new(width, height).unwrap(), blocks).is_ok());
        let mut physics = Env::new(config(width, height, blocks, rules, Backend::Physics)).unwrap();
        let mut grid = Env::new(config(width, height, blocks, rules, Backend::Grid)).unwrap();
        let first = physics.reset(seed);
        prop_assert_eq!(first.clone(), grid.reset(seed));
        let mut legal = first.legal_actions();
        for &a in &actions {
            prop_assert_eq!(legal.clone(), physics.legal_actions());
            let action = legal.nth(a % legal.count()).unwrap();
            let p = physics.step(action).unwrap();
            let g = grid.step(action).unwrap();
            prop_assert_eq!(p.clone(), g);
            prop_assert_eq!(p.info.action_mask.clone(), p.observation.legal_actions());
            legal = p.info.action_mask;
            if p.terminated || p.truncated {
                let next = physics.reset(None);
                prop_assert_eq!(next.clone(), grid.reset(None));
                legal = next.legal_actions();
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
        let mut physics = PhysicsWorld::new(grid, start.clone()).unwrap();
        let mut occupancy = GridWorld::new(grid, start.clone()).unwrap();
        // What `World::read_back` keeps up to date from the effects alone, per backend.
        let (mut physics_known, mut occupancy_known) = (start.clone(), start);
        for &a in &actions {
            let action = Action::from_index(a % Action::count(blocks), blocks).unwrap();
            let effect = physics.act(action).unwrap();
            prop_assert_eq!(effect, occupancy.act(action).unwrap());
            prop_assert_eq!(physics.state(), occupancy.state());
            physics.read_back(&mut physics_known, effect);
            occupancy.read_back(&mut occupancy_known, effect);
            prop_assert_eq!(&physics_known, &physics.state());
            prop_assert_eq!(&occupancy_known, &occupancy.state());
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
