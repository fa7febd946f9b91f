//! Goals of several towers (docs/world.md, "The side view"): parsing, printing, JSON, what
//! they ask in each view, and trajectory files that record them and the view beside files
//! written before either existed.

use sim::trajectory::{Record, TrajectoryReader};
use sim::{Action, Backend, BlockId, Cell, Env, EnvConfig, Goal, GoalSpec, Grid, RewardModel, SimError, State, View};

#[test]
fn one_tower_goals_read_as_before() {
    let g: Goal = "1,0,2".parse().unwrap();
    assert!(g.is_one_tower());
    assert_eq!(g.block_count(), 3);
    assert_eq!(g.order(), [BlockId(1), BlockId(0), BlockId(2)]);
    assert_eq!(g.to_string(), "1,0,2");
    assert_eq!(serde_json::to_string(&g).unwrap(), "[1,0,2]");
    assert_eq!(serde_json::from_str::<Goal>("[1,0,2]").unwrap(), g);
    assert_eq!(
        g.pairs().collect::<Vec<_>>(),
        [(BlockId(1), BlockId(0)), (BlockId(0), BlockId(2))]
    );
    assert!("0,3".parse::<Goal>().is_err(), "a tower still names every block 0..N");
    assert!(Goal::parse("0,1", Some(3)).is_err());
}

