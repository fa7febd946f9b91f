//! The reproduction of the paper (docs/world.md section 9): experiments E1-E8, each beside the
//! paper's figures, with their statistical tests, pictures, a report and machine-readable
//! results; and, as a benchmark of its own beside it, the classic Blocks World: E9, seen
//! from the side (docs/world.md section 12), and E10, one learned policy for that world at
//! every size (docs/dqn.md). `blockstack reproduce` is the command over the first
//! ([`Report::Paper`]), `blockstack benchmark` over the second ([`Report::BlocksWorld`]):
//! the same machinery, each its own report, since the benchmark is ours and measures what the
//! paper never did.
//!
//! [`reproduce`] runs the experiments asked for and returns the [`Reproduction`]: data only,
//! nothing printed, nothing written; [`write_report`] then draws the pictures and writes
//! `README.md`, `results.json` and the front page's summary, `summary.md` ([`summary`]),
//! into a directory, with where the run happened ([`Ran`]).
//!
//! # How a run is organised
//!
//! Every experiment is one module `e1` to `e10` with one signature, `run(&Context, &Shared)`,
//! listed once in [`EXPERIMENTS`] with its id, the jobs it reports and the parts of the
//! shared stage it needs; a [`Report`] runs its own of them. The shared stage (`Shared`) trains the agents several experiments
//! play (our learner, the paper's learner in the SPEC world) before the experiments that
//! need them, and only those the experiments asked for need: `--only E1` trains none of
//! them. The experiments that need nothing run while the shared stage trains.
//!
//! # How the experiments are run
//!
//! - **Two worlds.** The paper's figures were measured in the world its authors coded
//!   (docs/world.md section 10), not the one docs/world.md describes. E1-E6 run in both: under the `original`
//!   profile (the action protocol, start rule, reward, representation, schedule, oracle and
//!   correction rule of the authors' code, from `sim::Profile` and the agent crate's
//!   presets, [`TrainConfig::for_profile`]) and in the SPEC world; every row of a table puts
//!   the paper's figure, ours under `original` and ours in the SPEC world side by side. E1
//!   also plays the worlds between, one rule switched at a time ([`Decomposition`]). E7 and
//!   our own learner are the SPEC world's.
//! - **Spread.** Each of the paper's figures is placed against the range of our replicates
//!   in each world ([`PaperInside`], [`Spread`]): inside or outside its range, and the
//!   chance `(R - 1) / (R + 1)` that one more draw of ours would land inside the range of
//!   `R`.
//! - **Same starts for every arm.** Every arm of a comparison plays the same [`Suite`]:
//!   game `k` starts from `reset(episode_seed(test seed, k))`, with the same goal, so the
//!   paired tests (Wilcoxon) pair the same start, and an agent's random test actions come
//!   from its own stream of that seed (the starts never depend on the agent).
//! - **Replicates.** A learner's result depends a lot on its training seed (the paper's
//!   learner fails 20% to 40% of games depending on it), so each learner arm of E2-E6 is
//!   trained [`Scale::replicates`] times, with training seeds `seed, seed + 1, ...`, and
//!   every replicate plays the whole suite (E1's random agent: sets of the paper's 100
//!   games, each its own starts; E3's random agent likewise). Failures are given per
//!   replicate (mean and range), other figures over all games of all replicates, and a
//!   paired test pairs game `k` of replicate `r` of both arms (the same start, agents of
//!   the same training seed).
//! - **Steps.** The paper's "average number of steps" counts a failed game as the horizon
//!   (see [`paper`]); we print that figure beside the paper's, and also the mean and median
//!   over the games that reached the goal, and their ratio to the shortest plan (the exact
//!   solver's) from the same starts. The tests compare steps with a failure counted as
//!   the horizon.
//! - **Test policy.** Learners play as in the paper, a random action with probability 0.1
//!   ([`paper::SETTINGS`]), unless an experiment says otherwise (E2 is about the test
//!   epsilon; E3 and E7 also show learners playing greedily).
//! - **Deterministic.** Everything is fixed by [`Options::seed`]; independent runs go in
//!   parallel on rayon's pool (size it with a `rayon::ThreadPool`), and the results are
//!   the same whatever the number of threads.

mod arms;
mod budget;
mod e1;
mod e10;
mod e2;
mod e3;
mod e4;
mod e5;
mod e6;
mod e7;
mod e8;
mod e9;
pub mod paper;
mod ran;
mod report;
mod shared;
mod spread;
mod summary;
mod text;

pub use arms::{ArmResult, Goals, Measured, Row, Rules, Suite, Table, TestOutcome};
pub use budget::Budget;
pub use e1::{Decomposition, Gap, WorldArm};
pub use e8::{ArmRun, Game, arm_names as e8_arm_names, run_arm_of as run_e8_arm, start_order as e8_start_order};
pub use e9::{AgentFigures, Agreement, BlocksWorld, Group, Played, Problem};
pub use e10::{Family, General, SizeFigures, TrainingFigures};
pub use ran::Ran;
pub use report::{ReportFiles, write_report};
pub use spread::{PaperInside, Placement, Spread};
pub use summary::summary;

use agent::{Schedule, TrainConfig, Trained};
use rayon::prelude::*;
use serde::Serialize;
use sim::{Goal, Profile};
use thiserror::Error;

use crate::episode::EpisodeFrames;
use plots::{BarChart, BoxPlot, CurvesChart, LearningCurve, PlotError};
use shared::{Part, Shared};
use stats::StatsError;

/// The `format` field of `results.json`.
pub const FORMAT: &str = "blockstack-reproduction";
/// The `version` field of `results.json`; raised whenever a field changes meaning.
pub const VERSION: u32 = 1;

/// The horizon of every game (the paper's).
pub const HORIZON: u32 = paper::SETTINGS.horizon;

