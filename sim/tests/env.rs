//! The environment: seeding, episode ends, rewards, observations, config errors, VecEnv.

use std::ops::Range;

use sim::reward::{Dense, Paper, Sparse, StepCost, Transition};
use sim::{
    Action, Autoreset, Backend, BlockId, Cell, Env, EnvConfig, Goal, GoalSpec, Grid, PARALLEL_FROM_ENVS, RewardModel,
    SimError, State, VecEnv, VecStep,
};

fn goal(text: &str) -> Goal {
    text.parse().unwrap()
}

fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
    let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
    State::new(&cells, held.map(BlockId)).unwrap()
}

fn env(goal_text: &str, reward: &str, horizon: u32) -> Env {
    Env::new(EnvConfig {
        reward: RewardModel::from_name(reward).unwrap(),
        horizon,
        ..EnvConfig::with_goal(goal(goal_text))
    })
    .unwrap()
}

#[test]
fn the_same_seed_gives_the_same_start_on_every_machine() {
    let mut e = env("0,1,2", "sparse", 1000);
    let first = e.reset(7);
    assert_eq!(e.reset(7), first);
    // Pinned: the start of seed 7. If this changes, every recorded run's starts changed.
    assert_eq!(first.state, state(&[(6, 0), (0, 1), (1, 1)], None));
    assert_ne!(e.reset(8).state, first.state);
}

#[test]
fn reset_without_a_seed_continues_the_generator() {
    let mut a = env("0,1,2", "sparse", 1000);
    let mut b = env("0,1,2", "sparse", 1000);
    a.reset(3);
    b.reset(3);
    let (a2, b2) = (a.reset(None), b.reset(None));
    assert_eq!(a2, b2);
    assert_ne!(a2, a.reset(3));
}

#[test]
fn starts_never_satisfy_the_goal() {
    // On a 1x3 column with 2 blocks, a third of the placements satisfy 0,1.
    let mut e = Env::new(EnvConfig {
        grid: Grid::new(1, 3).unwrap(),
        ..EnvConfig::with_goal(goal("0,1"))
    })
    .unwrap();
    for seed in 0..300 {
        let obs = e.reset(seed);
        assert!(!obs.goal.holds(&obs.state), "seed {seed}");
    }
}

#[test]
fn random_goals_are_drawn_per_episode_and_cover_all_permutations() {
    let mut e = Env::new(EnvConfig {
        goal: GoalSpec::Random,
        ..EnvConfig::default()
    })
    .unwrap();
    let goals: std::collections::HashSet<String> = (0..200).map(|s| e.reset(s).goal.to_string()).collect();
    assert_eq!(goals.len(), 6);
}

#[test]
fn an_episode_terminates_on_the_goal_and_counts_the_last_step() {
    let mut e = env("0,1", "step-cost", 1000);
    e.reset_to(state(&[(2, 2), (3, 4)], None), goal("0,1")).unwrap();
    let plan = [Action::Pick(BlockId(1)), Action::Left, Action::Down];
    for (i, &a) in plan.iter().enumerate() {
        let s = e.step(a).unwrap();
        assert_eq!(s.info.steps, i as u32 + 1);
        assert_eq!(s.terminated, i == 2);
        assert_eq!(s.reward, if i == 2 { 0.0 } else { -1.0 });
        assert!(!s.truncated);
    }
    assert_eq!(e.step(Action::Drop), Err(SimError::EpisodeOver));
}

#[test]
fn an_episode_is_truncated_at_the_horizon() {
    let mut e = env("0,1,2", "sparse", 5);
    e.reset(1);
    for i in 1..=5 {
        let s = e.step(Action::Drop).unwrap();
        assert_eq!((s.terminated, s.truncated), (false, i == 5));
    }
    assert_eq!(e.step(Action::Drop), Err(SimError::EpisodeOver));
}

