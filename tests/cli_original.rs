//! `--profile original` and the flags that override its parts, end to end: run, render,
//! train, eval, correct; a model remembers the world it was trained in.

use std::path::{Path, PathBuf};

use crate::common::{blockstack, cli, model_metadata, path, scratch, stderr, stdout, train, train_model};

fn json(args: &[&str]) -> serde_json::Value {
    let o = blockstack(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap_or_else(|e| panic!("{args:?}: {e}: {}", stdout(&o)))
}

/// Trains the paper's learner as coded for a few short games on the grid backend.
fn train_original(dir: &Path) -> PathBuf {
    let out = dir.join("original.safetensors");
    let run = [
        "--profile",
        "original",
        "--games",
        "3",
        "--horizon",
        "300",
        "--backend",
        "grid",
        "--seed",
        "2",
    ];
    let o = train(&[&run[..], &["--out", path(&out)]].concat());
    assert!(stdout(&o).contains("profile original: protocol paper, start paper, schedule paper-code"));
    out
}

#[test]
fn run_under_the_original_profile_plays_the_authors_world() {
    let words = "run --profile original --agent random --blocks 2 --episodes 40 --seed 3 --backend grid --json";
    let v = json(&words.split(' ').collect::<Vec<_>>());
    assert_eq!(
        (&v["profile"], &v["protocol"], &v["start"]),
        (
            &serde_json::json!("original"),
            &serde_json::json!("paper"),
            &serde_json::json!("paper")
        )
    );
    let episodes = v["episodes"].as_f64().unwrap();
    let failures = v["failures"].as_f64().unwrap();
    let mean = v["mean_steps"].as_f64().unwrap_or(0.0);
    // The figure the paper reports: a failure counts as the horizon (1000).
    let expected = (failures * 1000.0 + mean * (episodes - failures)) / episodes;
    assert!((v["mean_steps_failures_as_horizon"].as_f64().unwrap() - expected).abs() < 1e-6);
    // The same under spec is another world: every action legal, uniform starts.
    let spec = json(&words.replace("original", "spec").split(' ').collect::<Vec<_>>());
    assert_eq!(
        (&spec["protocol"], &spec["start"]),
        (&serde_json::json!("free"), &serde_json::json!("uniform"))
    );
    // A part's flag overrides the profile.
    let mixed = json(&format!("{words} --protocol free").split(' ').collect::<Vec<_>>());
    assert_eq!(
        (&mixed["protocol"], &mixed["start"]),
        (&serde_json::json!("free"), &serde_json::json!("paper"))
    );
}

#[test]
fn trajectories_under_the_paper_protocol_hold_only_legal_actions() {
    let dir = scratch("trajectory");
    let file = dir.join("t.jsonl");
    let o = cli("run")
        .flag("profile", "original")
        .flag("agent", "random")
        .flag("episodes", "5")
        .flag("seed", "1")
        .flag("backend", "grid")
        .flag("trajectory", path(&file))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&file).unwrap();
    let mut held: Option<serde_json::Value> = None;
    let mut steps = 0;
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        match v["type"].as_str().unwrap() {
            "episode" => {
                held = None;
                // The paper's start rule: the 6 x 6 corner without the right column and
                // the bottom row.
                for cell in v["start"].as_array().unwrap() {
                    assert!(cell[0] != 6 && cell[1] != 0, "{line}");
                }
            }
            _ => {
                let action = v["action"].as_u64().unwrap();
                let holding = held.as_ref().is_some_and(|h| !h.is_null());
                // Nothing held: only picks (5 + i); holding: only moves and drop (0..5).
                assert_eq!(action >= 5, !holding, "{line}");
                held = Some(v["held"].clone());
                steps += 1;
            }
        }
    }
    assert!(steps > 100, "{steps}");
}

