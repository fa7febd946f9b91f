//! `blockstack reproduce --quick` and `blockstack benchmark --quick` end to end: the report
//! and results.json hold every experiment, the pictures exist, and an arm's figures are what
//! `blockstack run` gives on the same starts.
//!
//! CI runs `blockstack reproduce --quick --out DIR` once and sets `BLOCKSTACK_QUICK_REPORT=DIR`
//! so that this test checks that report instead of making its own.

use std::path::{Path, PathBuf};

use crate::common::{cli, scratch, stderr};

/// The quick report: CI's, or one made now.
fn quick_report() -> PathBuf {
    if let Some(dir) = std::env::var_os("BLOCKSTACK_QUICK_REPORT") {
        return PathBuf::from(dir);
    }
    // Under the target folder, one per checkout: a later run replaces it.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-reproduce-quick");
    let _ = std::fs::remove_dir_all(&dir);
    let o = cli("reproduce").arg("--quick").flag("out", dir.to_str().unwrap()).run();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("reproduced E1, E2, E3, E4, E5, E6, E7, E8 (quick run"),
        "{out}"
    );
    dir
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).expect("results.json exists")).expect("results.json is JSON")
}

#[test]
fn the_quick_report_holds_every_experiment() {
    let dir = quick_report();
    let readme = std::fs::read_to_string(dir.join("README.md")).expect("README.md exists");
    let json = read_json(&dir.join("results.json"));
    assert_eq!(json["format"], "blockstack-reproduction");
    assert_eq!(json["version"], 1);
    assert_eq!(json["options"]["quick"], true);
    // Where it ran: the commit (or "unknown"), the machine, the threads; at the top of the
    // report too.
    let ran = &json["ran"];
    let commit = ran["commit"].as_str().unwrap();
    assert!(!commit.is_empty() && !commit.contains(char::is_whitespace), "{ran}");
    assert!(ran["cpu"].as_str().is_some_and(|c| !c.is_empty()), "{ran}");
    assert!(ran["cores"].as_u64().unwrap() >= 1 && ran["threads"].as_u64().unwrap() >= 1);
    let top = readme.lines().nth(2).unwrap_or_default();
    assert!(top.starts_with(&format!("Ran at commit {commit}, ")), "{top}");
    // The front page's block, computed from results.json.
    let summary = std::fs::read_to_string(dir.join("summary.md")).expect("summary.md exists");
    let text = std::fs::read_to_string(dir.join("results.json")).unwrap();
    assert_eq!(summary, experiments::reproduce::summary(&text).unwrap());
    assert_eq!(summary.lines().filter(|l| l.starts_with("| E")).count(), 8, "{summary}");
    assert_eq!(json["options"]["report"], "paper");
    let experiments = json["experiments"].as_array().unwrap();
    let ids: Vec<&str> = experiments.iter().map(|e| e["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["E1", "E2", "E3", "E4", "E5", "E6", "E7", "E8"]);
    for e in experiments {
        let id = e["id"].as_str().unwrap();
        assert!(readme.contains(&format!("## {id}: ")), "{id} has no section");
        let reading = e["reading"].as_str().unwrap();
        assert!(!reading.is_empty() && readme.contains(reading), "{id}'s reading");
        let tables = e["tables"].as_array().unwrap();
        let curves = e["curves"].as_array().unwrap();
        assert!(e["blocks_world"].is_null() && e["general"].is_null(), "{id}");
        assert!(!tables.is_empty() || !curves.is_empty(), "{id} has no figures");
        for (t, row) in tables
            .iter()
            .enumerate()
            .flat_map(|(t, table)| table["rows"].as_array().unwrap().iter().map(move |row| (t, row)))
        {
            // E1-E6: each row of the paper's beside ours in both worlds (E4's Fig. 3 points and
            // E5's second table, at a shorter training, in the original world alone), with where
            // the paper's figures lie against each world's replicates; E7 and our learner's
            // rows in the SPEC world alone.
            let original_only = id == "E4" || (id == "E5" && t == 1);
            let worlds: Vec<&str> = ["original", "spec"].into_iter().filter(|w| !row[w].is_null()).collect();
            assert!(!worlds.is_empty(), "{id}: {row}");
            for world in &worlds {
                let arm = &row[world]["arm"];
                assert!(arm["games"].as_u64().unwrap() > 0, "{id}");
                assert!(arm["mean_steps_failures_at_horizon"].as_f64().is_some(), "{id}");
                if !row["paper"].is_null() {
                    let inside = &row[world]["paper_inside"];
                    assert!(inside["mean_steps"]["inside"].is_boolean(), "{id} {world}: {inside}");
                }
            }
            if !row["paper"].is_null() {
                assert!(worlds.contains(&"original"), "{id}: the paper's row in its own world");
                assert_eq!(worlds.len(), if original_only { 1 } else { 2 }, "{id}");
            } else {
                assert_eq!(worlds, ["spec"], "{id}");
            }
        }
        for figure in e["figures"].as_array().unwrap() {
            for file in figure["files"].as_array().unwrap() {
                let file = file.as_str().unwrap();
                let len = std::fs::metadata(dir.join(file)).map_or(0, |m| m.len());
                assert!(len > 0, "{id}: {file} is missing or empty");
            }
            assert!(readme.contains(&format!("]({})", figure["files"][0].as_str().unwrap())));
        }
    }
    // The paper's figures beside ours, and tests with p-values.
    let e5 = &experiments[4]["tables"][0]["rows"];
    assert_eq!(e5[0]["paper"]["failures"], 186);
    let p = e5[2]["spec"]["tests"][0]["p_value"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&p));
    // E7: every agent on the same starts; the exact solver is the optimum.
    let e7 = experiments[6]["tables"][0]["rows"].as_array().unwrap();
    assert_eq!(e7.len(), 7);
    let exact = &e7.iter().find(|r| r["name"] == "exact solver").unwrap()["spec"]["arm"];
    assert_eq!(exact["mean_ratio_to_optimum"], 1.0);
    assert_eq!(exact["failures"], 0.0);
    assert!(readme.contains("## The paper's figures beside ours"));
    let e4 = &experiments[3]["tables"][0]["rows"];
    assert_eq!(e4[0]["paper"]["failures"], 71, "Fig. 3, 5 games, test epsilon 0.1");
    for figure in [
        "e4-original.png",
        "e4-paper-learner.png",
        "e5-steps.png",
        "e6-all-goals.png",
        "e7-steps.png",
        "e7-best.gif",
        "e7-paper.gif",
    ] {
        assert!(dir.join(figure).is_file(), "{figure}");
    }

    // E8 says which budget made its figures, and tests every arm on every goal.
    let e8 = &experiments[7];
    assert!(
        e8["setup"][0]["value"].as_str().unwrap().starts_with("quick"),
        "{}",
        e8["setup"][0]
    );
    assert!(e8["reading"].as_str().unwrap().contains("(budget: quick)"));
    for table in e8["tables"].as_array().unwrap() {
        assert!(!table["rows"].as_array().unwrap().is_empty());
    }

    // E1: the paper's figure, ours in both worlds, and where the paper's lies against the
    // spread of each world's replicates, said in the reading.
    let e1 = &experiments[0];
    let row = &e1["tables"][0]["rows"][0];
    assert_eq!(row["paper"]["mean_steps"], 263.55);
    for world in ["original", "spec"] {
        let inside = &row[world]["paper_inside"]["mean_steps"];
        let (low, high) = (
            inside["spread"]["low"].as_f64().unwrap(),
            inside["spread"]["high"].as_f64().unwrap(),
        );
        assert_eq!(
            inside["inside"].as_bool().unwrap(),
            (low..=high).contains(&263.55),
            "{world}"
        );
    }
    let reading = e1["reading"].as_str().unwrap();
    assert!(
        reading.contains("spread of our 5 replicates in the original world"),
        "{reading}"
    );
    assert!(reading.contains("the protocol alone accounts for"), "{reading}");
    assert!(readme.contains("### The gap between the worlds, one rule at a time"));
    // E3: the paper's own p-value against what its counts allow.
    let notes = experiments[2]["paper_notes"].as_array().unwrap();
    assert!(
        notes
            .iter()
            .any(|n| n.as_str().unwrap().contains("at least 0.27 at 1000 steps"))
    );

    // E1's random agent in each world is `blockstack run --profile` on the same starts.
    let seed = json["seeds"]["test"].as_u64().unwrap().to_string();
    for world in ["original", "spec"] {
        let e1 = &row[world]["arm"];
        let replicates = e1["replicates"].as_f64().unwrap();
        let games = (e1["games"].as_u64().unwrap() * e1["replicates"].as_u64().unwrap()).to_string();
        let o = cli("run")
            .flag("profile", world)
            .flag("agent", "random")
            .flag("blocks", "2")
            .flag("episodes", &games)
            .flag("seed", &seed)
            .arg("--json")
            .run();
        assert!(o.status.success(), "{}", stderr(&o));
        let run: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(
            run["failures"].as_f64(),
            e1["failures"].as_f64().map(|f| f * replicates),
            "{world}"
        );
        assert_eq!(run["mean_steps"], e1["mean_steps"], "{world}");
        assert_eq!(run["median_steps"], e1["median_steps"], "{world}");
        let (ours, theirs) = (
            e1["mean_steps_failures_at_horizon"].as_f64().unwrap(),
            run["mean_steps_failures_as_horizon"].as_f64().unwrap(),
        );
        assert!((ours - theirs).abs() < 1e-9, "{world}: {ours} against {theirs}");
    }
}

#[test]
fn only_runs_the_experiments_asked_for() {
    let dir = scratch("reproduce-only");
    let out = dir.join("report");
    let o = cli("reproduce")
        .arg("--quick")
        .flag("only", "e1")
        .flag("jobs", "1")
        .flag("out", out.to_str().unwrap())
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("reproduced E1 (quick run, seed 1, 1 thread)"));
    let json = read_json(&out.join("results.json"));
    let ids: Vec<&str> = json["experiments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids, ["E1"]);
    assert_eq!(json["ran"]["threads"], 1);
    let o = cli("reproduce")
        .arg("--quick")
        .flag("only", "E11")
        .flag("out", out.to_str().unwrap())
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(stderr(&o).trim_end().lines().count(), 1, "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no experiment E11: name experiments E1 to E8"),
        "{}",
        stderr(&o)
    );
    // An experiment of the benchmark's, asked of the reproduction: the command that has it.
    let o = cli("reproduce")
        .arg("--quick")
        .flag("only", "E9")
        .flag("out", out.to_str().unwrap())
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("run `blockstack benchmark --only E9`"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn the_quick_benchmark_holds_e9_and_e10() {
    let dir = scratch("benchmark-quick");
    let o = cli("benchmark").arg("--quick").flag("out", dir.to_str().unwrap()).run();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("benchmarked E9, E10 (quick run, seed 1"), "{out}");
    let readme = std::fs::read_to_string(dir.join("README.md")).expect("README.md exists");
    assert!(readme.starts_with("# The Blocks World benchmark\n"), "{readme}");
    let json = read_json(&dir.join("results.json"));
    assert_eq!(json["options"]["report"], "blocks-world");
    let text = std::fs::read_to_string(dir.join("results.json")).unwrap();
    let summary = std::fs::read_to_string(dir.join("summary.md")).expect("summary.md exists");
    assert_eq!(summary, experiments::reproduce::summary(&text).unwrap());
    assert!(
        summary.starts_with("Measured by `blockstack benchmark --quick --seed 1`"),
        "{summary}"
    );
    let experiments = json["experiments"].as_array().unwrap();
    let ids: Vec<&str> = experiments.iter().map(|e| e["id"].as_str().unwrap()).collect();
    assert_eq!(ids, ["E9", "E10"]);
    for figure in ["e9-moves.png", "e9-reached.png", "e10-moves.png"] {
        assert!(dir.join(figure).is_file(), "{figure}");
    }
    // E9: the planners reach every goal, the near-optimal plans are at most twice the fewest
    // moves, and the physics and the grid model agree.
    let e9 = &experiments[0]["blocks_world"];
    for group in e9["by_blocks"].as_array().unwrap() {
        assert!(group["near_optimal_worst"].as_f64().unwrap() <= 2.0, "{group}");
        for agent in group["agents"].as_array().unwrap() {
            if agent["agent"] != "learner" {
                assert_eq!(agent["success"], 1.0, "{agent}");
            }
        }
    }
    for a in e9["agreement"].as_array().unwrap() {
        assert!(a["drops"].as_u64().unwrap() > 0, "{a}");
        assert_eq!(
            (&a["same_steps"], &a["same_landings"]),
            (&a["steps"], &a["drops"]),
            "{a}"
        );
    }
    assert!(readme.contains("### Physics against the grid model"));

    // E10: the learned policy played every size it was given, each against the near-optimal
    // planner, and against the fewest moves where searched; NLM's published figures beside.
    let e10 = &experiments[1]["general"];
    for row in e10["uniform"].as_array().unwrap() {
        assert!(row["problems"].as_u64().unwrap() > 0, "{row}");
        assert!((0.0..=1.0).contains(&row["success"].as_f64().unwrap()), "{row}");
    }
    for row in e10["exact"].as_array().unwrap() {
        // Over the problems the policy solved: at the quick budget's tiny training it may
        // solve none of a size, or only a problem whose start meets its goal (no move to
        // divide by), and then there is no ratio.
        match row["near_optimal_fewest_ratio"].as_f64() {
            Some(near) => assert!((1.0..=2.0).contains(&near), "{row}"),
            None => assert!(
                row["success"].as_f64() == Some(0.0) || row["fewest_moves"].as_f64() == Some(0.0),
                "{row}"
            ),
        }
    }
    assert_eq!(e10["nlm"][1]["published"][1], 85.8);
    assert!(readme.contains("### Neural Logic Machines' generator"));
}

#[test]
fn a_report_directory_that_cannot_be_made_fails_at_once() {
    let dir = scratch("reproduce-file");
    let file = dir.join("file");
    std::fs::write(&file, "not a directory").unwrap();
    let o = cli("reproduce")
        .arg("--quick")
        .flag("out", file.join("report").to_str().unwrap())
        .run();
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("cannot make the folder") && err.lines().count() == 1,
        "{err}"
    );
    let o = cli("reproduce").flag("jobs", "0").run();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    std::fs::remove_file(&file).unwrap();
}
