//! The report: `README.md` (one section per experiment, ours beside the paper's), the
//! pictures, `results.json` (every figure of the tables) and `summary.md` (the front page's
//! block, [`summary`]), written into one directory with where the run happened.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::arms::{ArmResult, Measured, Table, TestOutcome};
use super::paper::MeanOver;
use super::ran::Ran;
use super::spread::Spread;
use super::summary::summary;
use super::text::{ALPHA, failures, num, p_value, verdict};
use super::{Curve, Decomposition, Drawing, Experiment, Findings, Report, ReproduceError, Reproduction, Result};
use crate::episode::{GifOptions, episode_gif};
use plots::{bar_chart, box_plot, curves_chart, learning_curve};

mod blocks_world;
mod general;

/// The files a report is made of.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReportFiles {
    /// `README.md`.
    pub readme: PathBuf,
    /// `results.json`.
    pub results: PathBuf,
    /// `summary.md`.
    pub summary: PathBuf,
    /// Every picture, in the order of the report.
    pub pictures: Vec<PathBuf>,
}

/// `results.json`: the reproduction's figures, then where it ran.
#[derive(serde::Serialize)]
struct ResultsFile<'a> {
    #[serde(flatten)]
    reproduction: &'a Reproduction,
    ran: &'a Ran,
}

/// Draws the pictures of `r` and writes them, `README.md`, `results.json` and `summary.md`
/// into `dir` (made if missing), each file atomically; `ran` says where `r` was run.
pub fn write_report(r: &Reproduction, ran: &Ran, dir: &Path) -> Result<ReportFiles> {
    files::prepare_folder(dir)?;
    let mut pictures = Vec::new();
    for figure in r.experiments.iter().flat_map(|e| &e.figures) {
        let stem = dir.join(&figure.stem);
        match &figure.drawing {
            Drawing::Learning(c) => pictures.extend(chart(learning_curve(c, &stem)?)),
            Drawing::Boxes(b) => pictures.extend(chart(box_plot(b, &stem)?)),
            Drawing::Bars(b) => pictures.extend(chart(bar_chart(b, &stem)?)),
            Drawing::Curves(c) => pictures.extend(chart(curves_chart(c, &stem)?)),
            Drawing::Episode(frames) => {
                let path = dir.join(&figure.files[0]);
                episode_gif(frames, &GifOptions::default(), &path)?;
                pictures.push(path);
            }
        }
    }
    let results = dir.join("results.json");
    let json =
        serde_json::to_string_pretty(&ResultsFile { reproduction: r, ran }).map_err(|e| ReproduceError::Write {
            path: results.display().to_string(),
            reason: e.to_string(),
        })?;
    files::write(&results, json.as_bytes())?;
    let summary_md = dir.join("summary.md");
    files::write(&summary_md, summary(&json)?.as_bytes())?;
    let readme = dir.join("README.md");
    files::write(&readme, markdown(r, ran).as_bytes())?;
    Ok(ReportFiles {
        readme,
        results,
        summary: summary_md,
        pictures,
    })
}

fn chart(files: plots::ChartFiles) -> [PathBuf; 2] {
    [files.png, files.svg]
}

