//! The Q-learner: its update, what training teaches it, and determinism (model files:
//! `tests/model.rs`).

use agent::{AgentError, Assist, Policy, Progress, QAgent, QParams, ReprKind, TrainConfig, Trainer};
use sim::seeding::rng;
use sim::{
    Action, ActionProtocol, Backend, BlockId, Cell, Env, EnvConfig, Goal, GoalSpec, Grid, Observation, RewardModel,
    State,
};

fn goal(text: &str) -> Goal {
    text.parse().unwrap()
}

/// Our role + step-cost learner, on the grid backend (quick enough for tests).
fn role_config(goals: &[&str], games: u64, seed: u64) -> TrainConfig {
    TrainConfig {
        games,
        seed,
        ..TrainConfig::role_step_cost(goals.iter().map(|g| goal(g)).collect())
    }
    .with_backend(Backend::Grid)
}

#[test]
fn the_update_matches_a_hand_computed_mdp() {
    // A 1 x 3 column, goal 0,1: block 0 at the bottom, 1 at the top. Pick 1, then Down
    // reaches the goal. Step cost -1 (0 on the step that reaches the goal), alpha 0.5,
    // gamma 0.9, every value starting at 1.
    let grid = Grid::new(1, 3).unwrap();
    let g = goal("0,1");
    let params = QParams {
        alpha: 0.5,
        gamma: 0.9,
        epsilon: 0.0,
        initial_q: 1.0,
    };
    let mut q = QAgent::new(ReprKind::Raw, grid, 2, params).unwrap();
    let mut env = Env::new(EnvConfig {
        grid,
        blocks: 2,
        goal: GoalSpec::Fixed(g.clone()),
        reward: RewardModel::from_name("step-cost").unwrap(),
        backend: Backend::Grid,
        ..EnvConfig::default()
    })
    .unwrap();
    let start = State::new(&[Cell::new(0, 0), Cell::new(0, 2)], None).unwrap();
    let mut episode = |q: &mut QAgent| -> (Observation, Observation) {
        let s0 = env.reset_to(&start, &g).unwrap();
        let step = env.step(Action::Pick(BlockId(1))).unwrap();
        assert_eq!(step.reward, -1.0);
        q.update(
            &s0,
            Action::Pick(BlockId(1)),
            step.reward,
            &step.observation,
            step.terminated,
        )
        .unwrap();
        let s1 = step.observation;
        let step = env.step(Action::Down).unwrap();
        assert!(step.terminated);
        assert_eq!(step.reward, 0.0);
        q.update(&s1, Action::Down, step.reward, &step.observation, true)
            .unwrap();
        (s0, s1)
    };
    let close = |a: f32, b: f64| (f64::from(a) - b).abs() < 1e-6;

    let (s0, s1) = episode(&mut q);
    // Q(s0, pick 1) = 0.5 * 1 + 0.5 * (-1 + 0.9 * max Q(s1) = 1) = 0.45
    assert!(close(q.q(&s0, Action::Pick(BlockId(1))).unwrap(), 0.45));
    // Q(s1, down) = 0.5 * 1 + 0.5 * 0 (the goal ends the episode: no future) = 0.5
    assert!(close(q.q(&s1, Action::Down).unwrap(), 0.5));
    // Nothing else moved.
    assert!(close(q.q(&s0, Action::Drop).unwrap(), 1.0));
    assert!(close(q.q(&s1, Action::Up).unwrap(), 1.0));

    episode(&mut q);
    // max Q(s1) is still 1 (up, left, ...): Q(s0, pick 1) = 0.5 * 0.45 + 0.5 * (-0.1) = 0.175
    assert!(close(q.q(&s0, Action::Pick(BlockId(1))).unwrap(), 0.175));
    // Q(s1, down) = 0.5 * 0.5 + 0 = 0.25
    assert!(close(q.q(&s1, Action::Down).unwrap(), 0.25));
}

