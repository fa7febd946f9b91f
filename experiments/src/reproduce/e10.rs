//! E10 (ours, issue 29): one learned policy for the classic Blocks World at every size.
//!
//! The relational policy (`blockstack dqn --preset general`, [`neural::relational`]) is
//! trained on problems of at most 20 blocks, then plays, greedily and with no search, random
//! problems of 10 to 500 blocks; its block moves are set against the near-optimal planner's
//! (`oracle::towers::NearOptimal`, GN1 of Slaney & Thiebaux) on the same problems, and
//! against the fewest moves (`oracle::towers::ExactMoves`) where those are found, up to 8
//! blocks, and against the optimum the optimal solver proves (`oracle::towers::OptimalMoves`,
//! within its default time limit) at every size. Neural Logic Machines (Dong et al., "Neural Logic Machines", ICLR 2019) report
//! their figures on problems from their own generator: the policy plays that generator's
//! problems too, beside NLM's published figures.
//!
//! # How a problem is drawn
//!
//! Problem `j` of `N` blocks of a family has the seed `s = episode_seed(episode_seed(test
//! seed, 10,000 k + N), j)` (`k` the family: 1 uniform, 2 NLM's); its start is the family's
//! state of seed `s` and its goal the towers of the family's state of seed
//! `episode_seed(s, 1)`, naming every block. A uniform state is uniform over all Blocks
//! World states (`oracle::towers::random_state`); NLM's puts each block, in a random order,
//! on the table or on a random top (`oracle::towers::nlm_state`).
//!
//! # Success
//!
//! A game succeeds when the goal holds within [`neural::relational::move_limit`] moves (four
//! per block; the near-optimal planner never needs more than two): a policy that goes round
//! in circles fails.

use neural::relational::{RelationalConfig, RelationalModel};
use oracle::towers::{ExactMoves, NearOptimal, OptimalMoves, TowerGoal, Towers, nlm_state, random_state};
use rayon::prelude::*;
use serde::Serialize;
use sim::seeding::episode_seed;

use super::Budget;
use super::Findings;
use super::shared::Shared;
use super::text::num;
use super::{Context, Drawing, Experiment, Figure, Result, Setting};
use plots::{CurvesChart, Series};

/// The progress stage E10 reports under.
const STAGE: &str = "E10";

/// The numbers of blocks of the uniform problems, as the issue lists them.
pub const SIZES: [usize; 6] = [10, 20, 50, 100, 200, 500];

/// The numbers of blocks at which the fewest moves are searched for.
pub const EXACT_SIZES: [usize; 5] = [4, 5, 6, 7, 8];

/// Neural Logic Machines' published Blocks World figures (Dong et al., "Neural Logic
/// Machines", ICLR 2019, on problems of their generator): blocks, share of problems solved,
/// mean block moves.
pub const NLM_FIGURES: [(usize, f64, f64); 2] = [(10, 1.0, 12.5), (50, 1.0, 85.8)];

/// A family of random problems (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    /// Start and goal uniform over Blocks World states.
    Uniform,
    /// Start and goal from Neural Logic Machines' generator.
    Nlm,
}

impl Family {
    /// Its number in the problems' seeds.
    fn key(self) -> u64 {
        match self {
            Family::Uniform => 1,
            Family::Nlm => 2,
        }
    }

    /// Its state of `blocks` blocks from `seed`.
    fn state(self, blocks: usize, seed: u64) -> Towers {
        match self {
            Family::Uniform => random_state(blocks, seed),
            Family::Nlm => nlm_state(blocks, seed),
        }
    }
}

/// Problems per number of blocks of each table: (uniform sizes, exact sizes, NLM's).
fn problems(budget: Budget, blocks: usize) -> u64 {
    match budget {
        Budget::Quick => 4,
        // About 10 s of play on two cores at 500 blocks, less below.
        Budget::Default => match blocks {
            ..=100 => 100,
            101..=200 => 50,
            _ => 20,
        },
        Budget::Long => 1000,
    }
}

