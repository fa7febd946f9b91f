//! E5: oracle assistance while training (the paper's Table I, section VI-B2): none, on
//! oscillation, and on oscillation plus each step with probability 0.1; Wilcoxon against
//! none.
//!
//! Table I does not say how long its learners trained. Both worlds train for the paper's
//! learner's preset; the original world also trains for Fig. 3's middle point (50 games),
//! where the paper's unassisted figure sits on Fig. 3's curve, so that the report shows
//! how much of the gap to Table I is training length.

use agent::{Assist, OracleKind, Oscillation};
use sim::{Goal, Profile};

use super::Findings;
use super::arms::{
    ArmResult, Goals, Row, Suite, Table, TestOutcome, describe, play_replicates, steps_box_plot, suite_in,
};
use super::shared::Shared;
use super::text::{num, paper_against, significance, world_name};
use super::{Context, Drawing, Experiment, Figure, HORIZON, Result, Setting, WORLDS, paper, paper_learner};

/// The arms, in the paper's order.
const ASSISTS: [Assist; 3] = [
    Assist::None,
    Assist::Oscillation,
    Assist::OscillationOrChance { p: 0.1 },
];

/// Jobs reported: in each world, and in the original world at the shorter training, a
/// training and a suite per arm and replicate.
pub(super) fn jobs(ctx: &Context) -> u64 {
    let scale = &ctx.scale;
    2 * ((WORLDS.len() + 1) * ASSISTS.len() * scale.replicates) as u64
}

/// The shorter training of the original world's second table: Fig. 3's middle point.
fn short_training() -> u64 {
    paper::FIG3[0].points[1].games
}

/// One world's E5: an arm per assistance and the tests against none.
struct World {
    arms: Vec<ArmResult>,
    tests: Vec<TestOutcome>,
    suite: Suite,
    learner: String,
}

/// Runs E5 in `world`, training for `games` or for the learner's preset.
fn in_world(ctx: &Context, world: Profile, games: Option<u64>) -> Result<World> {
    let all = Goal::all(3)?;
    let suite = suite_in(world, 3, Goals::Drawn, ctx.scale.test_games, ctx.seeds.test);
    let optimum = suite.optimum()?;
    let eps = ctx.test_epsilon();
    let mut arms = Vec::new();
    let mut assisted_share = Vec::new();
    // The paper's learner in `world` with training seed `r`, for `games` if given.
    let learner = |r: usize| {
        let config = ctx.paper_config(world, &all, r);
        agent::TrainConfig {
            games: games.unwrap_or(config.games),
            ..config
        }
    };
    for assist in ASSISTS {
        let trained = ctx.train_replicates("E5", |r| agent::TrainConfig { assist, ..learner(r) })?;
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
    }
    let tests = arms
        .iter()
        .skip(1)
        .map(|arm| TestOutcome::wilcoxon(arm, &arms[0]))
        .collect::<Result<Vec<_>>>()?;
    let config = learner(0);
    let oracle = match config.oracle {
        OracleKind::Paper => "the authors' greedy centroid oracle",
        OracleKind::Astar => "the centroid + A* oracle",
    };
    let oscillation = match config.oscillation {
        Oscillation::Actions => "the last six actions are one pair three times in a row",
        Oscillation::Distances => "the last six pair distances of the authors' state alternate (period 2 or constant)",
    };
    Ok(World {
        learner: format!(
            "{}, {} training games on all six goals; {} agents per arm, training seeds {:?}; {oracle} chooses the \
             action when {oscillation} (it chose {:.1}% of training steps), and that or, at any step, with \
             probability 0.1 ({:.1}%)",
            paper_learner(&config),
            config.games,
            ctx.scale.replicates,
            ctx.seeds.training,
            100.0 * assisted_share[1],
            100.0 * assisted_share[2]
        ),
        arms,
        tests,
        suite,
    })
}

