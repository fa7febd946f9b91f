//! E8: the paper's Approach 1 (section III-C): a deep Q-network on the rendered screen, and
//! DQfD from demonstrations, reproduced; then made to learn (ours); and an ablation that
//! measures which of the paper's choices kept it from learning.
//!
//! Every arm is a `neural` training run with a fixed budget of steps (so the figures do not
//! depend on the machine), tested greedily on the same seeded starts of every goal along
//! the way (the learning curves) and at its end (the tables). The ablation starts from our
//! recipe and puts back one of the paper's choices at a time: a choice that alone stops a
//! working learner is one that kept the paper's from learning.
//!
//! Budgets: the default run (`blockstack reproduce`) trains our two plane arms only, at
//! [`DEFAULT_SHARE`] of their presets' budgets, small enough for the whole report to stay
//! within minutes; `--long` adds the paper's pixel runs, our DQN with hindsight relabelling
//! (`her-planes`), our recipe on the paper's pixels (`dqfd-pixels`), our recipe on a
//! screen drawn to be read (`pixels`, 3 blocks) and the same on the paper's own screen
//! (`pixels --screen paper`), and the whole ablation, every arm at its preset's full
//! budget (the ablation, and the default run's `dqfd-planes` arm, with the steps that
//! preset gives 2 blocks: [`dqfd_planes3`]); `--quick` checks the pipeline with tiny
//! versions of the default arms. The report says which budget produced its figures.

use std::path::Path;

use agent::EpisodeResult;
use neural::{DemoSource, DqnConfig, NetConfig, NetKind, OptimizerKind, Preset, TargetEvery, Trainer};
use serde::{Deserialize, Serialize};
use sim::{Goal, Profile, RewardModel, ScreenGoal};

use super::Findings;
use super::arms::{ArmResult, Goals, Row, Suite, Table, describe, suite_in};
use super::shared::Shared;
use super::text::num;
use super::{Budget, Context, Drawing, Experiment, Figure, HORIZON, Options, ReproduceError, Result, Setting};
use plots::{CurvesChart, Series};

/// E8's counts at each budget.
impl Budget {
    /// Test games per goal at the end of every arm.
    fn test_games(self) -> u64 {
        match self {
            Budget::Quick => 10,
            Budget::Default | Budget::Long => 500,
        }
    }

    /// Test games per goal at every point of a learning curve, and the number of points.
    fn curve(self) -> (u64, usize) {
        match self {
            Budget::Quick => (3, 2),
            Budget::Default => (30, 6),
            Budget::Long => (50, 8),
        }
    }
}

/// Which part of E8 an arm belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Paper,
    Ours,
    Ablation,
}

/// One training run.
struct Arm {
    name: String,
    part: Part,
    config: DqnConfig,
}

/// Scales a preset's budget: `fraction` of its self-play and pre-training steps and of its
/// demonstrations (at least one of each that it has).
fn scaled(mut c: DqnConfig, fraction: f64) -> DqnConfig {
    let scale = |v: u64| {
        if v == 0 {
            0
        } else {
            ((v as f64 * fraction).round() as u64).max(1)
        }
    };
    c.steps = scale(c.steps);
    c.pretrain_steps = scale(c.pretrain_steps);
    c.learning_starts = c.learning_starts.min(c.steps.max(1));
    c.epsilon.steps = scale(c.epsilon.steps);
    if let DemoSource::Exact(k) = c.demos {
        c.demos = DemoSource::Exact(scale(k));
    }
    c
}

fn preset(name: Preset, blocks: usize, seed: u64, fraction: f64) -> Result<DqnConfig> {
    Ok(scaled(
        DqnConfig {
            seed,
            ..DqnConfig::preset(name, blocks)?
        },
        fraction,
    ))
}

/// The `--long` arm of the `pixels` preset.
const PIXELS3: &str = "ours on pixels: DQfD, conv network, compact screen, 3 blocks";

/// The `--long` arm of the `pixels` preset on the paper's own screen (`--screen paper`):
/// [`PIXELS3`] but for how the goal is shown.
const PAPER_SCREEN3: &str = "ours on the paper's screen: DQfD, conv network, 3 blocks";

/// The share of the presets' budgets the default run trains its arms at.
const DEFAULT_SHARE: f64 = 0.6;

