//! E1: the random agent with 2 blocks, 100 games, horizon 1000 (paper section VI-A), in the
//! paper's world as coded and in ours, and the gap between the two worlds taken apart rule
//! by rule.
//!
//! The random agent learns nothing, so its figures depend on the world alone: the paper's
//! 4 failures and 263.55 mean steps against our SPEC world's are the plainest measure of how
//! far the worlds are apart. Two rules of `sim` differ for it (the reward and the learner do
//! not matter to a random agent): the action protocol and the start rule. Each is switched
//! to the paper's alone, on the same seeds, and the gap's remainder is the part that needs
//! both.

use agent::RandomPolicy;
use rayon::prelude::*;
use serde::Serialize;
use sim::{ActionProtocol, Profile, StartRule};

use super::Findings;
use super::arms::{ArmResult, Goals, Row, Rules, Suite, Table, describe, mean_of};
use super::shared::Shared;
use super::text::{num, paper_against};
use super::{Context, Experiment, HORIZON, Result, Setting, paper};

/// The worlds E1 plays, SPEC first, then one rule switched to the paper's, then both (the
/// original world).
const WORLDS: [Rules; 4] = [
    Rules::of(Profile::Spec),
    Rules {
        protocol: ActionProtocol::Paper,
        start: StartRule::Uniform,
    },
    Rules {
        protocol: ActionProtocol::Free,
        start: StartRule::Paper,
    },
    Rules::of(Profile::Original),
];

/// Jobs reported: one suite played per world.
pub(super) fn jobs(_: &Context) -> u64 {
    WORLDS.len() as u64
}

/// The random agent in one world.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorldArm {
    /// The world's rules.
    pub rules: Rules,
    /// "the SPEC world", "protocol paper, start rule uniform", ...
    pub world: String,
    /// The random agent's figures there.
    pub arm: ArmResult,
}

/// One figure's gap between the worlds and the part of it each rule accounts for.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Gap {
    /// The figure: "failures, % of games" or "mean steps*".
    pub figure: String,
    /// In the SPEC world.
    pub spec: f64,
    /// In the original world.
    pub original: f64,
    /// `original - spec`.
    pub gap: f64,
    /// The change when only the protocol is switched to the paper's.
    pub protocol: f64,
    /// The change when only the start rule is switched to the paper's.
    pub start: f64,
    /// What neither accounts for alone: `gap - protocol - start`.
    pub interaction: f64,
}

impl Gap {
    /// The gap in `figure` from its value in each of [`WORLDS`].
    fn of(figure: &str, values: [f64; 4]) -> Gap {
        let [spec, protocol, start, original] = values;
        let gap = original - spec;
        Gap {
            figure: figure.into(),
            spec,
            original,
            gap,
            protocol: protocol - spec,
            start: start - spec,
            interaction: gap - (protocol - spec) - (start - spec),
        }
    }

    /// The share of the gap `part` is, in percent (`None` without a gap).
    pub fn share(&self, part: f64) -> Option<f64> {
        (self.gap != 0.0).then(|| 100.0 * part / self.gap)
    }
}

/// E1's gap between the SPEC world and the original one, rule by rule.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Decomposition {
    /// The random agent in each world: SPEC, protocol alone switched, start rule alone
    /// switched, original.
    pub worlds: Vec<WorldArm>,
    /// The gap in the share of games failed (in percent) and in mean steps*.
    pub gaps: Vec<Gap>,
}