/// What can go wrong while reproducing.
#[derive(Debug, Error)]
pub enum ReproduceError {
    /// An agent could not train, play or be corrected.
    #[error(transparent)]
    Agent(#[from] agent::AgentError),
    /// The world refused something.
    #[error(transparent)]
    Sim(#[from] sim::SimError),
    /// A network could not be trained or played (E8).
    #[error(transparent)]
    Neural(#[from] neural::NeuralError),
    /// The exact solver could not plan.
    #[error(transparent)]
    Oracle(#[from] oracle::OracleError),
    /// A test could not run on the samples.
    #[error("statistics: {0}")]
    Stats(#[from] StatsError),
    /// A picture could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The report could not be written.
    #[error("cannot write {path}: {reason}")]
    Write {
        /// The file or directory.
        path: String,
        /// Why.
        reason: String,
    },
    /// The report's folder or one of its files could not be written.
    #[error(transparent)]
    Files(#[from] files::FilesError),
    /// An experiment id that is not one of the report's ([`Report::check`]).
    #[error("{}", unknown_experiment(id, *report))]
    UnknownExperiment {
        /// The id asked for.
        id: String,
        /// The report it was asked of.
        report: Report,
    },
    /// E8's arms could not be run where they were sent (a cluster).
    #[error("E8's arms: {0}")]
    Arms(String),
    /// A `results.json` that is not a reproduction's.
    #[error("not a reproduction's results.json: {reason}")]
    Results {
        /// What is missing or wrong.
        reason: String,
    },
}

/// Shorthand for results whose error is a [`ReproduceError`].
pub type Result<T, E = ReproduceError> = std::result::Result<T, E>;

/// Which report a run writes: the paper's reproduction or the Blocks World benchmark, each
/// with its own experiments, command and front matter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Report {
    /// The paper reproduced: E1-E8 (`blockstack reproduce`).
    #[default]
    Paper,
    /// The classic Blocks World, ours: E9 and E10 (`blockstack benchmark`).
    BlocksWorld,
}

impl Report {
    /// Its experiments, in the report's order.
    pub fn experiments(self) -> &'static [Spec] {
        match self {
            Report::Paper => &EXPERIMENTS[..8],
            Report::BlocksWorld => &EXPERIMENTS[8..],
        }
    }

    /// The `blockstack` subcommand that writes it.
    pub fn command(self) -> &'static str {
        match self {
            Report::Paper => "reproduce",
            Report::BlocksWorld => "benchmark",
        }
    }

    /// Its experiments' ids for messages: "E1 to E8", "E9 and E10".
    fn ids(self) -> String {
        let e = self.experiments();
        let join = if e.len() == 2 { "and" } else { "to" };
        format!("{} {join} {}", e[0].id, e[e.len() - 1].id)
    }

    /// `Ok` if every id of `only` names one of its experiments (in any case); otherwise the
    /// first that does not, with the report that has it if another does.
    pub fn check(self, only: &[String]) -> Result<()> {
        match only
            .iter()
            .find(|id| !self.experiments().iter().any(|e| e.id.eq_ignore_ascii_case(id)))
        {
            Some(id) => Err(ReproduceError::UnknownExperiment {
                id: id.clone(),
                report: self,
            }),
            None => Ok(()),
        }
    }
}

/// The message for an id `report` does not have: where it is, if another report has it.
fn unknown_experiment(id: &str, report: Report) -> String {
    let other = [Report::Paper, Report::BlocksWorld]
        .into_iter()
        .find(|r| *r != report && r.experiments().iter().any(|e| e.id.eq_ignore_ascii_case(id)));
    match other {
        Some(other) => format!(
            "{id} is not one of `blockstack {}`'s experiments ({}): run `blockstack {} --only {id}`",
            report.command(),
            report.ids(),
            other.command()
        ),
        None => format!("no experiment {id}: name experiments {}", report.ids()),
    }
}

/// What the user chose.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Options {
    /// The report: the paper's reproduction or the Blocks World benchmark.
    pub report: Report,
    /// The seed everything derives from.
    pub seed: u64,
    /// Small counts (a check that the pipeline works), not the paper's.
    pub quick: bool,
    /// E8's long budget: the pixel runs and the whole ablation ([`Budget::Long`]); E10's
    /// preset training and 1,000 problems per size; E9's
    /// many problems.
    pub long: bool,
    /// The experiments to run, by id (any case; the report's own: [`Report::experiments`]);
    /// empty for all of the report's. The agents they share are trained only when one of
    /// them needs them.
    pub only: Vec<String>,
}

impl Options {
    /// Whether experiment `id` is asked for.
    pub fn runs(&self, id: &str) -> bool {
        self.only.is_empty() || self.only.iter().any(|o| o.eq_ignore_ascii_case(id))
    }
}

/// How much is run: the paper's counts, or small ones with `--quick`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Scale {
    /// Agents trained (with different seeds) per learner arm of E2-E6.
    pub replicates: usize,
    /// E4: agents behind the paper's learner's curve in the SPEC world (the first of the
    /// training seeds; a long training, and no figure of the paper's to read against).
    pub curve_replicates: usize,
    /// E1's games per replicate (the paper's 100).
    pub e1_games: u64,
    /// E1's replicates: sets of `e1_games` games of their own, in each world.
    pub e1_replicates: usize,
    /// Test games of E2, E4's points, E5 and each table of E6 (the paper's 500), and of each
    /// goal in E7.
    pub test_games: u64,
    /// E3's test games per unseen goal (the paper's 100 in all, over two goals).
    pub e3_games_per_goal: u64,
    /// Training games of the paper's learner in the SPEC world (not given in the paper; the
    /// preset of [`TrainConfig::paper`]).
    pub paper_games: u64,
    /// Training games (of up to 5000 steps) of the paper's learner in the original world
    /// (the preset of [`TrainConfig::original`]: the most of Fig. 3, and E3's).
    pub original_games: u64,
    /// E4: where the paper's learner is tested along its training in the original world,
    /// in games (Fig. 3's points among them).
    pub original_curve: Vec<u64>,
    /// Training games of our learner ([`TrainConfig::role_step_cost`]'s preset).
    pub ours_games: u64,
    /// E4: where the paper's learner is tested along its training, in games.
    pub paper_curve: Vec<u64>,
    /// E4: where our learner is tested along its training, in games (the last is
    /// `ours_games`).
    pub ours_curve: Vec<u64>,
    /// E6: demonstrations per demonstrator (the paper's 10).
    pub demos: u64,
}

impl Scale {
    /// The paper's counts (`quick`: small ones). Training lengths are the agent crate's
    /// presets; the learning curves test at fractions and multiples of them.
    pub fn new(quick: bool) -> Scale {
        let paper_games = TrainConfig::paper(Vec::new()).games;
        let original_games = TrainConfig::original(Vec::new()).games;
        let ours_games = TrainConfig::role_step_cost(Vec::new()).games;
        let at = |games: u64, per_mille: &[u64]| -> Vec<u64> { per_mille.iter().map(|m| games * m / 1000).collect() };
        if quick {
            Scale {
                replicates: 2,
                curve_replicates: 2,
                e1_games: 100,
                e1_replicates: 5,
                test_games: 100,
                e3_games_per_goal: 50,
                paper_games,
                original_games,
                original_curve: at(original_games, &[50, 500, 1000]),
                ours_games,
                paper_curve: at(paper_games, &[0, 200, 1000]),
                ours_curve: at(ours_games, &[0, 50, 200, 1000]),
                demos: paper::E6_DEMOS,
            }
        } else {
            Scale {
                replicates: 20,
                curve_replicates: 5,
                e1_games: 100,
                e1_replicates: 20,
                test_games: 500,
                e3_games_per_goal: 50,
                paper_games,
                original_games,
                original_curve: at(original_games, &[0, 50, 100, 250, 500, 1000, 2000]),
                ours_games,
                paper_curve: at(paper_games, &[0, 100, 200, 400, 1000, 2000, 4000, 10_000]),
                ours_curve: at(ours_games, &[0, 20, 50, 100, 200, 500, 1000]),
                demos: paper::E6_DEMOS,
            }
        }
    }

