//! The front page's results: a short Markdown block of each experiment's headline figure,
//! the paper's beside ours, computed from a `results.json`.
//!
//! It reads the file rather than a [`Reproduction`](super::Reproduction) so that a test can
//! check the block a README quotes against the `results.json` committed beside it: the
//! README's figures are never typed in by hand.

use serde_json::Value;

use super::{ReproduceError, Result};

/// The Markdown block of `results_json` (a reproduction's `results.json`): a line saying
/// which run it is, then a table with one row per experiment run: its headline figure in
/// the paper, in the paper's world as coded (`original`) and in ours (`spec`).
///
/// Errors: text that is not a reproduction's results ([`ReproduceError::Results`]).
pub fn summary(results_json: &str) -> Result<String> {
    let bad = |reason: String| ReproduceError::Results { reason };
    let json: Value = serde_json::from_str(results_json).map_err(|e| bad(e.to_string()))?;
    if json["format"] != super::FORMAT {
        return Err(bad(format!(
            "its format is {}, not {:?}",
            json["format"],
            super::FORMAT
        )));
    }
    let experiments = json["experiments"]
        .as_array()
        .ok_or_else(|| bad("it has no list of experiments".into()))?;
    let options = &json["options"];
    // Written before the benchmark had a report of its own, a file names no report: the
    // paper's, which then held E9 and E10 too.
    let benchmark = options["report"] == "blocks-world";
    // The command as it was run, so that the figures say which budget made them.
    let (flag, run) = if options["quick"] == true {
        (" --quick", "small counts that check the pipeline, not the real figures")
    } else if options["long"] == true {
        (
            " --long",
            if benchmark {
                "every experiment at its long problem counts"
            } else {
                "every experiment, E8 at its long budget"
            },
        )
    } else {
        ("", "every experiment")
    };
    let only = match options["only"].as_array() {
        Some(ids) if !ids.is_empty() => {
            let ids: Vec<&str> = ids.iter().filter_map(serde_json::Value::as_str).collect();
            format!(" --only {}", ids.join(","))
        }
        _ => String::new(),
    };
    let ran = &json["ran"];
    let mut md = if benchmark {
        format!(
            "Measured by `blockstack benchmark{flag}{only} --seed {}` ({run}) at commit {}, on {} ({} cores, {} \
             threads).\n\n| experiment | ours |\n|---|---|\n",
            options["seed"],
            text(&ran["commit"]),
            text(&ran["cpu"]),
            ran["cores"],
            ran["threads"],
        )
    } else {
        format!(
            "Measured by `blockstack reproduce{flag}{only} --seed {}` ({run}; {} agents per learner arm) at commit {}, \
             on {} ({} cores, {} threads). Each figure: the paper's, ours in the paper's world as its authors coded \
             it (original), ours in the SPEC world (spec); failures are shares of the test games, steps* count a \
             failure as 1000.\n\n| experiment | paper | ours, original | ours, spec |\n|---|---|---|---|\n",
            options["seed"],
            json["scale"]["replicates"],
            text(&ran["commit"]),
            text(&ran["cpu"]),
            ran["cores"],
            ran["threads"],
        )
    };
    for e in experiments {
        let id = e["id"].as_str().ok_or_else(|| bad("an experiment has no id".into()))?;
        let cells = match id {
            "E1" => e1(e),
            "E2" => e2(e),
            "E3" => e3(e),
            "E4" => e4(e),
            "E5" => e5(e),
            "E6" => e6(e),
            "E7" => e7(e),
            "E8" => e8(e),
            "E9" => e9(e),
            "E10" => e10(e),
            _ => None,
        }
        .ok_or_else(|| bad(format!("{id}'s figures are not where a reproduction puts them")))?;
        // The benchmark's rows are ours alone (what it is, our figure); in a paper's table
        // (a file from before the benchmark had its own report) they have no paper's figure.
        let cells = match cells.as_slice() {
            [what, ours] if !benchmark => vec![what.clone(), "-".into(), "-".into(), ours.clone()],
            _ => cells,
        };
        md += &format!("| {id} {} |\n", cells.join(" | "));
    }
    Ok(md)
}

