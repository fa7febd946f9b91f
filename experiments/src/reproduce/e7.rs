//! E7, the table the paper never had: steps to goal of the random agent, each Q-learner
//! (the paper's and ours), the oracle and the exact solver, on the same starts of every
//! goal, against the shortest plans.

use agent::{EpisodeResult, PlayingModel, Policy, PolicyKind, PolicyOptions};
use rayon::prelude::*;
use sim::{Goal, Profile};

use super::arms::{ArmResult, Goals, Row, Rules, Suite, Table, TestOutcome, describe, mean_of};

use super::Findings;
use super::shared::{Shared, ours_description};
use super::text::{num, significance};
use super::{Context, Drawing, Experiment, Figure, HORIZON, Result, Setting};
use crate::episode::EpisodeFrames;
use plots::{Bar, BarChart, Reference};

/// The agents, in the table's order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Agent {
    Random,
    Paper { greedy: bool },
    Ours { greedy: bool },
    Oracle,
    Exact,
}

const AGENTS: [Agent; 7] = [
    Agent::Random,
    Agent::Paper { greedy: false },
    Agent::Paper { greedy: true },
    Agent::Ours { greedy: false },
    Agent::Ours { greedy: true },
    Agent::Oracle,
    Agent::Exact,
];

impl Agent {
    fn name(self) -> &'static str {
        match self {
            Agent::Random => "random",
            Agent::Paper { greedy: false } => "Q paper (chasing + paper reward)",
            Agent::Paper { greedy: true } => "Q paper, greedy",
            Agent::Ours { greedy: false } => "Q ours (role + step-cost)",
            Agent::Ours { greedy: true } => "Q ours, greedy",
            Agent::Oracle => "oracle",
            Agent::Exact => "exact solver",
        }
    }

    /// The name under its bar.
    fn short(self) -> &'static str {
        match self {
            Agent::Random => "random",
            Agent::Paper { greedy: false } => "Q paper",
            Agent::Paper { greedy: true } => "Q paper greedy",
            Agent::Ours { greedy: false } => "Q ours",
            Agent::Ours { greedy: true } => "Q ours greedy",
            Agent::Oracle => "oracle",
            Agent::Exact => "exact",
        }
    }

    fn is_learner(self) -> bool {
        matches!(self, Agent::Paper { .. } | Agent::Ours { .. })
    }

    /// The probability of a random action it plays with: none for a greedy learner, the
    /// test's `eps` otherwise.
    fn epsilon(self, eps: f64) -> f64 {
        match self {
            Agent::Paper { greedy: true } | Agent::Ours { greedy: true } => 0.0,
            _ => eps,
        }
    }

    /// The kind of policy it is, as `blockstack run --agent` names it.
    fn kind(self) -> PolicyKind {
        match self {
            Agent::Random => PolicyKind::Random,
            Agent::Paper { .. } | Agent::Ours { .. } => PolicyKind::Q,
            Agent::Oracle => PolicyKind::Oracle,
            Agent::Exact => PolicyKind::Exact,
        }
    }
}

/// Jobs reported: one suite per agent.
pub(super) fn jobs(_: &Context) -> u64 {
    AGENTS.len() as u64
}