/// `dqfd-planes` on 3 blocks with the steps the preset gives 2 blocks. The preset trains 3
/// blocks for three times those steps to meet its target; the default run's arm and the
/// ablation keep the 2-block steps so that they cost what they did (`--long`'s own
/// `dqfd-planes` arm trains at the preset's full budget).
fn dqfd_planes3(seed: u64, fraction: f64) -> Result<DqnConfig> {
    let two = DqnConfig::preset(Preset::DqfdPlanes, 2)?;
    let config = DqnConfig {
        steps: two.steps,
        pretrain_steps: two.pretrain_steps,
        seed,
        ..DqnConfig::preset(Preset::DqfdPlanes, 3)?
    };
    Ok(scaled(config, fraction))
}

/// The arms of `budget`, in the tables' order.
fn arms(budget: Budget, seed: u64) -> Result<Vec<Arm>> {
    let fraction = match budget {
        Budget::Quick => 0.005,
        Budget::Default => DEFAULT_SHARE,
        Budget::Long => 1.0,
    };
    let arm = |name: &str, part, config| Arm {
        name: name.into(),
        part,
        config,
    };
    let mut arms = vec![
        arm(
            "ours: DQfD, planes, 3 blocks",
            Part::Ours,
            if budget == Budget::Long {
                preset(Preset::DqfdPlanes, 3, seed, fraction)?
            } else {
                dqfd_planes3(seed, fraction)?
            },
        ),
        arm(
            "ours: DQN, planes, 2 blocks",
            Part::Ours,
            preset(Preset::DqnPlanes, 2, seed, fraction)?,
        ),
    ];
    if budget != Budget::Long {
        return Ok(arms);
    }
    let paper2 = preset(Preset::Paper, 2, seed, 1.0)?;
    let paper_dqfd2 = preset(Preset::PaperDqfd, 2, seed, 1.0)?;
    // Our learner on the paper's pixels and network: what the screen and the network cost.
    let ours_pixels2 = preset(Preset::DqfdPaperScreen, 2, seed, 1.0)?;
    let ours3 = dqfd_planes3(seed, 1.0)?;
    let pixels3 = preset(Preset::DqfdScreen, 3, seed, 1.0)?;
    arms.extend([
        arm("paper: DQN, pixels, 2 blocks", Part::Paper, paper2),
        arm("paper: DQfD, pixels, 2 blocks", Part::Paper, paper_dqfd2),
        arm(
            "ours: DQN with hindsight relabelling, planes, 3 blocks",
            Part::Ours,
            preset(Preset::HerPlanes, 3, seed, 1.0)?,
        ),
        arm(
            "ours on pixels: DQfD, paper network, 2 blocks",
            Part::Ours,
            ours_pixels2.clone(),
        ),
        // The `pixels` preset: our learner on a screen drawn to be read (docs/dqn.md).
        arm(PIXELS3, Part::Ours, pixels3.clone()),
        // The same learner and budget on the paper's screen: what the goal's presentation
        // alone costs.
        arm(
            PAPER_SCREEN3,
            Part::Ours,
            DqnConfig {
                net: NetConfig {
                    screen: ScreenGoal::Paper,
                    ..pixels3.net
                },
                ..pixels3
            },
        ),
    ]);
    arms.extend(ablation(seed, &ours3, ours_pixels2)?);
    Ok(arms)
}

/// The ablation: our recipe on 3 blocks (`ours3`) with one of the paper's choices put back,
/// and the paper network on pixels (`ours_pixels2`) without its batch norm.
fn ablation(seed: u64, ours3: &DqnConfig, ours_pixels2: DqnConfig) -> Result<Vec<Arm>> {
    let ablate = |name: &str, config: DqnConfig| Arm {
        name: format!("ours with {name}"),
        part: Part::Ablation,
        config,
    };
    let dense = RewardModel::from_name("dense")?;
    Ok(vec![
        ablate(
            "the paper's buffer (1000)",
            DqnConfig {
                buffer: 1000,
                ..ours3.clone()
            },
        ),
        ablate(
            "the paper's dense reward",
            DqnConfig {
                world: sim::EnvConfig {
                    reward: dense,
                    ..ours3.world.clone()
                },
                ..ours3.clone()
            },
        ),
        ablate(
            "the paper's gamma (0.1)",
            DqnConfig {
                gamma: 0.1,
                ..ours3.clone()
            },
        ),
        ablate(
            "the paper's optimiser (RMSprop 1e-4)",
            DqnConfig {
                optimizer: OptimizerKind::Rmsprop,
                lr: 1e-4,
                lr_final: 1e-4,
                ..ours3.clone()
            },
        ),
        ablate(
            "the paper's target refresh (every 3 games)",
            DqnConfig {
                target_every: TargetEvery::Games(3),
                ..ours3.clone()
            },
        ),
        ablate(
            "every action allowed (no mask)",
            DqnConfig {
                mask_noops: false,
                ..ours3.clone()
            },
        ),
        // DQN on 3 blocks: `her-planes` without its relabelling.
        ablate("no demonstrations", preset(Preset::DqnPlanes, 3, seed, 1.0)?),
        ablate(
            "absolute planes (an MLP, not centred)",
            DqnConfig {
                net: NetConfig {
                    kind: NetKind::Mlp,
                    ..ours3.net
                },
                ..ours3.clone()
            },
        ),
        ablate(
            "pixels and the paper network, without batch norm, 2 blocks",
            DqnConfig {
                net: NetConfig {
                    batch_norm: false,
                    ..NetConfig::paper()
                },
                ..ours_pixels2
            },
        ),
    ])
}

