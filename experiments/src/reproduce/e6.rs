//! E6: demonstrators correct a trained agent (the paper's Tables II-IV, section VI-C).
//! Simulated demonstrators (the agent crate's three presets) stand in for the paper's
//! three people; each gives 10 demonstrations on 4 of the 6 goals, and every corrected
//! agent is tested on all goals and on the two goals no one demonstrated, against the
//! uncorrected agent (Wilcoxon).

use agent::{CorrectionConfig, DemonstratorProfile, QAgent};
use rayon::prelude::*;
use sim::{Goal, Profile};

use super::arms::{ArmResult, Goals, Measured, Row, Rules, Suite, Table, TestOutcome, play_replicates, steps_box_plot};
use super::text::{num, significance};
use super::{Context, Drawing, Experiment, Figure, HORIZON, Result, Scale, Setting, goals, paper, paper_learner};

/// The simulated demonstrators, by preset number.
const DEMONSTRATORS: [u8; 3] = [1, 2, 3];

/// Jobs reported: trainings, corrections, and every agent's three suites.
pub(super) fn jobs(scale: &Scale) -> u64 {
    let agents = (scale.replicates * (1 + DEMONSTRATORS.len())) as u64;
    scale.replicates as u64 + (scale.replicates * DEMONSTRATORS.len()) as u64 + 3 * agents
}

/// The goals demonstrated on: the four not in [`paper::E6_UNSEEN_GOALS`].
fn demonstrated() -> Result<Vec<Goal>> {
    let unseen = goals(&paper::E6_UNSEEN_GOALS);
    Ok(Goal::all(3)?.into_iter().filter(|g| !unseen.contains(g)).collect())
}

