//! The paper's Tables II-IV (section VI-C): a trained agent corrected by each of the three
//! simulated demonstrators, against the uncorrected agent, on the same seeded starts.
//!
//! Each demonstrator gives 10 demonstrations on 4 of the 6 goals (0,1,2 1,0,2 2,1,0 1,2,0,
//! in turn; correction seed `--seed`, default 3), as the paper's people did. Every agent then
//! plays 500 seeded starts (base seed `--eval-seed`, default 2) with the paper's test policy
//! (epsilon 0.1), horizon 1000, physics backend: Table II with a goal drawn per start from
//! all six, Tables III and IV on the goals no one demonstrated, 0,2,1 and 2,0,1. The
//! Wilcoxon signed-rank test pairs each start's steps (a failure counts as 1000) with the
//! uncorrected agent's, SciPy's defaults (`experiments::stats::wilcoxon`).
//!
//! With `--seeds K` (default 10) it also repeats the corrections with seeds 1..=K, to show
//! how much one set of 10 demonstrations varies.
//!
//! The baseline is the paper's learner trained on the demonstrated goals:
//!
//! ```text
//! blockstack train --repr chasing --reward paper --goals 0,1,2:1,0,2:2,1,0:1,2,0 --out baseline.safetensors
//! cargo run --release --example demonstrator_tables -- baseline.safetensors
//! ```

use std::path::PathBuf;

use agent::{CorrectionConfig, DemonstratorProfile, EpisodeResult, QAgent, Summary, correct};
use anyhow::{Context, Result, bail};
use sim::{Backend, Env, EnvConfig, Goal, GoalSpec};

const DEMONSTRATED: &str = "0,1,2:1,0,2:2,1,0:1,2,0";
const DEMOS: u64 = 10;
const HORIZON: u32 = 1000;
const TEST_EPSILON: f64 = 0.1;