#[test]
fn the_oracles_play_as_chosen() {
    let base = "run --agent oracle --episodes 10 --seed 4 --backend grid --json";
    let run = |extra: &str| json(&format!("{base} {extra}").split_whitespace().collect::<Vec<_>>());
    assert_eq!(run("")["agent"], "oracle");
    assert_eq!(run("")["failures"], 0);
    assert_eq!(run("--profile original")["agent"], "paper-oracle");
    assert_eq!(run("--oracle paper")["agent"], "paper-oracle");
    let ours_in_theirs = run("--profile original --oracle astar");
    assert_eq!(
        (&ours_in_theirs["agent"], &ours_in_theirs["failures"]),
        (&serde_json::json!("oracle"), &serde_json::json!(0))
    );
    let exact = json(
        &"run --agent exact --profile original --episodes 10 --seed 4 --backend grid --json"
            .split(' ')
            .collect::<Vec<_>>(),
    );
    assert_eq!(exact["failures"], 0);
}

#[test]
fn a_model_trained_under_original_evaluates_under_original_by_default() {
    let dir = scratch("model");
    let model = train_original(&dir);
    let file = model_metadata(&model);
    assert_eq!(file["repr"], "chasing-code");
    assert_eq!(file["schedule"], "paper-code");
    let t = &file["training"];
    assert_eq!(
        (&t["profile"], &t["protocol"], &t["start"]),
        (
            &serde_json::json!("original"),
            &serde_json::json!("paper"),
            &serde_json::json!("paper")
        )
    );
    assert_eq!(t["reward"]["model"], "paper-code");
    assert_eq!(t["oracle"], "paper");
    let eval = |extra: &str| {
        let words = format!(
            "eval --model {} --goals 0,1,2 --episodes 20 --seed 5 --backend grid --json {extra}",
            path(&model)
        );
        json(&words.split_whitespace().collect::<Vec<_>>())
    };
    let v = eval("");
    assert_eq!(
        (&v["profile"], &v["protocol"], &v["start"]),
        (
            &serde_json::json!("original"),
            &serde_json::json!("paper"),
            &serde_json::json!("paper")
        )
    );
    assert!(v["mean_steps_failures_as_horizon"].as_f64().unwrap() >= 1.0);
    // Told otherwise: the whole profile, or one part.
    let v = eval("--profile spec");
    assert_eq!(
        (&v["protocol"], &v["start"]),
        (&serde_json::json!("free"), &serde_json::json!("uniform"))
    );
    let v = eval("--start uniform");
    assert_eq!(
        (&v["protocol"], &v["start"]),
        (&serde_json::json!("paper"), &serde_json::json!("uniform"))
    );
    // run --agent q too.
    let words = format!(
        "run --agent q --model {} --goal 0,1,2 --episodes 5 --seed 5 --backend grid --json",
        path(&model)
    );
    let v = json(&words.split_whitespace().collect::<Vec<_>>());
    assert_eq!(
        (&v["protocol"], &v["agent"]),
        (&serde_json::json!("paper"), &serde_json::json!("q-chasing-code"))
    );
}

