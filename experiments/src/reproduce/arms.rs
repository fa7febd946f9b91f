//! What every experiment is made of: seeded test suites that every arm plays in a world
//! (the paper's as coded, or ours), the figures of an arm, the tests between arms, and
//! tables of arms: the paper's figure, ours in the paper's world and ours in the SPEC world
//! side by side.

pub use agent::eval::{Goals, Suite};
use agent::optimality::mean_steps_failures_as_horizon;
use agent::{EpisodeResult, Policy, Summary};
use serde::Serialize;
use sim::{ActionProtocol, EnvConfig, Goal, Profile, StartRule};

use super::paper::{MeanOver, PaperRow, PaperTable};
use super::spread::{PaperInside, Placement};
use super::{ProgressSink, Result};
use plots::{Arm, BoxPlot};
use stats::{Method, TestResult};

/// The rules of `sim` a suite's games are played under that differ between the paper's
/// world as its authors coded it and ours: which actions are legal, and how a game starts.
/// (The reward does not change what a trained agent does in a test game, and test games end
/// at the goal in both worlds.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct Rules {
    /// Which actions are legal in a state.
    pub protocol: ActionProtocol,
    /// How a game's start is drawn.
    pub start: StartRule,
}

impl Rules {
    /// The rules of `profile`'s world.
    pub const fn of(profile: Profile) -> Rules {
        Rules {
            protocol: profile.protocol(),
            start: profile.start_rule(),
        }
    }

    /// The profile whose world these rules are, if any (E1 also plays worlds between the two).
    pub fn profile(self) -> Option<Profile> {
        [Profile::Original, Profile::Spec]
            .into_iter()
            .find(|&p| Rules::of(p) == self)
    }

    /// "the original world", "the SPEC world", or "protocol paper, start rule uniform".
    pub fn describe(self) -> String {
        match self.profile() {
            Some(Profile::Original) => "the original world".into(),
            Some(Profile::Spec) => "the SPEC world".into(),
            None => format!("protocol {}, start rule {}", self.protocol.name(), self.start.name()),
        }
    }
}

impl Rules {
    /// The world of these rules with `blocks` blocks and games cut off at `horizon` steps, on
    /// the paper's 7 x 7 grid, the goal drawn.
    pub fn world(self, blocks: usize, horizon: u32) -> EnvConfig {
        EnvConfig {
            blocks,
            horizon,
            protocol: self.protocol,
            start: self.start,
            ..EnvConfig::default()
        }
    }
}

/// `episodes` games per goal of `goals` with `blocks` blocks in `world`, starts from
/// `seed`, the paper's horizon: the suite every arm of an experiment plays
/// ([`agent::eval::Suite`]).
pub fn suite_in(world: Profile, blocks: usize, goals: Goals, episodes: u64, seed: u64) -> Suite {
    Suite {
        world: Rules::of(world).world(blocks, super::HORIZON),
        goals,
        episodes,
        seed,
    }
}

/// A suite described for the report: "500 games, goal drawn per game from all 6, 3 blocks,
/// horizon 1000, starts seed 1001" (the world is the table column's).
pub fn describe(suite: &Suite) -> String {
    let goals = match &suite.goals {
        Goals::Each(goals) if goals.len() == 1 => format!("{} games of goal {}", suite.episodes, goals[0]),
        Goals::Each(goals) => format!(
            "{} games of each goal {} ({} in all)",
            suite.episodes,
            goals.iter().map(Goal::to_string).collect::<Vec<_>>().join(" "),
            suite.games()
        ),
        Goals::Drawn => format!(
            "{} games, goal drawn per game from all {}",
            suite.episodes,
            goal_count(suite.world.blocks)
        ),
    };
    format!(
        "{goals}, {} blocks, horizon {}, starts seed {}",
        suite.world.blocks, suite.world.horizon, suite.seed
    )
}

/// The mean of `values` (`None` for none), e.g. of shortest plans' lengths.
pub fn mean_of(values: &[u32]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64)
}

/// `n!`: the number of goals of `n` blocks.
fn goal_count(blocks: usize) -> usize {
    (1..=blocks).product()
}

