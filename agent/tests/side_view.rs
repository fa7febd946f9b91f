//! The tabular learner in the side view (docs/world.md section 12): `train --view side`'s
//! settings learn every goal of towers of 3 blocks.

use agent::eval::{EvalPlan, evaluate};
use agent::{ReprKind, TrainConfig, TrainOverrides};
use oracle::ExactSolver;
use sim::{Backend, EnvConfig, Goal, Profile, View};

#[test]
fn the_side_view_learner_reaches_every_goal_of_towers_of_3_blocks_near_the_optimum() {
    // The grid backend plays the physics' rules (sim's tests prove it) at a fraction of
    // the cost; the figure, on physics, is in the closing note.
    let config = TrainConfig::resolve(&TrainOverrides {
        view: Some(View::Side),
        backend: Some(Backend::Grid),
        ..TrainOverrides::default()
    })
    .unwrap();
    assert_eq!(config.repr, ReprKind::RoleTowers);
    assert_eq!(config.goals, Goal::shapes(3).unwrap());
    let trained = agent::train(&config, None).unwrap();
    let plan = EvalPlan {
        world: EnvConfig {
            horizon: sim::DEFAULT_HORIZON,
            termination: sim::Termination::Goal,
            ..config.world
        },
        profile: Profile::Spec,
        goals: Goal::all_towers(3).unwrap(),
        episodes: 60,
        seed: 2,
    };
    let solver = ExactSolver::for_world(&plan.world);
    let agent = &trained.agent;
    let e = evaluate(
        &plan,
        agent.name(),
        String::new(),
        0.0,
        &solver,
        &mut || Ok(Box::new(agent.policy(0.0)?)),
        &mut || Ok(()),
    )
    .unwrap();
    assert_eq!(e.report.per_goal.len(), 13, "every goal of towers, two stacks included");
    for g in &e.report.per_goal {
        assert_eq!(g.summary.failures, 0, "goal {}", g.goal);
        let ratio = g.optimality.mean_ratio_to_optimum.unwrap();
        assert!(ratio <= 1.05, "goal {}: {ratio}x the fewest gripper steps", g.goal);
    }
}

#[test]
fn the_one_tower_representations_refuse_goals_of_towers_with_the_way_out() {
    let err = TrainConfig::resolve(&TrainOverrides {
        view: Some(View::Side),
        repr: Some(ReprKind::Role),
        games: Some(1),
        ..TrainOverrides::default()
    })
    .and_then(|c| agent::train(&c, None).map(|_| ()))
    .unwrap_err()
    .to_string();
    assert!(err.contains("--repr role-towers"), "{err}");
}
