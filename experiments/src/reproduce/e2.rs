//! E2: the paper's Q-learner with 2 blocks, tested with epsilon 0.01 and 0.05 (paper
//! section VI-A), in the paper's world as coded and in ours.

use sim::{Goal, Profile};

use super::Findings;
use super::arms::{ArmResult, Goals, Row, Suite, Table, TestOutcome, describe, mean_of, play_replicates, suite_in};
use super::shared::Shared;
use super::text::{mean_name, num, paper_against, significance, world_name};
use super::{Context, Experiment, HORIZON, Result, Setting, WORLDS, paper, paper_learner};

/// The test epsilons the paper reports.
const EPSILONS: [f64; 2] = [0.01, 0.05];

/// Jobs reported: in each world, the trainings, and one suite per replicate and epsilon.
pub(super) fn jobs(ctx: &Context) -> u64 {
    let scale = &ctx.scale;
    WORLDS.len() as u64 * scale.replicates as u64 * (1 + EPSILONS.len() as u64)
}

/// One world's E2: an arm per epsilon, and the test of 0.05 against 0.01.
struct World {
    arms: Vec<ArmResult>,
    test: TestOutcome,
    suite: Suite,
    optimum: Option<f64>,
    learner: String,
}

/// Runs E2 in `world`.
fn in_world(ctx: &Context, world: Profile) -> Result<World> {
    let goals = Goal::all(2)?;
    let trained = ctx.train_replicates("E2", |r| ctx.paper_config(world, &goals, r))?;
    let suite = suite_in(world, 2, Goals::Drawn, ctx.scale.test_games, ctx.seeds.test);
    let optimum = suite.optimum()?;
    let mut arms = Vec::new();
    for epsilon in EPSILONS {
        let results = play_replicates(
            &suite,
            &trained,
            |t| Ok(Box::new(t.agent.policy(epsilon)?)),
            ctx.progress,
            "E2",
        )?;
        arms.push(ArmResult::of(
            format!("Q-learning, test epsilon {epsilon}"),
            "the paper's learner",
            Some(epsilon),
            &results,
            &optimum,
            HORIZON,
        ));
    }
    let config = ctx.paper_config(world, &goals, 0);
    Ok(World {
        test: TestOutcome::wilcoxon(&arms[1], &arms[0])?,
        arms,
        suite,
        optimum: mean_of(&optimum),
        learner: format!(
            "{}, {} training games on goals 0,1 and 1,0",
            paper_learner(&config),
            config.games
        ),
    })
}

/// Runs E2.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let (original, spec) = ctx.in_both_worlds(|w| in_world(ctx, w))?;
    let rows: Vec<Row> = (0..EPSILONS.len())
        .map(|i| {
            let tests = |w: &World| if i == 0 { vec![None] } else { vec![Some(w.test.clone())] };
            Row::new(
                Some(paper::E2.rows[i]),
                Some((original.arms[i].clone(), tests(&original))),
                Some((spec.arms[i].clone(), tests(&spec))),
            )
        })
        .collect();
    let figures = |w: &World, profile: Profile| {
        let (a, b) = (&w.arms[0], &w.arms[1]);
        format!(
            "in {} mean steps over successes {} at epsilon 0.01 and {} at 0.05 (mean steps* {} and {}, failures {} \
             and {} per {} games; 0.05 against 0.01 {})",
            world_name(profile),
            num(a.mean_steps, 1),
            num(b.mean_steps, 1),
            num(Some(a.mean_steps_failures_at_horizon), 1),
            num(Some(b.mean_steps_failures_at_horizon), 1),
            num(Some(a.failures), 1),
            num(Some(b.failures), 1),
            a.games,
            significance(w.test.p_value),
        )
    };
    let theirs = paper::E2.rows;
    let reading = format!(
        "The paper gives {} {} and {} at test epsilon 0.01 and 0.05 and no failures; ours: {}; {}. {} {}",
        mean_name(theirs[0].mean_over),
        num(theirs[0].mean_steps, 2),
        num(theirs[1].mean_steps, 2),
        figures(&original, Profile::Original),
        figures(&spec, Profile::Spec),
        paper_against(&rows[0]),
        paper_against(&rows[1]),
    );
    let mut setup = Vec::new();
    for (w, profile) in [(&original, Profile::Original), (&spec, Profile::Spec)] {
        setup.push(Setting {
            name: format!("learner, {profile}"),
            value: w.learner.clone(),
        });
        setup.push(Setting {
            name: format!("mean optimum, {profile}"),
            value: format!("{} steps from these starts", num(w.optimum, 2)),
        });
    }
    setup.extend([
        Setting {
            name: "replicates".into(),
            value: format!(
                "{} agents per world, training seeds {:?}",
                ctx.scale.replicates, ctx.seeds.training
            ),
        },
        Setting {
            name: "games".into(),
            value: format!(
                "{} in each world (the paper does not say how many), per agent and epsilon",
                describe(&spec.suite)
            ),
        },
        Setting {
            name: "the paper's means".into(),
            value: "over the games that reached the goal, as docs/world.md section 9 reads them: the paper gives no failures, \
                    and a nearly greedy table is trapped in some games"
                .into(),
        },
        Setting {
            name: "test".into(),
            value: "Wilcoxon signed-rank, epsilon 0.05 vs 0.01, paired by start (the paper ran none)".into(),
        },
    ]);
    Ok(Experiment {
        id: "E2".into(),
        title: "Q-learning, 2 blocks, test epsilon 0.01 and 0.05".into(),
        setup,
        tables: vec![Table {
            title: "Q-learning, 2 blocks".into(),
            suite: format!("{}, in each world", describe(&spec.suite)),
            paper: Some(paper::E2),
            tests: vec!["Wilcoxon vs epsilon 0.01".into()],
            rows,
        }],
        paper_notes: Vec::new(),
        reading,
        figures: Vec::new(),
        findings: Findings::Tables,
    })
}
