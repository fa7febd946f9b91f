//! Evaluating a policy on seeded starts: the one evaluation that `blockstack eval`, Python's
//! `blockstack.train(eval_episodes=...)` and `Model.evaluate`, and the experiments share.
//!
//! An evaluation plays `episodes` episodes of a policy on each goal, a [`Suite`] of one goal
//! each: episode `k` of every goal reset with [`sim::seeding::episode_seed`]`(seed, k)` (so
//! any two policies evaluated with the same seed meet the same starts). It measures each
//! start's shortest legal plan with the exact solver, and sums it all up per goal and
//! overall ([`EvalReport`], which is what `blockstack eval --json` prints). Games end at the
//! goal or at the world's horizon. The experiments play their arms on [`Suite`]s too.

use oracle::ExactSolver;
use serde::Serialize;
use sim::{EnvConfig, Goal, GoalSpec, Profile, Termination};

use crate::error::{AgentError, Result};
use crate::optimality::{self, Optimality};
use crate::policy::Policy;
use crate::rollout::{EpisodeResult, Summary};

mod suite;

pub use suite::{Goals, Suite};

/// A run of a policy, as `blockstack run --json` reports it: the world, the seed and the
/// figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunReport {
    /// The policy's name.
    pub agent: String,
    /// Number of blocks.
    pub blocks: usize,
    /// The goals played, `:`-separated (`None`: drawn per episode).
    pub goal: Option<String>,
    /// The grid, `WxH`.
    pub grid: String,
    /// Steps before an episode is cut off.
    pub horizon: u32,
    /// The backend.
    pub backend: String,
    /// The base seed.
    pub seed: u64,
    /// The profile the world's rules came from.
    pub profile: String,
    /// The action protocol.
    pub protocol: String,
    /// The start rule, or `pddl` for episodes that all began at a PDDL task's start
    /// (`run --pddl`).
    pub start: String,
    /// Failures and steps.
    #[serde(flatten)]
    pub summary: Summary,
    /// Mean steps over every episode, a failure counted as the horizon (how the paper's
    /// figures read: 847.7 = 0.7 x 1000 + 0.3 x 492).
    pub mean_steps_failures_as_horizon: f64,
}

impl RunReport {
    /// The report of `results`, played by `agent` in `world` (whose rules came from
    /// `profile`) with base seed `seed`; `goal` names the goals played.
    pub fn new(
        agent: String,
        world: &EnvConfig,
        profile: Profile,
        goal: Option<String>,
        seed: u64,
        results: &[EpisodeResult],
    ) -> RunReport {
        RunReport {
            agent,
            blocks: world.blocks,
            goal,
            grid: world.grid.to_string(),
            horizon: world.horizon,
            backend: world.backend.to_string(),
            seed,
            profile: profile.to_string(),
            protocol: world.protocol.to_string(),
            start: world.start.to_string(),
            summary: Summary::of(results),
            mean_steps_failures_as_horizon: optimality::mean_steps_failures_as_horizon(results, world.horizon),
        }
    }
}

/// One goal's figures in an evaluation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GoalReport {
    /// The goal, bottom to top.
    pub goal: String,
    /// Failures and steps.
    #[serde(flatten)]
    pub summary: Summary,
    /// Steps against the shortest plans.
    #[serde(flatten)]
    pub optimality: Optimality,
    /// Mean steps over every episode, a failure counted as the horizon.
    pub mean_steps_failures_as_horizon: f64,
}

/// An evaluation's figures: the run's, the optimality over every goal, and each goal's
/// (`blockstack eval --json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EvalReport {
    /// The run over every goal.
    #[serde(flatten)]
    pub run: RunReport,
    /// Steps against the shortest plans, over every goal.
    #[serde(flatten)]
    pub optimality: Optimality,
    /// Where the model came from (its file).
    pub model: String,
    /// The probability of a random legal action.
    pub epsilon: f64,
    /// Per goal, in the order played.
    pub per_goal: Vec<GoalReport>,
}

