//! The first stage of a run: the agents that several experiments play, trained once.
//!
//! Our learner is played by E3 and E7 and its learning curve is E4's; the paper's learner
//! of the SPEC world (trained on all six goals, the first training seed, no assistance: the
//! same agent as E5's first unassisted replicate, since training is fixed by its config) is
//! played by E7. Each experiment lists the [`Part`]s it needs in the table of experiments,
//! and [`Shared::train`] trains only the parts the experiments asked for need, so
//! `--only E1` trains none of them and `--only E3` our learner alone (without the tests
//! along its curve, which only E4 needs).

use agent::{Assist, EpisodeResult, QAgent, TrainConfig, Trainer};
use sim::{Goal, Profile};

use super::arms::{ArmResult, Goals, Suite, describe, suite_in};
use super::{Context, Curve, CurvePoint, Result};

/// A part of the shared stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Part {
    /// Our learner, trained for the last point of its curve.
    Ours,
    /// Our learner's learning curve: the agent tested along its training.
    OursCurve,
    /// The paper's learner in the SPEC world, on all six goals, the first training seed.
    PaperSpec,
}

/// The progress stage the shared agents report under.
const STAGE: &str = "shared";

/// The agents several experiments share; a part is there when an experiment asked for needs
/// it.
#[derive(Default)]
pub(super) struct Shared {
    ours: Option<QAgent>,
    ours_curve: Option<Curve>,
    paper_spec: Option<QAgent>,
}

impl Shared {
    /// Jobs reported while training `needs`: our learner's training (or, with its curve, a
    /// training stretch and a suite per point), and the paper's learner's training.
    pub(super) fn jobs(ctx: &Context, needs: &[Part]) -> u64 {
        let ours = if needs.contains(&Part::OursCurve) {
            2 * ctx.scale.ours_curve.len() as u64
        } else {
            u64::from(needs.contains(&Part::Ours))
        };
        ours + u64::from(needs.contains(&Part::PaperSpec))
    }

    /// Trains the parts in `needs`, side by side on rayon's pool.
    pub(super) fn train(ctx: &Context, needs: &[Part]) -> Result<Shared> {
        let (ours, paper_spec) = rayon::join(
            || -> Result<(Option<QAgent>, Option<Curve>)> {
                if needs.contains(&Part::OursCurve) {
                    let (agent, curve) = train_ours_along(ctx)?;
                    Ok((Some(agent), Some(curve)))
                } else if needs.contains(&Part::Ours) {
                    let trained = agent::train(&ours_config(ctx), None)?;
                    ctx.progress.advance(STAGE);
                    Ok((Some(trained.agent), None))
                } else {
                    Ok((None, None))
                }
            },
            || -> Result<Option<QAgent>> {
                if !needs.contains(&Part::PaperSpec) {
                    return Ok(None);
                }
                let config = TrainConfig {
                    assist: Assist::None,
                    ..ctx.paper_config(Profile::Spec, &Goal::all(3)?, 0)
                };
                let trained = agent::train(&config, None)?;
                ctx.progress.advance(STAGE);
                Ok(Some(trained.agent))
            },
        );
        let (ours, ours_curve) = ours?;
        Ok(Shared {
            ours,
            ours_curve,
            paper_spec: paper_spec?,
        })
    }

    /// Our learner ([`Part::Ours`]).
    pub(super) fn ours(&self) -> &QAgent {
        self.ours
            .as_ref()
            .expect("the experiment lists Part::Ours among its needs")
    }

    /// Our learner's learning curve ([`Part::OursCurve`]).
    pub(super) fn ours_curve(&self) -> &Curve {
        self.ours_curve
            .as_ref()
            .expect("the experiment lists Part::OursCurve among its needs")
    }

    /// The paper's learner in the SPEC world ([`Part::PaperSpec`]).
    pub(super) fn paper_spec(&self) -> &QAgent {
        self.paper_spec
            .as_ref()
            .expect("the experiment lists Part::PaperSpec among its needs")
    }
}