    /// Training games of the paper's learner in `world`.
    pub fn paper_games(&self, world: Profile) -> u64 {
        match world {
            Profile::Spec => self.paper_games,
            Profile::Original => self.original_games,
        }
    }
}

/// The seeds of a run, all derived from [`Options::seed`] `s`.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Seeds {
    /// The training seed of each replicate: `s, s + 1, ...`.
    pub training: Vec<u64>,
    /// Our learner's training seed: `s`.
    pub ours: u64,
    /// The seed of every test suite's starts: `s + 1000`.
    pub test: u64,
    /// E6: each demonstrator's session seed (starts, the agent's proposals, the
    /// demonstrator's choices): `s + 2001`, `s + 2002`, `s + 2003`.
    pub demonstrations: Vec<u64>,
}

impl Seeds {
    /// The seeds derived from `seed` for `scale`.
    pub fn new(seed: u64, scale: &Scale) -> Seeds {
        Seeds {
            training: (0..scale.replicates.max(scale.curve_replicates) as u64)
                .map(|r| seed.wrapping_add(r))
                .collect(),
            ours: seed,
            test: seed.wrapping_add(1000),
            demonstrations: (1..=3).map(|d| seed.wrapping_add(2000 + d)).collect(),
        }
    }
}

/// Where progress goes: told the number of jobs once, then each job as it ends (from any
/// thread).
pub trait ProgressSink: Sync {
    /// The run has `jobs` jobs.
    fn begin(&self, _jobs: u64) {}
    /// A job of experiment `stage` (e.g. "E5") ended.
    fn advance(&self, _stage: &str) {}
    /// Part `part` of experiment `stage` ended after `took` of wall time (E8: an arm,
    /// trained and tested): where a long run's time goes, for its log; never a figure of
    /// the report, which does not depend on the machine.
    fn finished(&self, _stage: &str, _part: &str, _took: std::time::Duration) {}
}

/// No progress reports.
impl ProgressSink for () {}

/// One parameter of an experiment, for the report's "what was run".
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Setting {
    /// What it is.
    pub name: String,
    /// Its value.
    pub value: String,
}

/// One point of a learning curve: an agent tested after some training.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CurvePoint {
    /// Training games played.
    pub games: u64,
    /// Test games over all replicates.
    pub test_games: usize,
    /// Mean failures per replicate.
    pub failures: f64,
    /// Share of test games failed.
    pub failure_rate: f64,
    /// The share of test games failed, replicate by replicate (`None` for one replicate).
    pub failure_rate_spread: Option<Spread>,
    /// Mean steps, a failure counted as the horizon.
    pub mean_steps_failures_at_horizon: f64,
    /// Mean steps*, replicate by replicate (`None` for one replicate).
    pub mean_steps_failures_at_horizon_spread: Option<Spread>,
    /// Mean steps over the games that reached the goal.
    pub mean_steps: Option<f64>,
}

impl CurvePoint {
    /// The point after `games` training games whose tests gave `arm`.
    pub fn of(games: u64, arm: &ArmResult) -> CurvePoint {
        let spread = |values: &[f64]| Spread::of(values).filter(|s| s.replicates > 1);
        CurvePoint {
            games,
            test_games: arm.steps.len(),
            failures: arm.failures,
            failure_rate: arm.failure_rate(),
            failure_rate_spread: spread(&arm.failure_rate_per_replicate()),
            mean_steps_failures_at_horizon: arm.mean_steps_failures_at_horizon,
            mean_steps_failures_at_horizon_spread: spread(&arm.mean_steps_failures_at_horizon_per_replicate),
            mean_steps: arm.mean_steps,
        }
    }
}

/// A learner's learning curve.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Curve {
    /// The learner.
    pub learner: String,
    /// The world it learns and is tested in.
    pub world: Profile,
    /// The test-time probability of a random action.
    pub test_epsilon: f64,
    /// The test games at every point.
    pub suite: String,
    /// The points, by training games.
    pub points: Vec<CurvePoint>,
}

/// What a picture shows, to be drawn by [`write_report`].
#[derive(Clone, Debug, PartialEq)]
pub enum Drawing {
    /// A learning curve (PNG and SVG).
    Learning(LearningCurve),
    /// Box plots (PNG and SVG).
    Boxes(BoxPlot),
    /// A bar chart (PNG and SVG).
    Bars(BarChart),
    /// An animated episode (GIF).
    Episode(Vec<EpisodeFrames>),
    /// Several learners' curves on one chart (PNG and SVG).
    Curves(CurvesChart),
}