/// What to evaluate on: a world, its goals, how many seeded starts each and from which
/// base seed.
#[derive(Clone, Debug, PartialEq)]
pub struct EvalPlan {
    /// The world (its goal is each of [`EvalPlan::goals`] in turn; games end at the goal).
    pub world: EnvConfig,
    /// The profile the world's rules came from (reported).
    pub profile: Profile,
    /// The goals, each played [`EvalPlan::episodes`] times.
    pub goals: Vec<Goal>,
    /// Episodes per goal (at least 1).
    pub episodes: u64,
    /// The base seed of the starts.
    pub seed: u64,
}

/// What an evaluation of a trained model changes in the model's own world, each `None`
/// keeping what the model (or the evaluation's default) says: `blockstack eval`'s flags and
/// Python's `Model.evaluate` keywords, read by `neural::AnyModel::eval_plan_with`, the one
/// place an evaluation of a model is planned.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EvalOverrides {
    /// The goals (default: every goal of the model's world, `Goal::all_in`).
    pub goals: Option<Vec<Goal>>,
    /// Episodes per goal.
    pub episodes: u64,
    /// The base seed of the starts.
    pub seed: u64,
    /// The profile whose rules replace the model's (default: the model's own rules).
    pub profile: Option<Profile>,
    /// The action protocol (default: the profile's, else the model's).
    pub protocol: Option<sim::ActionProtocol>,
    /// The start rule (default: the profile's, else the model's).
    pub start: Option<sim::StartRule>,
    /// The reward summed in the episodes (default: the model's training reward, or the
    /// profile's when one is named).
    pub reward: Option<sim::RewardModel>,
    /// Steps before a game is cut off (default: the paper's 1000).
    pub horizon: Option<u32>,
    /// The backend (default: physics, whatever the model trained on).
    pub backend: Option<sim::Backend>,
    /// The number of blocks: the model's, or refused.
    pub blocks: Option<usize>,
    /// The grid: the model's, or refused.
    pub grid: Option<sim::Grid>,
    /// The view: the model's, or refused.
    pub view: Option<sim::View>,
}

/// One evaluation's outcome: the report and every episode played.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// The figures.
    pub report: EvalReport,
    /// Every episode, goal after goal.
    pub results: Vec<EpisodeResult>,
    /// The shortest plan's length from each episode's start, in the same order.
    pub optimal: Vec<u32>,
}