/// The report as Markdown; `ran` says where `r` was run.
pub fn markdown(r: &Reproduction, ran: &Ran) -> String {
    let mut md = String::new();
    let command = format!(
        "blockstack {} --seed {}{}{}{}",
        r.options.report.command(),
        r.options.seed,
        if r.options.quick { " --quick" } else { "" },
        if r.options.long { " --long" } else { "" },
        if r.options.only.is_empty() {
            String::new()
        } else {
            format!(" --only {}", r.options.only.join(","))
        }
    );
    let quick = if r.options.quick {
        " **Quick run:** small counts to check the pipeline, not the real figures; run without `--quick` for \
         them."
    } else {
        ""
    };
    match r.options.report {
        Report::Paper => {
            let _ = writeln!(md, "# The paper reproduced\n");
            let _ = writeln!(md, "Ran at {}.\n", ran.describe());
            let _ = writeln!(
                md,
                "Written by `{command}`: every experiment of docs/world.md section 9 on the paper's 7 x 7 grid (horizon \
                 {}, rapier2d physics), the figures of \"Interactive Robot Learning\" section VI beside ours in two \
                 worlds: `original`, the paper's world as its authors coded it (their action protocol, start rule, \
                 reward, representation and schedule), and `spec`, ours (docs/world.md). E1-E6 are run in both; E7 and \
                 our own learner in the SPEC world. Every figure below is computed by the run; the paper's come from \
                 `experiments::reproduce::paper`. The same figures, and more, are in [`results.json`](results.json). \
                 The classic Blocks World, ours, has a report of its own: `blockstack benchmark`.{quick}\n",
                r.paper_settings.horizon,
            );
        }
        Report::BlocksWorld => {
            let _ = writeln!(md, "# The Blocks World benchmark\n");
            let _ = writeln!(md, "Ran at {}.\n", ran.describe());
            let _ = writeln!(
                md,
                "Written by `{command}`: ours, the classic Blocks World, which the paper never measured. E9 plays it \
                 seen from the side (docs/world.md section 12): the planners' block moves against the fewest, the \
                 gripper carrying them out through the physics, a tabular learner, and the physics against the grid \
                 model; E10 trains one policy on small problems and plays it at every size, against the near-optimal \
                 planner and published results (docs/dqn.md). Every figure below is computed by the run. The same \
                 figures, and more, are in [`results.json`](results.json). The paper's reproduction has a report of \
                 its own: `blockstack reproduce`.{quick}\n"
            );
        }
    }
    let _ = writeln!(md, "| | experiment | reading |\n|---|---|---|");
    for e in &r.experiments {
        let _ = writeln!(
            md,
            "| [{}](#{}) | {} | {} |",
            e.id,
            anchor(&e.id, &e.title),
            e.title,
            e.reading
        );
    }
    if r.options.report == Report::Paper {
        how_to_read(&mut md, r);
        paper_beside_ours(&mut md, r);
    }
    for e in &r.experiments {
        experiment(&mut md, e);
    }
    md
}

/// What the paper's tables print, and how to read them against the paper's.
fn how_to_read(md: &mut String, r: &Reproduction) {
    let _ = writeln!(md, "\n## How to read the tables\n");
    for line in [
        format!(
            "**Same starts.** Every arm of a comparison plays the same games: game k starts from \
             `reset(episode_seed({}, k))` with the same goal, so the paired tests pair the same start.",
            r.seeds.test
        ),
        format!(
            "**Agents.** A learner's results depend much on its training seed, so each learner arm of E2-E6 is \
             {} agents trained with seeds {:?}, each playing every game; failures are per agent (mean, and range \
             over agents), the other figures over all games of all agents. A paired test pairs game k of the \
             agents with the same seed.",
            r.scale.replicates, r.seeds.training
        ),
        "**Worlds.** Each figure of the paper stands beside ours in the `original` world (the paper's, as coded) \
         and in the `spec` world (ours): columns \"paper\", \"original\", \"spec\"."
            .into(),
        format!(
            "**Spread.** A replicate repeats the paper's experiment once (a learner arm: one agent, its own training \
             seed; E1: one set of the paper's 100 games). The spread of a figure is its range over our replicates, \
             smallest to largest, printed in brackets; the paper's figure is *inside* when it lies in that range. \
             Were the paper's figure one more draw of ours, it would land inside the range of R replicates with \
             probability (R - 1) / (R + 1): {}% for the {} agents of a learner arm, {}% for E1's {} sets of games. \
             Failures are compared as shares of the games played.",
            coverage(r.scale.replicates),
            r.scale.replicates,
            coverage(r.scale.e1_replicates),
            r.scale.e1_replicates
        ),
        "**Steps.** The paper's mean steps count a failed game as the horizon (1000); \"mean steps*\" is that \
         figure. Beside it: the mean and median over the games that reached the goal, and their mean ratio to \
         the shortest plan from the same start (the exact solver's). Tests compare steps with a failure at 1000."
            .into(),
        format!(
            "**Test policy.** As in the paper, learners take a random action with probability {} unless a row \
             says otherwise (column ε).",
            r.paper_settings.test_epsilon
        ),
        "**Tests.** Wilcoxon signed-rank (paired), two-sample Kolmogorov-Smirnov: the `stats` crate, ports of \
         SciPy's defaults checked against SciPy; p is two-sided. Our p pools every agent's games; beside it, \
         (k/n) says for how many of the n agents alone (the paper's protocol: one agent) p is below 0.05."
            .into(),
    ] {
        let _ = writeln!(md, "- {line}");
    }
}