/// A picture of the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Figure {
    /// The files' name without extension, e.g. `e7-steps`.
    pub stem: String,
    /// What it shows.
    pub caption: String,
    /// The files it is written to, relative to the report.
    pub files: Vec<String>,
    /// The data.
    #[serde(skip)]
    pub drawing: Drawing,
}

impl Figure {
    /// A picture named `stem`.
    pub fn new(stem: &str, caption: String, drawing: Drawing) -> Figure {
        let files = match drawing {
            Drawing::Episode(_) => vec![format!("{stem}.gif")],
            _ => vec![format!("{stem}.png"), format!("{stem}.svg")],
        };
        Figure {
            stem: stem.into(),
            caption,
            files,
            drawing,
        }
    }
}

/// One experiment's results, ready for the report: what every experiment has (its setup,
/// tables, reading and pictures), and [`Findings`], what is its own.
#[derive(Clone, Debug, PartialEq)]
pub struct Experiment {
    /// "E1" to "E10".
    pub id: String,
    /// What it asks.
    pub title: String,
    /// What was run.
    pub setup: Vec<Setting>,
    /// Its tables, ours beside the paper's.
    pub tables: Vec<Table>,
    /// Where the paper's own figures cannot hold, each computed from them (E3's p-value).
    pub paper_notes: Vec<String>,
    /// One line saying what the figures show, computed from them.
    pub reading: String,
    /// Its pictures.
    pub figures: Vec<Figure>,
    /// What this experiment alone measures.
    pub findings: Findings,
}

/// What one experiment measures beyond the tables every experiment has: each experiment's
/// own result, so that none carries the others' fields.
#[derive(Clone, Debug, PartialEq)]
pub enum Findings {
    /// Tables only (E2, E3, E5 to E8).
    Tables,
    /// E1: the gap between the two worlds, rule by rule.
    Decomposition(Decomposition),
    /// E4: the learning curves.
    Curves(Vec<Curve>),
    /// E9: the problems, grouped, and the physics against the grid model.
    BlocksWorld(BlocksWorld),
    /// E10: the general policy's training and problems by size.
    General(General),
}

/// `results.json` keeps the layout it had before [`Findings`]: `curves` and
/// `decomposition` in every experiment (empty when not its own), `blocks_world` and
/// `general` only in E9's and E10's.
impl Serialize for Experiment {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let f = &self.findings;
        let own = usize::from(matches!(f, Findings::BlocksWorld(_) | Findings::General(_)));
        let mut s = serializer.serialize_struct("Experiment", 9 + own)?;
        s.serialize_field("id", &self.id)?;
        s.serialize_field("title", &self.title)?;
        s.serialize_field("setup", &self.setup)?;
        s.serialize_field("tables", &self.tables)?;
        let no_curves: &[Curve] = &[];
        s.serialize_field(
            "curves",
            if let Findings::Curves(c) = f {
                c.as_slice()
            } else {
                no_curves
            },
        )?;
        s.serialize_field(
            "decomposition",
            &if let Findings::Decomposition(d) = f {
                Some(d)
            } else {
                None
            },
        )?;
        s.serialize_field("paper_notes", &self.paper_notes)?;
        s.serialize_field("reading", &self.reading)?;
        s.serialize_field("figures", &self.figures)?;
        match f {
            Findings::BlocksWorld(w) => s.serialize_field("blocks_world", w)?,
            Findings::General(g) => s.serialize_field("general", g)?,
            _ => {}
        }
        s.end()
    }
}

/// The whole run's results: what `results.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Reproduction {
    /// [`FORMAT`].
    pub format: &'static str,
    /// [`VERSION`].
    pub version: u32,
    /// The options.
    pub options: Options,
    /// The counts.
    pub scale: Scale,
    /// The seeds.
    pub seeds: Seeds,
    /// The paper's learner settings, as the paper states them.
    pub paper_settings: paper::PaperSettings,
    /// The experiments run, in order.
    pub experiments: Vec<Experiment>,
}

/// What every experiment shares: the counts, the seeds, E8's budget, and where progress
/// goes.
pub(crate) struct Context<'a> {
    scale: Scale,
    seeds: Seeds,
    budget: Budget,
    progress: &'a dyn ProgressSink,
    arms: &'a dyn ArmRunner,
}

/// Runs E8's arms, its costliest work (each a network trained for up to an hour): here on
/// rayon's pool ([`LocalArms`]), or elsewhere, such as on the nodes of a cluster (the Python
/// package's `blockstack.reproduce --ray`), each arm then run by [`run_e8_arm`] with
/// this run's options. Every arm is fixed by its seed, so where it runs changes no figure.
pub trait ArmRunner: Sync {
    /// The runs of E8's arms `0..start.len()`, in the arms' order; `here` runs one in this
    /// process. `start` lists the arms' indices costliest first (E8's estimate): a runner
    /// with fewer threads than arms starts them in that order, so that the longest is not
    /// left to the end, when the other threads would have nothing to do.
    fn run_arms(&self, start: &[usize], here: &(dyn Fn(usize) -> Result<ArmRun> + Sync)) -> Result<Vec<ArmRun>>;
}

/// E8's arms run here, side by side on the current rayon pool: each thread takes the next
/// arm of `start` as it finishes one (the longest first, then the others: a greedy
/// packing whose end is within the last arm's length of the best). After an arm fails no
/// other is started, and the error of the first failed arm in the arms' order is returned.
pub struct LocalArms;