/// The sizes of each table a budget plays.
fn sizes(budget: Budget, table: &[usize]) -> Vec<usize> {
    match budget {
        Budget::Quick => table.iter().copied().filter(|&n| n <= 20).collect(),
        _ => table.to_vec(),
    }
}

/// The policy's training: the preset with `--long`, shorter runs otherwise (the default run
/// stays within minutes; a quick one checks the pipeline).
fn training(ctx: &Context) -> RelationalConfig {
    let preset = RelationalConfig::general();
    let config = match ctx.budget {
        Budget::Quick => RelationalConfig {
            problems: 2_000,
            iterations: 2,
            steps: 200,
            rollouts: 100,
            ..preset
        },
        Budget::Default => RelationalConfig {
            problems: 10_000,
            iterations: 5,
            steps: 1_000,
            rollouts: 300,
            ..preset
        },
        Budget::Long => preset,
    };
    RelationalConfig {
        seed: ctx.seeds.ours,
        ..config
    }
}

/// One problem and how it went.
#[derive(Clone, Debug, PartialEq)]
pub struct Solved {
    /// Blocks.
    pub blocks: usize,
    /// The near-optimal planner's moves.
    pub near_optimal: u32,
    /// The fewest moves, where searched.
    pub fewest: Option<u32>,
    /// The optimum, where the optimal solver proved it.
    pub optimum: Option<u32>,
    /// The policy's moves, if it reached the goal within the move limit.
    pub policy: Option<u32>,
}

/// The figures of one number of blocks.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SizeFigures {
    /// Blocks.
    pub blocks: usize,
    /// Problems played.
    pub problems: usize,
    /// Share the policy solved within the move limit.
    pub success: f64,
    /// The policy's mean block moves over the problems it solved.
    pub mean_moves: Option<f64>,
    /// The near-optimal planner's mean block moves over the same problems.
    pub near_optimal_moves: Option<f64>,
    /// The policy's moves over the near-optimal planner's, summed over the solved problems
    /// (the ratio of the two means).
    pub near_optimal_ratio: Option<f64>,
    /// The largest ratio of one problem.
    pub worst_ratio: Option<f64>,
    /// The mean fewest moves over the solved problems, where searched.
    pub fewest_moves: Option<f64>,
    /// The policy's moves over the fewest, summed over the solved problems.
    pub fewest_ratio: Option<f64>,
    /// The near-optimal planner's moves over the fewest, over the same problems.
    pub near_optimal_fewest_ratio: Option<f64>,
    /// Share of the problems whose optimum the optimal solver proved.
    pub proven: f64,
    /// The mean proven optimum over the solved problems, when every one is proven.
    pub optimum_moves: Option<f64>,
    /// The policy's moves over the optimum, summed over the solved problems.
    pub optimum_ratio: Option<f64>,
    /// The near-optimal planner's moves over the optimum, over the same problems.
    pub near_optimal_optimum_ratio: Option<f64>,
    /// The family's published figures, where there are (NLM's): share solved and mean moves.
    pub published: Option<(f64, f64)>,
}

/// The training's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrainingFigures {
    /// How it was trained.
    pub config: RelationalConfig,
    /// Labelled examples at the end.
    pub examples: u64,
    /// The last DAgger iteration's games (2 to `config.max_blocks` blocks): share that reached the goal.
    pub last_success: f64,
    /// Their moves over the fewest.
    pub last_moves_ratio: f64,
}

/// E10's results beside its tables: what `results.json` holds of it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct General {
    /// The training.
    pub training: TrainingFigures,
    /// Uniform problems by size.
    pub uniform: Vec<SizeFigures>,
    /// Uniform problems of a few blocks, against the fewest moves.
    pub exact: Vec<SizeFigures>,
    /// Problems of NLM's generator, beside NLM's figures.
    pub nlm: Vec<SizeFigures>,
}

