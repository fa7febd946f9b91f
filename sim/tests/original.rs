//! The paper's world as its authors coded it (docs/world.md section 10): the action protocols and their
//! masks, the paper start rule, the reward-above termination, and `paper-code` on
//! hand-computed states, through the environment and on both backends.

use sim::reward::{PaperCode, Transition};
use sim::{
    Action, ActionMask, ActionProtocol, Backend, BlockId, Cell, Env, EnvConfig, Goal, GoalSpec, Grid,
    PARALLEL_FROM_ENVS, Profile, ProfileParts, RewardModel, SimError, StartRule, State, Step, Termination, VecEnv,
    VecStep,
};

fn goal(text: &str) -> Goal {
    text.parse().unwrap()
}

fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
    let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
    State::new(&cells, held.map(BlockId)).unwrap()
}

/// The world of the `original` profile on a fixed goal.
fn original_config(goal_text: &str, backend: Backend) -> EnvConfig {
    EnvConfig {
        backend,
        ..ProfileParts::of(Profile::Original).apply(EnvConfig::with_goal(goal(goal_text)))
    }
}

/// An environment of the `original` profile on a fixed goal.
fn original(goal_text: &str, backend: Backend) -> Env {
    Env::new(original_config(goal_text, backend)).unwrap()
}

const BACKENDS: [Backend; 2] = [Backend::Grid, Backend::Physics];

fn actions(mask: ActionMask) -> Vec<Action> {
    mask.iter().collect()
}

#[test]
fn masks_on_hand_built_states_for_both_protocols_and_backends() {
    let moves_and_drop = [Action::Up, Action::Down, Action::Left, Action::Right, Action::Drop];
    let picks: Vec<Action> = (0..3).map(|b| Action::Pick(BlockId(b))).collect();
    for backend in BACKENDS {
        for protocol in [ActionProtocol::Free, ActionProtocol::Paper] {
            let mut env = Env::new(EnvConfig {
                backend,
                protocol,
                ..EnvConfig::with_goal(goal("0,1,2"))
            })
            .unwrap();
            let empty = env
                .reset_to(state(&[(0, 0), (3, 3), (6, 6)], None), goal("0,1,2"))
                .unwrap();
            let holding = state(&[(0, 0), (3, 3), (6, 6)], Some(1));
            let (when_empty, when_holding) = match protocol {
                ActionProtocol::Free => (Action::all(3).collect::<Vec<_>>(), Action::all(3).collect()),
                ActionProtocol::Paper => (picks.clone(), moves_and_drop.to_vec()),
            };
            assert_eq!(actions(env.legal_actions()), when_empty, "{backend} {protocol}");
            assert_eq!(actions(empty.legal_actions()), when_empty);
            // Picking block 1: the step's mask is that of the state after it.
            let step = env.step(Action::Pick(BlockId(1))).unwrap();
            assert_eq!(step.observation.state, holding);
            assert_eq!(
                actions(step.info.action_mask.clone()),
                when_holding,
                "{backend} {protocol}"
            );
            assert_eq!(actions(env.legal_actions()), when_holding);
            assert_eq!(step.observation.legal_actions(), step.info.action_mask);
            // Every action of the mask is one the environment takes.
            for a in step.info.action_mask.iter() {
                let mut probe = env.clone();
                assert!(probe.step(a).is_ok(), "{backend} {protocol} {a}");
            }
            let dropped = env.step(Action::Drop).unwrap();
            assert_eq!(actions(dropped.info.action_mask), when_empty);
        }
    }
}

