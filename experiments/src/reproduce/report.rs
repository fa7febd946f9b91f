//! The report: `README.md` (one section per experiment, ours beside the paper's), the
//! pictures, and `results.json` (every figure of the tables), written into one directory.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::arms::{ArmResult, Table, TestOutcome};
use super::text::{ALPHA, failures, num, p_value};
use super::{Curve, Drawing, Experiment, ReproduceError, Reproduction, Result};
use crate::plots::{GifOptions, bar_chart, box_plot, episode_gif, learning_curve};

/// The files a report is made of.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReportFiles {
    /// `README.md`.
    pub readme: PathBuf,
    /// `results.json`.
    pub results: PathBuf,
    /// Every picture, in the order of the report.
    pub pictures: Vec<PathBuf>,
}

/// Draws the pictures of `r` and writes them, `README.md` and `results.json` into `dir`
/// (made if missing), each file atomically.
pub fn write_report(r: &Reproduction, dir: &Path) -> Result<ReportFiles> {
    files::prepare_folder(dir)?;
    let mut pictures = Vec::new();
    for figure in r.experiments.iter().flat_map(|e| &e.figures) {
        let stem = dir.join(&figure.stem);
        match &figure.drawing {
            Drawing::Learning(c) => pictures.extend(chart(learning_curve(c, &stem)?)),
            Drawing::Boxes(b) => pictures.extend(chart(box_plot(b, &stem)?)),
            Drawing::Bars(b) => pictures.extend(chart(bar_chart(b, &stem)?)),
            Drawing::Episode(frames) => {
                let path = dir.join(&figure.files[0]);
                episode_gif(frames, &GifOptions::default(), &path)?;
                pictures.push(path);
            }
        }
    }
    let results = dir.join("results.json");
    let json = serde_json::to_vec_pretty(r).map_err(|e| ReproduceError::Write {
        path: results.display().to_string(),
        reason: e.to_string(),
    })?;
    files::write(&results, &json)?;
    let readme = dir.join("README.md");
    files::write(&readme, markdown(r).as_bytes())?;
    Ok(ReportFiles {
        readme,
        results,
        pictures,
    })
}

fn chart(files: crate::plots::ChartFiles) -> [PathBuf; 2] {
    [files.png, files.svg]
}

/// The report as Markdown.
pub fn markdown(r: &Reproduction) -> String {
    let mut md = String::new();
    let command = format!(
        "blockstack reproduce --seed {}{}",
        r.options.seed,
        if r.options.quick { " --quick" } else { "" }
    );
    let _ = writeln!(md, "# The paper reproduced\n");
    let _ = writeln!(
        md,
        "Written by `{command}`: every experiment of SPEC section 9 on the paper's world (7 x 7 grid, horizon {}, \
         rapier2d physics), ours beside the figures of \"Interactive Robot Learning\" section VI. Every figure \
         below is computed by the run; the paper's come from `experiments::reproduce::paper`. The same figures, \
         and more, are in [`results.json`](results.json).{}\n",
        r.paper_settings.horizon,
        if r.options.quick {
            " **Quick run:** small counts to check the pipeline, not the paper's; run without `--quick` for \
             the real figures."
        } else {
            ""
        }
    );
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
        "**Steps.** The paper's mean steps count a failed game as the horizon (1000); \"mean steps*\" is that \
         figure. Beside it: the mean and median over the games that reached the goal, and their mean ratio to \
         the shortest plan from the same start (the exact solver's). Tests compare steps with a failure at 1000."
            .into(),
        format!(
            "**Test policy.** As in the paper, learners take a random action with probability {} unless a row \
             says otherwise (column ε).",
            r.paper_settings.test_epsilon
        ),
        "**Tests.** Wilcoxon signed-rank (paired), two-sample Kolmogorov-Smirnov: `experiments::stats`, ports of \
         SciPy's defaults checked against SciPy; p is two-sided. Our p pools every agent's games; beside it, \
         (k/n) says for how many of the n agents alone (the paper's protocol: one agent) p is below 0.05."
            .into(),
    ] {
        let _ = writeln!(md, "- {line}");
    }
    for e in &r.experiments {
        experiment(&mut md, e);
    }
    md
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
    for c in &e.curves {
        curve(md, c);
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

fn table(md: &mut String, t: &Table) {
    let paper = t.paper.is_some();
    let _ = writeln!(md, "\n### {}\n", t.title);
    if let Some(p) = &t.paper {
        let _ = writeln!(md, "Paper: {}. Ours: {}.\n", p.source, t.suite);
    } else {
        let _ = writeln!(md, "{}.\n", t.suite);
    }
    let mut head = vec!["arm".to_string(), "ε".into()];
    if paper {
        head.push("failures, paper".into());
    }
    head.push("failures, ours".into());
    if paper {
        head.push("mean steps*, paper".into());
    }
    head.extend([
        "mean steps*, ours".into(),
        "mean, successes".into(),
        "median".into(),
        "× optimum".into(),
    ]);
    if let Some(test) = t.paper.and_then(|p| p.test) {
        head.push(format!("p, paper ({test})"));
    }
    head.extend(t.tests.iter().map(|name| format!("p, ours ({name})")));
    let _ = writeln!(md, "| {} |", head.join(" | "));
    let _ = writeln!(md, "|{}|", vec!["---"; head.len()].join("|"));
    for row in &t.rows {
        let a = &row.ours;
        let mut cells = vec![a.name.clone(), epsilon(a)];
        if paper {
            cells.push(row.paper.map_or("-".into(), |p| match (p.failures, p.games) {
                (Some(f), Some(n)) => format!("{f} / {n}"),
                _ => "-".into(),
            }));
        }
        cells.push(format!(
            "{} / {}",
            failures(&a.failures_per_replicate, a.failures),
            a.games
        ));
        if paper {
            cells.push(row.paper.map_or("-".into(), |p| num(p.mean_steps, 2)));
        }
        cells.extend([
            steps(Some(a.mean_steps_failures_at_horizon)),
            steps(a.mean_steps),
            num(a.median_steps, 1),
            num(a.mean_ratio_to_optimum, 3),
        ]);
        if t.paper.and_then(|p| p.test).is_some() {
            cells.push(row.paper.and_then(|p| p.p_value).map_or("-".into(), p_value));
        }
        cells.extend(row.tests.iter().map(|test| match test {
            Some(x) if x.method == TestOutcome::IDENTICAL => "identical".into(),
            Some(x) => match x.agents_below(ALPHA) {
                Some((k, n)) => format!("{} ({k}/{n})", p_value(x.p_value)),
                None => p_value(x.p_value),
            },
            None => "-".into(),
        }));
        let _ = writeln!(md, "| {} |", cells.join(" | "));
    }
}

fn curve(md: &mut String, c: &Curve) {
    let _ = writeln!(md, "\n### Learning curve: {}\n", c.learner);
    let _ = writeln!(md, "Tested on: {}.\n", c.suite);
    let _ = writeln!(
        md,
        "| training games | test games | failures (per agent) | failed | mean steps* | mean, successes |\n|---|---|---|---|---|---|"
    );
    for p in &c.points {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.1}% | {} | {} |",
            p.games,
            p.test_games,
            num(Some(p.failures), 1),
            100.0 * p.failure_rate,
            steps(Some(p.mean_steps_failures_at_horizon)),
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