/// Jobs reported: the training, then one per table row.
pub(super) fn jobs(ctx: &Context) -> u64 {
    (1 + sizes(ctx.budget, &SIZES).len() + sizes(ctx.budget, &EXACT_SIZES).len() + NLM_FIGURES.len()) as u64
}

/// Runs E10.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let config = training(ctx);
    let model = RelationalModel::train(&config, &mut |_| {})?;
    ctx.progress.advance(STAGE);
    let last = model.report().last().copied();
    let training = TrainingFigures {
        config,
        examples: last.map_or(0, |r| r.examples),
        last_success: last.map_or(0.0, |r| r.success),
        last_moves_ratio: last.map_or(0.0, |r| r.moves_ratio),
    };
    let table = |family: Family, sizes: Vec<usize>, exact: bool| -> Result<Vec<SizeFigures>> {
        sizes
            .into_iter()
            .map(|n| {
                let base = episode_seed(ctx.seeds.test, 10_000 * family.key() + n as u64);
                let solved = (0..problems(ctx.budget, n))
                    .into_par_iter()
                    .map(|j| play(&model, family, n, episode_seed(base, j), exact))
                    .collect::<Result<Vec<_>>>()?;
                ctx.progress.advance(STAGE);
                let published = (family == Family::Nlm)
                    .then(|| NLM_FIGURES.iter().find(|f| f.0 == n).map(|f| (f.1, f.2)))
                    .flatten();
                Ok(figures(n, &solved, published))
            })
            .collect()
    };
    let general = General {
        training,
        uniform: table(Family::Uniform, sizes(ctx.budget, &SIZES), false)?,
        exact: table(Family::Uniform, sizes(ctx.budget, &EXACT_SIZES), true)?,
        nlm: table(Family::Nlm, NLM_FIGURES.iter().map(|f| f.0).collect(), false)?,
    };
    Ok(experiment(ctx, &model, general))
}

/// Problem `seed` of `blocks` blocks of `family`, planned (`exact`: the fewest moves too)
/// and played by `model`.
fn play(model: &RelationalModel, family: Family, blocks: usize, seed: u64, exact: bool) -> Result<Solved> {
    let start = family.state(blocks, seed);
    let goal = TowerGoal::new(&family.state(blocks, episode_seed(seed, 1)).towers())?;
    let near_optimal = NearOptimal::new().plan(&start, &goal)?.len() as u32;
    let fewest = exact
        .then(|| ExactMoves::new().solve(&start, &goal).map(|p| p.len() as u32))
        .transpose()?;
    let certified = OptimalMoves::new().solve(&start, &goal)?;
    let optimum = certified.is_optimal().then_some(certified.plan.len() as u32);
    let game = model.play(&start, &goal)?;
    Ok(Solved {
        blocks,
        near_optimal,
        fewest,
        optimum,
        policy: game.reached.then_some(game.moves.len() as u32),
    })
}