#[test]
fn an_illegal_action_under_paper_is_an_error_that_changes_nothing() {
    for backend in BACKENDS {
        let mut env = original("0,1,2", backend);
        let start = state(&[(0, 1), (3, 3), (5, 5)], None);
        env.reset_to(start.clone(), goal("0,1,2")).unwrap();
        for illegal in [Action::Up, Action::Down, Action::Left, Action::Right, Action::Drop] {
            assert_eq!(
                env.step(illegal),
                Err(SimError::IllegalAction {
                    action: illegal,
                    held: None,
                    protocol: ActionProtocol::Paper
                })
            );
        }
        assert_eq!((env.steps(), env.state(), env.is_over()), (0, start, false));
        env.step(Action::Pick(BlockId(2))).unwrap();
        let holding = env.state();
        let err = env.step(Action::Pick(BlockId(0))).unwrap_err();
        assert_eq!(
            err.to_string(),
            "pick 0 is not legal under the paper action protocol while block 2 is held: only up, down, left, right and drop are allowed"
        );
        assert_eq!((env.steps(), env.state(), env.is_over()), (1, holding, false));
        // The episode goes on as if the illegal actions had never been tried.
        assert_eq!(env.step(Action::Left).unwrap().info.steps, 2);
        assert_eq!(env.state().cell(BlockId(2)), Cell::new(4, 5));
    }
}

#[test]
fn the_paper_start_rule_draws_from_the_corner_and_reaches_all_of_it() {
    // 7x7: columns 0..=5 and rows 1..=6, never x = 6 or y = 0.
    let mut env = Env::new(EnvConfig {
        backend: Backend::Grid,
        start: StartRule::Paper,
        ..EnvConfig::default()
    })
    .unwrap();
    let mut seen = std::collections::HashSet::new();
    for seed in 0..6000 {
        let obs = env.reset(seed);
        assert_eq!(obs.held_block(), None);
        for (b, &c) in obs.blocks().iter().enumerate() {
            assert!(c.x < 6 && c.y >= 1, "seed {seed}: block {b} at {c}");
            seen.insert((b, c));
        }
    }
    // Every block started on every one of the corner's 36 cells.
    assert_eq!(seen.len(), 3 * 36);
}

#[test]
fn paper_starts_meet_the_goal_at_the_expected_rate_and_end_on_the_first_action() {
    // 2 blocks on 7x7: the first block uniform on the 36 corner cells, the second on the
    // other 35; the goal holds for the 30 ordered placements of the upper block directly on
    // the lower one within the corner (6 columns x 5 row pairs): 30 / (36 x 35) = 1/42.
    let expected_rate = 30.0 / (36.0 * 35.0);
    let resets = 42_000;
    let mut env = Env::new(EnvConfig {
        backend: Backend::Grid,
        blocks: 2,
        start: StartRule::Paper,
        ..EnvConfig::default()
    })
    .unwrap();
    let mut met = Vec::new();
    for seed in 0..resets {
        let obs = env.reset(seed);
        if obs.goal.holds(&obs.state) {
            met.push(seed);
            // Kept, and running.
            assert!(!env.is_over());
        }
    }
    // Expected 1000 of 42,000 with a standard deviation of about 31: a 15 % band is more
    // than four of them, and the seeds are fixed.
    let rate = met.len() as f64 / resets as f64;
    assert!(
        (rate / expected_rate - 1.0).abs() < 0.15,
        "rate {rate}, expected {expected_rate}"
    );

    // Such a start ends, terminated, on its first action: under the paper protocol a Pick,
    // which moves nothing. The paper-code reward pays the standing pair on that step.
    for backend in BACKENDS {
        let mut env = Env::new(EnvConfig {
            backend,
            blocks: 2,
            ..Profile::Original.world()
        })
        .unwrap();
        let obs = env.reset(met[0]);
        assert!(obs.goal.holds(&obs.state));
        let step = env.step(obs.legal_actions().nth(0).unwrap()).unwrap();
        assert!(step.terminated && !step.truncated);
        assert_eq!((step.info.steps, step.reward), (1, 50.0));
        assert_eq!(env.step(Action::Drop), Err(SimError::EpisodeOver));
    }
    // The uniform rule never starts on the goal, and reset_to of a state meeting the goal
    // is over at once, as before.
    let mut uniform = Env::new(EnvConfig {
        backend: Backend::Grid,
        blocks: 2,
        ..EnvConfig::default()
    })
    .unwrap();
    assert!((0..resets).all(|seed| {
        let obs = uniform.reset(seed);
        !obs.goal.holds(&obs.state)
    }));
    let mut paper = original("0,1", Backend::Grid);
    paper.reset_to(state(&[(2, 2), (2, 3)], None), goal("0,1")).unwrap();
    assert!(paper.is_over());
}