/// One arm's figures over its games: all replicates (agents trained with different seeds)
/// playing the same suite.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ArmResult {
    /// The arm's name in the tables.
    pub name: String,
    /// What plays: the agent and its training.
    pub agent: String,
    /// The test-time probability of a random action, for learners (`None`: not a learner).
    pub test_epsilon: Option<f64>,
    /// Agents (training seeds) behind the arm; each played every game of the suite.
    pub replicates: usize,
    /// Games per replicate.
    pub games: usize,
    /// Failures of each replicate, in replicate order.
    pub failures_per_replicate: Vec<usize>,
    /// Mean failures per replicate.
    pub failures: f64,
    /// Mean steps over every game of every replicate, a failure counted as the horizon
    /// (the paper's reading).
    pub mean_steps_failures_at_horizon: f64,
    /// Each replicate's mean steps, a failure counted as the horizon.
    pub mean_steps_failures_at_horizon_per_replicate: Vec<f64>,
    /// Mean steps over the games that reached the goal.
    pub mean_steps: Option<f64>,
    /// Each replicate's mean steps over its games that reached the goal.
    pub mean_steps_per_replicate: Vec<Option<f64>>,
    /// Median steps over the games that reached the goal.
    pub median_steps: Option<f64>,
    /// Mean over the games that reached the goal of steps / shortest plan.
    pub mean_ratio_to_optimum: Option<f64>,
    /// Mean shortest-plan length from the starts of the games that reached the goal.
    pub mean_optimum: Option<f64>,
    /// Every game's steps, a failure counted as the horizon, replicate after replicate,
    /// in the suite's order (the samples of the tests and box plots).
    #[serde(skip)]
    pub steps: Vec<f64>,
}

impl ArmResult {
    /// Where `paper`'s figures fall against this arm's replicates; `None` if the paper
    /// gives no figure to place or the arm has no replicate.
    pub fn paper_inside(&self, paper: &PaperRow) -> Option<PaperInside> {
        let arm = self;
        let failure_rate = match (paper.failures, paper.games) {
            (Some(f), Some(n)) if n > 0 => {
                Placement::of(f64::from(f) / f64::from(n), &arm.failure_rate_per_replicate())
            }
            _ => None,
        };
        let ours: Vec<f64> = match paper.mean_over {
            MeanOver::FailuresAtHorizon => arm.mean_steps_failures_at_horizon_per_replicate.clone(),
            MeanOver::Successes => arm.mean_steps_per_replicate.iter().flatten().copied().collect(),
        };
        let mean_steps = paper.mean_steps.and_then(|m| Placement::of(m, &ours));
        (failure_rate.is_some() || mean_steps.is_some()).then_some(PaperInside {
            failure_rate,
            mean_steps,
            mean_over: paper.mean_over,
        })
    }

    /// The figures of `replicates` (each one agent's results on the same suite, whose
    /// shortest plans are `optimum`; empty for none).
    pub fn of(
        name: impl Into<String>,
        agent: impl Into<String>,
        test_epsilon: Option<f64>,
        replicates: &[Vec<EpisodeResult>],
        optimum: &[u32],
        horizon: u32,
    ) -> ArmResult {
        let optimal: Vec<u32> = replicates.iter().flat_map(|_| optimum.iter().copied()).collect();
        Self::of_games(name, agent, test_epsilon, replicates, &optimal, horizon)
    }

    /// The figures of one policy's `games` (as [`Suite::play`] orders them: `runs` runs, one
    /// per goal of the suite, of `per_replicate * R` games each), cut into `R` replicates
    /// of `per_replicate` games of each run, in order: replicate `r` holds games
    /// `r * per_replicate..(r + 1) * per_replicate` of every run (E1, E3: a replicate is a
    /// set of the paper's number of games of its own). `optimum` holds each game's shortest
    /// plan (empty for none).
    pub fn of_sets(
        name: impl Into<String>,
        agent: impl Into<String>,
        games: &[EpisodeResult],
        runs: usize,
        per_replicate: usize,
        optimum: &[u32],
        horizon: u32,
    ) -> ArmResult {
        let replicates = regroup(games, runs, per_replicate);
        let optimal: Vec<u32> = regroup(optimum, runs, per_replicate).concat();
        Self::of_games(name, agent, None, &replicates, &optimal, horizon)
    }