#[test]
fn train_flags_override_the_profile_part_by_part() {
    let dir = scratch("override");
    let out = train_model(
        &dir,
        "m.safetensors",
        &[
            "--profile",
            "original",
            "--repr",
            "chasing",
            "--schedule",
            "spec",
            "--oracle",
            "astar",
            "--games",
            "2",
            "--backend",
            "grid",
        ],
    );
    let file = model_metadata(&out);
    let t = &file["training"];
    assert_eq!(file["repr"], "chasing");
    assert_eq!(
        (&t["schedule"], &t["oracle"], &t["oscillation"]),
        (
            &serde_json::json!("spec"),
            &serde_json::json!("astar"),
            &serde_json::json!("distances")
        )
    );
    assert_eq!(
        (&t["protocol"], &t["reward"]["model"]),
        (&serde_json::json!("paper"), &serde_json::json!("paper-code"))
    );
    // --schedule alone sets the games' length with it.
    assert_eq!(t["horizon"], 1000);
    // The profile's own defaults: 100 games of up to 5000 steps.
    let o = cli("train")
        .flag("profile", "original")
        .flag("games", "0")
        .flag("out", path(&out))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let file = model_metadata(&out);
    assert_eq!(file["training"]["horizon"], 5000);
    // Without a profile nothing changed: the paper's learner in our world.
    let o = cli("train").flag("games", "0").flag("out", path(&out)).run();
    assert!(o.status.success(), "{}", stderr(&o));
    let file = model_metadata(&out);
    let t = &file["training"];
    assert_eq!(
        (
            &file["repr"],
            &t["schedule"],
            &t["protocol"],
            &t["horizon"],
            &t["games"]
        ),
        (
            &serde_json::json!("chasing"),
            &serde_json::json!("spec"),
            &serde_json::json!("free"),
            &serde_json::json!(1000),
            &serde_json::json!(0)
        )
    );
}

#[test]
fn corrections_under_original_use_the_plain_update_and_the_authors_goals() {
    let dir = scratch("correct");
    let model = train_original(&dir);
    let (out, record) = (dir.join("corrected.safetensors"), dir.join("demos.jsonl"));
    let o = cli("correct")
        .flag("model", path(&model))
        .flag("demonstrator", "2")
        .flag("demos", "2")
        .flag("seed", "3")
        .flag("out", path(&out))
        .flag("record", path(&record))
        .arg("--backend-note-unused")
        .run();
    // A flag that does not exist is refused before anything runs.
    assert_eq!(o.status.code(), Some(2));
    let o = cli("correct")
        .flag("model", path(&model))
        .flag("demonstrator", "2")
        .flag("demos", "2")
        .flag("seed", "3")
        .flag("out", path(&out))
        .flag("record", path(&record))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("on 0,1,2:2,1,0:1,2,0:1,0,2"), "{}", stdout(&o));
    let first: serde_json::Value =
        serde_json::from_str(std::fs::read_to_string(&record).unwrap().lines().next().unwrap()).unwrap();
    assert_eq!(first["rule"]["margin"], serde_json::Value::Null);
    // learn-from-demos replays it to the same table.
    let replayed = dir.join("replayed.safetensors");
    let o = cli("learn-from-demos")
        .arg(path(&record))
        .flag("model", path(&model))
        .flag("out", path(&replayed))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&replayed).unwrap(), std::fs::read(&out).unwrap());
}

#[test]
fn flags_that_do_not_apply_are_not_offered() {
    for args in [
        &["render", "--protocol", "paper"][..],
        &["eval", "--model", "m.json", "--repr", "role"],
        &["run", "--schedule", "paper-code"],
        &["render", "--oracle", "paper"],
    ] {
        let o = blockstack(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains("unexpected argument"), "{args:?}: {}", stderr(&o));
    }
    let o = cli("run").flag("profile", "paper").run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("spec, original"), "{}", stderr(&o));
    let o = cli("render").flag("profile", "original").flag("start", "corner").run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("uniform, paper"), "{}", stderr(&o));
}

#[test]
fn solve_plans_under_the_protocol_it_is_given() {
    let base = [
        "solve",
        "--start",
        "0,0;3,0;5,2",
        "--goal",
        "1,0,2",
        "--held",
        "0",
        "--json",
    ];
    let free = json(&base);
    let paper = json(&[&base[..], &["--protocol", "paper"]].concat());
    assert_eq!(
        (&free["length"], &paper["length"]),
        (&serde_json::json!(7), &serde_json::json!(8))
    );
    // Changing blocks costs a Drop (index 4) before the Pick (5 + 2) under paper.
    let actions = paper["actions"].as_array().unwrap();
    let pick = actions.iter().position(|a| a == 7).unwrap();
    assert_eq!(actions[pick - 1], 4);
}