/// Our learner's training config: the role representation with a step cost, on one goal
/// (enough for the role representation), for the last point of its curve (the scale's
/// `ours_games`), so that the agent trained alone is the one at the end of the curve.
fn ours_config(ctx: &Context) -> TrainConfig {
    TrainConfig {
        seed: ctx.seeds.ours,
        games: ctx.scale.ours_curve.last().copied().unwrap_or(ctx.scale.ours_games),
        ..TrainConfig::role_step_cost(vec![Goal::identity(3).expect("3 blocks make a goal")])
    }
}

/// Trains our learner, testing it along the way: the trained agent and its curve.
fn train_ours_along(ctx: &Context) -> Result<(QAgent, Curve)> {
    let suite = curve_suite(ctx);
    let schedule = &ctx.scale.ours_curve;
    let eps = ctx.test_epsilon();
    let (agent, tests) = train_along(ctx, STAGE, ours_config(ctx), schedule, &suite, &[eps])?;
    let optimum = suite.optimum()?;
    let points = schedule
        .iter()
        .zip(tests)
        .map(|(&games, mut at_point)| {
            let results = at_point.swap_remove(0);
            CurvePoint::of(
                games,
                &ArmResult::of("", "", Some(eps), &[results], &optimum, suite.world.horizon),
            )
        })
        .collect();
    let curve = Curve {
        learner: format!("ours: {}", ours_description(&agent)),
        world: Profile::Spec,
        test_epsilon: eps,
        suite: describe(&suite),
        points,
    };
    Ok((agent, curve))
}

/// Trains as `config` says, testing the agent at each of `schedule`'s game counts (in
/// increasing order) as [`agent::train`] would give it after that many games, once per
/// test epsilon of `epsilons`, and reporting progress under `stage`. Returns the agent at
/// the last point and, per point and epsilon, its test results.
pub(super) fn train_along(
    ctx: &Context,
    stage: &str,
    config: TrainConfig,
    schedule: &[u64],
    suite: &Suite,
    epsilons: &[f64],
) -> Result<(QAgent, Vec<Vec<Vec<EpisodeResult>>>)> {
    let mut trainer = Trainer::new(config)?;
    let mut tests = Vec::with_capacity(schedule.len());
    let mut agent = None;
    for &games in schedule {
        trainer.play_games(games.saturating_sub(trainer.report().games), None)?;
        let snapshot = trainer.snapshot().agent;
        ctx.progress.advance(stage);
        let mut at_point = Vec::with_capacity(epsilons.len());
        for &eps in epsilons {
            at_point.push(suite.play(&mut snapshot.policy(eps)?)?);
            ctx.progress.advance(stage);
        }
        tests.push(at_point);
        agent = Some(snapshot);
    }
    Ok((agent.expect("a schedule has points"), tests))
}
/// The SPEC world's test games at every point: all goals, drawn per game.
pub(super) fn curve_suite(ctx: &Context) -> Suite {
    suite_in(Profile::Spec, 3, Goals::Drawn, ctx.scale.test_games, ctx.seeds.test)
}

/// What our learner is, from its recorded training.
pub(super) fn ours_description(ours: &QAgent) -> String {
    match ours.training() {
        Some(t) => {
            let replays: Vec<&str> = [(t.backward_replay, "backward replay"), (t.final_replay, "final replay")]
                .iter()
                .filter(|(on, _)| *on)
                .map(|&(_, name)| name)
                .collect();
            format!(
                "{} representation, {} reward, alpha {}, gamma {}, epsilon {}{}, {} training games on {} (seed {}), \
                 {} backend",
                t.repr,
                t.world.reward,
                t.params.alpha,
                t.params.gamma,
                t.params.epsilon,
                replays.iter().map(|r| format!(", {r}")).collect::<String>(),
                t.games,
                t.goals.iter().map(ToString::to_string).collect::<Vec<_>>().join(" "),
                t.seed,
                t.world.backend
            )
        }
        None => ours.name(),
    }
}