#[test]
fn the_paper_start_rule_refuses_grids_it_cannot_fill() {
    // The corner of a W x H grid is (W - 1) x (H - 1) cells.
    let config = EnvConfig {
        grid: Grid::new(3, 3).unwrap(),
        blocks: 3,
        goal: GoalSpec::Random,
        start: StartRule::Paper,
        ..EnvConfig::default()
    };
    assert!(Env::new(config.clone()).is_ok(), "a 2x2 corner holds 3 blocks");
    // 2x5: a 1x4 corner, four cells for five blocks.
    let too_small = EnvConfig {
        grid: Grid::new(2, 5).unwrap(),
        blocks: 5,
        ..config.clone()
    };
    let err = Env::new(too_small).err().unwrap();
    assert_eq!(
        err,
        SimError::StartDoesNotFit {
            rule: StartRule::Paper,
            cells: 4,
            blocks: 5,
            width: 2,
            height: 5
        }
    );
    assert!(err.to_string().contains("uniform start rule"), "{err}");
    let one_column = EnvConfig {
        grid: Grid::new(1, 5).unwrap(),
        blocks: 2,
        ..config
    };
    assert!(matches!(
        Env::new(one_column),
        Err(SimError::StartDoesNotFit { cells: 0, .. })
    ));
}

#[test]
fn reward_above_ends_on_the_reward_not_on_the_goal() {
    for backend in BACKENDS {
        let config = |termination| EnvConfig {
            termination,
            ..original_config("0,1,2", backend)
        };
        // 1 stands on 0; 2 is held diagonally above 1. Left puts 2 on 1: d of (1, 2) falls
        // from 3125 to 625 (+1) and both pairs stand (+100): 101 > 70.
        let start = state(&[(3, 1), (3, 2), (4, 3)], Some(2));
        let mut env = Env::new(config(Termination::paper_training())).unwrap();
        env.reset_to(start, goal("0,1,2")).unwrap();
        let step = env.step(Action::Left).unwrap();
        assert_eq!((step.reward, step.terminated), (101.0, true), "{backend}");

        // Two blocks: reaching the goal pays 1 + 50, never above 70, so the game goes on.
        let mut two = Env::new(EnvConfig {
            blocks: 2,
            goal: GoalSpec::Fixed(goal("0,1")),
            horizon: 4,
            ..config(Termination::paper_training())
        })
        .unwrap();
        two.reset_to(state(&[(3, 1), (4, 2)], Some(1)), goal("0,1")).unwrap();
        let reached = two.step(Action::Left).unwrap();
        assert!(reached.observation.goal.holds(&reached.observation.state));
        assert_eq!((reached.reward, reached.terminated), (51.0, false));
        // Dropping changes the tuple while the pair stands: +50, still not above 70.
        let dropped = two.step(Action::Drop).unwrap();
        assert_eq!((dropped.reward, dropped.terminated), (50.0, false));
        two.step(Action::Pick(BlockId(0))).unwrap();
        let last = two.step(Action::Up).unwrap();
        assert!(last.truncated && !last.terminated);

        // A start meeting the goal runs under reward-above, and ends at once under goal.
        let stacked = state(&[(3, 1), (3, 2)], None);
        two.reset_to(stacked.clone(), goal("0,1")).unwrap();
        assert!(!two.is_over());
        let mut by_goal = Env::new(EnvConfig {
            blocks: 2,
            goal: GoalSpec::Fixed(goal("0,1")),
            ..config(Termination::Goal)
        })
        .unwrap();
        by_goal.reset_to(stacked, goal("0,1")).unwrap();
        assert!(by_goal.is_over());
        // Under goal termination, the step that reaches the goal ends the episode.
        by_goal
            .reset_to(state(&[(3, 1), (4, 2)], Some(1)), goal("0,1"))
            .unwrap();
        let step = by_goal.step(Action::Left).unwrap();
        assert_eq!((step.reward, step.terminated), (51.0, true));
    }
}