#[test]
fn stepping_before_reset_and_bad_indices_are_errors() {
    let mut e = env("0,1,2", "sparse", 10);
    assert_eq!(e.step(Action::Up), Err(SimError::NotReset));
    e.reset(0);
    assert_eq!(e.step_index(8), Err(SimError::ActionOutOfRange { index: 8, blocks: 3 }));
    assert_eq!(
        e.step(Action::Pick(BlockId(3))),
        Err(SimError::NoSuchBlock { block: 3, blocks: 3 })
    );
}

#[test]
fn info_reports_blocked_moves_and_pairs_in_place() {
    let mut e = env("0,1,2", "sparse", 100);
    // 1 stands on 0; block 2 is held against the left wall.
    e.reset_to(state(&[(3, 0), (3, 1), (0, 5)], Some(2)), goal("0,1,2"))
        .unwrap();
    let s = e.step(Action::Left).unwrap();
    assert!(s.info.blocked);
    assert_eq!(s.info.pairs_in_place, 1);
    assert!(!e.step(Action::Right).unwrap().info.blocked);
}

#[test]
fn bad_configs_are_named() {
    let base = EnvConfig::default();
    let check = |c: EnvConfig| Env::new(c).err().unwrap();
    assert!(matches!(
        check(EnvConfig {
            blocks: 1,
            ..base.clone()
        }),
        SimError::BadBlockCount { .. }
    ));
    assert!(matches!(
        check(EnvConfig {
            blocks: 17,
            ..base.clone()
        }),
        SimError::BadBlockCount { .. }
    ));
    assert!(matches!(
        check(EnvConfig {
            horizon: 0,
            ..base.clone()
        }),
        SimError::ZeroHorizon
    ));
    let tall = EnvConfig {
        grid: Grid::new(7, 2).unwrap(),
        ..base.clone()
    };
    assert!(matches!(check(tall), SimError::StackTooTall { blocks: 3, height: 2 }));
    let full = EnvConfig {
        grid: Grid::new(1, 3).unwrap(),
        ..base.clone()
    };
    assert!(matches!(check(full), SimError::TooManyBlocks { .. }));
    let mismatch = EnvConfig {
        goal: GoalSpec::Fixed(goal("1,0")),
        ..base.clone()
    };
    assert!(matches!(check(mismatch), SimError::BlockCountMismatch { .. }));
    assert!(matches!(Grid::new(0, 7), Err(SimError::GridSide { .. })));
    assert!(matches!(Grid::new(65_536, 7), Err(SimError::GridSide { .. })));
    // The top view's bitset holds 256 cells; the side view keeps none.
    let wide = EnvConfig {
        grid: Grid::new(17, 16).unwrap(),
        ..base.clone()
    };
    assert_eq!(
        check(wide.clone()).to_string(),
        "grid 17x16 is not allowed in the top view: it holds at most 256 cells (the side view takes larger grids)"
    );
    assert!(
        Env::new(EnvConfig {
            view: sim::View::Side,
            ..wide
        })
        .is_ok()
    );
    assert!(matches!("1,1,0".parse::<Goal>(), Err(SimError::BadGoal { .. })));
    assert!(matches!("0,3,1".parse::<Goal>(), Err(SimError::BadGoal { .. })));
    assert!(matches!("0,x".parse::<Goal>(), Err(SimError::Parse { .. })));
}

#[test]
fn goals_enumerate_every_permutation() {
    let all: Vec<String> = Goal::all(3).unwrap().iter().map(|g| g.to_string()).collect();
    assert_eq!(all, ["0,1,2", "0,2,1", "1,0,2", "1,2,0", "2,0,1", "2,1,0"]);
    assert_eq!(Goal::all(5).unwrap().len(), 120);
}