/// The figures of the problems of one size.
fn figures(blocks: usize, solved: &[Solved], published: Option<(f64, f64)>) -> SizeFigures {
    let won: Vec<&Solved> = solved.iter().filter(|s| s.policy.is_some()).collect();
    let sum = |f: &dyn Fn(&Solved) -> Option<u32>| -> Option<f64> {
        won.iter().map(|s| f(s).map(f64::from)).sum::<Option<f64>>()
    };
    let mean = |total: Option<f64>| total.filter(|_| !won.is_empty()).map(|t| t / won.len() as f64);
    let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) if b > 0.0 && !won.is_empty() => Some(a / b),
        _ => None,
    };
    let policy = sum(&|s| s.policy);
    let near = sum(&|s| Some(s.near_optimal));
    let fewest = sum(&|s| s.fewest);
    let optimum = sum(&|s| s.optimum);
    SizeFigures {
        blocks,
        problems: solved.len(),
        success: if solved.is_empty() {
            0.0
        } else {
            won.len() as f64 / solved.len() as f64
        },
        mean_moves: mean(policy),
        near_optimal_moves: mean(near),
        near_optimal_ratio: ratio(policy, near),
        worst_ratio: won
            .iter()
            .filter(|s| s.near_optimal > 0)
            .map(|s| f64::from(s.policy.unwrap_or(0)) / f64::from(s.near_optimal))
            .reduce(f64::max),
        fewest_moves: mean(fewest),
        fewest_ratio: ratio(policy, fewest),
        near_optimal_fewest_ratio: ratio(near, fewest),
        proven: if solved.is_empty() {
            0.0
        } else {
            solved.iter().filter(|s| s.optimum.is_some()).count() as f64 / solved.len() as f64
        },
        optimum_moves: mean(optimum),
        optimum_ratio: ratio(policy, optimum),
        near_optimal_optimum_ratio: ratio(near, optimum),
        published,
    }
}

/// The report's section from the results.
fn experiment(ctx: &Context, model: &RelationalModel, g: General) -> Experiment {
    Experiment {
        id: "E10".into(),
        title: "One learned policy for the classic Blocks World at every size (ours)".into(),
        setup: setup(ctx, model, &g),
        tables: Vec::new(),
        paper_notes: Vec::new(),
        reading: reading(&g),
        figures: charts(ctx, &g),
        findings: Findings::General(g),
    }
}