#[test]
fn towers_parse_print_and_round_trip() {
    let g: Goal = "0,1,2/3,4".parse().unwrap();
    assert!(!g.is_one_tower());
    assert_eq!(g.block_count(), 5);
    assert_eq!(g.tower_count(), 2);
    assert_eq!(g.tower_lists(), vec![vec![0, 1, 2], vec![3, 4]]);
    assert_eq!(g.pairs().count(), 3);
    assert_eq!(g.pair_count(), 3);
    assert_eq!(g.to_string(), "0,1,2/3,4");
    let json = serde_json::to_string(&g).unwrap();
    assert_eq!(json, r#"{"towers":[[0,1,2],[3,4]],"blocks":5}"#);
    assert_eq!(serde_json::from_str::<Goal>(&json).unwrap(), g);
    // Unnamed blocks are free; a lone partial tower prints with a trailing '/'.
    let free = Goal::parse("2,0/", Some(4)).unwrap();
    assert_eq!(
        (free.block_count(), free.tower_count(), free.to_string()),
        (4, 1, "2,0/".to_string())
    );
    assert_eq!(
        free.to_string().parse::<Goal>().unwrap().tower_lists(),
        free.tower_lists()
    );
    assert!(!free.names(BlockId(1)));
    for bad in ["0,1/1", "0,x/2", "/", "0,1/5"] {
        assert!(Goal::parse(bad, Some(4)).is_err(), "{bad}");
    }
    let err = g.one_tower("the paper reward").unwrap_err();
    assert_eq!(
        err.to_string(),
        "goal 0,1,2/3,4 is not one tower of every block: the paper reward handles only such goals (e.g. 0,1,2)"
    );
}

#[test]
fn towers_stand_anywhere_from_above_and_on_the_table_from_the_side() {
    let g: Goal = "0,1/2,3".parse().unwrap();
    let at = |cells: [(u16, u16); 4], held: Option<u16>| {
        let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
        State::new(&cells, held.map(BlockId)).unwrap()
    };
    let standing = at([(0, 0), (0, 1), (2, 0), (2, 1)], None);
    assert!(g.holds(&standing) && g.holds_in(View::Side, &standing));
    let raised = at([(0, 3), (0, 4), (2, 0), (2, 1)], None);
    assert!(g.holds(&raised) && !g.holds_in(View::Side, &raised));
    let held = at([(0, 0), (0, 1), (2, 0), (2, 1)], Some(3));
    assert!(
        g.holds(&held) && !g.holds_in(View::Side, &held),
        "a held block stands on nothing"
    );
    // More blocks on top of a tower do not spoil it.
    let g3: Goal = "0/1,2".parse().unwrap();
    assert!(g3.holds_in(View::Side, &at([(0, 0), (3, 0), (3, 1), (3, 2)], None)));
}

#[test]
fn rewards_that_need_one_tower_refuse_towers_and_trivial_goals_are_refused() {
    let towers = GoalSpec::Fixed("0,1/2".parse().unwrap());
    let config = |reward: &str, view| EnvConfig {
        blocks: 3,
        goal: towers.clone(),
        reward: RewardModel::from_name(reward).unwrap(),
        view,
        ..EnvConfig::default()
    };
    for view in [View::Top, View::Side] {
        assert!(Env::new(config("sparse", view)).is_ok());
        assert!(Env::new(config("dense", view)).is_ok());
        assert!(matches!(
            Env::new(config("paper", view)).err(),
            Some(SimError::NotOneTower { .. })
        ));
    }
    let trivial = EnvConfig {
        blocks: 3,
        goal: GoalSpec::Fixed("0/1/2".parse().unwrap()),
        ..EnvConfig::default()
    };
    assert!(Env::new(trivial.clone()).is_err(), "it holds in every state from above");
    assert!(
        Env::new(EnvConfig {
            view: View::Side,
            ..trivial
        })
        .is_ok(),
        "from the side it asks all on the table"
    );
}

#[test]
fn a_towers_episode_in_the_side_view_ends_when_its_towers_stand() {
    let mut env = Env::new(EnvConfig {
        grid: Grid::new(5, 4).unwrap(),
        blocks: 3,
        backend: Backend::Physics,
        view: View::Side,
        goal: GoalSpec::Fixed("1,0/2".parse().unwrap()),
        ..EnvConfig::default()
    })
    .unwrap();
    // 0 on the table, 1 on 0, 2 on 1: take 2 off, then 1, put 0 on 1.
    let start = State::new(&[Cell::new(0, 0), Cell::new(0, 1), Cell::new(0, 2)], None).unwrap();
    env.reset_to(start, env.goal().clone()).unwrap();
    let plan = [
        Action::Pick(BlockId(2)),
        Action::Up,
        Action::Right,
        Action::Right,
        Action::Drop,
        Action::Pick(BlockId(1)),
        Action::Up,
        Action::Up,
        Action::Right,
        Action::Drop,
        Action::Pick(BlockId(0)),
        Action::Up,
        Action::Up,
        Action::Right,
        Action::Drop,
    ];
    for (k, a) in plan.iter().enumerate() {
        let s = env.step(*a).unwrap();
        assert_eq!(
            s.terminated,
            k + 1 == plan.len(),
            "step {k}: {a}, {:?}",
            s.observation.state
        );
    }
}

#[test]
fn trajectory_headers_record_the_view_and_the_towers_and_old_headers_read_as_top() {
    let old = r#"{"type":"episode","episode":0,"seed":1,"grid":[7,7],"goal":[1,0,2],"horizon":1000,"start":[[6,0],[3,5],[0,5]]}"#;
    let record: Record = serde_json::from_str(old).unwrap();
    assert_eq!(
        serde_json::to_string(&record).unwrap(),
        old,
        "top-view headers are written as before"
    );
    let mut env = Env::new(EnvConfig {
        blocks: 3,
        backend: Backend::Grid,
        view: View::Side,
        goal: GoalSpec::Fixed("0/1,2".parse().unwrap()),
        ..EnvConfig::default()
    })
    .unwrap();
    let obs = env.reset(5);
    let mut lines = vec![
        serde_json::to_string(&Record::episode_in(
            View::Side,
            0,
            5,
            obs.grid,
            obs.goal.clone(),
            1000,
            &obs.state,
        ))
        .unwrap(),
    ];
    assert!(
        lines[0].contains(r#""view":"side""#) && lines[0].contains(r#""towers":[[0],[1,2]]"#),
        "{}",
        lines[0]
    );
    let mut mask = obs.legal_actions();
    for k in 0..40 {
        let action = mask.nth(k % mask.count()).unwrap();
        let step = env.step(action).unwrap();
        mask = step.info.action_mask.clone();
        lines.push(serde_json::to_string(&Record::step(0, action.index(), &step)).unwrap());
        if step.terminated || step.truncated {
            break;
        }
    }
    let text = lines.join("\n") + "\n";
    let episodes: Vec<_> = TrajectoryReader::new(text.as_bytes(), "side.jsonl")
        .collect::<Result<_, _>>()
        .unwrap();
    assert_eq!(episodes.len(), 1);
    assert_eq!((episodes[0].view, &episodes[0].goal), (View::Side, &obs.goal));
    assert_eq!(episodes[0].steps.len(), lines.len() - 1);
}

/// The towers of `goal` as a set (their order in the goal does not change what it asks).
fn tower_set(goal: &Goal) -> std::collections::BTreeSet<Vec<usize>> {
    goal.tower_lists().into_iter().collect()
}

#[test]
fn all_towers_lists_every_split_of_the_blocks_once() {
    for (blocks, count) in [(2, 3), (3, 13), (4, 73), (5, 501)] {
        let goals = Goal::all_towers(blocks).unwrap();
        assert_eq!(goals.len(), count, "{blocks} blocks");
        let sets: std::collections::BTreeSet<_> = goals.iter().map(tower_set).collect();
        assert_eq!(sets.len(), count, "no goal twice, whatever its towers' order");
        assert!(goals.iter().all(|g| g.order().len() == blocks), "every block named");
        assert_eq!(goals[..(1..=blocks).product::<usize>()], Goal::all(blocks).unwrap()[..]);
    }
    assert!(Goal::all_towers(3).unwrap().contains(&"0,1/2".parse().unwrap()));
    assert!(Goal::all_towers(3).unwrap().contains(&"0/1/2".parse().unwrap()));
    assert!(matches!(Goal::all_towers(7), Err(SimError::TooManyGoals { .. })));
    assert!(Goal::all_towers(100).is_err());
}

#[test]
fn random_towers_draws_every_goal_of_that_many_towers_alike_and_by_seed() {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut counts = std::collections::BTreeMap::new();
    for _ in 0..6000 {
        let g = Goal::random_towers(3, 2, &mut rng).unwrap();
        assert_eq!(g.tower_count(), 2);
        *counts.entry(g.to_string()).or_insert(0) += 1;
    }
    let two_towers: Vec<String> = Goal::all_towers(3)
        .unwrap()
        .iter()
        .filter(|g| g.tower_count() == 2)
        .map(|g| g.to_string())
        .collect();
    assert_eq!(counts.keys().cloned().collect::<Vec<_>>().len(), two_towers.len());
    assert!(two_towers.iter().all(|g| counts.contains_key(g)), "{counts:?}");
    assert!(counts.values().all(|&n| (850..1150).contains(&n)), "{counts:?}");
    let draw = |seed| {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..20)
            .map(|_| Goal::random_towers(8, 3, &mut rng).unwrap())
            .collect::<Vec<_>>()
    };
    assert_eq!(draw(3), draw(3));
    assert!(Goal::random_towers(3, 0, &mut rng).is_err());
    assert!(Goal::random_towers(3, 4, &mut rng).is_err());
}

#[test]
fn shapes_give_one_goal_for_each_split_into_towers() {
    let text = |n| {
        Goal::shapes(n)
            .unwrap()
            .iter()
            .map(|g| g.to_string())
            .collect::<Vec<_>>()
    };
    assert_eq!(text(2), ["0,1", "0/1"]);
    assert_eq!(text(3), ["0,1,2", "0,1/2", "0/1/2"]);
    assert_eq!(text(4), ["0,1,2,3", "0,1,2/3", "0,1/2,3", "0,1/2/3", "0/1/2/3"]);
    assert_eq!(Goal::shapes(10).unwrap().len(), 42, "the partitions of 10");
    assert!(Goal::shapes(17).is_err());
    assert!(Goal::shapes(0).is_err());
}
