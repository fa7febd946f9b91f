//! The learners, oracles and demonstrators of the `original` profile: every policy keeps to
//! the action protocol, the `paper-code` schedule updates as the authors' code did, and a
//! model trained under `original` remembers it.

use crate::common::temp_path;

use agent::correction::{CorrectionConfig, CorrectionRule, person_steps, session_world};
use agent::demonstrator::DemonstratorPlanner;
use agent::{
    Assist, DemoRecord, Demonstrator, DemonstratorProfile, ExactPolicy, OraclePolicy, PaperOraclePolicy, Policy,
    QAgent, QParams, RandomPolicy, ReprKind, Schedule, Summary, TrainConfig,
};
use proptest::prelude::*;
use sim::{
    Action, ActionProtocol, Backend, BlockId, Cell, Env, EnvConfig, Goal, Grid, Observation, Profile, State,
    Termination,
};

fn goal(text: &str) -> Goal {
    text.parse().unwrap()
}

fn obs(cells: &[(u16, u16)], held: Option<u16>, goal: Goal, protocol: ActionProtocol) -> Observation {
    let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
    Observation {
        grid: Grid::default(),
        state: State::new(&cells, held.map(BlockId)).unwrap(),
        goal,
        protocol,
        view: sim::View::Top,
    }
}

fn paper_agent(params: QParams) -> QAgent {
    QAgent::with_schedule(ReprKind::ChasingCode, Grid::default(), 3, params, Schedule::PaperCode).unwrap()
}

// --- The `paper-code` update on hand-built steps ---------------------------------------

#[test]
fn the_bootstrap_reads_only_the_actions_seen_in_the_next_state() {
    let g = goal("0,1,2");
    let s = obs(&[(0, 0), (3, 3), (6, 6)], Some(0), g.clone(), ActionProtocol::Paper);
    let next = obs(&[(0, 1), (3, 3), (6, 6)], Some(0), g.clone(), ActionProtocol::Paper);
    let mut a = paper_agent(QParams::default());
    // Nothing seen in s': Q(s, up) = r.
    assert_eq!(a.update(&s, Action::Up, 1.0, &next, false).unwrap(), 1.0);
    // One action seen in s', valued -3: the max over seen actions is -3, though the unseen
    // ones read 0 (the spec rule would take 0).
    a.set_q(&next, Action::Left, -3.0).unwrap();
    assert_eq!(a.update(&s, Action::Up, 1.0, &next, false).unwrap(), 1.0 + 0.1 * -3.0);
    let mut spec = QAgent::new(ReprKind::ChasingCode, Grid::default(), 3, QParams::default()).unwrap();
    spec.set_q(&next, Action::Left, -3.0).unwrap();
    assert_eq!(spec.update(&s, Action::Up, 1.0, &next, false).unwrap(), 1.0);
    // After a Drop the bootstrap is 0, whatever the next state has seen.
    let dropped = obs(&[(0, 0), (3, 3), (6, 6)], None, g, ActionProtocol::Paper);
    a.set_q(&dropped, Action::Pick(BlockId(1)), 40.0).unwrap();
    assert_eq!(a.update(&s, Action::Drop, -0.1, &dropped, false).unwrap(), -0.1);
    a.set_q(&next, Action::Right, 40.0).unwrap();
    assert_eq!(a.update(&s, Action::Up, 1.0, &next, false).unwrap(), 1.0 + 0.1 * 40.0);
}

#[test]
fn the_taken_entry_is_seen_before_the_bootstrap_reads_it() {
    // A blocked move leaves the tuple as it was: s' = s. The authors' code stored the entry
    // (at 0) before taking the max over s', so the second time it bootstraps from itself.
    let g = goal("0,1,2");
    let s = obs(&[(0, 0), (3, 3), (6, 6)], Some(0), g, ActionProtocol::Paper);
    let mut a = paper_agent(QParams::default());
    assert_eq!(a.update(&s, Action::Left, -0.1, &s, false).unwrap(), -0.1);
    let second = a.update(&s, Action::Left, -0.1, &s, false).unwrap();
    assert_eq!(second, (-0.1f64 + 0.1 * f64::from(-0.1f32)) as f32);
}

