//! E4: failures and steps to goal against training games, 3 blocks (the paper's Fig. 3).
//!
//! In the paper's world as coded, the paper's learner is tested after 5, 50 and 100
//! training games of up to 5000 steps (and at points between), on the paper's 100 test
//! games, at test epsilon 0.1 and 0.05: Fig. 3's points, its values beside ours. In the
//! SPEC world, the paper's learner and ours along their own (longer) trainings.

use agent::{EpisodeResult, TrainConfig};
use rayon::prelude::*;
use sim::{Goal, Profile};

use super::Findings;
use super::arms::{ArmResult, Goals, Row, Suite, Table, describe, suite_in};
use super::shared::{Shared, curve_suite, train_along};
use super::text::{mean_name, num, percent};
use super::{Context, Curve, CurvePoint, Drawing, Experiment, Figure, Result, Setting, paper, paper_learner};
use plots::{LearningCurve, LearningPoint, LearningSeries, SeriesStyle};

/// Jobs reported: a training stretch and a suite per point (a suite per test epsilon in the
/// original world), per replicate of the paper's learner (ours is the shared stage's).
pub(super) fn jobs(ctx: &Context) -> u64 {
    let scale = &ctx.scale;
    let original = scale.replicates * scale.original_curve.len() * (1 + paper::FIG3.len());
    (original + 2 * scale.curve_replicates * scale.paper_curve.len()) as u64
}

/// The original world's test games at every point: the paper's 100, goal drawn per game.
fn original_suite(ctx: &Context) -> Suite {
    let games = u64::from(paper::FIG3[0].test_games);
    suite_in(Profile::Original, 3, Goals::Drawn, games, ctx.seeds.test)
}

/// Trains `replicates` of `config(r)` in parallel along `schedule`, testing at each point
/// with every epsilon: per point and epsilon, the results of each replicate.
fn replicates_along<F>(
    ctx: &Context,
    replicates: usize,
    config: F,
    schedule: &[u64],
    suite: &Suite,
    epsilons: &[f64],
) -> Result<Vec<Vec<Vec<Vec<EpisodeResult>>>>>
where
    F: Fn(usize) -> TrainConfig + Sync,
{
    let runs: Vec<Vec<Vec<Vec<EpisodeResult>>>> = (0..replicates)
        .into_par_iter()
        .map(|r| Ok(train_along(ctx, "E4", config(r), schedule, suite, epsilons)?.1))
        .collect::<Result<_>>()?;
    // Regroup by point and epsilon: the results of each replicate.
    Ok((0..schedule.len())
        .map(|i| {
            (0..epsilons.len())
                .map(|e| runs.iter().map(|run| run[i][e].clone()).collect())
                .collect()
        })
        .collect())
}

/// The paper's learner along its training in both worlds.
struct PaperCurves {
    /// In the SPEC world, at the test epsilon 0.1.
    spec: Curve,
    /// In the original world, one curve per test epsilon of Fig. 3.
    original: Vec<Curve>,
    /// Fig. 3's points beside ours in the original world.
    table: Table,
}

/// Runs E4: the paper's learner's curves, beside our learner's from the shared stage.
pub(super) fn run(ctx: &Context, shared: &Shared) -> Result<Experiment> {
    Ok(experiment(ctx, paper_curves(ctx)?, shared.ours_curve().clone()))
}

/// The paper's learner's curves: in the SPEC world trained on all six goals in turn, in the
/// original world on a goal drawn per game from all six.
fn paper_curves(ctx: &Context) -> Result<PaperCurves> {
    let (original, spec) = rayon::join(|| original_curves(ctx), || spec_curve(ctx));
    let (original, table) = original?;
    Ok(PaperCurves {
        spec: spec?,
        original,
        table,
    })
}