/// A JSON string's text, or "unknown".
fn text(v: &Value) -> &str {
    v.as_str().unwrap_or("unknown")
}

/// The rows of table `t` of experiment `e`.
fn rows(e: &Value, t: usize) -> Option<&Vec<Value>> {
    e["tables"][t]["rows"].as_array()
}

/// The paper's share of games failed in `row`.
fn paper_failed(row: &Value) -> Option<f64> {
    Some(row["paper"]["failures"].as_f64()? / row["paper"]["games"].as_f64()?)
}

/// Our share of games failed in `row` in `world` (mean per replicate over games per
/// replicate).
fn failed(row: &Value, world: &str) -> Option<f64> {
    let arm = &row[world]["arm"];
    Some(arm["failures"].as_f64()? / arm["games"].as_f64()?)
}

/// A share in percent, one decimal.
fn percent(share: Option<f64>) -> String {
    share.map_or("-".into(), |s| format!("{:.1}%", 100.0 * s))
}

/// A number with `decimals` decimals, or "-".
fn number(v: Option<f64>, decimals: usize) -> String {
    v.map_or("-".into(), |v| format!("{v:.decimals$}"))
}

/// "a against b".
fn against(a: String, b: String) -> String {
    format!("{a} against {b}")
}

/// E1: the random agent's failures and mean steps*.
fn e1(e: &Value) -> Option<Vec<String>> {
    let r = rows(e, 0)?.first()?;
    let ours = |w: &str| {
        format!(
            "{}, {}",
            percent(failed(r, w)),
            number(r[w]["arm"]["mean_steps_failures_at_horizon"].as_f64(), 1)
        )
    };
    Some(vec![
        "random agent, 2 blocks: failed, mean steps*".into(),
        format!(
            "{}, {}",
            percent(paper_failed(r)),
            number(r["paper"]["mean_steps"].as_f64(), 2)
        ),
        ours("original"),
        ours("spec"),
    ])
}

/// E2: the paper's learner's mean steps over successes at the first test epsilon.
fn e2(e: &Value) -> Option<Vec<String>> {
    let r = rows(e, 0)?.first()?;
    let ours = |w: &str| number(r[w]["arm"]["mean_steps"].as_f64(), 1);
    Some(vec![
        format!("{}: mean steps over successes", r["name"].as_str()?),
        number(r["paper"]["mean_steps"].as_f64(), 2),
        ours("original"),
        ours("spec"),
    ])
}

/// E3: failures on the unseen goals, the paper's learner against the random agent.
fn e3(e: &Value) -> Option<Vec<String>> {
    let rows = rows(e, 0)?;
    let (learner, random) = (rows.first()?, rows.get(1)?);
    let ours = |w: &str| against(percent(failed(learner, w)), percent(failed(random, w)));
    Some(vec![
        "unseen goals: failed, the paper's learner against random".into(),
        against(percent(paper_failed(learner)), percent(paper_failed(random))),
        ours("original"),
        ours("spec"),
    ])
}

/// E4: Fig. 3's longest training at the first test epsilon, failures.
fn e4(e: &Value) -> Option<Vec<String>> {
    let rows = rows(e, 0)?;
    let epsilon = &rows.first()?["original"]["arm"]["test_epsilon"];
    let r = rows
        .iter()
        .rfind(|r| r["original"]["arm"]["test_epsilon"] == *epsilon)?;
    Some(vec![
        format!("Fig. 3, {}: failed", r["name"].as_str()?),
        percent(paper_failed(r)),
        percent(failed(r, "original")),
        "-".into(),
    ])
}

/// E5: failures with the oracle on oscillation and at random, against none.
fn e5(e: &Value) -> Option<Vec<String>> {
    let rows = rows(e, 0)?;
    let (none, both) = (rows.first()?, rows.last()?);
    let ours = |w: &str| against(percent(failed(both, w)), percent(failed(none, w)));
    Some(vec![
        format!("{} against none: failed", both["name"].as_str()?),
        against(percent(paper_failed(both)), percent(paper_failed(none))),
        ours("original"),
        ours("spec"),
    ])
}