#[test]
fn the_step_that_ends_the_game_sets_the_entry_to_its_reward() {
    let g = goal("0,1,2");
    let s = obs(&[(3, 1), (3, 2), (4, 3)], Some(2), g.clone(), ActionProtocol::Paper);
    let done = obs(&[(3, 1), (3, 2), (3, 3)], Some(2), g, ActionProtocol::Paper);
    let mut a = paper_agent(QParams::default());
    a.set_q(&done, Action::Up, 500.0).unwrap();
    assert_eq!(a.update(&s, Action::Left, 101.0, &done, true).unwrap(), 101.0);
    // At alpha 0.5: (1 - alpha) Q + alpha r.
    let mut half = paper_agent(QParams {
        alpha: 0.5,
        ..QParams::default()
    });
    half.set_q(&s, Action::Left, 4.0).unwrap();
    assert_eq!(half.update(&s, Action::Left, 100.0, &done, true).unwrap(), 52.0);
}

#[test]
fn a_training_game_ends_at_a_reward_above_70_only() {
    // The training world of the original profile: 3 blocks, one move from the goal.
    let config = TrainConfig::original(vec![goal("0,1,2")]);
    assert_eq!(config.world.horizon, 5000);
    let mut env = Env::new(EnvConfig {
        backend: Backend::Grid,
        ..config.env_config(goal("0,1,2"))
    })
    .unwrap();
    assert_eq!(env.config().termination, Termination::RewardAbove(70.0));
    let start = State::new(&[Cell::new(3, 1), Cell::new(3, 2), Cell::new(4, 3)], Some(BlockId(2))).unwrap();
    env.reset_to(start, goal("0,1,2")).unwrap();
    let step = env.step(Action::Left).unwrap();
    assert!(step.reward > 70.0 && step.terminated, "{step:?}");
    // Two blocks: the goal pays 50 per step and never ends a training game.
    let two = TrainConfig::original(vec![goal("0,1")]);
    assert_eq!(two.world.horizon, 1000);
    let mut env = Env::new(EnvConfig {
        backend: Backend::Grid,
        ..two.env_config(goal("0,1"))
    })
    .unwrap();
    env.reset_to(
        State::new(&[Cell::new(3, 1), Cell::new(4, 2)], Some(BlockId(1))).unwrap(),
        goal("0,1"),
    )
    .unwrap();
    let step = env.step(Action::Left).unwrap();
    assert!(step.reward >= 50.0 && !step.terminated, "{step:?}");
}

// --- Training under the original profile -----------------------------------------------

fn small_original(goals: &[&str], games: u64, seed: u64) -> TrainConfig {
    let base = TrainConfig::original(goals.iter().map(|g| goal(g)).collect()).with_backend(Backend::Grid);
    TrainConfig {
        games,
        seed,
        world: EnvConfig {
            horizon: 400,
            ..base.world
        },
        ..base
    }
}

#[test]
fn the_paper_learner_trains_in_the_authors_world_and_is_fixed_by_its_seed() {
    let config = small_original(&["0,1,2", "2,1,0", "1,2,0"], 12, 4);
    let a = agent::train(&config, None).unwrap();
    let b = agent::train(&config, None).unwrap();
    assert_eq!(a.agent, b.agent);
    assert_eq!(a.report, b.report);
    assert_eq!(a.agent.schedule(), Schedule::PaperCode);
    assert!(a.agent.table().tracks_seen() && !a.agent.table().seen_entries().is_empty());
    let c = agent::train(&TrainConfig { seed: 5, ..config }, None).unwrap();
    assert_ne!(a.agent, c.agent);
}

#[test]
fn paper_assistance_uses_the_walker_and_stays_legal() {
    for oracle in [agent::OracleKind::Paper, agent::OracleKind::Astar] {
        let config = TrainConfig {
            assist: Assist::OscillationOrChance { p: 0.3 },
            oracle,
            ..small_original(&["0,1,2"], 6, 2)
        };
        let trained = agent::train(&config, None).unwrap();
        assert!(trained.report.assisted_steps > 0, "{oracle}");
    }
}

#[test]
fn replays_belong_to_the_spec_schedule() {
    let config = TrainConfig {
        final_replay: true,
        ..small_original(&["0,1,2"], 1, 1)
    };
    let err = agent::train(&config, None).unwrap_err().to_string();
    assert!(err.contains("spec schedule"), "{err}");
}