/// The arms' indices, the costliest training first (ties in the arms' order): gradient
/// steps weighed by what a step of each network costs on one thread, relative to the small
/// network's. Measured on the 2-core AMD EPYC (short runs of each preset, one thread):
/// about 650 steps a second for the small network, 340 for `conv` on the compact screen,
/// 49 on the paper's, and 17 to 28 for the paper network. Only the order matters.
fn costliest_first(arms: &[Arm]) -> Vec<usize> {
    let cost = |c: &DqnConfig| {
        let per_step = match c.net.kind {
            NetKind::Small | NetKind::Mlp => 1.0,
            NetKind::Conv if c.net.screen == ScreenGoal::Paper => 13.0,
            NetKind::Conv => 2.0,
            NetKind::Paper => 30.0,
        };
        (c.steps + c.pretrain_steps) as f64 * per_step
    };
    let mut order: Vec<usize> = (0..arms.len()).collect();
    order.sort_by(|&a, &b| cost(&arms[b].config).total_cmp(&cost(&arms[a].config)));
    order
}

/// Jobs reported: every point of every arm's curve, and its final test.
pub(super) fn jobs(ctx: &Context) -> u64 {
    let budget = ctx.budget;
    let arms = arms(budget, 0).map_or(0, |a| a.len());
    (arms * (budget.curve().1 + 1)) as u64
}

/// One arm's results.
struct Outcome {
    /// The final test.
    arm: ArmResult,
    /// `(gradient steps, test results)` along training.
    curve: Vec<(u64, ArmResult)>,
    /// Gradient steps in all.
    gradient_steps: u64,
}

/// How one test game went (its start and goal are the suite's, the same wherever it was
/// played). The figures read its steps and whether it reached the goal, whole numbers that
/// cross JSON exactly.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Game {
    /// Actions taken.
    pub steps: u32,
    /// Whether the goal was reached.
    pub reached_goal: bool,
    /// Sum of the rewards.
    pub total_reward: f64,
}

/// One arm trained and tested: the games it played, to be made into its figures where the
/// report is written; what an arm run elsewhere (a cluster's node) sends back.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmRun {
    /// At each point of the learning curve: the gradient steps, and the curve suite's games.
    pub curve: Vec<(u64, Vec<Game>)>,
    /// The final test's games.
    pub games: Vec<Game>,
    /// Gradient steps in all.
    pub gradient_steps: u64,
}

/// The games as the suite's results: each paired with the start and goal the suite gave
/// it; an error if their number is not the suite's.
fn results_of(suite: &Suite, games: &[Game]) -> Result<Vec<EpisodeResult>> {
    let starts = suite.starts()?;
    if starts.len() != games.len() {
        return Err(ReproduceError::Results {
            reason: format!("an E8 arm sent {} games for a suite of {}", games.len(), starts.len()),
        });
    }
    let per_goal = suite.episodes.max(1);
    Ok(starts
        .iter()
        .zip(games)
        .enumerate()
        .map(|(i, (start, game))| {
            let k = i as u64 % per_goal;
            EpisodeResult {
                episode: k,
                seed: sim::seeding::episode_seed(suite.seed, k),
                goal: start.goal.clone(),
                start: start.state.clone(),
                steps: game.steps,
                reached_goal: game.reached_goal,
                total_reward: game.total_reward,
            }
        })
        .collect())
}