/// Runs E5.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let (original, spec) = ctx.in_both_worlds(|w| in_world(ctx, w, None))?;
    let short = in_world(ctx, Profile::Original, Some(short_training()))?;
    let short_rows: Vec<Row> = (0..ASSISTS.len())
        .map(|i| {
            let test = if i == 0 { None } else { Some(short.tests[i - 1].clone()) };
            Row::new(
                Some(paper::TABLE_I.rows[i]),
                Some((short.arms[i].clone(), vec![test])),
                None,
            )
        })
        .collect();
    let rows: Vec<Row> = (0..ASSISTS.len())
        .map(|i| {
            let tests = |w: &World| vec![if i == 0 { None } else { Some(w.tests[i - 1].clone()) }];
            Row::new(
                Some(paper::TABLE_I.rows[i]),
                Some((original.arms[i].clone(), tests(&original))),
                Some((spec.arms[i].clone(), tests(&spec))),
            )
        })
        .collect();
    let reading = reading(ctx, [&original, &spec, &short], &rows, &short_rows);
    let figure = Figure::new(
        "e5-steps",
        "Steps per game of each arm in each world (a failure at 1000), with the paper's mean".into(),
        Drawing::Boxes(steps_box_plot(
            "E5 (Table I): oracle assistance in training".into(),
            &rows,
            ctx.scale.replicates,
            &spec.suite,
        )),
    );
    Ok(Experiment {
        id: "E5".into(),
        title: "Oracle assistance in training (Table I)".into(),
        setup: setup(ctx, [&original, &spec, &short]),
        tables: vec![
            Table {
                title: "Oracle assistance in training".into(),
                suite: format!("{}, in each world", describe(&spec.suite)),
                paper: Some(paper::TABLE_I),
                tests: vec!["Wilcoxon vs baseline".into()],
                rows,
            },
            Table {
                title: format!(
                    "Oracle assistance in training, {} training games (Table I gives no length; Fig. 3's middle point)",
                    short_training()
                ),
                suite: format!("{}, in the original world", describe(&short.suite)),
                paper: Some(paper::TABLE_I),
                tests: vec!["Wilcoxon vs baseline".into()],
                rows: short_rows,
            },
        ],
        paper_notes: Vec::new(),
        reading,
        figures: vec![figure],
        findings: Findings::Tables,
    })
}

/// The run's reading; `worlds` are the original world's, the SPEC world's and the original
/// world's at the short training.
fn reading(ctx: &Context, worlds: [&World; 3], rows: &[Row], short_rows: &[Row]) -> String {
    let [original, spec, short] = worlds;
    let world = |w: &World, profile: Profile| {
        let (none, both) = (&w.arms[0], &w.arms[2]);
        format!(
            "in {} the learner with the oracle on oscillation + 0.1 failed {} games per {} against {} without \
             help, mean steps* {} against {}, {}; on oscillation alone {} failures, {}",
            world_name(profile),
            num(Some(both.failures), 1),
            both.games,
            num(Some(none.failures), 1),
            num(Some(both.mean_steps_failures_at_horizon), 1),
            num(Some(none.mean_steps_failures_at_horizon), 1),
            significance(w.tests[1].p_value),
            num(Some(w.arms[1].failures), 1),
            significance(w.tests[0].p_value),
        )
    };
    let theirs = paper::TABLE_I.rows;
    format!(
        "The paper: {} and {} failures of {} with and without help (p = {}), {} on oscillation alone (p = {}); {}; \
         {}. {} {} Table I gives no training length; trained for {} games instead of {}, {}: {}",
        num(theirs[2].failures.map(f64::from), 0),
        num(theirs[0].failures.map(f64::from), 0),
        theirs[0].games.unwrap_or_default(),
        num(theirs[2].p_value, 3),
        num(theirs[1].failures.map(f64::from), 0),
        num(theirs[1].p_value, 3),
        world(original, Profile::Original),
        world(spec, Profile::Spec),
        paper_against(&rows[0]),
        paper_against(&rows[2]),
        short_training(),
        ctx.scale.paper_games(Profile::Original),
        world(short, Profile::Original),
        short_rows.iter().map(paper_against).collect::<Vec<_>>().join(" "),
    )
}

/// What was run; `worlds` as for [`reading`].
fn setup(ctx: &Context, worlds: [&World; 3]) -> Vec<Setting> {
    let [original, spec, short] = worlds;
    let mut setup = Vec::new();
    for (w, name) in [
        (original, format!("learner, {}", Profile::Original)),
        (spec, format!("learner, {}", Profile::Spec)),
        (short, format!("learner, {}, second table", Profile::Original)),
    ] {
        setup.push(Setting {
            name,
            value: w.learner.clone(),
        });
    }
    setup.extend([
        Setting {
            name: "games".into(),
            value: format!("{} (the paper's 500) in each world, per agent", describe(&spec.suite)),
        },
        Setting {
            name: "test policy".into(),
            value: format!("random action with probability {} (the paper's)", ctx.test_epsilon()),
        },
        Setting {
            name: "test".into(),
            value: "Wilcoxon signed-rank against no assistance, paired by agent seed and start, steps with a failure \
                    counted as 1000"
                .into(),
        },
    ]);
    setup
}