#[test]
fn a_model_trained_under_original_remembers_its_world_and_seen_entries() {
    let trained = agent::train(&small_original(&["0,1,2", "1,0,2"], 5, 9), None).unwrap();
    let path = temp_path("original.safetensors");
    trained.agent.save(&path).unwrap();
    let loaded = QAgent::load(&path).unwrap();
    assert_eq!(loaded, trained.agent, "values and seen entries");
    assert_eq!(loaded.schedule(), Schedule::PaperCode);
    let t = loaded.training().unwrap();
    assert_eq!(
        (t.profile, t.world.protocol, t.world.start, t.world.reward.name()),
        (
            Profile::Original,
            ActionProtocol::Paper,
            sim::StartRule::Paper,
            "paper-code"
        )
    );
    // The world a correction session of it plays in is the authors'.
    let world = session_world(&loaded);
    assert_eq!(
        (world.protocol, world.horizon, world.termination),
        (ActionProtocol::Paper, 5000, Termination::RewardAbove(70.0))
    );
}

// --- Corrections as coded --------------------------------------------------------------

#[test]
fn corrections_as_coded_get_the_plain_update_and_replay_to_the_same_table() {
    let base = agent::train(&small_original(&["0,1,2", "2,1,0"], 4, 3), None)
        .unwrap()
        .agent;
    let mut preset = DemonstratorProfile::preset(2).unwrap();
    preset.takeover = 0.3;
    let config = CorrectionConfig {
        world: Some(EnvConfig {
            backend: Backend::Grid,
            horizon: 300,
            ..session_world(&base)
        }),
        ..CorrectionConfig::new(preset, agent::correction::demonstrated_goals(), 4, 6)
    };
    let out = agent::correct(base.clone(), &config, Vec::<DemoRecord>::new()).unwrap();
    assert!(out.report.corrections > 0);
    let DemoRecord::Session(session) = &out.sink[0] else {
        panic!("a session line first")
    };
    assert_eq!(session.rule, CorrectionRule::as_coded(), "the original profile's rule");
    assert_eq!(session.rule.margin, None);
    let mut replayed = base;
    agent::demos::learn_from_records(&mut replayed, &out.sink).unwrap();
    assert_eq!(replayed, out.agent);
}

#[test]
fn a_person_changes_blocks_by_a_drop_and_a_pick_under_paper() {
    let g = goal("0,1,2");
    let holding = obs(&[(0, 0), (3, 3), (6, 6)], Some(0), g.clone(), ActionProtocol::Paper);
    let pick = Action::Pick(BlockId(2));
    assert_eq!(person_steps(&holding, pick).unwrap(), [Action::Drop, pick]);
    assert!(person_steps(&holding, Action::Pick(BlockId(0))).unwrap().is_empty());
    assert_eq!(person_steps(&holding, Action::Up).unwrap(), [Action::Up]);
    let empty = obs(&[(0, 0), (3, 3), (6, 6)], None, g, ActionProtocol::Paper);
    let err = person_steps(&empty, Action::Up).unwrap_err().to_string();
    assert!(err.contains("only pick N is allowed"), "{err}");
    assert!(person_steps(&empty, Action::Pick(BlockId(7))).is_err());
    // Under free every action is taken as it is.
    let free = Observation {
        protocol: ActionProtocol::Free,
        ..holding
    };
    assert_eq!(person_steps(&free, pick).unwrap(), [pick]);
}

// --- Every policy keeps to the protocol -------------------------------------------------

/// A state of 3 blocks on 7 x 7 from `picks` (indices into the free cells), holding `held`
/// (3: nothing).
fn state_from(picks: &[usize], held: usize) -> State {
    let mut free: Vec<Cell> = Grid::default().cells().collect();
    let cells: Vec<Cell> = picks.iter().map(|&p| free.remove(p % free.len())).collect();
    State::new(&cells, (held < 3).then_some(BlockId::of(held))).unwrap()
}

