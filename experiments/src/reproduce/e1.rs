//! E1: the random agent with 2 blocks, 100 games, horizon 1000 (paper section VI-A).

use agent::RandomPolicy;

use super::arms::{ArmResult, Goals, Row, Suite, Table, mean_of};
use super::text::{num, relative};
use super::{Context, Experiment, HORIZON, Result, Scale, Setting, paper};

/// Jobs reported: one suite played.
pub(super) fn jobs(_: &Scale) -> u64 {
    1
}

/// Runs E1.
pub(super) fn run(ctx: &Context) -> Result<Experiment> {
    let suite = Suite {
        blocks: 2,
        goals: Goals::Drawn,
        episodes: ctx.scale.e1_games,
        seed: ctx.seeds.test,
        horizon: HORIZON,
    };
    let optimum = suite.optimum()?;
    let results = suite.play(&mut RandomPolicy)?;
    ctx.progress.advance("E1");
    let random = ArmResult::of(
        "random",
        "uniformly random actions",
        None,
        &[results],
        &optimum,
        HORIZON,
    );
    let theirs = paper::E1.rows[0];
    let reading = format!(
        "The random agent failed {} of {} games (paper: {} of {}) and took {} steps on average with a failure \
         counted as 1000, {} the paper's {}; from these starts a shortest plan takes {} steps on average.",
        random.failures,
        random.games,
        theirs.failures.unwrap_or_default(),
        theirs.games.unwrap_or_default(),
        num(Some(random.mean_steps_failures_at_horizon), 1),
        relative(
            random.mean_steps_failures_at_horizon,
            theirs.mean_steps.unwrap_or_default()
        ),
        num(theirs.mean_steps, 2),
        num(mean_of(&optimum), 2),
    );
    Ok(Experiment {
        id: "E1".into(),
        title: "Random agent, 2 blocks".into(),
        setup: vec![
            Setting {
                name: "agent".into(),
                value: "uniformly random actions among the 7 (4 moves, drop, pick either block)".into(),
            },
            Setting {
                name: "games".into(),
                value: suite.describe(),
            },
            Setting {
                name: "test".into(),
                value: "none (one arm)".into(),
            },
        ],
        tables: vec![Table {
            title: "Random agent, 2 blocks".into(),
            suite: suite.describe(),
            paper: Some(paper::E1),
            tests: Vec::new(),
            rows: vec![Row {
                ours: random,
                paper: Some(theirs),
                tests: Vec::new(),
            }],
        }],
        curves: Vec::new(),
        reading,
        figures: Vec::new(),
    })
}