/// Runs E6.
pub(super) fn run(ctx: &Context) -> Result<Experiment> {
    let shown = demonstrated()?;
    let baselines = ctx.train_replicates("E6", |r| ctx.paper_config(&shown, r))?;
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
    let eps = ctx.test_epsilon();
    let unseen = goals(&paper::E6_UNSEEN_GOALS);
    let suites = [
        (Goals::Drawn, paper::TABLE_II, "All goals", "e6-all-goals"),
        (
            Goals::Each(vec![unseen[0]]),
            paper::TABLE_III,
            "Goal 0,2,1",
            "e6-goal-021",
        ),
        (
            Goals::Each(vec![unseen[1]]),
            paper::TABLE_IV,
            "Goal 2,0,1",
            "e6-goal-201",
        ),
    ];
    let mut tables = Vec::new();
    let mut figures = Vec::new();
    for (goals, theirs, title, stem) in suites {
        let suite = Suite {
            blocks: 3,
            goals,
            episodes: ctx.scale.test_games,
            seed: ctx.seeds.test,
            horizon: HORIZON,
            rules: Rules::of(Profile::Spec),
        };
        let optimum = suite.optimum()?;
        let base = play_replicates(
            &suite,
            &base_agents,
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
        figures.push(Figure::new(
            stem,
            format!("{title}: steps per game of each agent (a failure at 1000), with the paper's mean"),
            Drawing::Boxes(steps_box_plot(
                format!("E6 ({}): {}", theirs.source, title.to_lowercase()),
                &arms,
                theirs.rows,
                ctx.scale.replicates,
                &suite,
            )),
        ));
        let mut tests = tests.into_iter();
        let rows = arms
            .into_iter()
            .zip(theirs.rows)
            .enumerate()
            .map(|(i, (ours, &p))| Row::spec(Some(p), ours, vec![if i == 0 { None } else { tests.next() }]))
            .collect();
        tables.push(Table {
            title: title.into(),
            suite: suite.describe(),
            paper: Some(theirs),
            tests: vec!["Wilcoxon vs baseline".into()],
            rows,
        });
    }
    let reading = reading(&tables);
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
    let config = ctx.paper_config(&shown, 0);
    let shown_text = shown.iter().map(Goal::to_string).collect::<Vec<_>>().join(" ");
    Ok(Experiment {
        id: "E6".into(),
        title: "Demonstrators correct a trained agent (Tables II-IV)".into(),
        setup: vec![
            Setting {
                name: "baseline".into(),
                value: format!(
                    "the paper's learner ({}) \
                     trained {} games on the demonstrated goals {shown_text} in turn, physics backend; {} agents, \
                     training seeds {:?}",
                    paper_learner(&config),
                    config.games,
                    ctx.scale.replicates,
                    ctx.seeds.training
                ),
            },
            Setting {
                name: "demonstrators".into(),
                value: format!(
                    "the agent crate's simulated demonstrators 1-3 stand in for the paper's three people; each gives \
                     {} demonstrations on {shown_text} in turn to every baseline agent (session seeds {:?}), \
                     correcting the agent's proposals (epsilon 0.1); the agent learns by Q-update plus large \
                     margin. {}",
                    ctx.scale.demos,
                    ctx.seeds.demonstrations,
                    corrections.join("; ")
                ),
            },
            Setting {
                name: "games".into(),
                value: format!(
                    "{} games per table (the paper's 500), per agent: goal drawn per game, then goal 0,2,1, then 2,0,1",
                    ctx.scale.test_games
                ),
            },
            Setting {
                name: "test policy".into(),
                value: format!("random action with probability {eps} (the paper's)"),
            },
            Setting {
                name: "test".into(),
                value: "Wilcoxon signed-rank against the uncorrected agent of the same training seed, paired by \
                        start, steps with a failure counted as 1000"
                    .into(),
            },
        ],
        tables,
        curves: Vec::new(),
        decomposition: None,
        paper_notes: Vec::new(),
        reading,
        figures,
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

/// Our table's tally in `world`, then the paper's.
fn tallies(t: &Table, world: Profile) -> (String, String) {
    let ours: Vec<(f64, Option<f64>)> = t
        .rows
        .iter()
        .filter_map(|r| r.in_world(world))
        .map(|m| {
            (
                m.arm.mean_steps_failures_at_horizon,
                m.tests.first().cloned().flatten().map(|x| x.p_value),
            )
        })
        .collect();
    let theirs: Vec<(f64, Option<f64>)> = t
        .paper
        .map(|p| {
            p.rows
                .iter()
                .map(|r| (r.mean_steps.unwrap_or(f64::NAN), r.p_value))
                .collect()
        })
        .unwrap_or_default();
    (
        tally_text(tally(&ours)),
        if theirs.is_empty() {
            "-".into()
        } else {
            tally_text(tally(&theirs))
        },
    )
}

/// The reading: how the corrected agents fared against the baseline on all goals, and on
/// the unseen ones (mean steps with a failure counted as 1000; significance by Wilcoxon).
fn reading(tables: &[Table]) -> String {
    let world = Profile::Spec;
    let all = &tables[0];
    fn in_world(r: &Row, world: Profile) -> &Measured {
        r.in_world(world).expect("every row has the world")
    }
    let best = all.rows[1..]
        .iter()
        .map(|r| in_world(r, world))
        .min_by(|a, b| {
            a.arm
                .mean_steps_failures_at_horizon
                .total_cmp(&b.arm.mean_steps_failures_at_horizon)
        })
        .expect("demonstrators");
    let (ours_all, paper_all) = tallies(all, world);
    let unseen: Vec<String> = tables[1..]
        .iter()
        .map(|t| {
            let (ours, theirs) = tallies(t, world);
            format!("{}: {ours} (paper: {theirs})", t.title.to_lowercase())
        })
        .collect();
    format!(
        "Corrected agents against the baseline's mean steps on all goals: {ours_all} (paper: {paper_all}); the \
         best, {}, failed {} games per {} against the baseline's {}, {}. On the goals no one demonstrated, {}.",
        best.arm.name,
        num(Some(best.arm.failures), 1),
        best.arm.games,
        num(Some(in_world(&all.rows[0], world).arm.failures), 1),
        best.tests[0]
            .as_ref()
            .map_or("not tested".into(), |t| significance(t.p_value)),
        unseen.join("; "),
    )
}