fn games_of(results: &[EpisodeResult]) -> Vec<Game> {
    results
        .iter()
        .map(|r| Game {
            steps: r.steps,
            reached_goal: r.reached_goal,
            total_reward: r.total_reward,
        })
        .collect()
}

/// The names of E8's arms at `options`' budget and seed, in the order [`run_arm_of`] takes
/// them.
pub fn arm_names(options: &Options) -> Result<Vec<String>> {
    Ok(arms(Budget::of(options), options.seed)?
        .into_iter()
        .map(|a| a.name)
        .collect())
}

/// The indices of [`arm_names`] in the order a runner should start them: the costliest
/// first (see [`ArmRunner`](super::ArmRunner)).
pub fn start_order(options: &Options) -> Result<Vec<usize>> {
    Ok(costliest_first(&arms(Budget::of(options), options.seed)?))
}

/// Trains and tests arm `index` of [`arm_names`], as the reproduction with `options` does
/// (the seeds are `options.seed`'s): the unit of work a cluster runs. With `checkpoint`,
/// the arm's training and the tests it has played are written there at every point of its
/// learning curve, and an arm whose checkpoint exists goes on from it (a node lost, the arm
/// run again elsewhere): the same run either way.
pub fn run_arm_of(options: &Options, index: usize, checkpoint: Option<&Path>) -> Result<ArmRun> {
    let budget = Budget::of(options);
    let arms = arms(budget, options.seed)?;
    let arm = arms.get(index).ok_or_else(|| ReproduceError::Results {
        reason: format!("E8 has {} arms at this budget, and no arm {index}", arms.len()),
    })?;
    let scale = super::Scale::new(options.quick);
    let ctx = Context {
        seeds: super::Seeds::new(options.seed, &scale),
        scale,
        budget,
        progress: &(),
        arms: &super::LocalArms,
    };
    run_arm(&ctx, arm, budget, checkpoint)
}

/// The suite every arm of `blocks` blocks is tested on: each goal, `games` starts.
fn suite(ctx: &Context, blocks: usize, games: u64) -> Result<Suite> {
    Ok(suite_in(
        Profile::Spec,
        blocks,
        Goals::Each(Goal::all(blocks)?),
        games,
        ctx.seeds.test,
    ))
}

/// Trains `arm`, testing along the way and at the end; with `checkpoint`, see
/// [`run_arm_of`].
fn run_arm(ctx: &Context, arm: &Arm, budget: Budget, checkpoint: Option<&Path>) -> Result<ArmRun> {
    let started = std::time::Instant::now();
    let c = &arm.config;
    let (curve_games, points) = budget.curve();
    let curve_suite = suite(ctx, c.blocks(), curve_games)?;
    let test_suite = suite(ctx, c.blocks(), budget.test_games())?;
    let out = checkpoint.map(files::OutputPath::check).transpose()?;
    let (mut trainer, mut curve) = match checkpoint.filter(|path| path.exists()) {
        Some(path) => {
            let (trainer, note) = Trainer::resume_with_note(path)?;
            let curve: Option<Vec<(u64, Vec<Game>)>> = note
                .map(serde_json::from_value)
                .transpose()
                .map_err(|e| ReproduceError::Arms(format!("{}: its tests do not read: {e}", path.display())))?;
            if trainer.config() != c || curve.as_ref().is_none_or(|curve| curve.len() > points) {
                return Err(ReproduceError::Arms(format!(
                    "{} holds a run of another arm, not {:?}'s",
                    path.display(),
                    arm.name
                )));
            }
            (trainer, curve.unwrap_or_default())
        }
        None => (Trainer::new(c.clone())?, Vec::with_capacity(points)),
    };
    let total = trainer.total_steps();
    let quiet = &mut |_: &neural::Progress| {};
    for i in curve.len() as u64 + 1..=points as u64 {
        trainer.train_until(total * i / points as u64, quiet)?;
        let snapshot = trainer.snapshot()?;
        let results = curve_suite.play(&mut snapshot.policy(0.0)?)?;
        curve.push((trainer.report().gradient_steps, games_of(&results)));
        if let Some(out) = &out {
            let note = serde_json::to_value(&curve).expect("whole numbers and flags");
            trainer.write_checkpoint_with(out, Some(&note))?;
        }
        ctx.progress.advance("E8");
    }
    let dqn = trainer.finish()?;
    let results = test_suite.play(&mut dqn.policy(0.0)?)?;
    ctx.progress.advance("E8");
    ctx.progress.finished("E8", &arm.name, started.elapsed());
    Ok(ArmRun {
        curve,
        games: games_of(&results),
        gradient_steps: dqn.report().gradient_steps,
    })
}