#[test]
fn chasing_follows_spec_section_6() {
    // Goal 1,0,2: 1 chases the cell below 0, 0 the cell below 2, 2 the cell above 0.
    let g = goal("1,0,2");
    let s = state(&[(2, 2), (5, 5), (4, 0)], None);
    let grid = Grid::default();
    assert_eq!(g.chased_cell(BlockId(1), &s, grid), Some(Cell::new(2, 1)));
    assert_eq!(g.chased_cell(BlockId(0), &s, grid), None); // below row 0
    assert_eq!(g.chased_distance(BlockId(0), &s), 2 + 3); // to (4, -1)
    assert_eq!(g.chased_cell(BlockId(2), &s, grid), Some(Cell::new(2, 3)));
    assert_eq!(g.chased_distance(BlockId(2), &s), 2 + 3);
}

fn transition<'a>(
    g: &'a Goal,
    before: &'a State,
    action: Action,
    prev: Option<Action>,
    after: &'a State,
) -> Transition<'a> {
    Transition {
        grid: Grid::default(),
        view: sim::View::Top,
        goal: g,
        before,
        action,
        previous_action: prev,
        after,
    }
}

#[test]
fn rewards_follow_spec_section_5() {
    let g = goal("0,1");
    let far = state(&[(0, 0), (3, 3)], Some(1));
    let closer = state(&[(0, 0), (2, 3)], Some(1));
    let done = state(&[(0, 0), (0, 1)], Some(1));
    let t = transition(&g, &far, Action::Left, None, &closer);
    let above = state(&[(0, 0), (0, 2)], Some(1));
    let at_goal = transition(&g, &above, Action::Down, None, &done);

    assert_eq!(RewardModel::Sparse(Sparse::default()).reward(&t), 0.0);
    assert_eq!(RewardModel::Sparse(Sparse::default()).reward(&at_goal), 10.0);
    assert_eq!(RewardModel::StepCost(StepCost::default()).reward(&t), -1.0);
    assert_eq!(RewardModel::StepCost(StepCost::default()).reward(&at_goal), 0.0);
    // d = |2-0| + |3-0| = 5, d_max = 1 * (6 + 6) = 12.
    assert_eq!(RewardModel::Dense(Dense::default()).reward(&t), -5.0 / 12.0);
    assert_eq!(
        RewardModel::Dense(Dense::default()).reward(&at_goal),
        -1.0 / 12.0 + 10.0
    );

    let paper = RewardModel::Paper(Paper::default());
    // Block 1 chases the cell above 0, (0, 1): distance 5 -> 4.
    assert_eq!(paper.reward(&t), 1.0);
    assert_eq!(paper.reward(&transition(&g, &closer, Action::Right, None, &far)), -5.0);
    // Reaching the goal: closer (+1), one adjacent pair (+5), one pair in place (+50).
    assert_eq!(paper.reward(&at_goal), 56.0);
    // A drop far from the chased cell straight after a pick: -0.1 twice.
    let dropped = far.with_held(None).unwrap();
    let r = paper.reward(&transition(
        &g,
        &far,
        Action::Drop,
        Some(Action::Pick(BlockId(1))),
        &dropped,
    ));
    assert!((r - -0.2).abs() < 1e-12, "{r}");
    // Picking changes no distance.
    let picked = far.with_held(Some(BlockId(0))).unwrap();
    assert_eq!(
        paper.reward(&transition(&g, &far, Action::Pick(BlockId(0)), None, &picked)),
        0.0
    );
}

#[test]
fn planes_are_one_hot() {
    let mut e = env("0,1,2", "sparse", 10);
    e.reset_to(state(&[(1, 2), (3, 4), (6, 0)], Some(1)), goal("0,1,2"))
        .unwrap();
    let p = e.observation().planes();
    assert_eq!((p.width, p.height, p.channels, p.data.len()), (7, 7, 4, 7 * 7 * 4));
    assert_eq!(p.data.iter().map(|&v| u32::from(v)).sum::<u32>(), 4);
    assert_eq!(
        (p.get(1, 2, 0), p.get(3, 4, 1), p.get(6, 0, 2), p.get(3, 4, 3)),
        (1, 1, 1, 1)
    );
}

