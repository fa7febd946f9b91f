//! Training checkpoints: a run written at any step (in pre-training, between games, in the
//! middle of a game) and resumed ends with the same network file, byte for byte, as a run
//! that never stopped; a checkpoint read back and written again gives the same bytes.

use std::path::Path;

use neural::checkpoint::CHECKPOINT_FORMAT;
use neural::{DemoSource, DqnConfig, NetConfig, OptimizerKind, Preset, TargetEvery, Trainer};
use sim::Backend;

fn quiet() -> impl FnMut(&neural::Progress) {
    |_: &neural::Progress| {}
}

fn out(path: &Path) -> files::OutputPath {
    files::OutputPath::check(path).unwrap()
}

/// DQfD with corrections on 2 blocks, a small network (the recommended recipe, shrunk).
fn dqfd() -> DqnConfig {
    DqnConfig {
        seed: 4,
        demos: DemoSource::Exact(40),
        pretrain_steps: 60,
        steps: 400,
        learning_starts: 50,
        batch: 16,
        net: NetConfig {
            hidden: 32,
            ..NetConfig::small()
        },
        ..DqnConfig::preset(Preset::DqfdPlanes, 2).unwrap()
    }
}

/// The configs checked: DQfD with loop corrections; DQN with hindsight relabelling on the
/// physics backend and a small ring (it wraps); the paper's network with batch
/// normalisation, RMSprop and the target refreshed every 3 games.
fn configs() -> Vec<(&'static str, DqnConfig)> {
    let mut her = DqnConfig {
        seed: 9,
        steps: 500,
        learning_starts: 40,
        buffer: 300,
        batch: 16,
        net: NetConfig {
            hidden: 32,
            ..NetConfig::small()
        },
        ..DqnConfig::preset(Preset::HerPlanes, 2).unwrap()
    };
    her.world.backend = Backend::Physics;
    her.world.horizon = 60;
    let paper = DqnConfig {
        seed: 2,
        steps: 40,
        learning_starts: 8,
        batch: 4,
        optimizer: OptimizerKind::Rmsprop,
        target_every: TargetEvery::Games(3),
        ..DqnConfig::preset(Preset::Paper, 2).unwrap()
    };
    let mut paper = paper;
    paper.world.horizon = 12;
    vec![("dqfd", dqfd()), ("her", her), ("paper", paper)]
}

#[test]
fn a_run_resumed_at_any_step_ends_with_the_same_network_file() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for (name, config) in configs() {
        let whole = dir.join(format!("{name}-whole.st"));
        Trainer::new(config.clone())
            .unwrap()
            .run(&mut quiet())
            .unwrap()
            .save(&whole)
            .unwrap();
        let total = config.pretrain_steps + config.steps;
        // In pre-training (if any), early in self-play, and late (mid-game, most likely).
        for stop in [config.pretrain_steps / 2, config.pretrain_steps + 7, total - 13] {
            let ck = dir.join(format!("{name}-{stop}.ck"));
            let mut trainer = Trainer::new(config.clone()).unwrap();
            trainer.train_until(stop, &mut quiet()).unwrap();
            trainer.write_checkpoint(&out(&ck)).unwrap();
            drop(trainer);
            let resumed = Trainer::resume(&ck).unwrap();
            assert_eq!(resumed.steps_done(), stop, "{name} at {stop}");
            // Read back and written again: the same bytes.
            let again = dir.join(format!("{name}-{stop}-again.ck"));
            resumed.write_checkpoint(&out(&again)).unwrap();
            assert!(
                std::fs::read(&ck).unwrap() == std::fs::read(&again).unwrap(),
                "{name} at {stop}: the checkpoint read and written again differs"
            );
            let path = dir.join(format!("{name}-{stop}.st"));
            resumed.run(&mut quiet()).unwrap().save(&path).unwrap();
            assert!(
                std::fs::read(&whole).unwrap() == std::fs::read(&path).unwrap(),
                "{name}: stopped at step {stop} of {total} and resumed, the network differs"
            );
        }
    }
}

#[test]
fn a_checkpoint_mid_game_holds_the_game() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let config = dqfd();
    let mut trainer = Trainer::new(config.clone()).unwrap();
    // The first self-play game of a barely trained network runs for a while.
    trainer.train_until(config.pretrain_steps + 3, &mut quiet()).unwrap();
    let ck = dir.join("ck");
    trainer.write_checkpoint(&out(&ck)).unwrap();
    let c = files::Container::read(
        &ck,
        &files::Expect {
            format: CHECKPOINT_FORMAT,
            version: 1,
            max_bytes: 1 << 30,
            what: "a checkpoint",
        },
    )
    .unwrap();
    assert_eq!(c.tensor("game").map(|t| t.shape().to_vec()), Some(vec![3]));
    let meta: serde_json::Value = c.metadata().unwrap();
    assert_eq!(meta["report"]["steps"], 3);
    assert_eq!(meta["report"]["pretrain_steps"], config.pretrain_steps);
}

#[test]
fn a_file_that_is_not_a_checkpoint_is_refused_with_a_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let config = dqfd();
    let model = dir.join("m.st");
    Trainer::new(config.clone())
        .unwrap()
        .finish()
        .unwrap()
        .save(&model)
        .unwrap();
    let ck = dir.join("ck");
    let mut trainer = Trainer::new(config).unwrap();
    trainer.train_until(10, &mut quiet()).unwrap();
    trainer.write_checkpoint(&out(&ck)).unwrap();
    let bytes = std::fs::read(&ck).unwrap();
    let truncated = dir.join("truncated");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    for (path, message) in [
        (model.as_path(), "blockstack-dqn file and not blockstack-dqn-checkpoint"),
        (truncated.as_path(), "truncated"),
        (dir.join("missing").as_path(), "No such file"),
    ] {
        let e = Trainer::resume(path).err().expect("refused").to_string();
        assert!(e.starts_with(&format!("checkpoint {}", path.display())), "{e}");
        assert!(e.contains(message), "{e}");
    }
}
