//! E5: oracle assistance while training (the paper's Table I, section VI-B2): none, on
//! oscillation, and on oscillation plus each step with probability 0.1; Wilcoxon against
//! none.

use agent::{Assist, QAgent};
use sim::{Goal, Profile};

use super::arms::{ArmResult, Goals, Row, Rules, Suite, Table, TestOutcome, play_replicates, steps_box_plot};
use super::text::{fewer_or_more, num, significance};
use super::{Context, Drawing, Experiment, Figure, HORIZON, Result, Scale, Setting, paper, paper_learner};

/// The arms, in the paper's order.
const ASSISTS: [Assist; 3] = [
    Assist::None,
    Assist::Oscillation,
    Assist::OscillationOrChance { p: 0.1 },
];

/// Jobs reported: a training and a suite per arm and replicate.
pub(super) fn jobs(scale: &Scale) -> u64 {
    2 * (ASSISTS.len() * scale.replicates) as u64
}

/// Runs E5; also returns the first replicate of the unassisted learner (the paper's
/// learner on all six goals), which E7 plays.
pub(super) fn run(ctx: &Context) -> Result<(Experiment, QAgent)> {
    let all = Goal::all(3)?;
    let suite = Suite {
        blocks: 3,
        goals: Goals::Drawn,
        episodes: ctx.scale.test_games,
        seed: ctx.seeds.test,
        horizon: HORIZON,
        rules: Rules::of(Profile::Spec),
    };
    let optimum = suite.optimum()?;
    let eps = ctx.test_epsilon();
    let mut arms = Vec::new();
    let mut assisted_share = Vec::new();
    let mut first_unassisted = None;
    for assist in ASSISTS {
        let trained = ctx.train_replicates("E5", |r| agent::TrainConfig {
            assist,
            ..ctx.paper_config(&all, r)
        })?;
        let (steps, by_oracle) = trained
            .iter()
            .fold((0, 0), |(s, o), t| (s + t.report.steps, o + t.report.assisted_steps));
        assisted_share.push(by_oracle as f64 / steps.max(1) as f64);
        let results = play_replicates(
            &suite,
            &trained,
            |t| Ok(Box::new(t.agent.policy(eps)?)),
            ctx.progress,
            "E5",
        )?;
        arms.push(ArmResult::of(
            paper::TABLE_I.rows[arms.len()].arm,
            format!("the paper's learner, trained with assistance \"{assist}\""),
            Some(eps),
            &results,
            &optimum,
            HORIZON,
        ));
        if assist == Assist::None {
            first_unassisted = trained.into_iter().next().map(|t| t.agent);
        }
    }
    let tests = arms
        .iter()
        .skip(1)
        .map(|arm| TestOutcome::wilcoxon(arm, &arms[0]))
        .collect::<Result<Vec<_>>>()?;
    let (none, both) = (&arms[0], &arms[2]);
    let p_both = tests[1].p_value;
    let reading = format!(
        "With the oracle on oscillation + 0.1 the learner failed {} games per {} against {} without help, {} \
         (paper: {} against {}), mean steps {} against {} (paper: {} against {}); the difference is {} (paper: \
         p = {}). Oscillation alone: {} failures, {}.",
        num(Some(both.failures), 1),
        both.games,
        num(Some(none.failures), 1),
        fewer_or_more(both.failures, none.failures),
        num(paper::TABLE_I.rows[2].failures.map(f64::from), 0),
        num(paper::TABLE_I.rows[0].failures.map(f64::from), 0),
        num(Some(both.mean_steps_failures_at_horizon), 1),
        num(Some(none.mean_steps_failures_at_horizon), 1),
        num(paper::TABLE_I.rows[2].mean_steps, 1),
        num(paper::TABLE_I.rows[0].mean_steps, 1),
        significance(p_both),
        num(paper::TABLE_I.rows[2].p_value, 3),
        num(Some(arms[1].failures), 1),
        significance(tests[0].p_value),
    );
    let figure = Figure::new(
        "e5-steps",
        "Steps per game of each arm (a failure at 1000), with the paper's mean".into(),
        Drawing::Boxes(steps_box_plot(
            "E5 (Table I): oracle assistance in training".into(),
            &arms,
            paper::TABLE_I.rows,
            ctx.scale.replicates,
            &suite,
        )),
    );
    let mut tests = tests.into_iter();
    let rows = arms
        .into_iter()
        .zip(paper::TABLE_I.rows)
        .enumerate()
        .map(|(i, (ours, &theirs))| Row::spec(Some(theirs), ours, vec![if i == 0 { None } else { tests.next() }]))
        .collect();
    let config = ctx.paper_config(&all, 0);
    let experiment = Experiment {
        id: "E5".into(),
        title: "Oracle assistance in training (Table I)".into(),
        setup: vec![
            Setting {
                name: "learner".into(),
                value: format!(
                    "the paper's: {}, {} training \
                     games on all six goals in turn, physics backend; {} agents per arm, training seeds {:?}",
                    paper_learner(&config),
                    config.games,
                    ctx.scale.replicates,
                    ctx.seeds.training
                ),
            },
            Setting {
                name: "assistance".into(),
                value: format!(
                    "none; the oracle chooses the action when the last six actions are one pair three times in a \
                     row (it chose {:.1}% of training steps); that or, at any step, with probability 0.1 ({:.1}%)",
                    100.0 * assisted_share[1],
                    100.0 * assisted_share[2]
                ),
            },
            Setting {
                name: "games".into(),
                value: format!("{} (the paper's 500), per agent", suite.describe()),
            },
            Setting {
                name: "test policy".into(),
                value: format!("random action with probability {eps} (the paper's)"),
            },
            Setting {
                name: "test".into(),
                value: "Wilcoxon signed-rank against no assistance, paired by agent seed and start, steps with a \
                        failure counted as 1000"
                    .into(),
            },
        ],
        tables: vec![Table {
            title: "Oracle assistance in training".into(),
            suite: suite.describe(),
            paper: Some(paper::TABLE_I),
            tests: vec!["Wilcoxon vs baseline".into()],
            rows,
        }],
        curves: Vec::new(),
        decomposition: None,
        paper_notes: Vec::new(),
        reading,
        figures: vec![figure],
    };
    let paper_agent = first_unassisted.expect("the unassisted arm has a replicate");
    Ok((experiment, paper_agent))
}
