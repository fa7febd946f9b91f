//! E4: failures and steps to goal against training games, 3 blocks (the paper's Fig. 3),
//! for the paper's learner and for ours.

use agent::{QAgent, TrainConfig, Trainer};
use rayon::prelude::*;
use sim::{Goal, Profile};

use super::arms::{ArmResult, Goals, Rules, Suite};
use super::e3::ours_description;
use super::text::num;
use super::{
    Context, Curve, CurvePoint, Drawing, Experiment, Figure, HORIZON, Result, Scale, Setting, paper, paper_learner,
};
use crate::plots::{LearningCurve, LearningPoint, LearningSeries, SeriesStyle};

/// Jobs reported: a training stretch and a suite per point, per replicate of the paper's
/// learner and for ours.
pub(super) fn jobs(scale: &Scale) -> u64 {
    2 * (scale.replicates * scale.paper_curve.len() + scale.ours_curve.len()) as u64
}

/// The test games at every point: all goals, drawn per game.
fn suite(ctx: &Context) -> Suite {
    Suite {
        blocks: 3,
        goals: Goals::Drawn,
        episodes: ctx.scale.test_games,
        seed: ctx.seeds.test,
        horizon: HORIZON,
        rules: Rules::of(Profile::Spec),
    }
}

/// The goal our learner trains on: one is enough for the role representation.
pub(super) fn ours_goal() -> Goal {
    Goal::identity(3).expect("3 blocks make a goal")
}

/// Our learner's training config.
pub(super) fn ours_config(ctx: &Context) -> TrainConfig {
    TrainConfig {
        seed: ctx.seeds.ours,
        games: ctx.scale.ours_games,
        ..TrainConfig::role_step_cost(vec![ours_goal()])
    }
}

/// Trains as `config` says, testing the agent at each of `schedule`'s game counts (in
/// increasing order) as [`agent::train`] would give it after that many games. Returns the
/// agent at the last point and, per point, its test results.
fn train_along(
    ctx: &Context,
    config: TrainConfig,
    schedule: &[u64],
    suite: &Suite,
) -> Result<(QAgent, Vec<Vec<agent::EpisodeResult>>)> {
    let eps = ctx.test_epsilon();
    let mut trainer = Trainer::new(config)?;
    let mut tests = Vec::with_capacity(schedule.len());
    let mut agent = None;
    for &games in schedule {
        trainer.play_games(games.saturating_sub(trainer.report().games), None)?;
        let snapshot = trainer.snapshot().agent;
        ctx.progress.advance("E4");
        tests.push(suite.play(&mut snapshot.policy(eps)?)?);
        ctx.progress.advance("E4");
        agent = Some(snapshot);
    }
    Ok((agent.expect("a schedule has points"), tests))
}

/// A curve's points from each point's test results (one list per replicate).
fn points(schedule: &[u64], per_point: &[Vec<Vec<agent::EpisodeResult>>], optimum: &[u32]) -> Vec<CurvePoint> {
    schedule
        .iter()
        .zip(per_point)
        .map(|(&games, replicates)| {
            let arm = ArmResult::of("", "", None, replicates, optimum, HORIZON);
            CurvePoint {
                games,
                test_games: arm.steps.len(),
                failures: arm.failures,
                failure_rate: arm.failure_rate(),
                mean_steps_failures_at_horizon: arm.mean_steps_failures_at_horizon,
                mean_steps: arm.mean_steps,
            }
        })
        .collect()
}

/// Trains our learner, testing it along the way: the trained agent and its curve.
pub(super) fn train_ours(ctx: &Context) -> Result<(QAgent, Curve)> {
    let suite = suite(ctx);
    let schedule = &ctx.scale.ours_curve;
    let (agent, tests) = train_along(ctx, ours_config(ctx), schedule, &suite)?;
    let per_point: Vec<Vec<_>> = tests.into_iter().map(|t| vec![t]).collect();
    let curve = Curve {
        learner: format!("ours: {}", ours_description(&agent)),
        suite: suite.describe(),
        points: points(schedule, &per_point, &suite.optimum()?),
    };
    Ok((agent, curve))
}

/// The paper's learner's curve, every replicate trained on all six goals.
pub(super) fn paper_curve(ctx: &Context) -> Result<Curve> {
    let suite = suite(ctx);
    let schedule = &ctx.scale.paper_curve;
    let all = Goal::all(3)?;
    let runs: Vec<Vec<Vec<agent::EpisodeResult>>> = (0..ctx.scale.replicates)
        .into_par_iter()
        .map(|r| {
            let config = TrainConfig {
                games: *schedule.last().expect("a schedule has points"),
                ..ctx.paper_config(&all, r)
            };
            Ok(train_along(ctx, config, schedule, &suite)?.1)
        })
        .collect::<Result<_>>()?;
    // Regroup by point: each point's results, one list per replicate.
    let per_point: Vec<Vec<_>> = (0..schedule.len())
        .map(|i| runs.iter().map(|run| run[i].clone()).collect())
        .collect();
    let config = ctx.paper_config(&all, 0);
    Ok(Curve {
        learner: format!(
            "the paper's: {}, on all six goals in \
             turn; {} agents, training seeds {:?}",
            paper_learner(&config),
            ctx.scale.replicates,
            ctx.seeds.training
        ),
        suite: suite.describe(),
        points: points(schedule, &per_point, &suite.optimum()?),
    })
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

/// E4 from the two curves.
pub(super) fn experiment(ctx: &Context, paper_learner: Curve, ours: Curve) -> Experiment {
    let rate = |p: Option<&CurvePoint>| p.map_or("-".into(), |p| format!("{:.0}%", 100.0 * p.failure_rate));
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
    let reading = format!(
        "The paper's learner failed {} of its test games untrained and {} after the {} training games the other \
         experiments use{}; its best point is {} at {} games. Ours fails {} untrained and {}, with mean {} steps \
         at the end.",
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
    );
    let note = format!(
        "Test policy: random action with probability {}. Failures are out of all test games of all agents.",
        ctx.test_epsilon()
    );
    let figures = vec![
        Figure::new(
            "e4-paper-learner",
            "The paper's learner: failures and mean steps to goal (over successes) against training games".into(),
            Drawing::Learning(learning(
                "E4: the paper's learner (chasing + paper reward), 3 blocks",
                &paper_learner,
                note.clone(),
            )),
        ),
        Figure::new(
            "e4-ours",
            "Our learner: failures and mean steps to goal (over successes) against training games".into(),
            Drawing::Learning(learning(
                "E4: our learner (role + step-cost), 3 blocks",
                &ours,
                format!(
                    "Each point is the agent as training for that many games gives it (final replay included). \
                     Test policy: random action with probability {}.",
                    ctx.test_epsilon()
                ),
            )),
        ),
    ];
    Experiment {
        id: "E4".into(),
        title: "Learning curve, 3 blocks (Fig. 3)".into(),
        setup: vec![
            Setting {
                name: "paper's learner".into(),
                value: paper_learner.learner.clone(),
            },
            Setting {
                name: "our learner".into(),
                value: ours.learner.clone(),
            },
            Setting {
                name: "games at every point".into(),
                value: format!("{}, per agent", paper_learner.suite),
            },
            Setting {
                name: "test policy".into(),
                value: format!("random action with probability {} (the paper's)", ctx.test_epsilon()),
            },
            Setting {
                name: "paper".into(),
                value: fig3_text(),
            },
        ],
        tables: Vec::new(),
        curves: vec![paper_learner, ours],
        decomposition: None,
        paper_notes: Vec::new(),
        reading,
        figures,
    }
}