/// Runs E7 with the paper's learner of the SPEC world and ours, from the shared stage.
pub(super) fn run(ctx: &Context, shared: &Shared) -> Result<Experiment> {
    let (paper_agent, ours) = (shared.paper_spec(), shared.ours());
    let suite = Suite {
        world: Rules::of(Profile::Spec).world(3, HORIZON),
        goals: Goals::Each(Goal::all(3)?),
        episodes: ctx.scale.test_games,
        seed: ctx.seeds.test,
    };
    let optimum = suite.optimum()?;
    let eps = ctx.test_epsilon();
    let world = &suite.world;
    let policy = |agent: Agent| -> Result<Box<dyn Policy + '_>> {
        let model: Option<&dyn PlayingModel> = match agent {
            Agent::Paper { .. } => Some(paper_agent),
            Agent::Ours { .. } => Some(ours),
            _ => None,
        };
        let options = PolicyOptions {
            epsilon: agent.epsilon(eps),
            ..PolicyOptions::default()
        };
        Ok(agent.kind().policy(world, model, &options)?)
    };
    let played: Vec<Vec<EpisodeResult>> = AGENTS
        .par_iter()
        .map(|&a| {
            let results = suite.play(policy(a)?.as_mut());
            ctx.progress.advance("E7");
            Ok(results?)
        })
        .collect::<Result<_>>()?;
    let arms: Vec<ArmResult> = AGENTS
        .iter()
        .zip(&played)
        .map(|(&a, results)| arm(a, std::slice::from_ref(results), &optimum, eps))
        .collect();
    let index = |agent: Agent| AGENTS.iter().position(|&a| a == agent).expect("every agent has an arm");
    let (exact, oracle) = (index(Agent::Exact), index(Agent::Oracle));
    let paper_index = index(Agent::Paper { greedy: false });
    let mut rows = Vec::new();
    for arm in &arms {
        // A row is not tested against itself.
        let tests = [paper_index, exact]
            .iter()
            .map(|&against| {
                (arm.name != arms[against].name)
                    .then(|| TestOutcome::wilcoxon(arm, &arms[against]))
                    .transpose()
            })
            .collect::<Result<Vec<_>>>()?;
        rows.push(Row::spec(None, arm.clone(), tests));
    }
    // The best learner, by mean steps with failures at the horizon.
    let best = AGENTS
        .iter()
        .zip(&arms)
        .enumerate()
        .filter(|(_, (a, _))| a.is_learner())
        .min_by(|(_, (_, x)), (_, (_, y))| {
            x.mean_steps_failures_at_horizon
                .total_cmp(&y.mean_steps_failures_at_horizon)
        })
        .map(|(i, _)| i)
        .expect("learners");
    let (start, gifs) = episodes(
        &suite,
        &played[paper_index],
        [(AGENTS[best], best), (AGENTS[paper_index], paper_index)],
        &policy,
        &arms,
    )?;
    let reading = reading(&arms, &rows, best, paper_index, exact, oracle);
    let mut figures = vec![steps_chart(&suite, &arms, &optimum, eps)];
    figures.extend(gifs);
    Ok(Experiment {
        id: "E7".into(),
        title: "Every agent against the optimum (ours)".into(),
        setup: setup(ctx, shared, &suite, &optimum, start),
        tables: vec![Table {
            title: "Steps to goal against the optimum".into(),
            suite: describe(&suite),
            paper: None,
            tests: vec!["Wilcoxon vs Q paper".into(), "Wilcoxon vs exact".into()],
            rows,
        }],
        paper_notes: Vec::new(),
        reading,
        figures,
        findings: Findings::Tables,
    })
}

/// An agent's arm from its games (`played`: one replicate); learners play at `eps`, or
/// greedily.
fn arm(a: Agent, played: &[Vec<EpisodeResult>], optimum: &[u32], eps: f64) -> ArmResult {
    let what = match a {
        Agent::Random => "uniformly random actions".to_string(),
        Agent::Paper { .. } => "the paper's learner, trained on all six goals (E5's first baseline agent)".into(),
        Agent::Ours { .. } => "our learner (E4's), trained on 0,1,2 only".into(),
        Agent::Oracle => "the centroid + A* oracle, planning from each start".into(),
        Agent::Exact => "the exact solver's shortest plan".into(),
    };
    ArmResult::of(
        a.name(),
        what,
        a.is_learner().then(|| a.epsilon(eps)),
        played,
        optimum,
        HORIZON,
    )
}

/// The settings: the agents, the games, the test policy, the optimum and the tests.
fn setup(ctx: &Context, shared: &Shared, suite: &Suite, optimum: &[u32], start: usize) -> Vec<Setting> {
    let (paper_agent, ours) = (shared.paper_spec(), shared.ours());
    let eps = ctx.test_epsilon();
    vec![
        Setting {
            name: "agents".into(),
            value: format!(
                "random; the paper's learner (chasing + paper reward, {} training games on all six goals, seed \
                     {}); ours ({}); the oracle; the exact solver",
                paper_agent.training().map_or(0, |t| t.games),
                paper_agent.training().map_or(0, |t| t.seed),
                ours_description(ours)
            ),
        },
        Setting {
            name: "games".into(),
            value: format!("{}, per agent", describe(suite)),
        },
        Setting {
            name: "test policy".into(),
            value: format!(
                "learners: random action with probability {eps} (the paper's), and greedy (epsilon 0) in the \
                     rows so marked; planners are deterministic"
            ),
        },
        Setting {
            name: "optimum".into(),
            value: format!(
                "the exact solver's shortest plan from each start: {} steps on average",
                num(mean_of(optimum), 2)
            ),
        },
        Setting {
            name: "tests".into(),
            value: "Wilcoxon signed-rank against the paper's learner and against the exact solver, paired by \
                        start, steps with a failure counted as 1000"
                .into(),
        },
        Setting {
            name: "episode pictures".into(),
            value: format!("game {start} of the table (the paper's learner's most typical success)"),
        },
    ]
}