/// The figures of `arm` from its run.
fn outcome(ctx: &Context, arm: &Arm, budget: Budget, run: &ArmRun) -> Result<Outcome> {
    let c = &arm.config;
    let curve_suite = suite(ctx, c.blocks(), budget.curve().0)?;
    let curve_optimum = curve_suite.optimum()?;
    let test_suite = suite(ctx, c.blocks(), budget.test_games())?;
    let curve = run
        .curve
        .iter()
        .map(|(steps, games)| {
            Ok((
                *steps,
                ArmResult::of(
                    format!("{} @ {steps}", arm.name),
                    c.describe(),
                    Some(0.0),
                    &[results_of(&curve_suite, games)?],
                    &curve_optimum,
                    HORIZON,
                ),
            ))
        })
        .collect::<Result<_>>()?;
    Ok(Outcome {
        arm: ArmResult::of(
            &arm.name,
            c.describe(),
            Some(0.0),
            &[results_of(&test_suite, &run.games)?],
            &test_suite.optimum()?,
            HORIZON,
        ),
        curve,
        gradient_steps: run.gradient_steps,
    })
}

/// Success in percent.
fn success(a: &ArmResult) -> f64 {
    100.0 * (1.0 - a.failure_rate())
}

/// Runs E8 at the run's budget.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let budget = ctx.budget;
    let arms = arms(budget, ctx.seeds.ours)?;
    let runs = ctx
        .arms
        .run_arms(&costliest_first(&arms), &|i| run_arm(ctx, &arms[i], budget, None))?;
    let outcomes: Vec<Outcome> = arms
        .iter()
        .zip(&runs)
        .map(|(a, run)| outcome(ctx, a, budget, run))
        .collect::<Result<_>>()?;
    Ok(Experiment {
        id: "E8".into(),
        title: "Deep Q-learning from pixels and planes, and DQfD (section III-C)".into(),
        setup: setup(budget, &arms, &outcomes),
        tables: tables(ctx, budget, &arms, &outcomes)?,
        paper_notes: Vec::new(),
        reading: reading(budget, &arms, &outcomes),
        figures: figures(budget, &arms, &outcomes),
        findings: Findings::Tables,
    })
}

/// The tables: each part's arms by block count, then every arm's learning curve.
fn tables(ctx: &Context, budget: Budget, arms: &[Arm], outcomes: &[Outcome]) -> Result<Vec<Table>> {
    let mut tables = Vec::new();
    for (part, title) in [
        (Part::Paper, "(a) The paper's DQN and DQfD on pixels"),
        (Part::Ours, "(b) Ours"),
        (
            Part::Ablation,
            "(c) Ablation: our recipe with one of the paper's choices put back",
        ),
    ] {
        for blocks in [2, 3] {
            let rows: Vec<Row> = arms
                .iter()
                .zip(outcomes)
                .filter(|(a, _)| a.part == part && a.config.blocks() == blocks)
                .map(|(_, o)| Row::spec(None, o.arm.clone(), Vec::new()))
                .collect();
            if !rows.is_empty() {
                tables.push(Table {
                    title: format!("{title}, {blocks} blocks"),
                    suite: describe(&suite(ctx, blocks, budget.test_games())?)
                        + ", greedy (every arm's network after its whole budget)",
                    paper: None,
                    tests: Vec::new(),
                    rows,
                });
            }
        }
    }
    tables.push(Table {
        title: "Learning curves: every arm along its training".into(),
        suite: format!(
            "{} starts per goal at each point (the first of the final tests' starts), greedy; \
             \"@ N\" is the network after N gradient steps",
            budget.curve().0
        ),
        paper: None,
        tests: Vec::new(),
        rows: outcomes
            .iter()
            .flat_map(|o| o.curve.iter().map(|(_, a)| Row::spec(None, a.clone(), Vec::new())))
            .collect(),
    });
    Ok(tables)
}