/// The paper's learner in the SPEC world, every replicate trained on all six goals in turn.
fn spec_curve(ctx: &Context) -> Result<Curve> {
    let suite = curve_suite(ctx);
    let schedule = &ctx.scale.paper_curve;
    let all = Goal::all(3)?;
    let eps = ctx.test_epsilon();
    let config = |r| TrainConfig {
        games: *schedule.last().expect("a schedule has points"),
        ..ctx.paper_config(Profile::Spec, &all, r)
    };
    let replicates = ctx.scale.curve_replicates;
    let per_point = replicates_along(ctx, replicates, config, schedule, &suite, &[eps])?;
    let optimum = suite.optimum()?;
    let config = ctx.paper_config(Profile::Spec, &all, 0);
    Ok(Curve {
        learner: format!(
            "the paper's: {}, on all six goals in turn; {replicates} agents, training seeds {:?}",
            paper_learner(&config),
            &ctx.seeds.training[..replicates]
        ),
        world: Profile::Spec,
        test_epsilon: eps,
        suite: describe(&suite),
        points: schedule
            .iter()
            .zip(&per_point)
            .map(|(&games, at_point)| {
                CurvePoint::of(
                    games,
                    &ArmResult::of("", "", Some(eps), &at_point[0], &optimum, suite.world.horizon),
                )
            })
            .collect(),
    })
}

/// The paper's learner in the original world, tested at every point at each test epsilon
/// of Fig. 3: one curve per epsilon, and the table of Fig. 3's points beside ours.
fn original_curves(ctx: &Context) -> Result<(Vec<Curve>, Table)> {
    let suite = original_suite(ctx);
    let schedule = &ctx.scale.original_curve;
    let all = Goal::all(3)?;
    let epsilons: Vec<f64> = paper::FIG3.iter().map(|c| c.test_epsilon).collect();
    let config = |r| TrainConfig {
        games: *schedule.last().expect("a schedule has points"),
        ..ctx.paper_config(Profile::Original, &all, r)
    };
    let per_point = replicates_along(ctx, ctx.scale.replicates, config, schedule, &suite, &epsilons)?;
    let optimum = suite.optimum()?;
    let config = ctx.paper_config(Profile::Original, &all, 0);
    let learner = format!(
        "the paper's: {}, on a goal drawn per game from all six; {} agents, training seeds {:?}",
        paper_learner(&config),
        ctx.scale.replicates,
        ctx.seeds.training
    );
    let mut curves = Vec::new();
    let mut rows = Vec::new();
    for (e, fig3) in paper::FIG3.iter().enumerate() {
        let eps = fig3.test_epsilon;
        let arms: Vec<ArmResult> = schedule
            .iter()
            .zip(&per_point)
            .map(|(games, at_point)| {
                ArmResult::of(
                    format!("{games} games, test epsilon {eps}"),
                    "the paper's learner",
                    Some(eps),
                    &at_point[e],
                    &optimum,
                    suite.world.horizon,
                )
            })
            .collect();
        for p in fig3.points {
            if let Some(i) = schedule.iter().position(|&g| g == p.games) {
                rows.push(Row::new(Some(fig3.row(p)), Some((arms[i].clone(), Vec::new())), None));
            }
        }
        curves.push(Curve {
            learner: learner.clone(),
            world: Profile::Original,
            test_epsilon: eps,
            suite: describe(&suite),
            points: schedule.iter().zip(&arms).map(|(&g, a)| CurvePoint::of(g, a)).collect(),
        });
    }
    let table = Table {
        title: "Fig. 3's points, the paper's learner in the original world".into(),
        suite: format!("{}, in the original world", describe(&suite)),
        paper: None,
        tests: Vec::new(),
        rows,
    };
    Ok((curves, table))
}
/// The picture of `curve`, one learner in the SPEC world.
fn learning(title: &str, curve: &Curve, note: String) -> LearningCurve {
    LearningCurve {
        title: title.into(),
        steps_label: "mean steps to goal over successful games".into(),
        series: vec![LearningSeries {
            name: format!(
                "failures and mean steps over {} test games",
                curve.points.first().map_or(0, |p| p.test_games)
            ),
            style: SeriesStyle::Line,
            colour: 0,
            points: curve
                .points
                .iter()
                .map(|p| LearningPoint {
                    games: p.games,
                    failure_rate: p.failure_rate,
                    failure_range: None,
                    mean_steps: p.mean_steps,
                    steps_range: None,
                })
                .collect(),
        }],
        note,
    }
}