/// The reading: the best learner against the paper's, the exact solver and the oracle.
fn reading(arms: &[ArmResult], rows: &[Row], best: usize, paper_index: usize, exact: usize, oracle: usize) -> String {
    let (b, p, x) = (&arms[best], &arms[paper_index], &arms[exact]);
    let to_paper = rows[best]
        .spec
        .as_ref()
        .and_then(|m| m.tests[0].as_ref())
        .map_or_else(|| "not tested".into(), |t| significance(t.p_value));
    format!(
        "The best learner, {}, failed {} of {} games with mean {} steps, {}x the shortest plan (the exact solver: \
         {} steps); the paper's learner failed {} with mean {} steps over its successes, {}x; the difference in \
         steps (a failure at 1000) is {}. The oracle averages {}x the optimum.",
        b.name,
        num(Some(b.failures), 0),
        b.games,
        num(b.mean_steps, 2),
        num(b.mean_ratio_to_optimum, 3),
        num(x.mean_steps, 2),
        num(Some(p.failures), 0),
        num(p.mean_steps, 1),
        num(p.mean_ratio_to_optimum, 1),
        to_paper,
        num(arms[oracle].mean_ratio_to_optimum, 4),
    )
}

/// The bar chart of mean steps per agent, beside the mean shortest plan.
fn steps_chart(suite: &Suite, arms: &[ArmResult], optimum: &[u32], eps: f64) -> Figure {
    let bars = BarChart {
        title: "E7: steps to goal on the same starts, every goal".into(),
        y_label: "mean steps (a failure counted as 1000)".into(),
        bars: AGENTS
            .iter()
            .zip(arms)
            .map(|(agent, a)| Bar {
                name: agent.short().into(),
                value: a.mean_steps_failures_at_horizon,
                interval: None,
                second: a.median_steps,
            })
            .collect(),
        value_label: "mean steps, a failure at 1000".into(),
        interval_label: String::new(),
        second_label: "median over successes".into(),
        reference: mean_of(optimum).map(|v| Reference {
            label: "mean shortest plan (exact solver)".into(),
            value: v,
        }),
        log_scale: true,
        note: format!(
            "{}. Learners play with a random action with probability {eps} unless marked greedy.",
            describe(suite)
        ),
    };
    Figure::new(
        "e7-steps",
        "Mean steps to goal per agent (a failure at 1000), median over successes, and the mean shortest plan".into(),
        Drawing::Bars(bars),
    )
}

/// The GIFs of `agents` (each with its arm's index) on one start: the game where the
/// paper's learner reached the goal in the number of steps nearest its median (the first
/// game if it never did). Returns the game's index and the figures.
fn episodes<'a>(
    suite: &Suite,
    paper_results: &[EpisodeResult],
    agents: [(Agent, usize); 2],
    policy: &dyn Fn(Agent) -> Result<Box<dyn Policy + 'a>>,
    arms: &[ArmResult],
) -> Result<(usize, Vec<Figure>)> {
    let median = arms[agents[1].1].median_steps.unwrap_or(0.0);
    let start = paper_results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.reached_goal)
        .min_by(|(_, a), (_, b)| {
            (f64::from(a.steps) - median)
                .abs()
                .total_cmp(&(f64::from(b.steps) - median).abs())
        })
        .map_or(0, |(i, _)| i);
    let mut figures = Vec::new();
    for (i, (agent, _)) in agents.iter().enumerate() {
        let observations = suite.record(policy(*agent)?.as_mut(), start)?;
        let goal = observations[0].goal.clone();
        let (stem, who) = if i == 0 {
            ("e7-best", "the best learner")
        } else {
            ("e7-paper", "the paper's learner")
        };
        figures.push(Figure::new(
            stem,
            format!(
                "One game of {who}, {}, goal {goal}, {} steps",
                agent.name(),
                observations.len() - 1
            ),
            Drawing::Episode(vec![EpisodeFrames {
                caption: format!("{}, goal {goal}", agent.name()),
                observations,
            }]),
        ));
    }
    Ok((start, figures))
}