    /// The figures of `replicates`, whose games' shortest plans are `optimal`, replicate
    /// after replicate (empty for none).
    fn of_games(
        name: impl Into<String>,
        agent: impl Into<String>,
        test_epsilon: Option<f64>,
        replicates: &[Vec<EpisodeResult>],
        optimal: &[u32],
        horizon: u32,
    ) -> ArmResult {
        let all: Vec<EpisodeResult> = replicates.iter().flatten().cloned().collect();
        let summary = Summary::of(&all);
        let optimality = agent::optimality::Optimality::of(&all, optimal);
        let failures_per_replicate: Vec<usize> = replicates.iter().map(|r| Summary::of(r).failures).collect();
        ArmResult {
            name: name.into(),
            agent: agent.into(),
            test_epsilon,
            replicates: replicates.len(),
            games: replicates.first().map_or(0, Vec::len),
            failures: failures_per_replicate.iter().sum::<usize>() as f64 / replicates.len().max(1) as f64,
            failures_per_replicate,
            mean_steps_failures_at_horizon: mean_steps_failures_as_horizon(&all, horizon),
            mean_steps_failures_at_horizon_per_replicate: replicates
                .iter()
                .map(|r| mean_steps_failures_as_horizon(r, horizon))
                .collect(),
            mean_steps: summary.mean_steps,
            mean_steps_per_replicate: replicates.iter().map(|r| Summary::of(r).mean_steps).collect(),
            median_steps: summary.median_steps,
            mean_ratio_to_optimum: optimality.mean_ratio_to_optimum,
            mean_optimum: optimality.mean_optimal_steps,
            steps: all
                .iter()
                .map(|r| f64::from(if r.reached_goal { r.steps } else { horizon }))
                .collect(),
        }
    }

    /// The share of games that failed, in `[0, 1]`.
    pub fn failure_rate(&self) -> f64 {
        self.failures / self.games.max(1) as f64
    }

    /// Each replicate's share of games that failed.
    pub fn failure_rate_per_replicate(&self) -> Vec<f64> {
        self.failures_per_replicate
            .iter()
            .map(|&f| f as f64 / self.games.max(1) as f64)
            .collect()
    }
}

/// `items` in `runs` equal runs, regrouped into sets of `per` items of each run: set `r`
/// holds items `r * per..(r + 1) * per` of every run, run after run.
fn regroup<T: Clone>(items: &[T], runs: usize, per: usize) -> Vec<Vec<T>> {
    let run_length = items.len() / runs.max(1);
    let sets = run_length / per.max(1);
    (0..sets)
        .map(|r| {
            items
                .chunks(run_length.max(1))
                .flat_map(|run| run[r * per..(r + 1) * per].iter().cloned())
                .collect()
        })
        .collect()
}

/// Which test compared two arms, and what it found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TestOutcome {
    /// The test: "Wilcoxon signed-rank" or "Kolmogorov-Smirnov".
    pub test: String,
    /// The arm compared against.
    pub against: String,
    /// The statistic as SciPy reports it.
    pub statistic: f64,
    /// The two-sided p-value.
    pub p_value: f64,
    /// How the p-value was computed: exact, permutation or asymptotic.
    pub method: String,
    /// Observations per sample (pairs, for the paired test).
    pub n: (usize, usize),
    /// When the arms have several agents: the same test agent by agent (each agent's games
    /// against the same-seed agent of `against`, or against all of `against` when it has
    /// one), the paper's protocol of one agent per arm.
    pub per_agent_p_values: Vec<f64>,
}

impl TestOutcome {
    fn from(test: &str, against: &ArmResult, n: (usize, usize), r: TestResult) -> TestOutcome {
        TestOutcome {
            per_agent_p_values: Vec::new(),
            test: test.into(),
            against: against.name.clone(),
            statistic: r.statistic,
            p_value: r.p_value,
            method: match r.method {
                Method::Exact => "exact",
                Method::Permutation => "permutation",
                Method::Asymptotic => "asymptotic",
            }
            .into(),
            n,
        }
    }

    /// The method of a paired test whose pairs are all equal.
    pub const IDENTICAL: &'static str = "identical samples";

    /// The paired Wilcoxon signed-rank test (SciPy's defaults) of `arm` against `base`:
    /// game by game, steps with a failure counted as the horizon. When every pair is equal
    /// no test can tell the arms apart (SciPy returns NaN): p is 1 and the method
    /// [`TestOutcome::IDENTICAL`].
    pub fn wilcoxon(arm: &ArmResult, base: &ArmResult) -> Result<TestOutcome> {
        let n = (arm.steps.len(), base.steps.len());
        if arm.steps == base.steps {
            return Ok(TestOutcome {
                test: "Wilcoxon signed-rank".into(),
                against: base.name.clone(),
                statistic: 0.0,
                p_value: 1.0,
                method: Self::IDENTICAL.into(),
                n,
                per_agent_p_values: Vec::new(),
            });
        }
        let r = stats::wilcoxon(&arm.steps, &base.steps, false)?;
        Ok(TestOutcome {
            per_agent_p_values: per_agent(arm, base, |x, y| {
                Ok(if x == y {
                    1.0
                } else {
                    stats::wilcoxon(x, y, false)?.p_value
                })
            })?,
            ..Self::from("Wilcoxon signed-rank", base, n, r)
        })
    }

