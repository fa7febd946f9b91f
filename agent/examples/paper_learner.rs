//! The paper's Q-learner on experiment E3 (train on four goals, test on the two unseen
//! ones), and what each change of one hyper-parameter does to it.
//!
//! Every arm trains the `chasing` + `paper` learner on 0,1,2 1,0,2 2,0,1 0,2,1 against the
//! physics world with training seeds 1..=5, and plays 500 seeded starts (base seed 2) of
//! each of 2,1,0 and 1,2,0 with horizon 1000; the figures are the means over the five
//! trained agents. Failures are out of 1000; mean steps are over the episodes that reached
//! the goal, and, in the last column, over all episodes with a failure counted as 1000.
//!
//! Run: `cargo run --release -p agent --example paper_learner`

use agent::{QParams, TrainConfig};
use sim::{Env, Goal};

const TRAIN_SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
const EPISODES: u64 = 500;
const EVAL_SEED: u64 = 2;

/// One arm: a name, the training config, and the test-time epsilon.
struct Arm {
    name: &'static str,
    config: TrainConfig,
    test_epsilon: f64,
}

fn goals(text: &str) -> Vec<Goal> {
    text.split(':').map(|g| g.parse().unwrap()).collect()
}

/// Failures, mean steps to goal, and mean steps with failures counted as the horizon, of
/// one agent on the unseen goals.
fn evaluate(config: &TrainConfig, test_epsilon: f64) -> agent::Result<(usize, f64, f64)> {
    let trained = agent::train(config, None)?;
    let mut results = Vec::new();
    for goal in goals("2,1,0:1,2,0") {
        let mut env = Env::new(config.env_config(goal))?;
        let mut policy = trained.agent.policy(test_epsilon)?;
        results.extend(agent::play(&mut env, &mut policy, EPISODES, EVAL_SEED, None)?);
    }
    let s = agent::Summary::of(&results);
    let with_failures = agent::optimality::mean_steps_failures_as_horizon(&results, config.horizon);
    Ok((s.failures, s.mean_steps.unwrap_or(f64::NAN), with_failures))
}

fn main() -> agent::Result<()> {
    let paper = TrainConfig::paper(goals("0,1,2:1,0,2:2,0,1:0,2,1"));
    let with = |f: fn(&mut QParams)| {
        let mut c = paper.clone();
        f(&mut c.params);
        c
    };
    let arms = vec![
        Arm {
            name: "paper (alpha 1, gamma 0.1, epsilon 0.1, 5000 games, test epsilon 0.1)",
            config: paper.clone(),
            test_epsilon: 0.1,
        },
        Arm {
            name: "games 1000",
            config: TrainConfig {
                games: 1000,
                ..paper.clone()
            },
            test_epsilon: 0.1,
        },
        Arm {
            name: "games 50000",
            config: TrainConfig {
                games: 50_000,
                ..paper.clone()
            },
            test_epsilon: 0.1,
        },
        Arm {
            name: "gamma 0",
            config: with(|p| p.gamma = 0.0),
            test_epsilon: 0.1,
        },
        Arm {
            name: "gamma 0.5",
            config: with(|p| p.gamma = 0.5),
            test_epsilon: 0.1,
        },
        Arm {
            name: "gamma 0.9",
            config: with(|p| p.gamma = 0.9),
            test_epsilon: 0.1,
        },
        Arm {
            name: "alpha 0.5",
            config: with(|p| p.alpha = 0.5),
            test_epsilon: 0.1,
        },
        Arm {
            name: "alpha 0.1",
            config: with(|p| p.alpha = 0.1),
            test_epsilon: 0.1,
        },
        Arm {
            name: "training epsilon 0.02",
            config: with(|p| p.epsilon = 0.02),
            test_epsilon: 0.1,
        },
        Arm {
            name: "training epsilon 0.3",
            config: with(|p| p.epsilon = 0.3),
            test_epsilon: 0.1,
        },
        Arm {
            name: "initial Q 100",
            config: with(|p| p.initial_q = 100.0),
            test_epsilon: 0.1,
        },
        Arm {
            name: "test epsilon 0",
            config: paper.clone(),
            test_epsilon: 0.0,
        },
        Arm {
            name: "test epsilon 0.05",
            config: paper.clone(),
            test_epsilon: 0.05,
        },
        Arm {
            name: "test epsilon 0.2",
            config: paper.clone(),
            test_epsilon: 0.2,
        },
        Arm {
            name: "test epsilon 0.3",
            config: paper.clone(),
            test_epsilon: 0.3,
        },
        Arm {
            name: "test epsilon 0.5",
            config: paper.clone(),
            test_epsilon: 0.5,
        },
        Arm {
            name: "gamma 0 and test epsilon 0.3",
            config: with(|p| p.gamma = 0.0),
            test_epsilon: 0.3,
        },
    ];
    println!("E3 with the paper's learner: train on 0,1,2 1,0,2 2,0,1 0,2,1, test on 2,1,0 1,2,0");
    println!("({EPISODES} starts per goal, eval seed {EVAL_SEED}, means over training seeds {TRAIN_SEEDS:?})");
    println!("paper: 70 failures out of 100, 847.7 mean steps\n");
    println!(
        "{:<72} {:>14} {:>11} {:>16} {:>18}",
        "arm", "failures/1000", "mean steps", "(range of fails)", "mean, fail = 1000"
    );
    for arm in &arms {
        let runs = TRAIN_SEEDS
            .iter()
            .map(|&seed| {
                evaluate(
                    &TrainConfig {
                        seed,
                        ..arm.config.clone()
                    },
                    arm.test_epsilon,
                )
            })
            .collect::<agent::Result<Vec<_>>>()?;
        let n = runs.len() as f64;
        let failures = runs.iter().map(|r| r.0 as f64).sum::<f64>() / n;
        let steps = runs.iter().map(|r| r.1).sum::<f64>() / n;
        let all = runs.iter().map(|r| r.2).sum::<f64>() / n;
        let (lo, hi) = (
            runs.iter().map(|r| r.0).min().unwrap(),
            runs.iter().map(|r| r.0).max().unwrap(),
        );
        println!(
            "{:<72} {failures:>14.1} {steps:>11.1} {:>16} {all:>18.1}",
            arm.name,
            format!("{lo}-{hi}")
        );
    }
    Ok(())
}