/// Every row the paper has, its figures beside ours in each world and the readings of the
/// spread: the report's overview (and the README's Results table).
fn paper_beside_ours(md: &mut String, r: &Reproduction) {
    let _ = writeln!(md, "\n## The paper's figures beside ours\n");
    let _ = writeln!(
        md,
        "Every row of the paper's tables: its failures and mean steps, ours in the `original` and the `spec` \
         world (mean over replicates, and the range), and whether the paper's figures lie inside the spread of \
         each world's replicates. Mean steps count a failure as 1000 (mean steps*), except where marked † (over \
         the games that reached the goal: E2, as docs/world.md section 9 reads the paper's).\n"
    );
    let _ = writeln!(
        md,
        "| | table | arm | failures, paper | failures, original | failures, spec | mean steps, paper | mean steps, \
         original | mean steps, spec | paper inside original's spread | paper inside spec's spread |\n\
         |---|---|---|---|---|---|---|---|---|---|---|"
    );
    for e in &r.experiments {
        for t in &e.tables {
            for row in t.rows.iter().filter(|row| row.paper.is_some()) {
                let mut cells = vec![e.id.clone(), t.title.clone(), row.name.clone()];
                let paper = row.paper.expect("filtered");
                let worlds = [row.original.as_ref(), row.spec.as_ref()];
                cells.push(match (paper.failures, paper.games) {
                    (Some(f), Some(n)) => format!("{f} / {n}"),
                    _ => "-".into(),
                });
                cells.extend(worlds.iter().map(|m| {
                    m.map_or("-".into(), |m| {
                        format!(
                            "{} / {}",
                            failures(&m.arm.failures_per_replicate, m.arm.failures),
                            m.arm.games
                        )
                    })
                }));
                let mark = match paper.mean_over {
                    MeanOver::FailuresAtHorizon => "",
                    MeanOver::Successes => " †",
                };
                cells.push(format!("{}{mark}", num(paper.mean_steps, 2)));
                cells.extend(worlds.iter().map(|m| {
                    m.map_or("-".into(), |m| match paper.mean_over {
                        MeanOver::FailuresAtHorizon => steps_spread(&m.arm),
                        MeanOver::Successes => format!("{}{mark}", successes_spread(&m.arm)),
                    })
                }));
                cells.extend(worlds.iter().map(|m| {
                    m.and_then(|m| m.paper_inside.as_ref())
                        .map_or("-".into(), |inside| verdict(inside).to_string())
                }));
                let _ = writeln!(md, "| {} |", cells.join(" | "));
            }
        }
    }
}

/// The chance, in whole percent, that one more draw lands inside the range of `replicates`
/// draws ([`Spread::coverage`]).
fn coverage(replicates: usize) -> String {
    format!("{:.0}", 100.0 * Spread::coverage_of(replicates))
}

/// The GitHub anchor of a section headed "E1: title".
fn anchor(id: &str, title: &str) -> String {
    format!("{id}: {title}")
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            'a'..='z' | '0'..='9' | '-' | '_' => Some(c),
            ' ' => Some('-'),
            _ => None,
        })
        .collect()
}

fn experiment(md: &mut String, e: &Experiment) {
    let _ = writeln!(md, "\n## {}: {}\n", e.id, e.title);
    let _ = writeln!(md, "What was run:\n");
    for s in &e.setup {
        let _ = writeln!(md, "- {}: {}", s.name, s.value);
    }
    for t in &e.tables {
        table(md, t);
    }
    match &e.findings {
        Findings::Tables => {}
        Findings::BlocksWorld(w) => blocks_world::tables(md, w),
        Findings::General(g) => general::tables(md, g),
        Findings::Decomposition(d) => decomposition(md, d),
        Findings::Curves(curves) => curves.iter().for_each(|c| curve(md, c)),
    }
    for note in &e.paper_notes {
        let _ = writeln!(md, "\n**The paper's own figures.** {note}");
    }
    let _ = writeln!(md, "\n**Reading.** {}", e.reading);
    for f in &e.figures {
        let _ = writeln!(md, "\n![{}]({})\n\n*{}*", f.caption, f.files[0], f.caption);
    }
}

/// Steps, with more decimals for small figures.
fn steps(v: Option<f64>) -> String {
    match v {
        Some(v) if v < 100.0 => num(Some(v), 2),
        _ => num(v, 1),
    }
}

fn epsilon(arm: &ArmResult) -> String {
    match arm.test_epsilon {
        Some(0.0) => "0 (greedy)".into(),
        Some(e) => e.to_string(),
        None => "-".into(),
    }
}