/// E6: on all goals, the corrected agents' failures (the mean over demonstrators) against
/// the uncorrected agent's.
fn e6(e: &Value) -> Option<Vec<String>> {
    let rows = rows(e, 0)?;
    let (base, corrected) = rows.split_first()?;
    let mean = |f: &dyn Fn(&Value) -> Option<f64>| -> Option<f64> {
        let shares: Option<Vec<f64>> = corrected.iter().map(f).collect();
        let shares = shares?;
        (!shares.is_empty()).then(|| shares.iter().sum::<f64>() / shares.len() as f64)
    };
    let ours = |w: &str| against(percent(mean(&|r| failed(r, w))), percent(failed(base, w)));
    Some(vec![
        "all goals: failed, corrected by a demonstrator (mean of 3) against uncorrected".into(),
        against(percent(mean(&paper_failed)), percent(paper_failed(base))),
        ours("original"),
        ours("spec"),
    ])
}

/// E7: the best learner's and the paper's learner's steps as multiples of the shortest
/// plan.
fn e7(e: &Value) -> Option<Vec<String>> {
    let learners: Vec<&Value> = rows(e, 0)?
        .iter()
        .filter(|r| !r["spec"]["arm"]["test_epsilon"].is_null())
        .collect();
    let steps = |r: &Value| {
        r["spec"]["arm"]["mean_steps_failures_at_horizon"]
            .as_f64()
            .unwrap_or(f64::MAX)
    };
    let best = learners.iter().min_by(|a, b| steps(a).total_cmp(&steps(b)))?;
    let paper = learners.first()?;
    let ratio = |r: &Value| {
        let ratio = r["spec"]["arm"]["mean_ratio_to_optimum"].as_f64();
        number(ratio, if ratio.is_some_and(|r| r >= 10.0) { 1 } else { 3 })
    };
    Some(vec![
        "every agent on the same starts: steps over successes, as a multiple of the shortest plan".into(),
        "-".into(),
        "-".into(),
        format!(
            "best learner ({}) {}x, {} failed; the paper's learner {}x, {} failed",
            best["name"].as_str()?,
            ratio(best),
            percent(failed(best, "spec")),
            ratio(paper),
            percent(failed(paper, "spec")),
        ),
    ])
}

/// E8: every network's greedy success at the end of its training, ours and (at the long
/// budget) the paper's.
fn e8(e: &Value) -> Option<Vec<String>> {
    let finals: Vec<String> = e["tables"]
        .as_array()?
        .iter()
        .filter(|t| {
            t["title"]
                .as_str()
                .is_some_and(|t| t.starts_with("(a)") || t.starts_with("(b)"))
        })
        .flat_map(|t| t["rows"].as_array().into_iter().flatten())
        .map(|r| {
            let name = r["name"].as_str()?;
            let success = percent(failed(r, "spec").map(|f| 1.0 - f));
            Some(format!("{} {success}", name.strip_prefix("ours: ").unwrap_or(name)))
        })
        .collect::<Option<_>>()?;
    Some(vec![
        "deep Q-networks: reached the goal, greedy".into(),
        "-".into(),
        "-".into(),
        finals.join("; "),
    ])
}