    /// The two-sample Kolmogorov-Smirnov test (SciPy's defaults) of `arm`'s steps against
    /// `base`'s, a failure counted as the horizon.
    pub fn ks(arm: &ArmResult, base: &ArmResult) -> Result<TestOutcome> {
        let r = stats::ks_2samp(&arm.steps, &base.steps)?;
        Ok(TestOutcome {
            per_agent_p_values: per_agent(arm, base, |x, y| Ok(stats::ks_2samp(x, y)?.p_value))?,
            ..Self::from("Kolmogorov-Smirnov", base, (arm.steps.len(), base.steps.len()), r)
        })
    }

    /// How many agents' tests have p below `alpha`, of how many (`None` without per-agent
    /// tests).
    pub fn agents_below(&self, alpha: f64) -> Option<(usize, usize)> {
        (!self.per_agent_p_values.is_empty()).then(|| {
            (
                self.per_agent_p_values.iter().filter(|&&p| p < alpha).count(),
                self.per_agent_p_values.len(),
            )
        })
    }
}

/// `test`'s p-value for each agent of `arm` against the same-seed agent of `base` (or all
/// of `base` when it has one agent); none unless `arm` has several agents.
fn per_agent(arm: &ArmResult, base: &ArmResult, test: impl Fn(&[f64], &[f64]) -> Result<f64>) -> Result<Vec<f64>> {
    if arm.replicates < 2 || arm.games == 0 || !(base.replicates == 1 || base.replicates == arm.replicates) {
        return Ok(Vec::new());
    }
    arm.steps
        .chunks(arm.games)
        .enumerate()
        .map(|(r, x)| {
            let y = if base.replicates == 1 {
                &base.steps[..]
            } else {
                &base.steps[r * base.games..(r + 1) * base.games]
            };
            test(x, y)
        })
        .collect()
}

/// One world's measurement of an arm: its figures, its tests (in the order of
/// [`Table::tests`], `None` where a test does not apply), and where the paper's figures
/// fall against its replicates.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Measured {
    /// The arm's figures.
    pub arm: ArmResult,
    /// Its tests.
    pub tests: Vec<Option<TestOutcome>>,
    /// The paper's figures against the spread of this arm's replicates, for a row the paper
    /// has.
    pub paper_inside: Option<PaperInside>,
}

/// One row of a table: the paper's arm, ours in the paper's world as coded (`original`), and
/// ours in the SPEC world (`spec`); a row may lack any of them (E7 and our learner exist in
/// the SPEC world only).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// The arm's name.
    pub name: String,
    /// The paper's.
    pub paper: Option<PaperRow>,
    /// Ours under the `original` profile.
    pub original: Option<Measured>,
    /// Ours in the SPEC world.
    pub spec: Option<Measured>,
}

impl Row {
    /// A row of `paper`'s arm (if any) and ours in each world, each arm with its tests;
    /// the name is the first arm's.
    pub fn new(
        paper: Option<PaperRow>,
        original: Option<(ArmResult, Vec<Option<TestOutcome>>)>,
        spec: Option<(ArmResult, Vec<Option<TestOutcome>>)>,
    ) -> Row {
        let measured = |m: Option<(ArmResult, Vec<Option<TestOutcome>>)>| {
            m.map(|(arm, tests)| Measured {
                paper_inside: paper.as_ref().and_then(|p| arm.paper_inside(p)),
                arm,
                tests,
            })
        };
        let (original, spec) = (measured(original), measured(spec));
        let name = original
            .iter()
            .chain(&spec)
            .map(|m| m.arm.name.clone())
            .next()
            .or_else(|| paper.map(|p| p.arm.to_string()))
            .unwrap_or_default();
        Row {
            name,
            paper,
            original,
            spec,
        }
    }

    /// A row of the SPEC world only, beside the paper's arm if any.
    pub fn spec(paper: Option<PaperRow>, arm: ArmResult, tests: Vec<Option<TestOutcome>>) -> Row {
        Row::new(paper, None, Some((arm, tests)))
    }

