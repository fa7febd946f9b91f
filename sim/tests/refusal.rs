//! Gymnasium's contract in the library: under `Refusal::Step` every action of the action
//! space is taken, and one the world's rules refuse changes nothing, counts as a step, and
//! gets the world's reward for a step that changes nothing; otherwise a step is exactly the
//! strict environment's. For every profile, view and backend.

use proptest::prelude::*;
use sim::reward::Transition;
use sim::{
    Action, ActionProtocol, Autoreset, Backend, BlockMove, Effect, Env, EnvConfig, Profile, ProfileParts, Refusal,
    VecEnv, VecStep, View,
};

/// The worlds: both profiles from above, both protocols from the side, on both backends.
fn worlds() -> Vec<EnvConfig> {
    let mut worlds = Vec::new();
    for backend in [Backend::Grid, Backend::Physics] {
        for profile in [Profile::Spec, Profile::Original] {
            worlds.push(EnvConfig {
                backend,
                horizon: 40,
                ..ProfileParts::of(profile).apply(EnvConfig::default())
            });
        }
        for protocol in [ActionProtocol::Free, ActionProtocol::Paper] {
            worlds.push(EnvConfig {
                backend,
                protocol,
                view: View::Side,
                horizon: 40,
                ..EnvConfig::default()
            });
        }
    }
    worlds
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn a_refused_action_changes_nothing_and_counts_as_a_step(
        world in 0usize..8,
        seed in 0u64..1000,
        actions in proptest::collection::vec(0usize..8, 1..60),
    ) {
        let config = worlds()[world].clone();
        let mut lenient = Env::new(config.clone()).unwrap().with_refusal(Refusal::Step);
        lenient.reset(seed);
        let blocks = config.blocks;
        for index in actions {
            if lenient.is_over() {
                break;
            }
            let action = Action::from_index(index, blocks).unwrap();
            let before = lenient.observation();
            let steps = lenient.steps();
            let strict = lenient.clone().with_refusal(Refusal::Error).step(action);
            let step = lenient.step(action).unwrap();
            match strict {
                Ok(expected) => prop_assert_eq!(step, expected),
                Err(e) => {
                    prop_assert!(e.is_refusal(), "{e}");
                    prop_assert_eq!(step.info.effect, Effect::Refused);
                    prop_assert_eq!(&step.observation.state, &before.state, "a refused action moves nothing");
                    prop_assert_eq!(lenient.steps(), steps + 1, "it counts towards the horizon");
                    let unchanged = Transition {
                        grid: config.grid,
                        view: config.view,
                        goal: &before.goal,
                        before: &before.state,
                        action,
                        previous_action: None,
                        after: &before.state,
                    };
                    // The reward models that look at the previous action do so only for a
                    // drop after a pick, which no protocol refuses.
                    prop_assert_eq!(step.reward, config.reward.reward(&unchanged));
                    prop_assert!(!step.terminated);
                    prop_assert_eq!(step.truncated, lenient.steps() >= config.horizon);
                }
            }
        }
    }
}

#[test]
fn strict_is_the_default_and_refuses_without_counting() {
    let config = ProfileParts::of(Profile::Original).apply(EnvConfig::default());
    let mut env = Env::new(config).unwrap();
    assert_eq!(env.refusal(), Refusal::Error);
    env.reset(3);
    // Nothing held under the paper protocol: only picks are legal.
    let err = env.step(Action::Up).unwrap_err();
    assert!(err.is_refusal(), "{err}");
    assert_eq!(env.steps(), 0);
    assert!(env.check_action(Action::Up).is_err());
    let env = env.with_refusal(Refusal::Step);
    assert!(env.check_action(Action::Up).is_ok());
}

#[test]
fn the_horizon_ends_an_episode_of_refused_actions() {
    let config = EnvConfig {
        horizon: 5,
        ..ProfileParts::of(Profile::Original).apply(EnvConfig::default())
    };
    let mut env = Env::new(config).unwrap().with_refusal(Refusal::Step);
    env.reset(1);
    for k in 1..=5 {
        let step = env.step(Action::Drop).unwrap();
        assert_eq!(step.info.effect, Effect::Refused);
        // The authors' code: -0.1 for a step that leaves the state as it was.
        assert!((step.reward - -0.1).abs() < 1e-12, "{}", step.reward);
        assert_eq!(step.truncated, k == 5);
    }
    assert!(env.is_over());
}

#[test]
fn a_block_move_the_rules_refuse_is_one_step_that_changes_nothing() {
    let config = EnvConfig {
        view: View::Side,
        horizon: 30,
        ..EnvConfig::default()
    };
    let (blocks, grid) = (config.blocks, config.grid);
    for refusal in [Refusal::Error, Refusal::Step] {
        let mut env = Env::new(config.clone()).unwrap().with_refusal(refusal);
        env.reset(4);
        let legal = env.legal_moves();
        let refused = (0..legal.len()).find(|&i| !legal[i]).expect("some move is illegal");
        let mv = BlockMove::from_index(refused, blocks, grid).unwrap();
        let before = env.observation();
        match refusal {
            Refusal::Error => assert!(env.step_block_move(mv).is_err()),
            Refusal::Step => {
                let moved = env.step_block_move(mv).unwrap();
                assert_eq!(moved.gripper_steps, 1);
                assert_eq!(moved.step.info.effect, Effect::Refused);
                assert_eq!(moved.step.observation.state, before.state);
                assert_eq!(env.steps(), 1);
            }
        }
    }
}

#[test]
fn a_vector_env_takes_refused_actions_as_each_environment_does() {
    let config = ProfileParts::of(Profile::Original).apply(EnvConfig {
        backend: Backend::Grid,
        horizon: 20,
        ..EnvConfig::default()
    });
    // Enough environments to be stepped on a pool of two threads as well as on one.
    let n = sim::PARALLEL_FROM_ENVS;
    for threads in [1, 2] {
        let mut vec = VecEnv::new(config.clone(), n, threads)
            .unwrap()
            .with_autoreset(Autoreset::NextStep)
            .with_refusal(Refusal::Step);
        let mut singles: Vec<Env> = (0..n)
            .map(|_| Env::new(config.clone()).unwrap().with_refusal(Refusal::Step))
            .collect();
        vec.reset(10);
        for (i, env) in singles.iter_mut().enumerate() {
            env.reset(10 + i as u64);
        }
        let mut refused = 0;
        for t in 0..30 {
            let actions: Vec<Action> = (0..n)
                .map(|i| Action::from_index((i * 7 + t * 3) % 8, 3).unwrap())
                .collect();
            let steps = vec.step(&actions).unwrap();
            for ((env, &action), got) in singles.iter_mut().zip(&actions).zip(&steps) {
                if env.is_over() {
                    assert_eq!(got, &VecStep::Reset(env.reset(None)));
                    continue;
                }
                let want = env.step(action).unwrap();
                refused += usize::from(want.info.effect == Effect::Refused);
                assert_eq!(got, &VecStep::Stepped(want));
            }
        }
        assert!(refused > 0, "the actions include refused ones");
    }
}