fn paper_code(goal: &Goal, before: &State, action: Action, after: &State) -> f64 {
    RewardModel::PaperCode(PaperCode::default()).reward(&Transition {
        grid: Grid::default(),
        view: sim::View::Top,
        goal,
        before,
        action,
        previous_action: None,
        after,
    })
}

/// `paper-code` on hand-computed steps. Pair distances `d` (squared pixels from the lower
/// block's centre to the upper block's bottom-edge midpoint): 625 stacked, 3125 beside or
/// diagonally above, 5625 with the upper block directly below or two cells above.
#[test]
fn paper_code_rewards_hand_computed_steps() {
    let g = goal("0,1");
    let close = |a: f64, b: f64| (a - b).abs() < 1e-12;
    // Block 1 held at (4, 4), block 0 at (2, 2): d = 100^2 + 75^2 = 15625. Left: d =
    // 50^2 + 75^2 = 8125, fell: +1; the tuple changed but no pair stands: nothing more.
    let far = state(&[(2, 2), (4, 4)], Some(1));
    let nearer = state(&[(2, 2), (3, 4)], Some(1));
    assert_eq!(paper_code(&g, &far, Action::Left, &nearer), 1.0);
    assert_eq!(paper_code(&g, &nearer, Action::Right, &far), -5.0);
    // Diagonally above (3125) to beside (3125): d equal, but the heading changed ('u' to
    // '-'), so the tuple changed: 0, not the blocked-move penalty.
    let diagonal = state(&[(2, 2), (3, 3)], Some(1));
    let beside = state(&[(2, 2), (3, 2)], Some(1));
    assert_eq!(paper_code(&g, &diagonal, Action::Down, &beside), 0.0);
    // A blocked move leaves the tuple as it was: -0.1.
    let walled = state(&[(2, 2), (0, 4)], Some(1));
    assert!(close(paper_code(&g, &walled, Action::Left, &walled), -0.1));
    // Reaching the goal: d 3125 -> 625 (+1), one pair in place (+50).
    let stacked = state(&[(2, 2), (2, 3)], Some(1));
    assert_eq!(paper_code(&g, &diagonal, Action::Left, &stacked), 51.0);
    // Moving off the stack and back while it stands: +50 on every state-changing step.
    let above_two = state(&[(2, 2), (2, 4)], Some(1));
    assert_eq!(paper_code(&g, &stacked, Action::Up, &above_two), -5.0);
    assert_eq!(paper_code(&g, &above_two, Action::Down, &stacked), 51.0);

    // Drops: far (d > 5000) costs 0.1, near does not; a standing pair pays +50 because
    // the tuple changed (held -> nothing held).
    let drop = |s: &State| paper_code(&g, s, Action::Drop, &s.with_held(None).unwrap());
    assert!(close(drop(&far), -0.1));
    assert!(close(drop(&above_two), -0.1), "5625 is far");
    let below = state(&[(2, 2), (2, 1)], Some(1));
    assert!(close(drop(&below), -0.1), "5625 is far");
    assert_eq!(drop(&beside), 0.0);
    assert_eq!(drop(&stacked), 50.0);
    // Picks: no move term; the tuple changes; +50 if a pair stands.
    let pick = |s: &State| paper_code(&g, s, Action::Pick(BlockId(0)), &s.with_held(Some(BlockId(0))).unwrap());
    assert_eq!(pick(&far.with_held(None).unwrap()), 0.0);
    assert_eq!(pick(&stacked.with_held(None).unwrap()), 50.0);

    // Three blocks: a pair standing elsewhere pays on each move of the third block.
    let g3 = goal("0,1,2");
    let before = state(&[(1, 1), (1, 2), (5, 5)], Some(2));
    let after = state(&[(1, 1), (1, 2), (4, 5)], Some(2));
    // d of (1, 2): 200^2 + 125^2 = 55625 -> 150^2 + 125^2 = 38125: +1, and +50.
    assert_eq!(paper_code(&g3, &before, Action::Left, &after), 51.0);
    // The middle block held: its pair is (1, 2), not (0, 1); moving it off the stack
    // breaks the standing pair: d of (1, 2) grows (-5), no pair stands.
    let middle = state(&[(1, 1), (1, 2), (5, 5)], Some(1));
    let off = state(&[(1, 1), (0, 2), (5, 5)], Some(1));
    assert_eq!(paper_code(&g3, &middle, Action::Left, &off), -5.0);
}