/// The run's reading: one paragraph computed from the figures.
fn reading(g: &General) -> String {
    let c = &g.training.config;
    let all = |rows: &[SizeFigures]| -> (usize, f64) {
        let problems: usize = rows.iter().map(|r| r.problems).sum();
        let won: f64 = rows.iter().map(|r| r.success * r.problems as f64).sum();
        (problems, if problems == 0 { 0.0 } else { won / problems as f64 })
    };
    let (uniform_problems, uniform_success) = all(&g.uniform);
    let largest = g.uniform.last();
    let range = |rows: &[SizeFigures], f: &dyn Fn(&SizeFigures) -> Option<f64>| -> String {
        let values: Vec<f64> = rows.iter().filter_map(f).collect();
        match (
            values.iter().copied().reduce(f64::min),
            values.iter().copied().reduce(f64::max),
        ) {
            (Some(lo), Some(hi)) => format!("{}-{}", num(Some(lo), 3), num(Some(hi), 3)),
            _ => "-".into(),
        }
    };
    let nlm = g
        .nlm
        .iter()
        .map(|r| {
            format!(
                "{} blocks: {}% in {} moves (NLM: {}% in {})",
                r.blocks,
                num(Some(100.0 * r.success), 1),
                num(r.mean_moves, 1),
                num(r.published.map(|p| 100.0 * p.0), 0),
                num(r.published.map(|p| p.1), 1)
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    format!(
        "Trained on problems of 2 to {} blocks, the policy solved {}% of {uniform_problems} uniform problems of {} \
         blocks greedily, with no search, in {}x the near-optimal planner's block moves (by size; {} at {} blocks); \
         on {} to {} blocks it took {}x the fewest moves, the near-optimal planner {}x. Against the optimum, proven \
         for {}% of the uniform problems: the policy {}x, the near-optimal planner {}x (by size). On NLM's \
         generator: {nlm}.",
        c.max_blocks,
        num(Some(100.0 * uniform_success), 2),
        g.uniform
            .iter()
            .map(|r| r.blocks.to_string())
            .collect::<Vec<_>>()
            .join(", "),
        range(&g.uniform, &|r| r.near_optimal_ratio),
        num(largest.and_then(|r| r.near_optimal_ratio), 3),
        largest.map_or(0, |r| r.blocks),
        g.exact.first().map_or(0, |r| r.blocks),
        g.exact.last().map_or(0, |r| r.blocks),
        range(&g.exact, &|r| r.fewest_ratio),
        range(&g.exact, &|r| r.near_optimal_fewest_ratio),
        num(Some(100.0 * proven_share(&g.uniform)), 2),
        range(&g.uniform, &|r| r.optimum_ratio),
        range(&g.uniform, &|r| r.near_optimal_optimum_ratio),
    )
}

/// The share of `rows`' problems whose optimum was proven.
fn proven_share(rows: &[SizeFigures]) -> f64 {
    let problems: usize = rows.iter().map(|r| r.problems).sum();
    let proven: f64 = rows.iter().map(|r| r.proven * r.problems as f64).sum();
    if problems == 0 { 0.0 } else { proven / problems as f64 }
}

/// The chart: the policy's block moves against the near-optimal planner's, by size.
fn charts(ctx: &Context, g: &General) -> Vec<Figure> {
    let c = &g.training.config;
    let percent_of_near = |rows: &[SizeFigures]| -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|r| Some((r.blocks as f64, 100.0 * r.near_optimal_ratio?)))
            .collect()
    };
    let mut series = vec![
        Series {
            name: "near-optimal planner".into(),
            points: g
                .uniform
                .iter()
                .chain(&g.exact)
                .map(|r| (r.blocks as f64, 100.0))
                .collect(),
        },
        Series {
            name: "policy, uniform problems".into(),
            points: percent_of_near(&g.exact)
                .into_iter()
                .chain(percent_of_near(&g.uniform))
                .collect(),
        },
        Series {
            name: "policy, NLM's generator".into(),
            points: percent_of_near(&g.nlm),
        },
        Series {
            name: "fewest moves".into(),
            points: g
                .exact
                .iter()
                .filter_map(|r| Some((r.blocks as f64, 100.0 / r.near_optimal_fewest_ratio?)))
                .collect(),
        },
    ];
    for s in &mut series {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    series.retain(|s| !s.points.is_empty());
    let chart = CurvesChart {
        title: "E10: block moves against the near-optimal planner's, by number of blocks".into(),
        x_label: "blocks".into(),
        y_label: "block moves (% of the near-optimal planner's, over solved problems)".into(),
        y_range: None,
        series,
        note: format!(
            "One policy trained on 2-{} blocks; greedy, no search. {} problems per size up to 100 blocks at this \
             budget.",
            c.max_blocks,
            problems(ctx.budget, 100)
        ),
    };
    vec![Figure::new(
        "e10-moves",
        "The policy's block moves as a share of the near-optimal planner's on the same problems, by number of \
             blocks; the fewest moves (A*) where they were found"
            .into(),
        Drawing::Curves(chart),
    )]
}

/// What was run: the policy, its training, the problems and the yardsticks.
fn setup(ctx: &Context, model: &RelationalModel, g: &General) -> Vec<Setting> {
    let t = &g.training;
    let c = &t.config;
    let per_size = |rows: &[SizeFigures]| {
        rows.iter()
            .map(|r| format!("{}: {}", r.blocks, r.problems))
            .collect::<Vec<_>>()
            .join(", ")
    };
    vec![
        Setting {
            name: "policy".into(),
            value: format!(
                "{}: scans up and down the towers and a hop across the goal, {} rounds, width {}, over the raw \
                 relations only (on, on-table, clear, the goal's on and on-table); one forward pass per block \
                 move, the best-scored legal move taken (docs/dqn.md, \"The general policy\")",
                model.name(),
                c.shape.rounds,
                c.shape.width
            ),
        },
        Setting {
            name: "training".into(),
            value: format!(
                "imitation of the optimum with DAgger, seed {}: {} random problems of 2 to {} blocks labelled \
                 with every optimal move, then {} iterations of {} Adam steps (batch {}, learning rate {} to {}) \
                 each followed by {} greedy games whose states are labelled and kept; {} examples in the end, \
                 the last iteration's games {}% solved at {}x the fewest moves{}",
                c.seed,
                c.problems,
                c.max_blocks,
                c.iterations,
                c.steps,
                c.batch,
                c.lr,
                c.lr_final,
                c.rollouts,
                t.examples,
                num(Some(100.0 * t.last_success), 1),
                num(Some(t.last_moves_ratio), 3),
                if ctx.budget == Budget::Long {
                    " (the preset, `blockstack dqn --preset general`)"
                } else {
                    " (shorter than the preset's, which --long trains)"
                }
            ),
        },
        Setting {
            name: "problems".into(),
            value: format!(
                "uniform start and goal states naming every block (Slaney & Thiebaux's distribution), per size \
                 {}; up to 8 blocks {} against the fewest moves; NLM's generator {}; problem j of N blocks of \
                 family k from seed episode_seed(episode_seed({}, 10000 k + N), j) (k = 1 uniform, 2 NLM's)",
                per_size(&g.uniform),
                per_size(&g.exact),
                per_size(&g.nlm),
                ctx.seeds.test
            ),
        },
        Setting {
            name: "yardsticks".into(),
            value: "the near-optimal planner (`oracle::towers::NearOptimal`, GN1 of Slaney & Thiebaux, \"Blocks \
                    World revisited\", 2001: at most twice the fewest moves); the fewest moves by A* \
                    (`ExactMoves`) up to 8 blocks; Neural Logic Machines' published figures (Dong et al., \
                    \"Neural Logic Machines\", ICLR 2019) on their generator"
                .into(),
        },
        Setting {
            name: "success".into(),
            value: "the goal holds within 4 N block moves (the near-optimal planner needs at most 2 N); moves are \
                    counted over the problems solved"
                .into(),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::super::{Options, Report, reproduce};
    use super::*;

    fn quick() -> Experiment {
        let options = Options {
            report: Report::BlocksWorld,
            seed: 3,
            quick: true,
            long: false,
            only: vec!["E10".into()],
        };
        reproduce(&options, &()).unwrap().experiments.swap_remove(0)
    }

    #[test]
    fn nlm_figures_are_nlms_generator() {
        // The two families differ, and each is seeded.
        for n in [5, 10] {
            assert_eq!(Family::Nlm.state(n, 4), Family::Nlm.state(n, 4));
            assert_eq!(Family::Nlm.state(n, 4).blocks(), n);
        }
        assert_ne!(Family::Nlm.state(10, 4), Family::Uniform.state(10, 4));
    }

    #[test]
    fn e10_alone_trains_plays_every_size_and_is_seeded() {
        let e = quick();
        assert_eq!(e.id, "E10");
        let Findings::General(g) = &e.findings else {
            panic!("E10 reports its training")
        };
        assert_eq!(
            g.uniform.iter().map(|r| r.blocks).collect::<Vec<_>>(),
            sizes(Budget::Quick, &SIZES)
        );
        for r in g.uniform.iter().chain(&g.exact).chain(&g.nlm) {
            assert_eq!(r.problems as u64, problems(Budget::Quick, r.blocks), "{r:?}");
            assert!((0.0..=1.0).contains(&r.success));
        }
        for r in &g.exact {
            // The near-optimal planner is never below the fewest, nor above twice it.
            let ratio = r.near_optimal_fewest_ratio.unwrap_or(1.0);
            assert!((1.0..=2.0).contains(&ratio), "{r:?}");
            if let Some(policy) = r.fewest_ratio {
                assert!(policy >= 1.0, "no policy beats the fewest moves: {r:?}");
            }
        }
        assert_eq!(
            g.nlm.iter().map(|r| r.published).collect::<Vec<_>>(),
            [Some((1.0, 12.5)), Some((1.0, 85.8))]
        );
        assert_eq!(e.figures.len(), 1);
        assert_eq!(quick(), e, "seeded");
    }
}