/// The settings: the budget, the paper's setup, the test, and every arm's configuration.
fn setup(budget: Budget, arms: &[Arm], outcomes: &[Outcome]) -> Vec<Setting> {
    let mut setup = vec![
        Setting {
            name: "budget".into(),
            value: format!(
                "{}: {}",
                budget.name(),
                match budget {
                    Budget::Quick => "tiny runs that check the pipeline, not results".into(),
                    Budget::Default => format!(
                        "the plane arms at {:.0}% of the presets' budgets, `dqfd-planes` with the steps it gives 2 \
                         blocks (`reproduce --only E8 --long` runs every arm at full budget)",
                        100.0 * DEFAULT_SHARE
                    ),
                    Budget::Long => "every arm at its preset's full budget, the ablation with the steps \
                                     `dqfd-planes` gives 2 blocks"
                        .into(),
                }
            ),
        },
        Setting {
            name: "paper".into(),
            value: "section III-C: pixels (100 x 100 x 3, goal image in a corner, held block white), two \
                    convolutions with batch norm and two linear layers, buffer 1000, batch 64, RMSprop 1e-4, \
                    MSE or Huber, sparse or dense reward, target every 3 or 5 epochs, DQfD pre-training on human \
                    demonstrations; after 2-8 hours it \"didn't seem to learn anything apart from picking a block\""
                .into(),
        },
        Setting {
            name: "test".into(),
            value: "every goal, the same seeded starts for every arm, horizon 1000, greedy (epsilon 0), \
                    physics backend; the ratio is to the exact solver's shortest plan from each start"
                .into(),
        },
    ];
    for (a, o) in arms.iter().zip(outcomes) {
        setup.push(Setting {
            name: a.name.clone(),
            value: format!(
                "{}; seed {}; {} gradient steps",
                a.config.describe(),
                a.config.seed,
                o.gradient_steps
            ),
        });
    }
    setup
}

/// The learning-curve charts: ours (with the paper's runs), and the ablation.
fn figures(budget: Budget, arms: &[Arm], outcomes: &[Outcome]) -> Vec<Figure> {
    let series = |part: Part| -> Vec<Series> {
        arms.iter()
            .zip(outcomes)
            .filter(|(a, _)| a.part == part || (part == Part::Ours && a.part == Part::Paper))
            .map(|(a, o)| Series {
                name: a.name.clone(),
                points: o.curve.iter().map(|(s, r)| (*s as f64, success(r))).collect(),
            })
            .collect()
    };
    let chart = |title: &str, series: Vec<Series>| CurvesChart {
        title: title.into(),
        x_label: "gradient steps (pre-training included)".into(),
        y_label: "reached the goal, greedy (%)".into(),
        y_range: Some((0.0, 100.0)),
        series,
        note: format!(
            "Each point: the network after that many gradient steps, greedy, on {} seeded starts of every goal \
             (horizon 1000). Budget: {}.",
            budget.curve().0,
            budget.name()
        ),
    };
    // The chart says what it plots: the paper's runs are trained at the long budget only.
    let (title, caption) = if arms.iter().any(|a| a.part == Part::Paper) {
        ("E8: the paper's DQN and ours", "the paper's configuration and ours")
    } else {
        (
            "E8: our DQN and DQfD (the paper's runs need the long budget)",
            "our networks (the paper's configuration is trained at the long budget only)",
        )
    };
    let mut figures = vec![Figure::new(
        "e8-curves",
        format!("Greedy success against training: {caption}"),
        Drawing::Curves(chart(title, series(Part::Ours))),
    )];
    let ablation = series(Part::Ablation);
    if !ablation.is_empty() {
        figures.push(Figure::new(
            "e8-ablation",
            "Greedy success against training: our recipe with one of the paper's choices put back".into(),
            Drawing::Curves(chart("E8: ablation", ablation)),
        ));
    }
    figures
}