#[test]
fn rgb_frames_show_blocks_in_their_colours() {
    let mut e = env("0,1,2", "sparse", 10);
    let obs = e
        .reset_to(state(&[(0, 0), (6, 6), (3, 3)], None), goal("0,1,2"))
        .unwrap();
    let img = obs.rgb();
    let cell = sim::render::CELL_PIXELS;
    // Centre of cell (0, 0) is at the bottom-left of the grid area.
    let px = |x: u32, y: u32| img.get_pixel(x * cell + cell / 2, (6 - y) * cell + cell / 2).0;
    assert_eq!(px(0, 0), sim::render::PALETTE[0]);
    assert_eq!(px(6, 6), sim::render::PALETTE[1]);
    assert_eq!(px(3, 3), sim::render::PALETTE[2]);
    assert_eq!(px(1, 1), [250, 250, 250]);
}

#[test]
fn ascii_marks_the_held_block_and_shows_the_goal() {
    let mut e = env("1,0,2", "sparse", 10);
    let obs = e
        .reset_to(state(&[(0, 0), (6, 6), (3, 3)], Some(2)), goal("1,0,2"))
        .unwrap();
    let text = sim::render::ascii(&obs, sim::render::Colour::Never);
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines[0].starts_with(" .  .  .  .  .  .  1 "), "{text}");
    assert!(lines[0].ends_with("goal"));
    assert!(lines[3].contains("[2]"));
    // The goal column lists the stack top first: 2, 0, 1.
    let column: Vec<char> = lines[1..4]
        .iter()
        .map(|l| l.trim_end().chars().last().unwrap())
        .collect();
    assert_eq!(column, ['2', '0', '1']);
    assert!(text.ends_with("held: 2\n"));
}

/// A lent result's pairs in place describe the observation it lends, in both autoreset
/// modes, across episode ends (where the outcome's count is the ended episode's).
#[test]
fn vec_step_ref_counts_the_pairs_of_the_observation_it_lends() {
    for mode in [Autoreset::SameStep, Autoreset::NextStep] {
        let config = EnvConfig {
            horizon: 5,
            backend: Backend::Grid,
            ..EnvConfig::default()
        };
        let mut v = VecEnv::new(config, 8, 1).unwrap().with_autoreset(mode);
        v.reset(3);
        let mut slots = vec![(0, 0, false); 8];
        let mut ends = 0;
        for k in 0..40 {
            let actions: Vec<Action> = (0..8).map(|i| Action::from_index((i + k) % 8, 3).unwrap()).collect();
            v.step_with(&actions, &mut slots, |r, slot| {
                let obs = r.observation;
                *slot = (
                    r.pairs_in_place(),
                    obs.goal.pairs_in_place(&obs.state),
                    r.outcome.is_some_and(|o| o.truncated || o.terminated),
                );
            })
            .unwrap();
            for &(lent, counted, ended) in &slots {
                assert_eq!(lent, counted);
                ends += usize::from(ended);
            }
        }
        assert!(ends > 0, "{mode:?}: no episode ended");
    }
}

#[test]
fn vec_env_seeds_each_env_and_resets_in_the_same_step() {
    let config = EnvConfig {
        horizon: 3,
        backend: Backend::Grid,
        ..EnvConfig::with_goal(goal("0,1,2"))
    };
    // One thread steps on the caller's thread, two on a pool: same results.
    for threads in [1, 2] {
        let mut v = VecEnv::new(config.clone(), 4, threads).unwrap();
        let first = v.reset(10);
        for (i, obs) in first.iter().enumerate() {
            assert_eq!(*obs, Env::new(config.clone()).unwrap().reset(10 + i as u64));
        }
        let drops = vec![Action::Drop; 4];
        v.step(&drops).unwrap();
        v.step(&drops).unwrap();
        let last = v.step(&drops).unwrap();
        for (i, s) in last.iter().enumerate() {
            let VecStep::Stepped(s) = s else {
                panic!("same-step autoreset never returns a bare reset")
            };
            assert!(s.truncated);
            assert_eq!(s.info.final_observation.clone().unwrap().state, first[i].state);
            // The returned observation starts the next episode: the env's generator continued.
            let mut solo = Env::new(config.clone()).unwrap();
            solo.reset(10 + i as u64);
            assert_eq!(s.observation, solo.reset(None));
        }
        assert!(matches!(
            v.step(&drops[..3]),
            Err(SimError::ActionCountMismatch { envs: 4, actions: 3 })
        ));
    }
}