/// Runs E1.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let per_replicate = ctx.scale.e1_games;
    let suite = |rules: Rules| Suite {
        world: rules.world(2, HORIZON),
        goals: Goals::Drawn,
        episodes: per_replicate * ctx.scale.e1_replicates as u64,
        seed: ctx.seeds.test,
    };
    let played: Vec<(WorldArm, Option<f64>)> = WORLDS
        .par_iter()
        .map(|&rules| {
            let suite = suite(rules);
            let optimum = suite.optimum()?;
            let results = suite.play(&mut RandomPolicy)?;
            ctx.progress.advance("E1");
            let arm = ArmResult::of_sets(
                "random",
                "uniformly random legal actions",
                &results,
                1,
                per_replicate as usize,
                &optimum,
                HORIZON,
            );
            let world = WorldArm {
                rules,
                world: rules.describe(),
                arm,
            };
            Ok((world, mean_of(&optimum)))
        })
        .collect::<Result<_>>()?;
    let spec_optimum = played[0].1;
    let worlds: Vec<WorldArm> = played.into_iter().map(|(w, _)| w).collect();
    let figure = |f: fn(&ArmResult) -> f64| -> [f64; 4] { std::array::from_fn(|i| f(&worlds[i].arm)) };
    let gaps = vec![
        Gap::of("failures, % of games", figure(|a| 100.0 * a.failure_rate())),
        Gap::of("mean steps*", figure(|a| a.mean_steps_failures_at_horizon)),
    ];
    let (spec, original) = (&worlds[0].arm, &worlds[3].arm);
    let theirs = paper::E1.rows[0];
    let row = Row::new(
        Some(theirs),
        Some((original.clone(), Vec::new())),
        Some((spec.clone(), Vec::new())),
    );
    let reading = reading(original, spec, &row, &gaps[1]);
    let games = describe(&suite(Rules::of(Profile::Spec)));
    Ok(Experiment {
        id: "E1".into(),
        title: "Random agent, 2 blocks".into(),
        setup: setup(ctx, &games, spec_optimum),
        tables: vec![Table {
            title: "Random agent, 2 blocks".into(),
            suite: format!(
                "{games} in each world, {} replicates of {per_replicate}",
                ctx.scale.e1_replicates
            ),
            paper: Some(paper::E1),
            tests: Vec::new(),
            rows: vec![row],
        }],
        paper_notes: Vec::new(),
        reading,
        figures: Vec::new(),
        findings: Findings::Decomposition(Decomposition { worlds, gaps }),
    })
}

/// The run's reading: the random agent in both worlds, and where the gap in mean steps*
/// comes from (`steps`, the gap's decomposition).
fn reading(original: &ArmResult, spec: &ArmResult, row: &Row, steps: &Gap) -> String {
    let part = |value: f64| {
        format!(
            "{value:+.1}{}",
            steps.share(value).map_or(String::new(), |s| format!(" ({s:.0}%)"))
        )
    };
    format!(
        "In the paper's world as coded the random agent failed {} of {} games and took {} steps* on average; in \
         ours {} and {}. {} Of the gap in mean steps* ({} in the SPEC world, {} in the original), switching one rule \
         at a time from the SPEC world, the protocol alone accounts for {}, the start rule alone for {}, and their \
         interaction for {}.",
        num(Some(original.failures), 1),
        original.games,
        num(Some(original.mean_steps_failures_at_horizon), 1),
        num(Some(spec.failures), 1),
        num(Some(spec.mean_steps_failures_at_horizon), 1),
        paper_against(row),
        num(Some(steps.spec), 1),
        num(Some(steps.original), 1),
        part(steps.protocol),
        part(steps.start),
        part(steps.interaction),
    )
}

/// What was run; `games` describes the SPEC world's suite.
fn setup(ctx: &Context, games: &str, spec_optimum: Option<f64>) -> Vec<Setting> {
    let per_replicate = ctx.scale.e1_games;
    vec![
        Setting {
            name: "agent".into(),
            value: "uniformly random legal actions: among the 7 (4 moves, drop, pick either block) in the SPEC \
                    world; a random block when nothing is held and one of the 4 moves and drop when holding in \
                    the original world (the authors' random agent)"
                .into(),
        },
        Setting {
            name: "games".into(),
            value: format!(
                "{games}, in each world, cut into {} replicates of the paper's {per_replicate} games",
                ctx.scale.e1_replicates,
            ),
        },
        Setting {
            name: "worlds between".into(),
            value: format!(
                "the same games in {} and in {}: one rule of the SPEC world switched to the paper's",
                WORLDS[1].describe(),
                WORLDS[2].describe()
            ),
        },
        Setting {
            name: "mean optimum".into(),
            value: format!(
                "{} steps from the SPEC world's starts (the exact solver's)",
                num(spec_optimum, 2)
            ),
        },
        Setting {
            name: "test".into(),
            value: "none (one arm)".into(),
        },
    ]
}