#[test]
fn greedy_choice_breaks_ties_at_random_and_follows_the_table() {
    let grid = Grid::default();
    let g = goal("0,1,2");
    let mut q = QAgent::new(ReprKind::Role, grid, 3, QParams::default()).unwrap();
    let state = State::new(&[Cell::new(3, 0), Cell::new(3, 1), Cell::new(3, 3)], None).unwrap();
    let obs = Observation {
        grid,
        state,
        goal: g,
        protocol: ActionProtocol::Free,
        view: sim::View::Top,
    };
    let mut r = rng(5);
    let seen: std::collections::HashSet<Action> = (0..200).map(|_| q.greedy_action(&obs, &mut r).unwrap()).collect();
    assert_eq!(seen.len(), 8, "all-equal values: every action is chosen sometimes");
    q.set_q(&obs, Action::Pick(BlockId(2)), 1.0).unwrap();
    assert!((0..50).all(|_| q.greedy_action(&obs, &mut r).unwrap() == Action::Pick(BlockId(2))));
    // The role table stores the pick of block 2 in the column of goal place 2: renaming the
    // goal moves the preference with the block that stands at that place.
    let values = q.q_values(&obs).unwrap();
    assert_eq!(values[Action::Pick(BlockId(2)).index()], 1.0);
    assert_eq!(values.iter().filter(|&&v| v == 0.0).count(), 7);
}

#[test]
fn a_trained_agent_finishes_an_easy_stack() {
    let trained = agent::train(&role_config(&["0,1,2"], 30_000, 1), None).unwrap();
    let q = &trained.agent;
    let grid = Grid::default();
    // 0 and 1 stacked at the bottom of column 3, 2 one cell above the stack.
    let cells = [Cell::new(3, 0), Cell::new(3, 1), Cell::new(3, 3)];
    let held = Observation {
        grid,
        state: State::new(&cells, Some(BlockId(2))).unwrap(),
        goal: goal("0,1,2"),
        protocol: ActionProtocol::Free,
        view: sim::View::Top,
    };
    let free = Observation {
        state: held.state.with_held(None).unwrap(),
        ..held.clone()
    };
    let mut r = rng(3);
    assert_eq!(q.greedy_action(&held, &mut r).unwrap(), Action::Down);
    assert_eq!(q.greedy_action(&free, &mut r).unwrap(), Action::Pick(BlockId(2)));
    // Trained on 0,1,2 only, the role agent does the same for a goal it never saw: the
    // same picture with the blocks renamed.
    let unseen = Observation {
        state: State::new(&[Cell::new(3, 3), Cell::new(3, 0), Cell::new(3, 1)], Some(BlockId(0))).unwrap(),
        goal: goal("1,2,0"),
        grid,
        protocol: ActionProtocol::Free,
        view: sim::View::Top,
    };
    assert_eq!(q.greedy_action(&unseen, &mut r).unwrap(), Action::Down);
}

#[test]
fn same_seed_same_table_and_evaluation() {
    let config = TrainConfig {
        games: 300,
        ..TrainConfig::paper(vec![goal("0,1,2"), goal("2,0,1")])
    }
    .with_backend(Backend::Grid);
    let a = agent::train(&config, None).unwrap();
    let b = agent::train(&config, None).unwrap();
    assert_eq!(a.agent, b.agent);
    assert_eq!(a.report, b.report);
    let c = agent::train(
        &TrainConfig {
            seed: 2,
            ..config.clone()
        },
        None,
    )
    .unwrap();
    assert_ne!(a.agent.table(), c.agent.table());

    let evaluate = |q: &QAgent| {
        let mut env = Env::new(EnvConfig {
            backend: Backend::Grid,
            ..EnvConfig::with_goal(goal("1,2,0"))
        })
        .unwrap();
        let mut policy = q.policy(0.1).unwrap();
        agent::play(&mut env, &mut policy, 20, 9, &mut ()).unwrap()
    };
    assert_eq!(evaluate(&a.agent), evaluate(&b.agent));
}

#[test]
fn physics_and_grid_training_give_the_same_agent() {
    let grid_run = role_config(&["1,0,2"], 2000, 4);
    let physics_run = TrainConfig { ..grid_run.clone() }.with_backend(Backend::Physics);
    let a = agent::train(&grid_run, None).unwrap();
    let b = agent::train(&physics_run, None).unwrap();
    assert_eq!(a.agent.table(), b.agent.table());
    assert_eq!(a.report, b.report);
}

#[test]
fn training_reports_progress_after_every_game() {
    let mut trainer = Trainer::new(role_config(&["0,1,2"], 0, 1)).unwrap();
    let mut seen: Vec<Progress> = Vec::new();
    trainer
        .play_games(150, Some(&mut |p: &Progress| seen.push(*p)))
        .unwrap();
    assert_eq!(seen.len(), 150);
    assert!(
        seen.iter()
            .enumerate()
            .all(|(i, p)| p.games_played == i as u64 + 1 && p.games_target == 150)
    );
    let last = seen.last().unwrap();
    assert_eq!(last.recent.games, 100);
    assert!(last.recent.successes <= 100);
    // Playing on continues the same run: 150 + 50 games equal 200 in one go.
    trainer.play_games(50, None).unwrap();
    let snapshot = trainer.snapshot();
    let split = trainer.finish();
    assert_eq!(snapshot.agent, split.agent);
    assert_eq!(snapshot.report, split.report);
    let whole = agent::train(&role_config(&["0,1,2"], 200, 1), None).unwrap();
    assert_eq!(split.agent, whole.agent);
    assert_eq!(split.agent.training().unwrap().games, 200);
}