    /// The measurement in `profile`'s world.
    pub fn in_world(&self, profile: Profile) -> Option<&Measured> {
        match profile {
            Profile::Original => self.original.as_ref(),
            Profile::Spec => self.spec.as_ref(),
        }
    }
}

/// A table of arms, the paper's beside ours in each world.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Table {
    /// The table's title.
    pub title: String,
    /// The games every arm played, per world: "original: ...", "spec: ...".
    pub suite: String,
    /// The paper's table this one reproduces, if any.
    pub paper: Option<PaperTable>,
    /// The tests' column headings, e.g. "Wilcoxon vs baseline".
    pub tests: Vec<String>,
    /// The rows.
    pub rows: Vec<Row>,
}

impl Table {
    /// The row named `name`.
    pub fn row(&self, name: &str) -> Option<&Row> {
        self.rows.iter().find(|r| r.name == name)
    }

    /// The worlds some row was measured in, the paper's first.
    pub fn worlds(&self) -> Vec<Profile> {
        [Profile::Original, Profile::Spec]
            .into_iter()
            .filter(|&p| self.rows.iter().any(|r| r.in_world(p).is_some()))
            .collect()
    }
}

/// Plays `suite` with each replicate's policy, on rayon's pool, one job each; the results
/// in replicate order whatever the threads.
pub fn play_replicates<'a, P, F>(
    suite: &Suite,
    replicates: &'a [P],
    policy: F,
    progress: &dyn ProgressSink,
    stage: &str,
) -> Result<Vec<Vec<EpisodeResult>>>
where
    P: Sync,
    F: Fn(&'a P) -> Result<Box<dyn Policy + 'a>> + Sync,
{
    use rayon::prelude::*;
    replicates
        .par_iter()
        .map(|p| {
            let mut policy = policy(p)?;
            let results = suite.play(policy.as_mut());
            progress.advance(stage);
            Ok(results?)
        })
        .collect()
}

/// A log-scale box plot of each row's steps per game in each world (a failure counted as
/// the horizon), each marked with the mean of the paper's row: E5's and E6's pictures.
pub fn steps_box_plot(title: String, rows: &[Row], replicates: usize, suite: &Suite) -> BoxPlot {
    let mut arms = Vec::new();
    for profile in [Profile::Original, Profile::Spec] {
        for row in rows {
            if let Some(m) = row.in_world(profile) {
                arms.push(Arm {
                    name: format!("{}, {profile}", row.name),
                    steps: m.arm.steps.clone(),
                    reference: row
                        .paper
                        .filter(|p| p.mean_over == MeanOver::FailuresAtHorizon)
                        .and_then(|p| p.mean_steps),
                });
            }
        }
    }
    BoxPlot {
        title,
        y_label: "steps to goal (failures at 1000)".into(),
        arms,
        reference_label: "paper's mean".into(),
        log_scale: true,
        note: format!(
            "{replicates} agents per arm, each {} (the same games for every arm of a world), in the original world \
             (the paper's, as coded) and in the SPEC world (ours).",
            describe(suite)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{Cell, State};

    fn suite(goals: Goals) -> Suite {
        suite_in(Profile::Spec, 3, goals, 4, 9)
    }

    #[test]
    fn a_recorded_game_is_the_played_one() {
        let s = suite(Goals::Each(vec!["0,1,2".parse().unwrap(), "2,1,0".parse().unwrap()]));
        let played = s.play(&mut agent::RandomPolicy).unwrap();
        assert_eq!(played.len(), 8);
        for index in [0, 5] {
            let obs = s.record(&mut agent::RandomPolicy, index).unwrap();
            assert_eq!(obs[0].state, played[index].start);
            assert_eq!(obs.len() as u32 - 1, played[index].steps);
            assert_eq!(obs[0].goal, played[index].goal);
        }
    }

    #[test]
    fn every_arm_plays_the_same_starts_and_the_optimum_is_below_them() {
        let s = suite(Goals::Drawn);
        let random = s.play(&mut agent::RandomPolicy).unwrap();
        let exact = s.play(&mut agent::ExactPolicy::new(s.world.grid)).unwrap();
        let optimum = s.optimum().unwrap();
        for ((r, e), o) in random.iter().zip(&exact).zip(&optimum) {
            assert_eq!((r.start.clone(), r.goal.clone()), (e.start.clone(), e.goal.clone()));
            assert_eq!(e.steps, *o);
            assert!(!r.reached_goal || r.steps >= *o);
        }
        let arm = ArmResult::of("exact", "exact", None, &[exact.clone(), exact], &optimum, 1000);
        assert_eq!(arm.mean_ratio_to_optimum, Some(1.0));
        assert_eq!((arm.replicates, arm.games, arm.failures), (2, 4, 0.0));
        assert_eq!(arm.steps.len(), 8);
    }

    #[test]
    fn sets_take_the_same_share_of_every_run() {
        // Two runs (goals) of three sets of two games.
        let items: Vec<u32> = (0..12).collect();
        assert_eq!(
            regroup(&items, 2, 2),
            vec![vec![0, 1, 6, 7], vec![2, 3, 8, 9], vec![4, 5, 10, 11]]
        );
        assert_eq!(
            regroup(&items, 1, 4),
            vec![vec![0, 1, 2, 3], vec![4, 5, 6, 7], vec![8, 9, 10, 11]]
        );
        let s = Suite {
            episodes: 6,
            ..suite(Goals::Each(vec!["0,1,2".parse().unwrap(), "2,1,0".parse().unwrap()]))
        };
        let played = s.play(&mut agent::RandomPolicy).unwrap();
        let arm = ArmResult::of_sets("random", "random", &played, 2, 2, &s.optimum().unwrap(), 1000);
        assert_eq!((arm.replicates, arm.games), (3, 4));
        assert_eq!(arm.steps.len(), 12);
    }

    #[test]
    fn failures_count_as_the_horizon_in_the_samples() {
        let mut s = suite(Goals::Drawn);
        s.world.horizon = 3;
        let random = s.play(&mut agent::RandomPolicy).unwrap();
        let arm = ArmResult::of(
            "random",
            "random",
            None,
            std::slice::from_ref(&random),
            &s.optimum().unwrap(),
            3,
        );
        assert_eq!(arm.failures as usize, random.iter().filter(|r| !r.reached_goal).count());
        for (r, &v) in random.iter().zip(&arm.steps) {
            assert_eq!(v, if r.reached_goal { f64::from(r.steps) } else { 3.0 });
        }
    }

    fn game(steps: u32, reached_goal: bool) -> EpisodeResult {
        EpisodeResult {
            episode: 0,
            seed: 0,
            goal: "1,0".parse::<Goal>().unwrap(),
            start: State::new(&[Cell::new(0, 0), Cell::new(3, 0)], None).unwrap(),
            steps,
            reached_goal,
            total_reward: 0.0,
        }
    }

    #[test]
    fn the_papers_row_is_placed_replicate_by_replicate() {
        // Two replicates of two games: failure rates 0.5 and 0, mean steps* 505 and 15.
        let replicates = [
            vec![game(10, true), game(7, false)],
            vec![game(10, true), game(20, true)],
        ];
        let arm = ArmResult::of("q", "q", Some(0.1), &replicates, &[], 1000);
        let row = |failures, mean| PaperRow {
            arm: "q",
            failures: Some(failures),
            games: Some(4),
            mean_steps: Some(mean),
            mean_over: MeanOver::FailuresAtHorizon,
            p_value: None,
        };
        let inside = arm.paper_inside(&row(1, 300.0)).unwrap();
        let f = inside.failure_rate.unwrap();
        assert_eq!((f.paper, f.spread.low, f.spread.high, f.inside), (0.25, 0.0, 0.5, true));
        let m = inside.mean_steps.unwrap();
        assert_eq!((m.spread.low, m.spread.high), (15.0, 505.0));
        // Over successes (E2's reading): 10 and 15.
        let successes = PaperRow {
            failures: None,
            mean_over: MeanOver::Successes,
            ..row(0, 12.0)
        };
        let inside = arm.paper_inside(&successes).unwrap();
        assert_eq!(inside.failure_rate, None);
        let m = inside.mean_steps.unwrap();
        assert_eq!((m.spread.low, m.spread.high, m.inside), (10.0, 15.0, true));
        assert!(inside.all_inside());
        let outside = arm.paper_inside(&row(3, 300.0)).unwrap();
        assert!(!outside.failure_rate.unwrap().inside && !outside.all_inside());
        let no_figures = PaperRow {
            failures: None,
            mean_steps: None,
            ..row(0, 0.0)
        };
        assert_eq!(arm.paper_inside(&no_figures), None);
    }
}
