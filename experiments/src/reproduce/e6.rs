//! E6: demonstrators correct a trained agent (the paper's Tables II-IV, section VI-C).
//! Simulated demonstrators (the agent crate's three presets) stand in for the paper's
//! three people; each gives 10 demonstrations on 4 of the 6 goals, and every corrected
//! agent is tested on all goals and on the two goals no one demonstrated, against the
//! uncorrected agent (Wilcoxon).

use agent::{CorrectionConfig, DemonstratorProfile, QAgent};
use rayon::prelude::*;
use sim::{Goal, Profile};

use super::Findings;
use super::arms::{
    ArmResult, Goals, Row, Suite, Table, TestOutcome, describe, play_replicates, steps_box_plot, suite_in,
};
use super::paper::PaperTable;
use super::shared::Shared;
use super::{Context, Drawing, Experiment, Figure, HORIZON, Result, Setting, WORLDS, goals, paper, paper_learner};

/// The simulated demonstrators, by preset number.
const DEMONSTRATORS: [u8; 3] = [1, 2, 3];

/// Jobs reported: in each world, trainings, corrections, and every agent's three suites.
pub(super) fn jobs(ctx: &Context) -> u64 {
    let scale = &ctx.scale;
    let agents = (scale.replicates * (1 + DEMONSTRATORS.len())) as u64;
    let world = scale.replicates as u64 + (scale.replicates * DEMONSTRATORS.len()) as u64 + 3 * agents;
    WORLDS.len() as u64 * world
}

/// The goals demonstrated on in the SPEC world: the four not in
/// [`paper::E6_UNSEEN_GOALS`].
fn demonstrated() -> Result<Vec<Goal>> {
    let unseen = goals(&paper::E6_UNSEEN_GOALS);
    Ok(Goal::all(3)?.into_iter().filter(|g| !unseen.contains(g)).collect())
}

/// The test suites of the three tables: all goals, then each goal no one demonstrated.
fn suites() -> [(Goals, PaperTable, &'static str, &'static str); 3] {
    let unseen = goals(&paper::E6_UNSEEN_GOALS);
    [
        (Goals::Drawn, paper::TABLE_II, "All goals", "e6-all-goals"),
        (
            Goals::Each(vec![unseen[0].clone()]),
            paper::TABLE_III,
            "Goal 0,2,1",
            "e6-goal-021",
        ),
        (
            Goals::Each(vec![unseen[1].clone()]),
            paper::TABLE_IV,
            "Goal 2,0,1",
            "e6-goal-201",
        ),
    ]
}

/// A suite of one of the experiment's tables, its arms (the baseline first) and each
/// corrected arm's test against the baseline.
type PlayedTable = (Suite, Vec<ArmResult>, Vec<TestOutcome>);

/// One world's E6: per table, the suite, the arms (baseline first) and each corrected
/// arm's test against the baseline; and what was run.
struct World {
    tables: Vec<PlayedTable>,
    baseline: String,
    demonstrations: String,
}

/// Runs E6 in `world`.
fn in_world(ctx: &Context, world: Profile) -> Result<World> {
    // The authors' baselines learnt every goal and their people showed four (docs/world.md section 10,
    // "Demonstrations"); ours learn and are shown the same four.
    let (trained_on, shown) = match world {
        Profile::Original => (Goal::all(3)?, agent::correction::demonstrated_goals()),
        Profile::Spec => (demonstrated()?, demonstrated()?),
    };
    let baselines = ctx.train_replicates("E6", |r| ctx.paper_config(world, &trained_on, r))?;
    let profiles = DEMONSTRATORS
        .iter()
        .map(|&d| DemonstratorProfile::preset(d))
        .collect::<agent::Result<Vec<_>>>()?;
    // Every (demonstrator, replicate) pair, demonstrator-major.
    let pairs: Vec<(usize, usize)> = (0..profiles.len())
        .flat_map(|d| (0..ctx.scale.replicates).map(move |r| (d, r)))
        .collect();
    let corrected: Vec<(QAgent, agent::correction::SessionReport)> = pairs
        .par_iter()
        .map(|&(d, r)| {
            let config = CorrectionConfig::new(
                profiles[d].clone(),
                shown.clone(),
                ctx.scale.demos,
                ctx.seeds.demonstrations[d],
            );
            let c = agent::correct(baselines[r].agent.clone(), &config, ())?;
            ctx.progress.advance("E6");
            Ok((c.agent, c.report))
        })
        .collect::<Result<_>>()?;
    let base_agents: Vec<QAgent> = baselines.into_iter().map(|t| t.agent).collect();
    let by_demonstrator: Vec<&[(QAgent, agent::correction::SessionReport)]> =
        corrected.chunks(ctx.scale.replicates).collect();
    let tables = play_tables(ctx, world, &base_agents, &by_demonstrator, &profiles)?;
    let corrections: Vec<String> = by_demonstrator
        .iter()
        .enumerate()
        .map(|(d, agents)| {
            let (steps, fixes) = agents
                .iter()
                .fold((0, 0), |(s, c), (_, r)| (s + r.steps, c + r.corrections));
            format!(
                "{} ({}): {:.0} steps and {:.0} corrections per session",
                DEMONSTRATORS[d],
                profiles[d].name,
                steps as f64 / agents.len().max(1) as f64,
                fixes as f64 / agents.len().max(1) as f64
            )
        })
        .collect();
    let config = ctx.paper_config(world, &trained_on, 0);
    let text = |goals: &[Goal]| goals.iter().map(Goal::to_string).collect::<Vec<_>>().join(" ");
    let rule = agent::CorrectionRule::for_profile(world);
    Ok(World {
        tables,
        baseline: format!(
            "the paper's learner ({}) trained {} games on {}; {} agents, training seeds {:?}",
            paper_learner(&config),
            config.games,
            text(&trained_on),
            ctx.scale.replicates,
            ctx.seeds.training
        ),
        demonstrations: format!(
            "each gives {} demonstrations on {} in turn to every baseline agent (session seeds {:?}), correcting \
             the agent's proposals (epsilon 0.1); the agent learns by {}. {}",
            ctx.scale.demos,
            text(&shown),
            ctx.seeds.demonstrations,
            match rule.margin {
                Some(m) => format!("Q-update plus a large margin ({m})"),
                None => "the plain Q-update (the authors' rule)".into(),
            },
            corrections.join("; ")
        ),
    })
}