/// Plays the policies that `make_policy` makes (a fresh one per goal) on `plan`, measures
/// every start's optimum with `solver` (whose protocol should be the world's), and reports
/// it all with `name` (the policy's), `model` (where it came from) and `epsilon`. `tick`
/// is called once per episode played and once per start solved (a progress bar's hook); an
/// error it returns (e.g. [`AgentError::Interrupted`] on Ctrl-C) stops the evaluation.
pub fn evaluate<'a>(
    plan: &EvalPlan,
    name: String,
    model: String,
    epsilon: f64,
    solver: &ExactSolver,
    make_policy: &mut dyn FnMut() -> Result<Box<dyn Policy + 'a>>,
    tick: &mut dyn FnMut() -> Result<()>,
) -> Result<Evaluation> {
    if plan.episodes == 0 {
        return Err(AgentError::Config(
            "an evaluation plays at least one episode per goal".into(),
        ));
    }
    if plan.goals.is_empty() {
        return Err(AgentError::Config("an evaluation needs at least one goal".into()));
    }
    let world = EnvConfig {
        termination: Termination::Goal,
        goal: GoalSpec::Random,
        ..plan.world.clone()
    };
    let (mut results, mut optimal) = (Vec::new(), Vec::new());
    let mut per_goal = Vec::with_capacity(plan.goals.len());
    for goal in &plan.goals {
        let suite = Suite {
            world: world.clone(),
            goals: Goals::Each(vec![goal.clone()]),
            episodes: plan.episodes,
            seed: plan.seed,
        };
        let mut policy = make_policy()?;
        let played = suite.play_with(policy.as_mut(), tick)?;
        let best = played
            .iter()
            .map(|r| {
                let d = optimality::optimal_steps_by(solver, std::slice::from_ref(r))?;
                tick()?;
                Ok(d[0])
            })
            .collect::<Result<Vec<u32>>>()?;
        per_goal.push(GoalReport {
            goal: goal.to_string(),
            summary: Summary::of(&played),
            optimality: Optimality::of(&played, &best),
            mean_steps_failures_as_horizon: optimality::mean_steps_failures_as_horizon(&played, world.horizon),
        });
        results.extend(played);
        optimal.extend(best);
    }
    let goals = plan.goals.iter().map(Goal::to_string).collect::<Vec<_>>().join(":");
    let report = EvalReport {
        run: RunReport::new(name, &world, plan.profile, Some(goals), plan.seed, &results),
        optimality: Optimality::of(&results, &optimal),
        model,
        epsilon,
        per_goal,
    };
    Ok(Evaluation {
        report,
        results,
        optimal,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planner_policy::ExactPolicy;

    fn plan(episodes: u64) -> EvalPlan {
        EvalPlan {
            world: EnvConfig {
                blocks: 2,
                backend: sim::Backend::Grid,
                ..EnvConfig::default()
            },
            profile: Profile::Spec,
            goals: vec!["0,1".parse().unwrap(), "1,0".parse().unwrap()],
            episodes,
            seed: 3,
        }
    }

    #[test]
    fn the_exact_planner_is_optimal_on_every_start_and_counted_once_per_tick() {
        let solver = ExactSolver::new(sim::Grid::default());
        let mut ticks = 0;
        let e = evaluate(
            &plan(4),
            "exact".into(),
            "-".into(),
            0.0,
            &solver,
            &mut || Ok(Box::new(ExactPolicy::new(sim::Grid::default()))),
            &mut || {
                ticks += 1;
                Ok(())
            },
        )
        .unwrap();
        assert_eq!(ticks, 2 * 2 * 4);
        assert_eq!(e.results.len(), 8);
        assert_eq!(e.report.run.summary.failures, 0);
        assert_eq!(e.report.optimality.mean_ratio_to_optimum, Some(1.0));
        assert_eq!(e.report.per_goal.len(), 2);
        assert_eq!(e.report.run.goal.as_deref(), Some("0,1:1,0"));
        let json = serde_json::to_value(&e.report).unwrap();
        assert_eq!(json["episodes"], 8);
        assert_eq!(json["per_goal"][1]["goal"], "1,0");
    }

    #[test]
    fn a_tick_that_says_stop_stops_the_evaluation() {
        let solver = ExactSolver::new(sim::Grid::default());
        let mut ticks = 0;
        let err = evaluate(
            &plan(50),
            "exact".into(),
            "-".into(),
            0.0,
            &solver,
            &mut || Ok(Box::new(ExactPolicy::new(sim::Grid::default()))),
            &mut || {
                ticks += 1;
                if ticks == 3 {
                    Err(AgentError::Interrupted)
                } else {
                    Ok(())
                }
            },
        )
        .unwrap_err();
        assert!(matches!(err, AgentError::Interrupted));
        assert_eq!(ticks, 3);
    }

    #[test]
    fn no_episodes_is_an_error_not_a_report_of_nothing() {
        let solver = ExactSolver::new(sim::Grid::default());
        let err = evaluate(
            &plan(0),
            "exact".into(),
            "-".into(),
            0.0,
            &solver,
            &mut || Ok(Box::new(ExactPolicy::new(sim::Grid::default()))),
            &mut || Ok(()),
        )
        .unwrap_err();
        assert!(err.to_string().contains("at least one episode"), "{err}");
    }
}