#[test]
fn paper_code_is_the_reward_of_the_original_profile_s_env() {
    for backend in BACKENDS {
        let mut env = original("0,1", backend);
        // Block 1 held on the top row: d = 100^2 + 175^2, then 50^2 + 175^2 after Left.
        env.reset_to(state(&[(2, 2), (4, 6)], Some(1)), goal("0,1")).unwrap();
        assert_eq!(env.step(Action::Left).unwrap().reward, 1.0);
        let blocked = env.step(Action::Up).unwrap();
        assert!(blocked.info.blocked);
        assert!((blocked.reward - -0.1).abs() < 1e-12);
    }
}

/// The steps of a same-step `VecEnv`, which never returns a bare reset.
fn stepped(steps: Vec<VecStep>) -> Vec<Step> {
    steps
        .into_iter()
        .map(|s| match s {
            VecStep::Stepped(step) => step,
            VecStep::Reset(_) => panic!("same-step autoreset never returns a bare reset"),
        })
        .collect()
}

#[test]
fn vec_env_masks_and_autoresets_under_paper() {
    let config = EnvConfig {
        horizon: 3,
        ..original_config("0,1,2", Backend::Grid)
    };
    for threads in [1, 2] {
        let mut v = VecEnv::new(config.clone(), 3, threads).unwrap();
        let first = v.reset(20);
        let picks: Vec<Action> = (0..3).map(|b| Action::Pick(BlockId(b))).collect();
        for obs in &first {
            assert_eq!(actions(obs.legal_actions()), picks);
        }
        // An illegal action in one environment: an error, and no environment stepped.
        let mixed = [Action::Pick(BlockId(0)), Action::Up, Action::Pick(BlockId(2))];
        assert_eq!(
            v.step(&mixed).unwrap_err(),
            SimError::IllegalAction {
                action: Action::Up,
                held: None,
                protocol: ActionProtocol::Paper
            }
        );
        assert!(v.envs().iter().all(|e| e.steps() == 0));
        let picked = stepped(v.step(&[Action::Pick(BlockId(0)); 3]).unwrap());
        for s in &picked {
            assert_eq!(s.info.action_mask, s.observation.legal_actions());
            assert_eq!(s.info.action_mask.count(), 5);
        }
        v.step(&[Action::Up; 3]).unwrap();
        // The third step reaches the horizon: each environment resets in the same step. The
        // mask is that of the new episode's first observation (nothing held: picks), while
        // the ended episode's last observation still holds block 0.
        let last = stepped(v.step(&[Action::Down; 3]).unwrap());
        for (i, s) in last.iter().enumerate() {
            assert!(s.truncated || s.terminated, "env {i}");
            let ended = s.info.final_observation.clone().unwrap();
            assert_eq!(ended.held_block(), Some(BlockId(0)));
            assert_eq!(actions(ended.legal_actions()).len(), 5);
            assert_eq!(actions(s.info.action_mask.clone()), picks);
            assert_eq!(s.info.action_mask, v.envs()[i].legal_actions());
        }
    }
}