/// The picture of the original world's curves beside Fig. 3: for each test epsilon, ours
/// (a line, the range over replicates as bars) and the paper's (diamonds) in one colour;
/// mean steps count a failure as the horizon, as Fig. 3's do.
fn beside_fig3(curves: &[Curve], replicates: usize) -> LearningCurve {
    let range = |s: Option<super::Spread>| s.map(|s| (s.low, s.high));
    let mut series = Vec::new();
    for (colour, (curve, fig3)) in curves.iter().zip(&paper::FIG3).enumerate() {
        series.push(LearningSeries {
            name: format!("ours, test epsilon {}", curve.test_epsilon),
            style: SeriesStyle::Line,
            colour,
            points: curve
                .points
                .iter()
                .map(|p| LearningPoint {
                    games: p.games,
                    failure_rate: p.failure_rate,
                    failure_range: range(p.failure_rate_spread),
                    mean_steps: Some(p.mean_steps_failures_at_horizon),
                    steps_range: range(p.mean_steps_failures_at_horizon_spread),
                })
                .collect(),
        });
        series.push(LearningSeries {
            name: format!("paper, Fig. 3, test epsilon {}", fig3.test_epsilon),
            style: SeriesStyle::Diamonds,
            colour,
            points: fig3
                .points
                .iter()
                .map(|p| LearningPoint {
                    games: p.games,
                    failure_rate: f64::from(p.failures) / f64::from(fig3.test_games),
                    failure_range: None,
                    mean_steps: Some(p.mean_steps),
                    steps_range: None,
                })
                .collect(),
        });
    }
    LearningCurve {
        title: "E4 (Fig. 3): the paper's learner in the original world, 3 blocks".into(),
        steps_label: "mean steps (a failure counted as 1000)".into(),
        series,
        note: format!(
            "Training games of up to {} steps, each on a goal drawn from all six. Ours: {replicates} agents, each \
             tested on {} games at every point; the line joins the means, the bars span the agents. The paper's \
             values are read from its Fig. 3 (its error bars, +-10% of each value, are not a measured spread).",
            paper::FIG3[0].training_game_steps,
            paper::FIG3[0].test_games
        ),
    }
}