#[test]
fn the_oracle_assists_as_asked_and_the_table_learns_its_actions() {
    let base = TrainConfig {
        games: 200,
        ..TrainConfig::paper(vec![goal("0,1,2"), goal("2,1,0")])
    }
    .with_backend(Backend::Grid);
    let run = |assist| agent::train(&TrainConfig { assist, ..base.clone() }, None).unwrap();
    let none = run(Assist::None);
    assert_eq!(none.report.assisted_steps, 0);
    let oscillation = run(Assist::Oscillation);
    assert!(oscillation.report.assisted_steps > 0);
    assert!(oscillation.report.assisted_steps < oscillation.report.steps / 10);
    let chance = run(Assist::OscillationOrChance { p: 0.1 });
    assert!(chance.report.assisted_steps > chance.report.steps / 20);
    assert_eq!(
        chance.agent,
        run(Assist::OscillationOrChance { p: 0.1 }).agent,
        "deterministic"
    );
    // Handing every step to the oracle: every game reaches the goal on the oracle's plan
    // (about ten steps from a random start), and the table learns from those steps.
    let always = run(Assist::OscillationOrChance { p: 1.0 });
    assert_eq!(always.report.successes, 200);
    assert_eq!(always.report.assisted_steps, always.report.steps);
    assert!(always.report.steps < 200 * 20);
    assert_ne!(always.agent.table(), none.agent.table());
}

#[test]
fn agents_and_training_cross_threads() {
    fn send<T: Send>() {}
    fn sync<T: Sync>() {}
    send::<Trainer>();
    send::<QAgent>();
    sync::<QAgent>();
    send::<TrainConfig>();
}

#[test]
fn bad_configs_are_errors_not_panics() {
    let base = TrainConfig::paper(vec![goal("0,1,2")]);
    let message = |c: TrainConfig| Trainer::new(c).err().expect("an error").to_string();
    assert!(
        message(TrainConfig {
            goals: vec![],
            ..base.clone()
        })
        .contains("no goals")
    );
    let params = QParams {
        alpha: 0.0,
        ..QParams::default()
    };
    assert!(message(TrainConfig { params, ..base.clone() }).contains("alpha 0"));
    assert!(
        message(TrainConfig {
            goals: vec![goal("0,1")],
            ..base.clone()
        })
        .contains("block counts differ")
    );
    let q = QAgent::new(ReprKind::Role, Grid::default(), 3, QParams::default()).unwrap();
    let two = Observation {
        grid: Grid::default(),
        state: State::new(&[Cell::new(0, 0), Cell::new(1, 1)], None).unwrap(),
        goal: goal("0,1"),
        protocol: ActionProtocol::Free,
        view: sim::View::Top,
    };
    assert!(matches!(q.key(&two), Err(AgentError::ModelMismatch(_))));
    let mut r = rng(0);
    assert!(q.policy(1.5).is_err());
    assert!(q.choose_action(&two, 0.0, &mut r).is_err());
}

#[test]
fn a_model_for_another_world_is_refused() {
    let trained = agent::train(&role_config(&["0,1,2"], 10, 2), None).unwrap();
    let q = trained.agent;
    assert!(q.check_world(Grid::default(), 3).is_ok());
    let err = q.check_world(Grid::default(), 4).unwrap_err().to_string();
    assert!(err.contains("3 blocks") && err.contains("4 blocks"), "{err}");
    assert!(q.check_world(Grid::new(8, 8).unwrap(), 3).is_err());
    // Playing it in the wrong world is an error from the episode runner, not a panic.
    let mut env = Env::new(EnvConfig {
        backend: Backend::Grid,
        ..EnvConfig::with_goal(goal("0,1"))
    })
    .unwrap();
    let mut policy = q.policy(0.0).unwrap();
    assert!(agent::play(&mut env, &mut policy, 1, 0, &mut ()).is_err());
    assert_eq!(policy.name(), "q-role");
}