/// One of the paper's tables: its title, what is played, and the paper's rows (failures
/// out of 500, mean steps, Wilcoxon p), baseline first.
struct Table {
    title: &'static str,
    goal: Option<&'static str>,
    paper: [(u32, f64, Option<&'static str>); 4],
}

const TABLES: [Table; 3] = [
    Table {
        title: "Table II: all goals",
        goal: None,
        paper: [
            (160, 534.35, None),
            (101, 415.14, Some("1.16e-05")),
            (107, 419.212, Some("3.23e-06")),
            (113, 453.83, Some("0.0013")),
        ],
    },
    Table {
        title: "Table III: unseen fixed goal 0,2,1",
        goal: Some("0,2,1"),
        paper: [
            (96, 398.0, None),
            (124, 454.574, Some("0.022")),
            (102, 405.414, Some("0.976")),
            (82, 387.644, Some("0.957")),
        ],
    },
    Table {
        title: "Table IV: unseen fixed goal 2,0,1",
        goal: Some("2,0,1"),
        paper: [
            (148, 498.28, None),
            (143, 510.418, Some("0.811")),
            (152, 520.962, Some("0.449")),
            (122, 457.596, Some("0.123")),
        ],
    },
];

struct Args {
    model: PathBuf,
    seed: u64,
    eval_seed: u64,
    episodes: u64,
    seeds: u64,
}

fn args() -> Result<Args> {
    let mut args = Args {
        model: PathBuf::new(),
        seed: 3,
        eval_seed: 2,
        episodes: 500,
        seeds: 10,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut value = |name: &str| -> Result<u64> {
            it.next()
                .with_context(|| format!("{name} needs a value"))?
                .parse()
                .with_context(|| format!("{name} needs a whole number"))
        };
        match a.as_str() {
            "--seed" => args.seed = value("--seed")?,
            "--eval-seed" => args.eval_seed = value("--eval-seed")?,
            "--episodes" => args.episodes = value("--episodes")?,
            "--seeds" => args.seeds = value("--seeds")?,
            _ if a.starts_with("--") => bail!("unknown option {a}"),
            _ => args.model = PathBuf::from(a),
        }
    }
    if args.model.as_os_str().is_empty() {
        bail!(
            "usage: demonstrator_tables BASELINE.safetensors [--seed 3] [--eval-seed 2] [--episodes 500] [--seeds 10]"
        );
    }
    Ok(args)
}

/// `agent` on the table's starts.
fn play(agent: &QAgent, table: &Table, args: &Args) -> Result<Vec<EpisodeResult>> {
    let goal = match table.goal {
        Some(g) => GoalSpec::Fixed(Goal::parse(g, Some(agent.blocks()))?),
        None => GoalSpec::Random,
    };
    let reward = agent.training().context("the baseline must be a trained model")?.reward;
    let mut env = Env::new(EnvConfig {
        grid: agent.grid(),
        blocks: agent.blocks(),
        goal,
        horizon: HORIZON,
        reward,
        backend: Backend::Physics,
        ..EnvConfig::default()
    })?;
    Ok(agent::play(
        &mut env,
        &mut agent.policy(TEST_EPSILON)?,
        args.episodes,
        args.eval_seed,
        None,
    )?)
}

/// Each start's steps, a failure counting as the horizon.
fn steps(results: &[EpisodeResult]) -> Vec<f64> {
    results
        .iter()
        .map(|r| f64::from(if r.reached_goal { r.steps } else { HORIZON }))
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// The corrected agents of demonstrators 1..=3 with correction seed `seed`.
fn corrected(baseline: &QAgent, seed: u64) -> Result<Vec<QAgent>> {
    let goals = DEMONSTRATED
        .split(':')
        .map(|g| Goal::parse(g, Some(baseline.blocks())))
        .collect::<sim::Result<Vec<_>>>()?;
    (1..=3)
        .map(|d| {
            let config = CorrectionConfig::new(DemonstratorProfile::preset(d)?, goals.clone(), DEMOS, seed);
            Ok(correct(baseline.clone(), &config, ())?.agent)
        })
        .collect()
}

fn main() -> Result<()> {
    let args = args()?;
    let baseline = QAgent::load(&args.model)?;
    let agents = corrected(&baseline, args.seed)?;
    println!(
        "Baseline {} ({}); {DEMOS} demonstrations per demonstrator on {DEMONSTRATED}, correction seed {}; \
         {} starts per table (eval seed {}), test epsilon {TEST_EPSILON}, horizon {HORIZON}, physics.\n",
        args.model.display(),
        baseline.name(),
        args.seed,
        args.episodes,
        args.eval_seed
    );
    let names = ["Baseline", "Demonstrator 1", "Demonstrator 2", "Demonstrator 3"];
    for table in &TABLES {
        println!("### {}\n", table.title);
        println!(
            "| agent | failures / {n} | mean steps, failure = {HORIZON} | mean steps over successes | Wilcoxon p | paper: failures / 500 | paper: mean steps | paper: Wilcoxon p |",
            n = args.episodes
        );
        println!("|---|---|---|---|---|---|---|---|");
        let base_results = play(&baseline, table, &args)?;
        let base = steps(&base_results);
        for (i, agent) in std::iter::once(&baseline).chain(&agents).enumerate() {
            let results = if i == 0 {
                base_results.clone()
            } else {
                play(agent, table, &args)?
            };
            let summary = Summary::of(&results);
            let ours = steps(&results);
            let p = if i == 0 {
                "NA".to_string()
            } else {
                format!("{:.2e}", experiments::stats::wilcoxon(&ours, &base, false)?.p_value)
            };
            let (pf, pm, pp) = table.paper[i];
            println!(
                "| {} | {} | {:.2} | {} | {p} | {pf} | {pm} | {} |",
                names[i],
                summary.failures,
                mean(&ours),
                summary.mean_steps.map_or("-".into(), |m| format!("{m:.2}")),
                pp.unwrap_or("NA")
            );
        }
        println!();
    }
    if args.seeds > 0 {
        println!(
            "### Over correction seeds 1..={}: mean failures / {} (and how many seeds gave p < 0.05 with fewer mean steps)\n",
            args.seeds, args.episodes
        );
        println!("| table | baseline | demonstrator 1 | demonstrator 2 | demonstrator 3 |");
        println!("|---|---|---|---|---|");
        let runs: Vec<Vec<QAgent>> = (1..=args.seeds)
            .map(|s| corrected(&baseline, s))
            .collect::<Result<_>>()?;
        for table in &TABLES {
            let base_results = play(&baseline, table, &args)?;
            let base = steps(&base_results);
            let mut cells = vec![format!("{}", Summary::of(&base_results).failures)];
            for d in 0..3 {
                let (mut failures, mut better) = (0, 0);
                for run in &runs {
                    let results = play(&run[d], table, &args)?;
                    failures += Summary::of(&results).failures;
                    let ours = steps(&results);
                    let p = experiments::stats::wilcoxon(&ours, &base, false)?.p_value;
                    better += usize::from(p < 0.05 && mean(&ours) < mean(&base));
                }
                cells.push(format!(
                    "{:.1} ({better}/{})",
                    failures as f64 / args.seeds as f64,
                    args.seeds
                ));
            }
            println!("| {} | {} |", table.title, cells.join(" | "));
        }
    }
    Ok(())
}