/// E9: the near-optimal planner's plans against the fewest block moves, the planners'
/// success through the gripper, and how often physics and grid agreed on a drop (what it
/// is, and ours: no paper's figure).
fn e9(e: &Value) -> Option<Vec<String>> {
    let world = &e["blocks_world"];
    let blocks = world["by_blocks"].as_array()?;
    let problems: f64 = blocks.iter().map(|g| g["problems"].as_f64()).sum::<Option<f64>>()?;
    // The means over all problems, from the groups' means weighted by their problems.
    let weighted = |f: &dyn Fn(&Value) -> Option<f64>| -> Option<f64> {
        let sum: f64 = blocks
            .iter()
            .map(|g| Some(f(g)? * g["problems"].as_f64()?))
            .sum::<Option<f64>>()?;
        Some(sum / problems)
    };
    let ratio = weighted(&|g| g["near_optimal_ratio"].as_f64())?;
    let worst = blocks
        .iter()
        .map(|g| g["near_optimal_worst"].as_f64())
        .collect::<Option<Vec<f64>>>()?
        .into_iter()
        .fold(0.0, f64::max);
    // Every agent's success over all its games, and the numbers of blocks it played when not
    // all of them.
    let mut agents: Vec<(String, f64, f64, Vec<String>)> = Vec::new();
    for g in blocks {
        for a in g["agents"].as_array()? {
            let name = a["agent"].as_str()?;
            let games = a["games"].as_f64()?;
            let won = a["success"].as_f64()? * games;
            let n = g["key"].to_string();
            match agents.iter_mut().find(|(agent, ..)| agent == name) {
                Some(entry) => {
                    entry.1 += won;
                    entry.2 += games;
                    entry.3.push(n);
                }
                None => agents.push((name.to_string(), won, games, vec![n])),
            }
        }
    }
    let reached: Vec<String> = agents
        .iter()
        .map(|(name, won, games, played)| {
            let on = if played.len() < blocks.len() {
                format!(" ({} blocks)", played.join(", "))
            } else {
                String::new()
            };
            format!("{name}{on} {}", percent(Some(won / games)))
        })
        .collect();
    let agreement = world["agreement"].as_array()?;
    let count = |field: &str| -> Option<u64> { agreement.iter().map(|a| a[field].as_u64()).sum() };
    Some(vec![
        "classic Blocks World, 3-10 blocks, 1-3 towers: block moves against the fewest; reached the goal; physics \
         against grid"
            .into(),
        format!(
            "near-optimal plans {}x the fewest (worst {}x); reached: {}; drops landing alike {} / {}",
            number(Some(ratio), 3),
            number(Some(worst), 2),
            reached.join(", "),
            count("same_landings")?,
            count("drops")?,
        ),
    ])
}

/// E10: the learned policy's success and block moves against the near-optimal planner's
/// over the uniform problems' sizes, and the fewest moves up to 8 blocks (what it is, and
/// ours).
fn e10(e: &Value) -> Option<Vec<String>> {
    let g = &e["general"];
    let uniform = g["uniform"].as_array()?;
    let exact = g["exact"].as_array()?;
    let problems: f64 = uniform.iter().map(|r| r["problems"].as_f64()).sum::<Option<f64>>()?;
    let won: f64 = uniform
        .iter()
        .map(|r| Some(r["success"].as_f64()? * r["problems"].as_f64()?))
        .sum::<Option<f64>>()?;
    let sizes = |rows: &[Value]| -> Option<String> {
        Some(format!(
            "{}-{}",
            rows.first()?["blocks"].as_u64()?,
            rows.last()?["blocks"].as_u64()?
        ))
    };
    let span = |rows: &[Value], field: &str| -> String {
        let values: Vec<f64> = rows.iter().filter_map(|r| r[field].as_f64()).collect();
        match (
            values.iter().copied().reduce(f64::min),
            values.iter().copied().reduce(f64::max),
        ) {
            (Some(lo), Some(hi)) => format!("{}-{}", number(Some(lo), 3), number(Some(hi), 3)),
            _ => "-".into(),
        }
    };
    Some(vec![
        format!(
            "one policy learnt on 2-{} blocks plays {} blocks: solved; block moves against the near-optimal planner \
             and the fewest",
            g["training"]["config"]["max_blocks"].as_u64()?,
            sizes(uniform)?
        ),
        format!(
            "solved {} of {} uniform problems; {}x the near-optimal planner's moves by size; {}x the fewest on {} \
             blocks",
            percent(Some(won / problems)),
            problems,
            span(uniform, "near_optimal_ratio"),
            span(exact, "fewest_ratio"),
            sizes(exact)?
        ),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_not_a_reproduction_is_an_error() {
        for bad in [
            "",
            "[]",
            "{\"format\": \"other\"}",
            "{\"format\": \"blockstack-reproduction\"}",
        ] {
            let err = summary(bad).unwrap_err();
            assert!(matches!(err, ReproduceError::Results { .. }), "{bad}: {err}");
        }
        let missing = r#"{"format": "blockstack-reproduction", "experiments": [{"id": "E1", "tables": []}]}"#;
        let err = summary(missing).unwrap_err().to_string();
        assert!(err.contains("E1's figures"), "{err}");
    }
}
