//! `AnyModel::legal_q_values`: what `blockstack serve` shows beside a watched model's
//! choice, for both kinds of model.

use neural::{AnyModel, DemoSource, DqnConfig, NetConfig, Trainer};
use sim::{Action, Env, EnvConfig, Goal};

#[test]
fn legal_q_values_map_a_networks_columns_back_to_actions() {
    // Role planes: a Pick column names a goal place, not a block id.
    let config = DqnConfig {
        demos: DemoSource::None,
        pretrain_steps: 0,
        net: NetConfig {
            hidden: 16,
            ..NetConfig::small()
        },
        ..DqnConfig::preset(neural::Preset::DqfdPlanes, 2).unwrap()
    };
    let dqn = Trainer::new(config).unwrap().finish().unwrap();
    let goal: Goal = "1,0".parse().unwrap();
    let obs = Env::new(EnvConfig::with_goal(goal.clone())).unwrap().reset(3);
    let by_column = dqn.q_values(&obs).unwrap();
    let input = *dqn.net().input();
    let model = AnyModel::Dqn(Box::new(dqn));
    let legal = model.legal_q_values(&obs).unwrap();
    assert_eq!(
        legal.iter().map(|(a, _)| *a).collect::<Vec<_>>(),
        obs.legal_actions().iter().collect::<Vec<_>>()
    );
    for (a, q) in legal {
        assert_eq!(q, by_column[input.column(&goal, a)], "{a}");
    }
}

#[test]
fn legal_q_values_of_a_table_are_its_row_under_the_protocol() {
    let mut q = agent::QAgent::new(
        agent::ReprKind::Chasing,
        sim::Grid::default(),
        3,
        agent::QParams::default(),
    )
    .unwrap();
    let obs = Env::new(EnvConfig {
        protocol: sim::ActionProtocol::Paper,
        ..EnvConfig::with_goal("0,1,2".parse().unwrap())
    })
    .unwrap()
    .reset(5);
    q.set_q(&obs, Action::Pick(sim::BlockId(1)), 4.5).unwrap();
    let legal = AnyModel::Q(Box::new(q)).legal_q_values(&obs).unwrap();
    // Nothing held under the paper protocol: only the picks.
    assert_eq!(legal.len(), 3);
    assert_eq!(legal[1], (Action::Pick(sim::BlockId(1)), 4.5));
}