/// The one-paragraph reading, computed from the outcomes.
fn reading(budget: Budget, arms: &[Arm], outcomes: &[Outcome]) -> String {
    let find = |name: &str| arms.iter().position(|a| a.name == name).map(|i| &outcomes[i].arm);
    let figures_of = |a: Option<&ArmResult>| match a {
        None => "-".to_string(),
        Some(a) if a.mean_ratio_to_optimum.is_none() => format!("{:.1}%", success(a)),
        Some(a) => format!("{:.1}% at {}x the optimum", success(a), num(a.mean_ratio_to_optimum, 3)),
    };
    let mut reading = format!(
        "Ours (DQfD on centred planes) reaches {} on 3 blocks; DQN without demonstrations {} on 2 blocks",
        figures_of(find("ours: DQfD, planes, 3 blocks")),
        figures_of(find("ours: DQN, planes, 2 blocks")),
    );
    if let Some(h) = find("ours: DQN with hindsight relabelling, planes, 3 blocks") {
        reading += &format!(
            "; DQN with hindsight relabelling, no demonstrations, {} on 3 blocks",
            figures_of(Some(h))
        );
    }
    if let Some(p) = find("ours on pixels: DQfD, paper network, 2 blocks") {
        reading += &format!(
            "; our DQfD with the paper's network on its screen {} on 2 blocks",
            figures_of(Some(p))
        );
    }
    if let Some(p) = find(PIXELS3) {
        reading += &format!(
            "; with the conv network on the compact screen (the `pixels` preset) {} on 3 blocks",
            figures_of(Some(p))
        );
    }
    if let Some(p) = find(PAPER_SCREEN3) {
        reading += &format!(
            ", and on the paper's own screen, its goal a picture in the corner, {}",
            figures_of(Some(p))
        );
    }
    if let (Some(p), Some(d)) = (
        find("paper: DQN, pixels, 2 blocks"),
        find("paper: DQfD, pixels, 2 blocks"),
    ) {
        reading += &format!(
            "; the paper's configuration on pixels {} without and {} with DQfD on 2 blocks",
            figures_of(Some(p)),
            figures_of(Some(d))
        );
    }
    let breaking: Vec<String> = arms
        .iter()
        .zip(outcomes)
        .filter(|(a, o)| a.part == Part::Ablation && success(&o.arm) < 90.0)
        .map(|(a, o)| format!("{} ({:.0}%)", a.name.trim_start_matches("ours with "), success(&o.arm)))
        .collect();
    if arms.iter().any(|a| a.part == Part::Ablation) {
        reading += &if breaking.is_empty() {
            ". No single choice of the paper's, put back into our recipe, brought it below 90%".into()
        } else {
            format!(
                ". Put back into our recipe alone, these choices of the paper's bring it below 90%: {}",
                breaking.join(", ")
            )
        };
    }
    reading += &format!(" (budget: {}).", budget.name());
    reading
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_arm_of_every_budget_is_a_valid_run() {
        for budget in [Budget::Quick, Budget::Default, Budget::Long] {
            let arms = arms(budget, 1).unwrap();
            for a in &arms {
                a.config.validate().unwrap_or_else(|e| panic!("{}: {e}", a.name));
            }
            let names: std::collections::HashSet<&str> = arms.iter().map(|a| a.name.as_str()).collect();
            assert_eq!(names.len(), arms.len(), "names are unique");
        }
        let long = arms(Budget::Long, 1).unwrap();
        assert!(
            long.iter()
                .any(|a| a.part == Part::Paper && a.config.net.kind == NetKind::Paper)
        );
        assert!(long.iter().filter(|a| a.part == Part::Ablation).count() >= 5);
        // The pixels preset's 3-block arm, at its full budget, only under --long.
        let pixels = long.iter().find(|a| a.name == PIXELS3).unwrap();
        assert_eq!(pixels.config.net.kind, NetKind::Conv);
        assert_eq!(
            pixels.config.steps,
            DqnConfig::preset(Preset::DqfdScreen, 3).unwrap().steps
        );
        assert!(arms(Budget::Default, 1).unwrap().iter().all(|a| a.name != PIXELS3));
        // The costliest arm starts first: the one on the paper's screen, then the paper
        // network's.
        let order = costliest_first(&long);
        assert_eq!(long[order[0]].name, PAPER_SCREEN3);
        assert_eq!(long[order[1]].config.net.kind, NetKind::Paper);
        let mut sorted = order.clone();
        sorted.sort();
        assert_eq!(sorted, (0..long.len()).collect::<Vec<_>>());
        // Its twin on the paper's screen differs from it in the screen alone.
        let paper = long.iter().find(|a| a.name == PAPER_SCREEN3).unwrap();
        assert_eq!(paper.config.obs(), sim::ObsKind::PaperScreen);
        let as_pixels = DqnConfig {
            net: NetConfig {
                screen: ScreenGoal::Colours,
                ..paper.config.net
            },
            ..paper.config.clone()
        };
        assert_eq!(as_pixels, pixels.config);
        assert_eq!(
            arms(Budget::Quick, 1).unwrap().len(),
            arms(Budget::Default, 1).unwrap().len()
        );
    }
}