fn legal(o: &Observation, a: Action) -> Result<(), TestCaseError> {
    prop_assert!(
        o.legal_actions().contains(a),
        "{a} in {:?} held {:?}",
        o.state,
        o.held_block()
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn no_policy_proposes_an_illegal_action_under_paper(
        picks in prop::collection::vec(0usize..1000, 3), held in 0usize..4, g in 0usize..6,
        values in prop::collection::vec(-5.0f32..5.0, 8), seed in 0u64..1000,
    ) {
        let goal = Goal::all(3).unwrap()[g].clone();
        let state = state_from(&picks, held);
        prop_assume!(!goal.holds(&state));
        let o = Observation { grid: Grid::default(), state, goal, protocol: ActionProtocol::Paper, view: sim::View::Top };
        let mut rng = sim::seeding::rng(seed);
        let grid = o.grid;
        let mut policies: Vec<Box<dyn Policy>> = vec![
            Box::new(RandomPolicy),
            Box::new(OraclePolicy::new(grid)),
            Box::new(ExactPolicy::new(grid)),
            Box::new(PaperOraclePolicy::new(grid)),
        ];
        for p in &mut policies {
            p.begin_episode(&o);
            for _ in 0..5 {
                legal(&o, p.act(&o, &mut rng).unwrap())?;
            }
        }
        // Q-learners with random values in the state's row, greedy and not, over every
        // representation (role renames its pick columns).
        for kind in ReprKind::ALL {
            let mut q = QAgent::new(kind, grid, 3, QParams::default()).unwrap();
            for (i, &v) in values.iter().enumerate() {
                q.set_q(&o, Action::from_index(i, 3).unwrap(), v).unwrap();
            }
            for epsilon in [0.0, 0.5, 1.0] {
                legal(&o, q.choose_action(&o, epsilon, &mut rng).unwrap())?;
            }
            legal(&o, q.greedy_action(&o, &mut rng).unwrap())?;
        }
        // Demonstrators that always step in, both planners, slipping or not.
        for (planner, slip) in [(DemonstratorPlanner::Exact, 0.0), (DemonstratorPlanner::Oracle, 0.0), (DemonstratorPlanner::Exact, 1.0), (DemonstratorPlanner::Oracle, 1.0)] {
            let profile = DemonstratorProfile {
                name: "test".into(),
                attention: 1.0,
                notices_loops: true,
                takeover: 1.0,
                planner,
                slip,
            };
            let mut d = Demonstrator::new(profile, grid);
            d.begin_episode(&o, seed);
            let proposed = RandomPolicy.act(&o, &mut rng).unwrap();
            let chosen = d.review(&o, proposed).unwrap().expect("a demonstrator that always takes over");
            legal(&o, chosen)?;
        }
    }
}

#[test]
fn under_free_a_q_agent_draws_as_before_protocols() {
    // With every action legal the masked choice is the unmasked one: the same draws, so the
    // same actions, from the same generator.
    let g = goal("1,0,2");
    let o = obs(&[(0, 0), (3, 3), (6, 6)], Some(1), g.clone(), ActionProtocol::Free);
    let mut q = QAgent::new(ReprKind::Role, Grid::default(), 3, QParams::default()).unwrap();
    q.set_q(&o, Action::Up, 2.0).unwrap();
    q.set_q(&o, Action::Pick(BlockId(2)), 2.0).unwrap();
    let mut rng = sim::seeding::rng(8);
    let mut again = sim::seeding::rng(8);
    let drawn: Vec<Action> = (0..300).map(|_| q.choose_action(&o, 0.3, &mut rng).unwrap()).collect();
    // The draw made before protocols existed: a coin, then an index among all 8 columns, or
    // a tie among the two best columns.
    use rand::RngExt;
    let expected: Vec<Action> = (0..300)
        .map(|_| {
            let column = if again.random_bool(0.3) {
                again.random_range(0..8)
            } else {
                let best = [Action::Up.index(), 5 + g.place_of(BlockId(2))];
                best[again.random_range(0..2)]
            };
            q.action_of_column(&g, column)
        })
        .collect();
    assert_eq!(drawn, expected);
}

#[test]
fn planners_play_the_authors_world_to_the_goal_legally() {
    let config = EnvConfig {
        backend: Backend::Grid,
        ..Profile::Original.world()
    };
    let grid = config.grid;
    let mut env = Env::new(config).unwrap();
    let exact = agent::play(&mut env, &mut ExactPolicy::new(grid), 40, 3, &mut ()).unwrap();
    let oracle = agent::play(&mut env, &mut OraclePolicy::new(grid), 40, 3, &mut ()).unwrap();
    assert_eq!(Summary::of(&exact).failures, 0);
    assert_eq!(Summary::of(&oracle).failures, 0);
    let solver = oracle::ExactSolver::new(grid).with_protocol(ActionProtocol::Paper);
    for (e, o) in exact.iter().zip(&oracle) {
        assert_eq!(e.start, o.start);
        if !e.goal.holds(&e.start) {
            assert_eq!(e.steps, solver.distance(&e.start, &e.goal).unwrap());
        }
        assert!(o.steps >= e.steps);
    }
    // The paper's oracle plays too (it may get stuck: the episodes end either way).
    let walker = agent::play(&mut env, &mut PaperOraclePolicy::new(grid), 40, 3, &mut ()).unwrap();
    assert!(Summary::of(&walker).failures < 40);
}
