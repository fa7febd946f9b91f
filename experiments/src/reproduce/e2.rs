//! E2: the paper's Q-learner with 2 blocks, tested with epsilon 0.01 and 0.05 (paper
//! section VI-A).

use sim::{Goal, Profile};

use super::arms::{ArmResult, Goals, Row, Rules, Suite, Table, TestOutcome, mean_of, play_replicates};
use super::text::{num, significance};
use super::{Context, Experiment, HORIZON, Result, Scale, Setting, paper, paper_learner};

/// The test epsilons the paper reports.
const EPSILONS: [f64; 2] = [0.01, 0.05];

/// Jobs reported: the trainings, and one suite per replicate and epsilon.
pub(super) fn jobs(scale: &Scale) -> u64 {
    scale.replicates as u64 * (1 + EPSILONS.len() as u64)
}

/// Runs E2.
pub(super) fn run(ctx: &Context) -> Result<Experiment> {
    let goals = Goal::all(2)?;
    let trained = ctx.train_replicates("E2", |r| ctx.paper_config(&goals, r))?;
    let suite = Suite {
        blocks: 2,
        goals: Goals::Drawn,
        episodes: ctx.scale.test_games,
        seed: ctx.seeds.test,
        horizon: HORIZON,
        rules: Rules::of(Profile::Spec),
    };
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
            "the paper's learner (chasing representation, paper reward)",
            Some(epsilon),
            &results,
            &optimum,
            HORIZON,
        ));
    }
    let test = TestOutcome::wilcoxon(&arms[1], &arms[0])?;
    let (a, b) = (&arms[0], &arms[1]);
    let (pa, pb) = (paper::E2.rows[0].mean_steps, paper::E2.rows[1].mean_steps);
    let (a_mean, b_mean) = (a.mean_steps_failures_at_horizon, b.mean_steps_failures_at_horizon);
    let (pa, pb) = (pa.unwrap_or(f64::NAN), pb.unwrap_or(f64::NAN));
    let reading = format!(
        "Mean steps* {} at epsilon 0.01 and {} at 0.05 (paper: {} and {}): 0.01 is {} here, {} the paper, the \
         difference {}; failures {} and {} per {} games; over its successes the learner takes {} steps, {}x the \
         shortest plan.",
        num(Some(a_mean), 1),
        num(Some(b_mean), 1),
        num(Some(pa), 2),
        num(Some(pb), 2),
        if a_mean < b_mean { "the better" } else { "the worse" },
        if (a_mean < b_mean) == (pa < pb) {
            "as in"
        } else {
            "unlike in"
        },
        significance(test.p_value),
        num(Some(a.failures), 1),
        num(Some(b.failures), 1),
        a.games,
        num(a.mean_steps, 1),
        num(a.mean_ratio_to_optimum, 1),
    );
    let rows = vec![
        Row::spec(Some(paper::E2.rows[0]), arms[0].clone(), vec![None]),
        Row::spec(Some(paper::E2.rows[1]), arms[1].clone(), vec![Some(test)]),
    ];
    let config = ctx.paper_config(&goals, 0);
    Ok(Experiment {
        id: "E2".into(),
        title: "Q-learning, 2 blocks, test epsilon 0.01 and 0.05".into(),
        setup: vec![
            Setting {
                name: "learner".into(),
                value: format!(
                    "the paper's: {}, {} training \
                     games on goals 0,1 and 1,0 in turn, physics backend",
                    paper_learner(&config),
                    config.games
                ),
            },
            Setting {
                name: "replicates".into(),
                value: format!(
                    "{} agents, training seeds {:?}",
                    ctx.scale.replicates, ctx.seeds.training
                ),
            },
            Setting {
                name: "games".into(),
                value: format!(
                    "{} (the paper does not say how many), per agent and epsilon",
                    suite.describe()
                ),
            },
            Setting {
                name: "mean optimum".into(),
                value: format!("{} steps from these starts", num(mean_of(&optimum), 2)),
            },
            Setting {
                name: "test".into(),
                value: "Wilcoxon signed-rank, epsilon 0.05 vs 0.01, paired by start (the paper ran none)".into(),
            },
        ],
        tables: vec![Table {
            title: "Q-learning, 2 blocks".into(),
            suite: suite.describe(),
            paper: Some(paper::E2),
            tests: vec!["Wilcoxon vs epsilon 0.01".into()],
            rows,
        }],
        curves: Vec::new(),
        decomposition: None,
        paper_notes: Vec::new(),
        reading,
        figures: Vec::new(),
    })
}