#[test]
fn vec_env_in_next_step_mode_returns_the_last_observation_then_resets() {
    let config = EnvConfig {
        horizon: 2,
        backend: Backend::Grid,
        ..EnvConfig::with_goal(goal("0,1,2"))
    };
    for threads in [1, 2] {
        let mut v = VecEnv::new(config.clone(), 3, threads)
            .unwrap()
            .with_autoreset(Autoreset::NextStep);
        let mut solo: Vec<Env> = (0..3).map(|_| Env::new(config.clone()).unwrap()).collect();
        let first = v.reset(4);
        for (i, env) in solo.iter_mut().enumerate() {
            assert_eq!(first[i], env.reset(4 + i as u64));
        }
        let picks = vec![Action::Pick(BlockId(1)); 3];
        v.step(&picks).unwrap();
        let ended = v.step(&[Action::Up, Action::Drop, Action::Left]).unwrap();
        for (i, s) in ended.iter().enumerate() {
            solo[i].step(picks[i]).unwrap();
            let expected = solo[i].step([Action::Up, Action::Drop, Action::Left][i]).unwrap();
            // The step that ends the episode returns its last observation, as a lone env does.
            assert_eq!(*s, VecStep::Stepped(expected.clone()));
            assert!(expected.truncated && expected.info.final_observation.is_none());
        }
        // The next step ignores its action (even a pick) and starts the next episode.
        let reset = v.step(&picks).unwrap();
        for (i, s) in reset.iter().enumerate() {
            assert_eq!(*s, VecStep::Reset(solo[i].reset(None)));
        }
        let again = v.step(&picks).unwrap();
        for (i, s) in again.iter().enumerate() {
            assert_eq!(*s, VecStep::Stepped(solo[i].step(picks[i]).unwrap()));
        }
    }
}

/// A batch large enough to be cut into one chunk per thread (an odd count: chunks of
/// unequal length) plays the same episodes on two threads as on one, in both autoreset
/// modes and on both backends.
#[test]
fn vec_env_chunked_on_two_threads_plays_as_one_thread() {
    let envs = PARALLEL_FROM_ENVS + 3;
    let mut rng = sim::seeding::rng(9);
    let batches: Vec<Vec<Action>> = (0..24)
        .map(|_| {
            (0..envs)
                .map(|_| Action::from_index(rand::RngExt::random_range(&mut rng, 0..Action::count(3)), 3).unwrap())
                .collect()
        })
        .collect();
    for backend in [Backend::Grid, Backend::Physics] {
        for mode in [Autoreset::SameStep, Autoreset::NextStep] {
            let config = EnvConfig {
                horizon: 5,
                backend,
                ..EnvConfig::default()
            };
            let play = |threads: usize| {
                let mut v = VecEnv::new(config.clone(), envs, threads).unwrap().with_autoreset(mode);
                let mut seen = vec![VecStep::Reset(v.reset(3).swap_remove(envs - 1))];
                for actions in &batches {
                    seen.extend(v.step(actions).unwrap());
                }
                seen
            };
            assert_eq!(play(1), play(2), "{backend} {mode:?}");
        }
    }
}