/// The paper's Fig. 3 in words, from [`paper::FIG3`].
fn fig3_text() -> String {
    let curves: Vec<String> = paper::FIG3
        .iter()
        .map(|c| {
            let points: Vec<String> = c
                .points
                .iter()
                .map(|p| format!("{} after {} games", p.failures, p.games))
                .collect();
            format!(
                "at test epsilon {}: {} failures of {} (mean steps* {})",
                c.test_epsilon,
                points.join(", "),
                c.test_games,
                c.points
                    .iter()
                    .map(|p| p.mean_steps.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    format!(
        "{}; training games of up to {} steps; {}",
        paper::FIG3[0].source,
        paper::FIG3[0].training_game_steps,
        curves.join("; ")
    )
}

/// E4 from the paper's learner's curves and ours.
fn experiment(ctx: &Context, paper_curves: PaperCurves, ours: Curve) -> Experiment {
    let PaperCurves {
        spec: paper_learner,
        original,
        table,
    } = paper_curves;
    let reading = reading(ctx, &original, &paper_learner, &table, &ours);
    let figures = figures(ctx, &original, &paper_learner, &ours);
    let mut curves = original;
    curves.extend([paper_learner, ours]);
    Experiment {
        id: "E4".into(),
        title: "Learning curve, 3 blocks (Fig. 3)".into(),
        setup: setup(ctx, &curves),
        tables: vec![table],
        paper_notes: Vec::new(),
        reading,
        figures,
        findings: Findings::Curves(curves),
    }
}

/// The run's reading: Fig. 3 against our spread in the original world, then both learners
/// in the SPEC world.
fn reading(ctx: &Context, original: &[Curve], paper_learner: &Curve, table: &Table, ours: &Curve) -> String {
    let rate = |p: Option<&CurvePoint>| p.map_or("-".into(), |p| percent(p.failure_rate));
    let points = &paper_learner.points;
    let at_preset = points.iter().find(|p| p.games == ctx.scale.paper_games);
    let best = points
        .iter()
        .filter(|p| p.games > 0)
        .min_by(|a, b| a.failure_rate.total_cmp(&b.failure_rate));
    // The first point from which every point is free of failures.
    let solved = (0..ours.points.len())
        .find(|&i| ours.points[i..].iter().all(|p| p.failure_rate == 0.0))
        .map(|i| &ours.points[i]);
    // Fig. 3 in the original world: each of the paper's figures against our spread.
    let placements: Vec<bool> = table
        .rows
        .iter()
        .filter_map(|r| r.original.as_ref()?.paper_inside)
        .flat_map(|inside| inside.placements().map(|p| p.inside).collect::<Vec<_>>())
        .collect();
    let fig3_points: Vec<String> = original
        .first()
        .map(|c| {
            paper::FIG3[0]
                .points
                .iter()
                .filter_map(|fp| {
                    let p = c.points.iter().find(|p| p.games == fp.games)?;
                    Some(format!(
                        "{} after {} games (paper: {} of {})",
                        percent(p.failure_rate),
                        p.games,
                        fp.failures,
                        paper::FIG3[0].test_games
                    ))
                })
                .collect()
        })
        .unwrap_or_default();
    format!(
        "In the original world, at test epsilon {}, the paper's learner failed {}; of Fig. 3's {} figures (failures \
         and {} at both test epsilons), {} lie inside the spread of our {} agents. In the SPEC world the paper's \
         learner failed {} of its test games untrained and {} after the {} training games the other experiments \
         use{}; its best point is {} at {} games. Ours fails {} untrained and {}, with mean {} steps at the end.",
        paper::FIG3[0].test_epsilon,
        fig3_points.join(", "),
        placements.len(),
        mean_name(paper::MeanOver::FailuresAtHorizon),
        placements.iter().filter(|&&i| i).count(),
        ctx.scale.replicates,
        rate(points.first()),
        rate(at_preset),
        ctx.scale.paper_games,
        points
            .last()
            .filter(|p| p.games != ctx.scale.paper_games)
            .map_or(String::new(), |p| format!(", {} after {}", rate(Some(p)), p.games)),
        rate(best),
        best.map_or(0, |p| p.games),
        rate(ours.points.first()),
        solved.map_or_else(
            || format!(
                "{} after {} games",
                rate(ours.points.last()),
                ours.points.last().map_or(0, |p| p.games)
            ),
            |p| format!("none from {} games on", p.games)
        ),
        num(ours.points.last().and_then(|p| p.mean_steps), 2),
    )
}

/// The three pictures: Fig. 3 beside ours, the paper's learner and ours in the SPEC world.
fn figures(ctx: &Context, original: &[Curve], paper_learner: &Curve, ours: &Curve) -> Vec<Figure> {
    let note = format!(
        "Test policy: random action with probability {}. Failures are out of all test games of all agents.",
        ctx.test_epsilon()
    );
    vec![
        Figure::new(
            "e4-original",
            "Fig. 3 beside ours: the paper's learner in the original world, failures and mean steps* against \
             training games of up to 5000 steps, at test epsilon 0.1 and 0.05"
                .into(),
            Drawing::Learning(beside_fig3(original, ctx.scale.replicates)),
        ),
        Figure::new(
            "e4-paper-learner",
            "The paper's learner in the SPEC world: failures and mean steps to goal (over successes) against \
             training games"
                .into(),
            Drawing::Learning(learning(
                "E4: the paper's learner in the SPEC world, 3 blocks",
                paper_learner,
                note.clone(),
            )),
        ),
        Figure::new(
            "e4-ours",
            "Our learner: failures and mean steps to goal (over successes) against training games".into(),
            Drawing::Learning(learning(
                "E4: our learner (role + step-cost), 3 blocks",
                ours,
                format!(
                    "Each point is the agent as training for that many games gives it (final replay included). \
                     Test policy: random action with probability {}.",
                    ctx.test_epsilon()
                ),
            )),
        ),
    ]
}

/// What was run; `curves` are the original world's, then the paper's learner's and ours in
/// the SPEC world.
fn setup(ctx: &Context, curves: &[Curve]) -> Vec<Setting> {
    vec![
        Setting {
            name: "paper's learner, original".into(),
            value: curves[0].learner.clone(),
        },
        Setting {
            name: "games at every point, original".into(),
            value: format!(
                "{} (the paper's 100), per agent and test epsilon ({})",
                curves[0].suite,
                paper::FIG3
                    .iter()
                    .map(|c| c.test_epsilon.to_string())
                    .collect::<Vec<_>>()
                    .join(" and ")
            ),
        },
        Setting {
            name: "paper's learner, spec".into(),
            value: curves[paper::FIG3.len()].learner.clone(),
        },
        Setting {
            name: "our learner, spec".into(),
            value: curves[paper::FIG3.len() + 1].learner.clone(),
        },
        Setting {
            name: "games at every point, spec".into(),
            value: format!(
                "{}, per agent, test epsilon {} (the paper's)",
                curves[paper::FIG3.len()].suite,
                ctx.test_epsilon()
            ),
        },
        Setting {
            name: "paper".into(),
            value: fig3_text(),
        },
    ]
}