/// A test's cell: its p-value, and for how many agents alone p is below [`ALPHA`].
fn test_cell(test: Option<&TestOutcome>) -> String {
    match test {
        Some(x) if x.method == TestOutcome::IDENTICAL => "identical".into(),
        Some(x) => match x.agents_below(ALPHA) {
            Some((k, n)) => format!("{} ({k}/{n})", p_value(x.p_value)),
            None => p_value(x.p_value),
        },
        None => "-".into(),
    }
}

/// A table: the paper's figure, then ours in each world the table has, figure by figure.
/// The median is shown only in a table of one world (it is in `results.json` for all).
fn table(md: &mut String, t: &Table) {
    let worlds = t.worlds();
    let paper = t.rows.iter().any(|r| r.paper.is_some());
    let paper_test = t.paper.and_then(|p| p.test);
    let _ = writeln!(md, "\n### {}\n", t.title);
    if let Some(p) = &t.paper {
        let _ = writeln!(md, "Paper: {}. Ours: {}.\n", p.source, t.suite);
    } else {
        let _ = writeln!(md, "{}.\n", t.suite);
    }
    // Which of the paper's means the table has: over every game (a failure at the
    // horizon), over successes (E2's reading), or both.
    let paper_mean = |over: MeanOver| t.rows.iter().any(|r| r.paper.is_some_and(|p| p.mean_over == over));
    let (paper_star, paper_successes) = (paper_mean(MeanOver::FailuresAtHorizon), paper_mean(MeanOver::Successes));
    let mut head = vec!["arm".to_string(), "ε".into()];
    let mut group = |figure: &str, with_paper: bool| {
        if with_paper {
            head.push(format!("{figure}, paper"));
        }
        head.extend(worlds.iter().map(|w| format!("{figure}, {w}")));
    };
    group("failures", paper);
    group("mean steps*", paper_star);
    group("mean, successes", paper_successes);
    if worlds.len() == 1 {
        group("median", false);
    }
    group("× optimum", false);
    if let Some(test) = paper_test {
        head.push(format!("p, paper ({test})"));
    }
    for name in &t.tests {
        head.extend(worlds.iter().map(|w| format!("p, {w} ({name})")));
    }
    if paper {
        head.extend(worlds.iter().map(|w| format!("paper inside {w}'s spread")));
    }
    let mut rows = Vec::new();
    for row in &t.rows {
        let measured: Vec<Option<&Measured>> = worlds.iter().map(|&w| row.in_world(w)).collect();
        let each = |f: &dyn Fn(&ArmResult) -> String| -> Vec<String> {
            measured.iter().map(|m| m.map_or("-".into(), |m| f(&m.arm))).collect()
        };
        let mut cells = vec![
            row.name.clone(),
            measured.iter().flatten().next().map_or("-".into(), |m| epsilon(&m.arm)),
        ];
        if paper {
            cells.push(row.paper.map_or("-".into(), |p| match (p.failures, p.games) {
                (Some(f), Some(n)) => format!("{f} / {n}"),
                _ => "-".into(),
            }));
        }
        cells.extend(each(&|a| {
            format!("{} / {}", failures(&a.failures_per_replicate, a.failures), a.games)
        }));
        let paper_mean = |over: MeanOver| {
            row.paper
                .filter(|p| p.mean_over == over)
                .map_or("-".into(), |p| num(p.mean_steps, 2))
        };
        if paper_star {
            cells.push(paper_mean(MeanOver::FailuresAtHorizon));
        }
        cells.extend(each(&|a| steps_spread(a)));
        if paper_successes {
            cells.push(paper_mean(MeanOver::Successes));
        }
        cells.extend(each(&|a| steps(a.mean_steps)));
        if worlds.len() == 1 {
            cells.extend(each(&|a| num(a.median_steps, 1)));
        }
        cells.extend(each(&|a| num(a.mean_ratio_to_optimum, 3)));
        if paper_test.is_some() {
            cells.push(row.paper.and_then(|p| p.p_value).map_or("-".into(), p_value));
        }
        for i in 0..t.tests.len() {
            cells.extend(
                measured
                    .iter()
                    .map(|m| test_cell(m.and_then(|m| m.tests.get(i)).and_then(Option::as_ref))),
            );
        }
        if paper {
            cells.extend(measured.iter().map(|m| {
                m.and_then(|m| m.paper_inside.as_ref())
                    .map_or("-".into(), |inside| verdict(inside).to_string())
            }));
        }
        rows.push(cells);
    }
    markdown_table(md, &head, rows);
}