impl ArmRunner for LocalArms {
    fn run_arms(&self, start: &[usize], here: &(dyn Fn(usize) -> Result<ArmRun> + Sync)) -> Result<Vec<ArmRun>> {
        use std::sync::Mutex;
        use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
        let (next, failed) = (AtomicUsize::new(0), AtomicBool::new(false));
        let runs: Vec<Mutex<Option<Result<ArmRun>>>> = start.iter().map(|_| Mutex::new(None)).collect();
        rayon::scope(|s| {
            for _ in 0..rayon::current_num_threads().min(start.len()) {
                s.spawn(|_| {
                    while !failed.load(Ordering::Acquire) {
                        let Some(&arm) = start.get(next.fetch_add(1, Ordering::AcqRel)) else {
                            break;
                        };
                        let run = here(arm);
                        if run.is_err() {
                            failed.store(true, Ordering::Release);
                        }
                        *runs[arm].lock().expect("no arm panics holding it") = Some(run);
                    }
                });
            }
        });
        // The arms that ran, in the arms' order: after a failure some never started, and
        // the first failed arm's error is the answer; without one, every arm ran.
        let runs = runs
            .into_iter()
            .filter_map(|m| m.into_inner().expect("no arm panics holding it"))
            .collect::<Result<Vec<ArmRun>>>()?;
        assert_eq!(runs.len(), start.len(), "every arm ran");
        Ok(runs)
    }
}

/// One experiment of the reproduction, as [`EXPERIMENTS`] lists it.
pub struct Spec {
    /// "E1" to "E10".
    pub id: &'static str,
    /// The parts of the shared stage it plays.
    needs: &'static [Part],
    /// The jobs it reports to the [`ProgressSink`].
    jobs: fn(&Context) -> u64,
    /// Runs it.
    run: fn(&Context, &Shared) -> Result<Experiment>,
}

/// Every experiment, in the reports' order: E1-E7 are the paper's section VI (E7 the table
/// it never had), E8 its section III-C ([`Report::Paper`]); E9 the classic Blocks World
/// (ours), E10 one learned policy for it at every size (ours) ([`Report::BlocksWorld`]).
pub const EXPERIMENTS: [Spec; 10] = [
    Spec {
        id: "E1",
        needs: &[],
        jobs: e1::jobs,
        run: e1::run,
    },
    Spec {
        id: "E2",
        needs: &[],
        jobs: e2::jobs,
        run: e2::run,
    },
    Spec {
        id: "E3",
        needs: &[Part::Ours],
        jobs: e3::jobs,
        run: e3::run,
    },
    Spec {
        id: "E4",
        needs: &[Part::OursCurve],
        jobs: e4::jobs,
        run: e4::run,
    },
    Spec {
        id: "E5",
        needs: &[],
        jobs: e5::jobs,
        run: e5::run,
    },
    Spec {
        id: "E6",
        needs: &[],
        jobs: e6::jobs,
        run: e6::run,
    },
    Spec {
        id: "E7",
        needs: &[Part::Ours, Part::PaperSpec],
        jobs: e7::jobs,
        run: e7::run,
    },
    Spec {
        id: "E8",
        needs: &[],
        jobs: e8::jobs,
        run: e8::run,
    },
    Spec {
        id: "E9",
        needs: &[],
        jobs: e9::jobs,
        run: e9::run,
    },
    Spec {
        id: "E10",
        needs: &[],
        jobs: e10::jobs,
        run: e10::run,
    },
];

/// The worlds E1-E6 are run in: the paper's as coded, then ours.
const WORLDS: [Profile; 2] = [Profile::Original, Profile::Spec];

/// The paper's learner as the report names it: representation, reward, schedule and the
/// hyper-parameters of `config`.
fn paper_learner(config: &TrainConfig) -> String {
    let p = &config.params;
    let schedule = match config.schedule {
        Schedule::Spec => format!(
            "training games of up to {} steps ended by the goal",
            config.world.horizon
        ),
        Schedule::PaperCode => format!(
            "the authors' schedule: training games of up to {} steps on a goal drawn per game, ended by a step \
             reward above 70, alpha lowered after step 4000, the update over seen entries",
            config.world.horizon
        ),
    };
    format!(
        "{} representation, {} reward, alpha {}, gamma {}, epsilon {}, {schedule}",
        config.repr,
        config.world.reward.name(),
        p.alpha,
        p.gamma,
        p.epsilon
    )
}

impl Context<'_> {
    /// The paper's learner in `world` on `goals`, replicate `r`'s seed: the agent crate's
    /// preset of that world ([`TrainConfig::for_profile`]) for the scale's games there.
    fn paper_config(&self, world: Profile, goals: &[Goal], r: usize) -> TrainConfig {
        TrainConfig {
            seed: self.seeds.training[r],
            games: self.scale.paper_games(world),
            ..TrainConfig::for_profile(world, goals.to_vec())
        }
    }

    /// `f` in the original world and in the SPEC world, side by side on rayon's pool.
    fn in_both_worlds<T, F>(&self, f: F) -> Result<(T, T)>
    where
        T: Send,
        F: Fn(Profile) -> Result<T> + Sync,
    {
        let (original, spec) = rayon::join(|| f(Profile::Original), || f(Profile::Spec));
        Ok((original?, spec?))
    }

    /// Trains every replicate of `config(r)` in parallel, one job each.
    fn train_replicates<F>(&self, stage: &str, config: F) -> Result<Vec<Trained>>
    where
        F: Fn(usize) -> TrainConfig + Sync,
    {
        (0..self.scale.replicates)
            .into_par_iter()
            .map(|r| {
                let trained = agent::train(&config(r), None)?;
                self.progress.advance(stage);
                Ok(trained)
            })
            .collect()
    }

    /// The paper's test policy's epsilon.
    fn test_epsilon(&self) -> f64 {
        paper::SETTINGS.test_epsilon
    }
}

/// Parses goals written by [`paper`] (known good).
fn goals(texts: &[&str]) -> Vec<Goal> {
    texts
        .iter()
        .map(|t| t.parse().expect("the paper's goals parse"))
        .collect()
}

/// The parts of the shared stage `chosen` need, each once.
fn needs(chosen: &[&Spec]) -> Vec<Part> {
    let mut needs = Vec::new();
    for part in chosen.iter().flat_map(|e| e.needs) {
        if !needs.contains(part) {
            needs.push(*part);
        }
    }
    needs
}