/// Every suite of the experiment's tables played by the baselines and by each
/// demonstrator's corrected agents, with each corrected arm's test against the baseline.
fn play_tables(
    ctx: &Context,
    world: Profile,
    base_agents: &[QAgent],
    by_demonstrator: &[&[(QAgent, agent::correction::SessionReport)]],
    profiles: &[DemonstratorProfile],
) -> Result<Vec<PlayedTable>> {
    let eps = ctx.test_epsilon();
    let mut tables = Vec::new();
    for (goals, _, _, _) in suites() {
        let suite = suite_in(world, 3, goals, ctx.scale.test_games, ctx.seeds.test);
        let optimum = suite.optimum()?;
        let base = play_replicates(
            &suite,
            base_agents,
            |a| Ok(Box::new(a.policy(eps)?)),
            ctx.progress,
            "E6",
        )?;
        let mut arms = vec![ArmResult::of(
            "baseline",
            "the paper's learner, uncorrected",
            Some(eps),
            &base,
            &optimum,
            HORIZON,
        )];
        for (d, agents) in by_demonstrator.iter().enumerate() {
            let results = play_replicates(
                &suite,
                agents,
                |(a, _)| Ok(Box::new(a.policy(eps)?)),
                ctx.progress,
                "E6",
            )?;
            arms.push(ArmResult::of(
                format!("demonstrator {}", DEMONSTRATORS[d]),
                format!("the baseline corrected by the simulated {}", profiles[d].name),
                Some(eps),
                &results,
                &optimum,
                HORIZON,
            ));
        }
        let tests = arms[1..]
            .iter()
            .map(|a| TestOutcome::wilcoxon(a, &arms[0]))
            .collect::<Result<Vec<_>>>()?;
        tables.push((suite, arms, tests));
    }
    Ok(tables)
}

/// Runs E6.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let (original, spec) = ctx.in_both_worlds(|w| in_world(ctx, w))?;
    let mut tables = Vec::new();
    let mut figures = Vec::new();
    for (i, (_, theirs, title, stem)) in suites().into_iter().enumerate() {
        let (suite, o_arms, o_tests) = &original.tables[i];
        let (_, s_arms, s_tests) = &spec.tables[i];
        let tests = |tests: &[TestOutcome], k: usize| vec![if k == 0 { None } else { Some(tests[k - 1].clone()) }];
        let rows: Vec<Row> = (0..o_arms.len())
            .map(|k| {
                Row::new(
                    Some(theirs.rows[k]),
                    Some((o_arms[k].clone(), tests(o_tests, k))),
                    Some((s_arms[k].clone(), tests(s_tests, k))),
                )
            })
            .collect();
        figures.push(Figure::new(
            stem,
            format!("{title}: steps per game of each agent in each world (a failure at 1000), with the paper's mean"),
            Drawing::Boxes(steps_box_plot(
                format!("E6 ({}): {}", theirs.source, title.to_lowercase()),
                &rows,
                ctx.scale.replicates,
                suite,
            )),
        ));
        tables.push(Table {
            title: title.into(),
            suite: format!("{}, in each world", describe(suite)),
            paper: Some(theirs),
            tests: vec!["Wilcoxon vs baseline".into()],
            rows,
        });
    }
    let reading = reading(&tables);
    Ok(Experiment {
        id: "E6".into(),
        title: "Demonstrators correct a trained agent (Tables II-IV)".into(),
        setup: vec![
            Setting {
                name: "baseline, original".into(),
                value: original.baseline,
            },
            Setting {
                name: "baseline, spec".into(),
                value: spec.baseline,
            },
            Setting {
                name: "demonstrators".into(),
                value: "the agent crate's simulated demonstrators 1-3 stand in for the paper's three people, playing \
                        by each world's protocol"
                    .into(),
            },
            Setting {
                name: "demonstrations, original".into(),
                value: original.demonstrations,
            },
            Setting {
                name: "demonstrations, spec".into(),
                value: spec.demonstrations,
            },
            Setting {
                name: "games".into(),
                value: format!(
                    "{} games per table (the paper's 500) in each world, per agent: goal drawn per game, then goal \
                     0,2,1, then 2,0,1",
                    ctx.scale.test_games
                ),
            },
            Setting {
                name: "test policy".into(),
                value: format!("random action with probability {} (the paper's)", ctx.test_epsilon()),
            },
            Setting {
                name: "test".into(),
                value: "Wilcoxon signed-rank against the uncorrected agent of the same training seed, paired by \
                        start, steps with a failure counted as 1000"
                    .into(),
            },
        ],
        tables,
        paper_notes: Vec::new(),
        reading,
        figures,
        findings: Findings::Tables,
    })
}