/// On two threads a large batch is checked chunk by chunk in parallel: the error is still
/// the first refusal in environment order, and no environment steps.
#[test]
fn vec_env_on_two_threads_reports_the_first_refusal_and_steps_nothing() {
    let config = original_config("0,1,2", Backend::Grid);
    let envs = PARALLEL_FROM_ENVS + 1;
    for threads in [1, 2] {
        let mut v = VecEnv::new(config.clone(), envs, threads).unwrap();
        v.reset(0);
        // Nothing is held at the start: only picks are legal. The refusals are in both
        // halves of the batch; the first is reported.
        let mut actions = vec![Action::Pick(BlockId(0)); envs];
        actions[envs / 2 - 10] = Action::Left;
        actions[envs - 1] = Action::Up;
        assert_eq!(
            v.step(&actions).unwrap_err(),
            SimError::IllegalAction {
                action: Action::Left,
                held: None,
                protocol: ActionProtocol::Paper
            },
            "{threads} thread(s)"
        );
        assert!(v.envs().iter().all(|e| e.steps() == 0));
    }
}

/// Actions given as indices are converted on the threads that step them: a value out of
/// range is refused as a refused action is, the first in environment order, and nothing
/// steps; in range, the batch steps as the converted actions would.
#[test]
fn vec_env_converts_action_values_where_it_steps_them() {
    let config = original_config("0,1,2", Backend::Grid);
    let envs = PARALLEL_FROM_ENVS + 1;
    let convert = |&i: &i64| match usize::try_from(i) {
        Ok(i) => Action::from_index(i, 3),
        Err(_) => Err(SimError::ActionOutOfRange {
            index: usize::MAX,
            blocks: 3,
        }),
    };
    for threads in [1, 2] {
        let mut v = VecEnv::new(config.clone(), envs, threads).unwrap();
        v.reset(0);
        let mut chunks = vec![(); v.chunks().len()];
        // Nothing is held: Left is refused in the first half, 9 is out of range in the
        // second; with the refusal moved after it, the value is the first error.
        let mut values = vec![5i64; envs];
        values[envs - 3] = 9;
        for (left_at, expected) in [
            (
                envs / 2 - 10,
                SimError::IllegalAction {
                    action: Action::Left,
                    held: None,
                    protocol: ActionProtocol::Paper,
                },
            ),
            (envs - 1, SimError::ActionOutOfRange { index: 9, blocks: 3 }),
        ] {
            let mut with_left = values.clone();
            with_left[left_at] = 2;
            let e = v
                .step_chunks_of(&with_left, convert, &mut chunks, |_, _, _| {})
                .unwrap_err();
            assert_eq!(e, expected, "{threads} thread(s)");
            assert!(v.envs().iter().all(|e| e.steps() == 0));
        }
        let picks: Vec<Action> = vec![Action::Pick(BlockId(0)); envs];
        let mut by_index = VecEnv::new(config.clone(), envs, threads).unwrap();
        by_index.reset(0);
        let stepped = std::sync::Mutex::new(0);
        by_index
            .step_chunks_of(&vec![5i64; envs], convert, &mut chunks, |_, _, _| {
                *stepped.lock().unwrap() += 1
            })
            .unwrap();
        v.step(&picks).unwrap();
        assert_eq!(*stepped.lock().unwrap(), envs);
        let states = |v: &VecEnv| v.envs().iter().map(|e| e.state().clone()).collect::<Vec<_>>();
        assert_eq!(states(&by_index), states(&v));
    }
}