/// A Markdown table: `head`'s cells, the rule under them, then each row's cells.
fn markdown_table(md: &mut String, head: &[String], rows: impl IntoIterator<Item = Vec<String>>) {
    let _ = writeln!(md, "| {} |", head.join(" | "));
    let _ = writeln!(md, "|{}|", vec!["---"; head.len()].join("|"));
    for cells in rows {
        let _ = writeln!(md, "| {} |", cells.join(" | "));
    }
}

/// Cells from their headings or values as text.
fn cells<const N: usize>(texts: [&str; N]) -> Vec<String> {
    texts.map(String::from).to_vec()
}

/// Mean steps*, with the range over replicates when there are several.
fn steps_spread(a: &ArmResult) -> String {
    let mean = steps(Some(a.mean_steps_failures_at_horizon));
    match Spread::of(&a.mean_steps_failures_at_horizon_per_replicate) {
        Some(s) if s.replicates > 1 => format!("{mean} ({:.0}-{:.0})", s.low, s.high),
        _ => mean,
    }
}

/// Mean steps over successes, with the range over replicates when there are several.
fn successes_spread(a: &ArmResult) -> String {
    let per_replicate: Vec<f64> = a.mean_steps_per_replicate.iter().flatten().copied().collect();
    match Spread::of(&per_replicate) {
        Some(s) if s.replicates > 1 => format!("{} ({:.0}-{:.0})", steps(a.mean_steps), s.low, s.high),
        _ => steps(a.mean_steps),
    }
}

/// E1's worlds, one rule switched at a time, and each figure's gap taken apart.
fn decomposition(md: &mut String, d: &Decomposition) {
    let _ = writeln!(md, "\n### The gap between the worlds, one rule at a time\n");
    let _ = writeln!(
        md,
        "| world | protocol | start rule | failures | mean steps* | mean, successes |\n|---|---|---|---|---|---|"
    );
    for w in &d.worlds {
        let a = &w.arm;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} / {} | {} | {} |",
            w.world,
            w.rules.protocol.name(),
            w.rules.start.name(),
            failures(&a.failures_per_replicate, a.failures),
            a.games,
            steps_spread(a),
            steps(a.mean_steps)
        );
    }
    let _ = writeln!(
        md,
        "\n| figure | SPEC world | original world | gap | protocol alone | start rule alone | the two together |\n\
         |---|---|---|---|---|---|---|"
    );
    for g in &d.gaps {
        let value = |v: f64| num(Some(v), 1);
        let part = |v: f64| format!("{v:+.1}");
        let share = |v: f64| {
            format!(
                "{}{}",
                part(v),
                g.share(v).map_or(String::new(), |s| format!(" ({s:.0}%)"))
            )
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            g.figure,
            value(g.spec),
            value(g.original),
            part(g.gap),
            share(g.protocol),
            share(g.start),
            share(g.interaction)
        );
    }
}

fn curve(md: &mut String, c: &Curve) {
    let _ = writeln!(
        md,
        "\n### Learning curve, {} world, test epsilon {}: {}\n",
        c.world, c.test_epsilon, c.learner
    );
    let _ = writeln!(md, "Tested on: {}.\n", c.suite);
    let _ = writeln!(
        md,
        "| training games | test games | failures (per agent) | failed (range over agents) | mean steps* (range) | mean, successes |\n|---|---|---|---|---|---|"
    );
    // A range over the agents beside a figure, when there are several.
    let range = |s: Option<Spread>, scale: f64, decimals: usize| {
        s.map_or(String::new(), |s| {
            format!(" ({:.decimals$}-{:.decimals$})", scale * s.low, scale * s.high)
        })
    };
    for p in &c.points {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.1}%{} | {}{} | {} |",
            p.games,
            p.test_games,
            num(Some(p.failures), 1),
            100.0 * p.failure_rate,
            range(p.failure_rate_spread, 100.0, 0),
            steps(Some(p.mean_steps_failures_at_horizon)),
            range(p.mean_steps_failures_at_horizon_spread, 1.0, 0),
            steps(p.mean_steps)
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn anchors_are_githubs() {
        assert_eq!(
            anchor("E5", "Oracle assistance in training (Table I)"),
            "e5-oracle-assistance-in-training-table-i"
        );
    }
}
