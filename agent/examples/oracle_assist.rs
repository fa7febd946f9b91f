//! The three arms of the paper's Table I: the paper's learner trained with no help, with
//! the oracle taking over when it oscillates, and with the oracle also taking each step
//! with probability 0.1.
//!
//! Each arm trains the `chasing` + `paper` learner (alpha 1, gamma 0.1, epsilon 0.1) for
//! 5000 games on all six goals against the physics world, with training seeds 1..=5, and
//! plays the same 500 seeded starts (base seed 2) of each of the six goals, horizon 1000,
//! with the paper's test policy (epsilon 0.1). Failures are out of 3000.
//!
//! Run: `cargo run --release -p agent --example oracle_assist`

use agent::{Assist, EpisodeResult, Summary, TrainConfig};
use sim::{Env, Goal};

const TRAIN_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
const EPISODES: u64 = 500;
const EVAL_SEED: u64 = 2;
const TEST_EPSILON: f64 = 0.1;

/// Trains with `config` and plays the six goals' starts.
fn evaluate(config: &TrainConfig) -> agent::Result<(Vec<EpisodeResult>, u64)> {
    let trained = agent::train(config, None)?;
    let mut results = Vec::new();
    for goal in Goal::all(3)? {
        let mut env = Env::new(config.env_config(goal))?;
        let mut policy = trained.agent.policy(TEST_EPSILON)?;
        results.extend(agent::play(&mut env, &mut policy, EPISODES, EVAL_SEED, None)?);
    }
    Ok((results, trained.report.assisted_steps))
}

fn main() -> agent::Result<()> {
    let paper = TrainConfig::paper(Goal::all(3)?);
    let arms = [
        Assist::None,
        Assist::Oscillation,
        Assist::OscillationOrChance { p: 0.1 },
    ];
    println!("Table I: the paper's learner trained with oracle assistance, all six goals,");
    println!(
        "{EPISODES} starts per goal (eval seed {EVAL_SEED}), test epsilon {TEST_EPSILON}, training seeds {TRAIN_SEEDS:?}"
    );
    println!(
        "paper (failures out of 500, mean steps): none 186, 578.6; oscillation 157, 554.3; oscillation+0.1 125, 518.7\n"
    );
    println!(
        "{:<16} {:>5} {:>14} {:>11} {:>18} {:>15}",
        "assistance", "seed", "failures/3000", "mean steps", "mean, fail = 1000", "oracle's steps"
    );
    for assist in arms {
        let (mut failures, mut steps, mut all) = (0.0, 0.0, 0.0);
        for seed in TRAIN_SEEDS {
            let (results, assisted) = evaluate(&TrainConfig {
                seed,
                assist,
                ..paper.clone()
            })?;
            let s = Summary::of(&results);
            let with_failures = agent::optimality::mean_steps_failures_as_horizon(&results, paper.horizon);
            let mean = s.mean_steps.unwrap_or(f64::NAN);
            println!(
                "{:<16} {seed:>5} {:>14} {mean:>11.1} {with_failures:>18.1} {assisted:>15}",
                assist.to_string(),
                s.failures
            );
            failures += s.failures as f64;
            steps += mean;
            all += with_failures;
        }
        let n = TRAIN_SEEDS.len() as f64;
        println!(
            "{:<16} {:>5} {:>14.1} {:>11.1} {:>18.1}",
            assist.to_string(),
            "mean",
            failures / n,
            steps / n,
            all / n
        );
    }
    Ok(())
}