/// Runs the experiments `options` ask for, reporting progress to `progress`, on the
/// current rayon pool.
pub fn reproduce(options: &Options, progress: &dyn ProgressSink) -> Result<Reproduction> {
    reproduce_with(options, Scale::new(options.quick), progress)
}

/// [`reproduce`] with E8's arms run by `arms` (a cluster, say), the rest here: the same
/// figures.
pub fn reproduce_on(options: &Options, progress: &dyn ProgressSink, arms: &dyn ArmRunner) -> Result<Reproduction> {
    run(options, Scale::new(options.quick), progress, arms)
}

/// Runs the experiments `options` ask for with counts of one's own for E1-E7 (each schedule
/// in `scale` must have a point, and `replicates` must be at least 1); E8's budget comes
/// from `options`.
///
/// The shared stage trains what the chosen experiments need while those that need nothing
/// of it run; then the others run. Every result is fixed by its seed, so neither this
/// order nor the number of threads changes any figure.
pub fn reproduce_with(options: &Options, scale: Scale, progress: &dyn ProgressSink) -> Result<Reproduction> {
    run(options, scale, progress, &LocalArms)
}

/// [`reproduce_with`], E8's arms run by `arms`.
fn run(options: &Options, scale: Scale, progress: &dyn ProgressSink, arms: &dyn ArmRunner) -> Result<Reproduction> {
    options.report.check(&options.only)?;
    let chosen: Vec<&Spec> = options
        .report
        .experiments()
        .iter()
        .filter(|e| options.runs(e.id))
        .collect();
    let needs = needs(&chosen);
    let seeds = Seeds::new(options.seed, &scale);
    let ctx = Context {
        scale,
        seeds,
        budget: Budget::of(options),
        progress,
        arms,
    };
    progress.begin(Shared::jobs(&ctx, &needs) + chosen.iter().map(|e| (e.jobs)(&ctx)).sum::<u64>());
    let (free, bound): (Vec<&Spec>, Vec<&Spec>) = chosen.iter().partition(|e| e.needs.is_empty());
    let run_all = |specs: &[&Spec], shared: &Shared| -> Result<Vec<Experiment>> {
        specs.iter().map(|e| (e.run)(&ctx, shared)).collect()
    };
    // Our learner trains for longest: it goes on one thread while the rest share the others.
    let (shared, free) = rayon::join(|| Shared::train(&ctx, &needs), || run_all(&free, &Shared::default()));
    let (shared, free) = (shared?, free?);
    let bound = run_all(&bound, &shared)?;
    // Back in the table's order.
    let mut experiments: Vec<Experiment> = free.into_iter().chain(bound).collect();
    experiments.sort_by_key(|e| EXPERIMENTS.iter().position(|s| s.id == e.id));
    Ok(Reproduction {
        format: FORMAT,
        version: VERSION,
        options: options.clone(),
        scale: ctx.scale,
        seeds: ctx.seeds,
        paper_settings: paper::SETTINGS,
        experiments,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Counts the jobs announced and reported, and keeps the parts said to have finished.
    #[derive(Default)]
    struct Count {
        announced: AtomicU64,
        done: AtomicU64,
        finished: std::sync::Mutex<Vec<String>>,
    }

    impl ProgressSink for Count {
        fn begin(&self, jobs: u64) {
            self.announced.store(jobs, Ordering::SeqCst);
        }

        fn advance(&self, _stage: &str) {
            self.done.fetch_add(1, Ordering::SeqCst);
        }

        fn finished(&self, stage: &str, part: &str, _took: std::time::Duration) {
            self.finished.lock().unwrap().push(format!("{stage}: {part}"));
        }
    }

    /// Tiny counts: the whole pipeline in about a second.
    fn tiny() -> Scale {
        Scale {
            replicates: 2,
            curve_replicates: 2,
            e1_games: 6,
            e1_replicates: 2,
            test_games: 6,
            e3_games_per_goal: 3,
            paper_games: 60,
            original_games: 5,
            original_curve: vec![0, 5],
            ours_games: 3000,
            paper_curve: vec![0, 60, 120],
            ours_curve: vec![0, 3000],
            demos: 2,
        }
    }

    /// The experiments of `report` that `only` asks for, on `threads` threads: the results,
    /// the jobs announced and the jobs reported.
    fn run_only(threads: usize, report: Report, only: &[&str]) -> (Reproduction, u64, u64) {
        let count = Count::default();
        let r = run_counted(threads, report, only, &count);
        (r, count.announced.into_inner(), count.done.into_inner())
    }

    /// The quick run of `report`'s `only` (empty: all) that these tests make, seed 5.
    fn quick_options(report: Report, only: &[&str]) -> Options {
        Options {
            report,
            seed: 5,
            quick: true,
            long: false,
            only: only.iter().map(|id| id.to_string()).collect(),
        }
    }

    /// That run with [`tiny`] counts on `threads` threads, its progress told to `count`.
    fn run_counted(threads: usize, report: Report, only: &[&str], count: &Count) -> Reproduction {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| reproduce_with(&quick_options(report, only), tiny(), count))
            .unwrap()
    }

    fn run(threads: usize, report: Report) -> (Reproduction, u64, u64) {
        run_only(threads, report, &[])
    }

    /// The jobs the run of `report`'s `only` (empty: all) announces: each experiment's and
    /// the shared parts they need.
    fn jobs(report: Report, only: &[&str]) -> u64 {
        let ctx = Context {
            scale: tiny(),
            seeds: Seeds::new(5, &tiny()),
            budget: Budget::Quick,
            progress: &(),
            arms: &LocalArms,
        };
        let chosen: Vec<&Spec> = report
            .experiments()
            .iter()
            .filter(|e| only.is_empty() || only.contains(&e.id))
            .collect();
        Shared::jobs(&ctx, &needs(&chosen)) + chosen.iter().map(|e| (e.jobs)(&ctx)).sum::<u64>()
    }

    #[test]
    fn the_results_do_not_depend_on_the_threads_and_every_job_is_reported() {
        for (report, expected) in [
            (Report::Paper, &["E1", "E2", "E3", "E4", "E5", "E6", "E7", "E8"][..]),
            (Report::BlocksWorld, &["E9", "E10"][..]),
        ] {
            let (one, announced, done) = run(1, report);
            let (three, _, _) = run(3, report);
            assert_eq!(
                serde_json::to_string(&one).unwrap(),
                serde_json::to_string(&three).unwrap()
            );
            assert_eq!(one, three, "the samples behind the tables too");
            assert_eq!(announced, jobs(report, &[]));
            assert_eq!(done, announced);
            let ids: Vec<&str> = one.experiments.iter().map(|e| e.id.as_str()).collect();
            assert_eq!(ids, expected);
        }
    }

    /// Each E8 arm is said to have finished once, by its name, whichever thread ran it.
    #[test]
    fn every_e8_arm_is_said_to_have_finished_once() {
        let count = Count::default();
        run_counted(2, Report::Paper, &["E8"], &count);
        let mut finished = count.finished.into_inner().unwrap();
        finished.sort();
        let mut arms: Vec<String> = e8::arm_names(&quick_options(Report::Paper, &["E8"]))
            .unwrap()
            .into_iter()
            .map(|name| format!("E8: {name}"))
            .collect();
        arms.sort();
        assert!(!arms.is_empty());
        assert_eq!(finished, arms);
    }

    /// Local arms start in the order given and come back in the arms' order; after a
    /// failure no arm starts, and the error is the first failed arm's.
    #[test]
    fn local_arms_start_costliest_first_and_come_back_in_order() {
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let run = |i: usize| ArmRun {
            curve: Vec::new(),
            games: Vec::new(),
            gradient_steps: i as u64,
        };
        let started = std::sync::Mutex::new(Vec::new());
        let runs = one
            .install(|| {
                LocalArms.run_arms(&[2, 0, 3, 1], &|i| {
                    started.lock().unwrap().push(i);
                    Ok(run(i))
                })
            })
            .unwrap();
        assert_eq!(*started.lock().unwrap(), [2, 0, 3, 1]);
        assert_eq!(runs, (0..4).map(run).collect::<Vec<_>>());
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let started = std::sync::Mutex::new(Vec::new());
            let e = pool
                .install(|| {
                    LocalArms.run_arms(&[3, 1, 0, 2], &|i| {
                        started.lock().unwrap().push(i);
                        match i {
                            3 => Err(ReproduceError::Arms("arm 3".into())),
                            i => Ok(run(i)),
                        }
                    })
                })
                .unwrap_err();
            assert_eq!(e.to_string(), "E8's arms: arm 3");
            if threads == 1 {
                assert_eq!(*started.lock().unwrap(), [3], "nothing starts after a failure");
            }
        }
    }

    /// E8's arms run one at a time by [`run_e8_arm`] with their runs sent through JSON, as
    /// a cluster's nodes send them.
    struct ThroughJson(Options);

    impl ArmRunner for ThroughJson {
        fn run_arms(&self, start: &[usize], _: &(dyn Fn(usize) -> Result<ArmRun> + Sync)) -> Result<Vec<ArmRun>> {
            (0..start.len())
                .map(|i| {
                    let sent = serde_json::to_string(&run_e8_arm(&self.0, i, None)?).unwrap();
                    Ok(serde_json::from_str(&sent).unwrap())
                })
                .collect()
        }
    }

    #[test]
    fn e8_arms_run_elsewhere_give_the_same_report() {
        let options = Options {
            report: Report::Paper,
            seed: 3,
            quick: true,
            long: false,
            only: vec!["E8".into()],
        };
        let here = reproduce(&options, &()).unwrap();
        let elsewhere = reproduce_on(&options, &(), &ThroughJson(options.clone())).unwrap();
        assert_eq!(
            serde_json::to_string(&here).unwrap(),
            serde_json::to_string(&elsewhere).unwrap()
        );
        assert_eq!(here, elsewhere, "the samples behind the tables too");
        assert_eq!(e8_arm_names(&options).unwrap().len(), 2);
        assert!(run_e8_arm(&options, 2, None).is_err(), "no third arm at this budget");
    }

    #[test]
    fn an_e8_arm_goes_on_from_its_checkpoint() {
        let options = Options {
            report: Report::Paper,
            seed: 3,
            quick: true,
            long: false,
            only: vec!["E8".into()],
        };
        let dir = tempfile::tempdir().unwrap();
        let ck = dir.path().join("arm1");
        let whole = run_e8_arm(&options, 1, None).unwrap();
        assert_eq!(run_e8_arm(&options, 1, Some(&ck)).unwrap(), whole);
        // Its checkpoint holds every point of its curve: run again, it only plays the final
        // tests, the same games.
        assert_eq!(run_e8_arm(&options, 1, Some(&ck)).unwrap(), whole);
        let e = run_e8_arm(&options, 0, Some(&ck)).unwrap_err().to_string();
        assert!(e.contains("holds a run of another arm"), "{e}");
    }

    #[test]
    fn each_experiment_alone_trains_only_what_it_needs_and_gives_the_same_figures() {
        for report in [Report::Paper, Report::BlocksWorld] {
            let (all, _, _) = run(2, report);
            assert_eq!(all.experiments.len(), report.experiments().len());
            for (spec, full) in report.experiments().iter().zip(&all.experiments) {
                let (alone, announced, done) = run_only(2, report, &[spec.id]);
                assert_eq!(alone.experiments, std::slice::from_ref(full), "{}", spec.id);
                assert_eq!((announced, done), (jobs(report, &[spec.id]), announced), "{}", spec.id);
            }
        }
        // E1 needs no shared agent; E3 plays our learner, trained without the tests along its
        // curve, which only E4 needs (and which give E3 its agent when both run).
        let scale = tiny();
        let e1_own = EXPERIMENTS[0].jobs;
        let e3_own = WORLDS.len() as u64 * (2 * scale.replicates as u64 + 1) + 2;
        let curve = 2 * scale.ours_curve.len() as u64;
        let ctx = Context {
            scale: tiny(),
            seeds: Seeds::new(5, &tiny()),
            budget: Budget::Quick,
            progress: &(),
            arms: &LocalArms,
        };
        let paper = Report::Paper;
        assert_eq!(jobs(paper, &["E1"]), e1_own(&ctx));
        assert_eq!(jobs(paper, &["E3"]), e3_own + 1, "one training of our learner");
        assert_eq!(jobs(paper, &["E4"]), e4::jobs(&ctx) + curve);
        assert_eq!(jobs(paper, &["E3", "E4"]), e3_own + e4::jobs(&ctx) + curve);
        let (e3, _, _) = run_only(1, paper, &["e3"]);
        assert_eq!(e3.experiments.len(), 1, "ids in any case");
        // An id no report has, and one the other report has: each says what to run instead.
        for (report, id, message) in [
            (paper, "E11", "no experiment E11: name experiments E1 to E8"),
            (
                paper,
                "e9",
                "e9 is not one of `blockstack reproduce`'s experiments (E1 to E8): run `blockstack benchmark --only e9`",
            ),
            (
                Report::BlocksWorld,
                "E8",
                "E8 is not one of `blockstack benchmark`'s experiments (E9 and E10): run `blockstack reproduce --only E8`",
            ),
        ] {
            let options = Options {
                report,
                seed: 5,
                quick: true,
                long: false,
                only: vec![id.into()],
            };
            let err = reproduce_with(&options, tiny(), &()).unwrap_err();
            assert_eq!(err.to_string(), message);
        }
    }

    #[test]
    fn the_report_holds_every_experiment_and_its_pictures() {
        let (r, _, _) = run(2, Report::Paper);
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path().join("report");
        let ran = Ran {
            commit: "abc1234".into(),
            cpu: "a test CPU".into(),
            cores: 4,
            threads: 2,
        };
        let files = write_report(&r, &ran, &dir).unwrap();
        let readme = std::fs::read_to_string(&files.readme).unwrap();
        for e in &r.experiments {
            assert!(readme.contains(&format!("## {}: {}", e.id, e.title)), "{}", e.id);
            assert!(readme.contains(&e.reading));
            for f in &e.figures {
                for file in &f.files {
                    assert!(dir.join(file).is_file(), "{file}");
                }
                assert!(readme.contains(&format!("]({})", f.files[0])));
            }
        }
        assert_eq!(
            files.pictures.len(),
            r.experiments
                .iter()
                .map(|e| e.figures.iter().map(|f| f.files.len()).sum::<usize>())
                .sum::<usize>()
        );
        assert!(readme.contains("Ran at commit abc1234, a test CPU (4 cores), 2 threads."));
        let text = std::fs::read_to_string(&files.results).unwrap();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(json["format"], FORMAT);
        // Where it ran, after the figures, which are the reproduction's as they are.
        assert_eq!(json["ran"]["commit"], "abc1234");
        assert_eq!(json["ran"]["threads"], 2);
        let figures = serde_json::to_string_pretty(&r).unwrap();
        assert!(text.starts_with(figures.trim_end_matches(['}', '\n'])));
        // The front page's block, from results.json: a line per experiment.
        let summary_md = std::fs::read_to_string(&files.summary).unwrap();
        assert_eq!(summary_md, summary(&text).unwrap());
        assert!(summary_md.contains("at commit abc1234, on a test CPU (4 cores, 2 threads)"));
        let table: Vec<&str> = summary_md.lines().filter(|l| l.starts_with("| E")).collect();
        assert_eq!(table.len(), 8, "{summary_md}");
        assert!(table[0].starts_with("| E1 random agent, 2 blocks"), "{}", table[0]);
        assert!(
            table[0].contains("| 4.0%, 263.55 |"),
            "the paper's E1 figures: {}",
            table[0]
        );
        assert_eq!(json["experiments"].as_array().unwrap().len(), 8);
        // Every arm's figures and the paper's beside them.
        let e5 = &json["experiments"][4]["tables"][0]["rows"];
        assert_eq!(e5[0]["paper"]["failures"], 186);
        assert!(e5[2]["spec"]["tests"][0]["p_value"].as_f64().is_some());
        // E1: the paper's figure, ours in both worlds, where the paper's lies against each
        // world's replicates, and the gap rule by rule.
        let e1 = &json["experiments"][0];
        let row = &e1["tables"][0]["rows"][0];
        for world in ["original", "spec"] {
            assert_eq!(row[world]["arm"]["replicates"], 2, "{world}");
            let inside = &row[world]["paper_inside"]["failure_rate"];
            assert_eq!(inside["paper"], 0.04);
            assert!(inside["inside"].is_boolean());
        }
        assert!(
            readme.contains("| random | - | 4 / 100 |"),
            "E1's row with the paper's figure first"
        );
        let worlds = e1["decomposition"]["worlds"].as_array().unwrap();
        assert_eq!(worlds.len(), 4);
        let gap = &e1["decomposition"]["gaps"][1];
        let parts =
            gap["protocol"].as_f64().unwrap() + gap["start"].as_f64().unwrap() + gap["interaction"].as_f64().unwrap();
        assert!((parts - gap["gap"].as_f64().unwrap()).abs() < 1e-9);
        // The benchmark's report: its own title, command and summary rows, none of the
        // paper's front matter.
        let (b, _, _) = run(2, Report::BlocksWorld);
        let bench = tempfile::tempdir().unwrap();
        let files = write_report(&b, &ran, bench.path()).unwrap();
        let readme = std::fs::read_to_string(&files.readme).unwrap();
        assert!(readme.starts_with("# The Blocks World benchmark\n"), "{readme}");
        assert!(readme.contains("Written by `blockstack benchmark --seed 5 --quick`"));
        assert!(!readme.contains("The paper's figures beside ours"));
        let summary_md = std::fs::read_to_string(&files.summary).unwrap();
        assert!(
            summary_md.starts_with("Measured by `blockstack benchmark --quick --seed 5`"),
            "{summary_md}"
        );
        let rows: Vec<&str> = summary_md.lines().filter(|l| l.starts_with("| E")).collect();
        assert_eq!(rows.len(), 2, "{summary_md}");
        assert!(
            rows[0].starts_with("| E9 ") && rows[1].starts_with("| E10 "),
            "{summary_md}"
        );
    }
}
