//! The relational policy (`dqn --preset general`): its network file round-trips and says
//! what is wrong with a bad one, it refuses the top view in one line, every move it makes is
//! legal whatever its weights, and the same seed trains the same bytes on one thread or two.

use neural::AnyModel;
use neural::relational::{RelationalConfig, RelationalModel, RelationalNet, Shape};
use oracle::towers::{Table, TowerGoal, Towers, random_goal, random_state};
use proptest::prelude::*;
use sim::{Env, EnvConfig, View};

/// A run of a few seconds: a small network, few steps.
fn tiny(seed: u64) -> RelationalConfig {
    RelationalConfig {
        shape: Shape {
            width: 6,
            hidden: 8,
            score_hidden: 8,
            rounds: 2,
        },
        seed,
        problems: 300,
        iterations: 2,
        steps: 40,
        rollouts: 30,
        batch: 16,
        ..RelationalConfig::general()
    }
}

fn trained(seed: u64) -> RelationalModel {
    RelationalModel::train(&tiny(seed), &mut |_| {}).unwrap()
}

#[test]
fn the_network_file_round_trips_and_plays_the_same_moves() {
    let model = trained(3);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("general.safetensors");
    model.save(&path).unwrap();
    let read = RelationalModel::load(&path).unwrap();
    assert_eq!(read.config(), model.config());
    assert_eq!(read.report(), model.report());
    assert_eq!(read.net().params(), model.net().params());
    for seed in 0..20 {
        let n = 3 + seed as usize % 20;
        let start = random_state(n, seed);
        let goal = TowerGoal::new(&random_state(n, seed + 100).towers()).unwrap();
        assert_eq!(read.play(&start, &goal).unwrap(), model.play(&start, &goal).unwrap());
    }
    // AnyModel knows the format, and names the relational policy.
    let any = AnyModel::load(&path).unwrap();
    assert!(matches!(any, AnyModel::Relational(_)));
    assert!(any.name().starts_with("relational policy"), "{}", any.name());
    assert_eq!(any.world().view, View::Side);
}

#[test]
fn a_bad_file_is_refused_with_what_is_wrong() {
    let model = trained(4);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("general.safetensors");
    model.save(&path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let truncated = dir.path().join("truncated");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let missing = dir.path().join("missing");
    for bad in [truncated, missing] {
        let e = RelationalModel::load(&bad).unwrap_err().to_string();
        assert!(e.starts_with("cannot read network") && !e.contains('\n'), "{e}");
    }
}

#[test]
fn the_top_view_is_refused_in_one_line() {
    let model = trained(5);
    let mut env = Env::new(EnvConfig::default()).unwrap();
    let obs = env.reset(1);
    let mut policy = model.policy(0.0).unwrap();
    let e = policy
        .block_move(&obs, &mut sim::seeding::rng(0))
        .unwrap_err()
        .to_string();
    assert!(e.contains("plays the side view") && !e.contains('\n'), "{e}");
    let any = AnyModel::Relational(Box::new(model));
    assert!(
        any.legal_q_values(&obs).is_err(),
        "it scores block moves, not gripper actions"
    );
}

#[test]
fn it_plays_the_side_view_through_the_gripper() {
    let model = trained(6);
    let mut env = Env::new(EnvConfig {
        view: View::Side,
        blocks: 4,
        ..EnvConfig::default()
    })
    .unwrap();
    let mut policy = model.policy(0.0).unwrap();
    // Whatever it reaches, every action it takes is one the world accepts.
    let results = agent::play(&mut env, &mut policy, 5, 3, &mut ()).unwrap();
    assert_eq!(results.len(), 5);
}

#[test]
fn the_same_seed_trains_the_same_bytes_on_one_thread_or_two() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = |threads: usize, seed: u64| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let model = pool.install(|| trained(seed));
        let path = dir.path().join(format!("{threads}-{seed}"));
        model.save(&path).unwrap();
        std::fs::read(&path).unwrap()
    };
    let one = bytes(1, 7);
    assert_eq!(one, bytes(2, 7));
    assert_ne!(one, bytes(1, 8), "another seed, another network");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Whatever its weights, the policy's move is legal, on an unbounded table or a table
    /// of few columns (where a move to the table needs a free one).
    #[test]
    fn every_move_is_legal(weights in 0u64..1000, n in 1usize..40, seed in 0u64..1000, partial: bool, columns in 1usize..8) {
        let net = RelationalNet::new(tiny(0).shape, &mut sim::seeding::rng(weights)).unwrap();
        let mut policy = neural::relational::MovePolicy::new(&net);
        let goal = if partial {
            random_goal(n, 1, n.min(2), seed).unwrap()
        } else {
            TowerGoal::new(&random_state(n, seed + 1).towers()).unwrap()
        };
        let mut state: Towers = random_state(n, seed);
        for table in [Table::Unbounded, Table::Columns(columns.max(state.tower_count()))] {
            for _ in 0..n {
                match policy.choose(&state, &goal, table) {
                    Some(mv) => state.apply(mv, table).unwrap(),
                    None => {
                        prop_assert!(goal.holds(&state) || state.moves(table).is_empty());
                        break;
                    }
                }
            }
        }
    }
}