/// A batch is handed out in consecutive ranges covering every environment: one below
/// the threshold or on one thread, one per thread above it; a writer per range sees each of
/// its environments once, by its index in the range, and writes what `step` returns.
#[test]
fn vec_env_hands_each_thread_one_range_and_its_writer_sees_every_env_of_it() {
    let config = EnvConfig {
        backend: Backend::Grid,
        ..EnvConfig::default()
    };
    let big = PARALLEL_FROM_ENVS + 3;
    let ranges = |envs: usize, threads: usize| VecEnv::new(config.clone(), envs, threads).unwrap().chunks();
    assert_eq!(ranges(5, 2), vec![Range { start: 0, end: 5 }]);
    assert_eq!(ranges(big, 1), vec![Range { start: 0, end: big }]);
    assert_eq!(ranges(big, 2), [0..big.div_ceil(2), big.div_ceil(2)..big]);
    let mut v = VecEnv::new(config.clone(), big, 2).unwrap();
    let mut solo = VecEnv::new(config.clone(), big, 1).unwrap();
    v.reset(7);
    solo.reset(7);
    let actions: Vec<Action> = (0..big).map(|i| Action::from_index(i % 8, 3).unwrap()).collect();
    let mut chunks: Vec<Vec<(usize, VecStep)>> = vec![Vec::new(); 2];
    v.step_chunks(&actions, &mut chunks, |chunk, i, step| {
        chunk.push((i, step.to_vec_step()))
    })
    .unwrap();
    let expected = solo.step(&actions).unwrap();
    let mut seen = Vec::new();
    for (range, chunk) in v.chunks().into_iter().zip(chunks) {
        let indices: Vec<usize> = chunk.iter().map(|(i, _)| range.start + i).collect();
        assert_eq!(indices, range.collect::<Vec<_>>());
        seen.extend(chunk.into_iter().map(|(_, step)| step));
    }
    assert_eq!(seen, expected);
}

#[test]
fn vec_env_refuses_to_step_before_reset_and_steps_nothing() {
    let mut v = VecEnv::new(EnvConfig::default(), 2, 1).unwrap();
    assert_eq!(v.step(&[Action::Up, Action::Up]), Err(SimError::NotReset));
    assert!(v.envs().iter().all(|e| e.steps() == 0));
}

/// A world written while it still held the observation kind (`"obs"`, a consumer's choice)
/// reads back, the entry ignored.
#[test]
fn a_world_that_named_its_observation_reads_back() {
    let mut written = serde_json::to_value(EnvConfig::default()).unwrap();
    assert!(written.get("obs").is_none());
    written["obs"] = serde_json::json!("paper-screen");
    let read: EnvConfig = serde_json::from_value(written).unwrap();
    assert_eq!(read, EnvConfig::default());
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// `Env::advance` plays the episode `Env::step` plays, and what it leaves in place (the
    /// current observation, its legal actions) is what `step` returns: in either view, on
    /// either backend, under either protocol, across episode ends.
    #[test]
    fn advance_leaves_in_place_what_step_returns(
        side in proptest::bool::ANY,
        physics in proptest::bool::ANY,
        paper in proptest::bool::ANY,
        blocks in 2usize..=5,
        seed in 0u64..1_000,
        picks in proptest::collection::vec(0usize..64, 1..200),
    ) {
        let config = EnvConfig {
            blocks,
            view: if side { sim::View::Side } else { sim::View::Top },
            backend: if physics { Backend::Physics } else { Backend::Grid },
            protocol: if paper { sim::ActionProtocol::Paper } else { sim::ActionProtocol::Free },
            horizon: 40,
            ..EnvConfig::default()
        };
        let (mut stepped, mut advanced) = (Env::new(config.clone()).unwrap(), Env::new(config).unwrap());
        proptest::prop_assert_eq!(stepped.reset(seed), advanced.reset(seed));
        for pick in picks {
            let mask = stepped.legal_actions();
            let action = mask.nth(pick % mask.count()).unwrap();
            let step = stepped.step(action).unwrap();
            let outcome = advanced.advance(action).unwrap();
            proptest::prop_assert_eq!(
                &outcome.into_step(advanced.current_observation().clone(), advanced.legal_actions()),
                &step
            );
            if step.terminated || step.truncated {
                proptest::prop_assert_eq!(stepped.reset(None), advanced.reset(None));
            }
        }
    }
}
