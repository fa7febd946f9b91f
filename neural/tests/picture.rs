//! `Dqn::act_on_picture`: a network on pixels plays on the picture an environment renders
//! what it plays on the state (Python's `predict` on the `screen` and `paper-screen`
//! observations).

use neural::mask::ActionSet;
use neural::{DemoSource, Dqn, DqnConfig, NetConfig, ObsKind, Trainer};
use sim::{Action, Env, EnvConfig, ScreenGoal};

fn untrained(preset: neural::Preset, net: NetConfig) -> Dqn {
    let config = DqnConfig {
        demos: DemoSource::None,
        pretrain_steps: 0,
        mask_noops: false,
        net,
        ..DqnConfig::preset(preset, 3).unwrap()
    };
    Trainer::new(config).unwrap().finish().unwrap()
}

fn small_conv() -> NetConfig {
    NetConfig {
        hidden: 16,
        ..NetConfig::conv()
    }
}

#[test]
fn a_pixel_network_acts_on_its_picture_as_on_the_state() {
    acts_on_its_picture_as_on_the_state(small_conv(), ObsKind::Screen);
}

#[test]
fn the_conv_network_on_the_papers_screen_acts_on_it_as_on_the_state() {
    let net = NetConfig {
        screen: ScreenGoal::Paper,
        ..small_conv()
    };
    acts_on_its_picture_as_on_the_state(net, ObsKind::PaperScreen);
}

/// The `conv` network `net` plays on the environment's `kind` observation what it plays on
/// the state, among every action or some.
fn acts_on_its_picture_as_on_the_state(net: NetConfig, kind: ObsKind) {
    use rand::RngExt;
    let dqn = untrained(neural::Preset::DqfdScreen, net);
    assert_eq!(dqn.picture(), Some(kind));
    let input = *dqn.net().input();
    let count = Action::count(3);
    let every = ActionSet::from_indices(0..count);
    let rng = &mut sim::seeding::rng(1);
    let mut env = Env::new(EnvConfig::default()).unwrap();
    let mut picks = 0;
    for seed in 0..40 {
        let mut obs = env.reset(seed);
        if seed % 2 == 1 {
            // Hold a block, so that the ring is drawn too.
            obs = env
                .step(Action::Pick(sim::BlockId::of(seed as usize % 3)))
                .unwrap()
                .observation;
        }
        let mut picture = vec![0; input.len()];
        kind.write(&obs, &mut picture).unwrap();
        let on_state = dqn.greedy_action(&obs).unwrap();
        assert_eq!(
            dqn.act_on_picture(&picture, &obs.goal, every, 0.0, rng).unwrap(),
            on_state
        );
        // Among any allowed actions: the best of them by the state's Q-values (whose Pick
        // columns name goal places on the compact screen, blocks on the paper's).
        let q = dqn.q_values(&obs).unwrap();
        for round in 0..6 {
            // Every third set among the Picks alone, so that Pick columns are chosen often.
            let first = if round % 3 == 2 { 5 } else { 0 };
            let allowed: Vec<usize> = (first..count).filter(|_| rng.random_bool(0.5)).collect();
            let Some(&best) = allowed.iter().max_by(|&&a, &&b| {
                let value = |a: usize| q[input.column(&obs.goal, Action::from_index(a, 3).unwrap())];
                value(a).total_cmp(&value(b))
            }) else {
                continue;
            };
            let set = ActionSet::from_indices(allowed.iter().copied());
            let chosen = dqn.act_on_picture(&picture, &obs.goal, set, 0.0, rng).unwrap();
            assert_eq!(chosen.index(), best, "seed {seed}, allowed {allowed:?}");
            picks += usize::from(matches!(chosen, Action::Pick(_)));
        }
        // epsilon 1: a random allowed action.
        let one = ActionSet::from_indices([2]);
        assert_eq!(
            dqn.act_on_picture(&picture, &obs.goal, one, 1.0, rng).unwrap().index(),
            2
        );
        // A picture of another size is refused.
        assert!(dqn.act_on_picture(&picture[1..], &obs.goal, every, 0.0, rng).is_err());
    }
    assert!(picks > 10, "the comparison chose Pick columns {picks} times");
}

#[test]
fn networks_that_no_environment_shows_refuse_a_picture() {
    let strip = untrained(
        neural::Preset::DqfdScreen,
        NetConfig {
            screen: ScreenGoal::Strip,
            ..small_conv()
        },
    );
    let planes = untrained(
        neural::Preset::DqfdPlanes,
        NetConfig {
            hidden: 16,
            ..NetConfig::small()
        },
    );
    let obs = Env::new(EnvConfig::default()).unwrap().reset(1);
    let every = ActionSet::from_indices(0..Action::count(3));
    for (dqn, says) in [(strip, "strip"), (planes, "role-planes")] {
        assert_eq!(dqn.picture(), None);
        let picture = vec![0; dqn.net().input().len()];
        let err = dqn
            .act_on_picture(&picture, &obs.goal, every, 0.0, &mut sim::seeding::rng(1))
            .unwrap_err()
            .to_string();
        assert!(err.contains(says) && err.contains("state observation"), "{err}");
    }
}
