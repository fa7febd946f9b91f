//! The learner end to end, at sizes that run in seconds: a tiny run learns, a network file
//! gives back the same network, and the same seed gives the same weights.

use agent::{RandomPolicy, Summary};
use neural::{DemoSource, Dqn, DqnConfig, NetConfig, NetKind, Trainer};
use sim::{Backend, Env, Goal};

/// DQfD on 2 blocks with a small network: 150 exact demonstrations, then a little self-play.
fn tiny(seed: u64) -> DqnConfig {
    DqnConfig {
        seed,
        demos: DemoSource::Exact(150),
        pretrain_steps: 400,
        steps: 600,
        learning_starts: 100,
        net: NetConfig {
            hidden: 64,
            ..NetConfig::small()
        },
        ..DqnConfig::preset(neural::Preset::DqfdPlanes, 2).unwrap()
    }
}

fn weights(dqn: &Dqn) -> Vec<Vec<f32>> {
    dqn.net().tensors().map(|t| t.values.to_vec()).collect()
}

/// Failures and mean steps (a failure counted as the horizon) over 40 seeded games of each
/// goal, in the grid world, horizon 200.
fn score(policy: &mut dyn agent::Policy) -> (usize, f64) {
    let mut all = Vec::new();
    for goal in Goal::all(2).unwrap() {
        let mut env = Env::new(sim::EnvConfig {
            backend: Backend::Grid,
            horizon: 200,
            ..sim::EnvConfig::with_goal(goal)
        })
        .unwrap();
        all.extend(agent::play(&mut env, policy, 40, 77, &mut ()).unwrap());
    }
    let s = Summary::of(&all);
    (s.failures, agent::optimality::mean_steps_failures_as_horizon(&all, 200))
}

#[test]
fn a_tiny_run_lowers_its_loss_and_beats_random_play() {
    let mut trainer = Trainer::new(tiny(3)).unwrap();
    let mut losses = Vec::new();
    trainer
        .pretrain(400, &mut |p: &neural::Progress| losses.push(p.loss.total))
        .unwrap();
    let first: f32 = losses[..20].iter().sum::<f32>() / 20.0;
    let last: f32 = losses[losses.len() - 20..].iter().sum::<f32>() / 20.0;
    assert!(last < 0.75 * first, "the loss fell from {first} to {last}");
    trainer.play(600, &mut |_: &neural::Progress| {}).unwrap();
    let dqn = trainer.finish().unwrap();
    let (random_failures, random_steps) = score(&mut RandomPolicy);
    let (failures, steps) = score(&mut dqn.policy(0.0).unwrap());
    assert!(
        failures < random_failures && steps < 0.5 * random_steps,
        "greedy: {failures} failures, {steps} mean steps; random: {random_failures}, {random_steps}"
    );
}

#[test]
fn the_same_seed_gives_the_same_weights_and_another_seed_others() {
    let run = |seed| {
        let config = DqnConfig {
            pretrain_steps: 50,
            steps: 150,
            learning_starts: 50,
            ..tiny(seed)
        };
        neural::train(config, &mut |_: &neural::Progress| {}).unwrap()
    };
    let (a, b, c) = (run(5), run(5), run(6));
    assert_eq!(weights(&a), weights(&b));
    assert_eq!(a.report(), b.report());
    assert_ne!(weights(&a), weights(&c));
}

#[test]
fn a_network_file_gives_back_the_same_network() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    // The paper network, trained a few steps so its batch-norm statistics moved.
    let config = DqnConfig {
        demos: DemoSource::Exact(5),
        pretrain_steps: 2,
        steps: 0,
        batch: 8,
        loss: neural::LossKind::Dqfd,
        ..DqnConfig::preset(neural::Preset::Paper, 2).unwrap()
    };
    assert_eq!(config.net.kind, NetKind::Paper);
    for (name, config) in [("paper", config), ("small", tiny(1))] {
        let trained = Trainer::new(DqnConfig {
            pretrain_steps: 2,
            steps: 0,
            ..config
        })
        .unwrap()
        .run(&mut |_: &neural::Progress| {})
        .unwrap();
        let path = dir.join(format!("{name}.safetensors"));
        trained.save(&path).unwrap();
        let loaded = Dqn::load(&path).unwrap();
        assert_eq!(weights(&loaded), weights(&trained), "{name}");
        assert_eq!(loaded.config(), trained.config());
        assert_eq!(loaded.report(), trained.report());
        let mut env = Env::new(sim::EnvConfig::with_goal("1,0".parse().unwrap())).unwrap();
        let obs = env.reset(4);
        assert_eq!(loaded.q_values(&obs).unwrap(), trained.q_values(&obs).unwrap());
        // A 3-block world is refused by a 2-block network.
        let mut three = Env::new(sim::EnvConfig::default()).unwrap();
        assert!(loaded.q_values(&three.reset(1)).is_err());
    }
    // A file whose config names another network does not load.
    let small = dir.join("small.safetensors");
    let expect = files::Expect {
        format: neural::model::FORMAT,
        version: neural::model::VERSION,
        max_bytes: neural::model::MAX_NETWORK_BYTES,
        what: "a network file",
    };
    let container = files::Container::read(&small, &expect).unwrap();
    let metadata: serde_json::Value = container.metadata().unwrap();
    let metadata: serde_json::Value =
        serde_json::from_str(&metadata.to_string().replace("\"hidden\":64", "\"hidden\":32")).unwrap();
    let names = container.names();
    let tensors: Vec<(&str, files::Tensor<'_>)> = names
        .iter()
        .map(|n| (n.as_str(), container.tensor(n).unwrap()))
        .collect();
    let bytes = files::container::to_bytes(neural::model::FORMAT, neural::model::VERSION, &metadata, &tensors).unwrap();
    let bad = dir.join("bad.safetensors");
    std::fs::write(&bad, bytes).unwrap();
    let err = Dqn::load(&bad).err().unwrap().to_string();
    assert!(err.contains("bad.safetensors") && err.contains("does not fit"), "{err}");
}

#[test]
fn hindsight_stores_the_games_again_and_is_seeded() {
    let config = |hindsight| DqnConfig {
        seed: 5,
        steps: 3_000,
        learning_starts: 500,
        hindsight,
        net: NetConfig {
            hidden: 32,
            ..NetConfig::small()
        },
        ..DqnConfig::preset(neural::Preset::HerPlanes, 2).unwrap()
    };
    let quiet = &mut |_: &neural::Progress| {};
    let her = Trainer::new(config(4)).unwrap().run(quiet).unwrap();
    let again = Trainer::new(config(4)).unwrap().run(quiet).unwrap();
    let plain = Trainer::new(config(0)).unwrap().run(quiet).unwrap();
    // Random play on 2 blocks builds stacks: up to 4 relabelled copies of most steps.
    assert!(her.report().relabelled > 3_000, "{:?}", her.report());
    assert_eq!(plain.report().relabelled, 0);
    assert_eq!(weights(&her), weights(&again), "same seed, same network");
    assert_ne!(weights(&her), weights(&plain));
    // The network file keeps the setting.
    let path = std::env::temp_dir().join(format!("blockstack-her-{}.safetensors", std::process::id()));
    her.save(&path).unwrap();
    let loaded = Dqn::load(&path).unwrap();
    std::fs::remove_file(&path).unwrap();
    assert_eq!((loaded.config(), loaded.report()), (her.config(), her.report()));
}