/// Of the demonstrators' rows: how many beat the baseline's mean steps, how many of those
/// significantly (p < 5%), how many were significantly worse, and how many rows; from
/// `(mean, p)` pairs, baseline first.
fn tally(rows: &[(f64, Option<f64>)]) -> (usize, usize, usize, usize) {
    let base = rows[0].0;
    let significant = |(_, p): &&(f64, Option<f64>)| p.is_some_and(|p| p < super::text::ALPHA);
    let better = rows[1..].iter().filter(|(m, _)| *m < base);
    let worse = rows[1..].iter().filter(|(m, _)| *m > base);
    (
        better.clone().count(),
        better.filter(significant).count(),
        worse.filter(significant).count(),
        rows.len() - 1,
    )
}

/// "2 of 3 better, 1 significantly; 1 significantly worse".
fn tally_text((better, significant, worse, n): (usize, usize, usize, usize)) -> String {
    let worse = if worse > 0 {
        format!("; {worse} significantly worse")
    } else {
        String::new()
    };
    format!("{better} of {n} better, {significant} significantly{worse}")
}

/// A table's tally: our rows' in `world`, or the paper's (`None`).
fn tally_of(t: &Table, world: Option<Profile>) -> String {
    let rows: Vec<(f64, Option<f64>)> = match world {
        Some(w) => t
            .rows
            .iter()
            .filter_map(|r| r.in_world(w))
            .map(|m| {
                (
                    m.arm.mean_steps_failures_at_horizon,
                    m.tests.first().cloned().flatten().map(|x| x.p_value),
                )
            })
            .collect(),
        None => t
            .rows
            .iter()
            .filter_map(|r| r.paper)
            .map(|p| (p.mean_steps.unwrap_or(f64::NAN), p.p_value))
            .collect(),
    };
    if rows.is_empty() {
        "-".into()
    } else {
        tally_text(tally(&rows))
    }
}

/// The paper's tally of `t`, then ours in each world.
fn tallies(t: &Table) -> String {
    format!(
        "paper {}; original {}; spec {}",
        tally_of(t, None),
        tally_of(t, Some(Profile::Original)),
        tally_of(t, Some(Profile::Spec))
    )
}

/// How many of the paper's figures in `tables` lie inside the spread of our replicates in
/// `world`, of how many.
fn inside_count(tables: &[Table], world: Profile) -> (usize, usize) {
    let placed: Vec<bool> = tables
        .iter()
        .flat_map(|t| &t.rows)
        .filter_map(|r| r.in_world(world)?.paper_inside)
        .flat_map(|inside| inside.placements().map(|p| p.inside).collect::<Vec<_>>())
        .collect();
    (placed.iter().filter(|&&i| i).count(), placed.len())
}

/// The reading: how the corrected agents fared against the baseline on all goals and on
/// the unseen ones, the paper's and ours in each world (mean steps with a failure counted
/// as 1000; significance by Wilcoxon), and how many of the paper's figures lie inside our
/// spread.
fn reading(tables: &[Table]) -> String {
    let unseen: Vec<String> = tables[1..]
        .iter()
        .map(|t| format!("{}: {}", t.title.to_lowercase(), tallies(t)))
        .collect();
    let (original_in, figures) = inside_count(tables, Profile::Original);
    let (spec_in, _) = inside_count(tables, Profile::Spec);
    format!(
        "Corrected agents against the baseline's mean steps* on all goals: {}. On the goals no one demonstrated, \
         {}. Of the paper's {figures} figures (failures and mean steps* of every row), {original_in} lie inside \
         the spread of our agents in the original world and {spec_in} in the SPEC world.",
        tallies(&tables[0]),
        unseen.join("; "),
    )
}
