//! `blockstack train`, `eval` and `run --agent q` end to end, and their answers to bad input.

use std::path::{Path, PathBuf};

use crate::common::{ROLE_ON_GRID, blockstack, cli, model_metadata, path, scratch, stderr, stdout, train, train_model};

/// Trains the role learner on one goal, on the grid backend (quick), and returns the model.
fn train_role(dir: &Path, name: &str, games: &str) -> PathBuf {
    let out = dir.join(name);
    let run = [
        "--games",
        games,
        "--seed",
        "1",
        "--backward-replay",
        "--final-replay",
        "--out",
        path(&out),
    ];
    let o = train(&[&ROLE_ON_GRID[..], &run].concat());
    // Not a terminal: no progress bar, nothing on stderr.
    assert_eq!(stderr(&o), "");
    assert!(stdout(&o).contains("games"), "{}", stdout(&o));
    out
}

#[test]
fn train_then_eval_on_unseen_goals() {
    let dir = scratch("train-eval");
    let model = train_role(&dir, "role.safetensors", "30000");
    let eval_json = || {
        let words = "eval --goals 2,1,0:1,2,0 --episodes 100 --seed 2 --epsilon 0 --backend grid --json";
        let mut args: Vec<&str> = words.split(' ').collect();
        args.extend(["--model", path(&model)]);
        blockstack(&args)
    };
    let o = eval_json();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let run_fields = ["agent", "blocks", "goal", "grid", "horizon", "backend", "seed"];
    for field in run_fields
        .into_iter()
        .chain(["episodes", "failures", "mean_steps", "median_steps"])
    {
        assert!(v.get(field).is_some(), "no {field} in {v}");
    }
    assert_eq!(v["agent"], "q-role");
    assert_eq!(v["episodes"], 200);
    assert_eq!(v["per_goal"].as_array().unwrap().len(), 2);
    assert_eq!(v["per_goal"][0]["goal"], "2,1,0");
    // Against the exact optimum: a ratio of at least 1, and the optimum below the steps.
    assert!(v["mean_ratio_to_optimum"].as_f64().unwrap() >= 1.0, "{v}");
    assert!(
        v["mean_optimal_steps"].as_f64().unwrap() <= v["mean_steps"].as_f64().unwrap(),
        "{v}"
    );
    assert!(v["mean_steps_failures_as_horizon"].as_f64().unwrap() >= v["mean_steps"].as_f64().unwrap());
    // Trained on 0,1,2 only, the role learner plays goals it never saw, greedily, without
    // a failure and within 5% of the shortest plans (the random agent fails most of them).
    assert_eq!(v["failures"], 0, "{v}");
    assert!(v["mean_ratio_to_optimum"].as_f64().unwrap() <= 1.05, "{v}");
    // No timings: the same command prints the same line.
    assert_eq!(stdout(&eval_json()), stdout(&o));
    // The text form: a line per goal and one for all.
    let text = cli("eval")
        .flag("model", path(&model))
        .flag("goals", "2,1,0:1,2,0")
        .flag("episodes", "5")
        .run();
    assert!(text.status.success(), "{}", stderr(&text));
    let out = stdout(&text);
    for label in ["2,1,0", "1,2,0", "all", "failures", "mean steps", "mean ratio"] {
        assert!(out.contains(label), "{out}");
    }
}

#[test]
fn the_same_seed_trains_the_same_model_file() {
    let dir = scratch("same-seed");
    let a = train_role(&dir, "a.safetensors", "500");
    let b = train_role(&dir, "b.safetensors", "500");
    // Compared whole, without printing megabytes on a failure.
    assert!(
        std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
        "the model files differ"
    );
}

#[test]
fn run_plays_a_q_model_and_writes_trajectories() {
    let dir = scratch("run-q");
    let model = train_role(&dir, "role.safetensors", "3000");
    let trajectory = dir.join("t.jsonl");
    let v: serde_json::Value = cli("run")
        .flag("agent", "q")
        .flag("model", path(&model))
        .flag("epsilon", "0.1")
        .flag("goal", "1,0,2")
        .flag("episodes", "5")
        .flag("seed", "3")
        .flag("trajectory", path(&trajectory))
        .arg("--json")
        .json();
    assert_eq!(v["agent"], "q-role");
    assert_eq!(v["episodes"], 5);
    let lines = std::fs::read_to_string(&trajectory).unwrap();
    assert_eq!(lines.lines().filter(|l| l.contains("\"type\":\"episode\"")).count(), 5);
}

#[test]
fn the_paper_learner_trains_with_its_defaults() {
    let dir = scratch("paper");
    let out = train_model(
        &dir,
        "paper.safetensors",
        &["--goals", "0,1,2:1,0,2", "--games", "20", "--backend", "grid"],
    );
    let model = model_metadata(&out);
    assert_eq!(model["repr"], "chasing");
    assert_eq!(model["params"]["gamma"], 0.1);
    assert_eq!(model["training"]["reward"]["model"], "paper");
    assert_eq!(model["training"]["goals"], serde_json::json!([[0, 1, 2], [1, 0, 2]]));
}

#[test]
fn bad_models_and_arguments_are_one_line_errors() {
    let dir = scratch("bad");
    let model = train_role(&dir, "role.safetensors", "50");
    let check = |args: &[&str], needle: &str| {
        let o = blockstack(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains(needle), "{args:?}: {err}");
    };
    let bytes = std::fs::read(&model).unwrap();
    let truncated = dir.join("truncated.safetensors");
    std::fs::write(&truncated, &bytes[..bytes.len() - 10]).unwrap();
    check(&["eval", "--model", path(&truncated)], "truncated");
    check(&["run", "--agent", "q", "--model", path(&truncated)], "truncated");
    check(
        &["eval", "--model", path(&dir.join("missing.safetensors"))],
        "missing.safetensors",
    );
    check(
        &["run", "--agent", "q", "--model", path(&model), "--blocks", "4"],
        "4 blocks",
    );
    check(&["run", "--agent", "q"], "--model");
    check(&["eval", "--model", path(&model), "--goals", "0,1"], "goal 0,1");
    check(&["eval", "--model", path(&model), "--epsilon", "2"], "epsilon 2");
    let out = dir.join("x.safetensors");
    check(
        &["train", "--repr", "deep", "--out", path(&out)],
        "choose raw, pairwise, chasing, chasing-code, role or role-towers",
    );
    check(&["train", "--alpha", "0", "--out", path(&out)], "alpha 0");
    check(
        &["train", "--goals", "0,1,3", "--out", path(&out)],
        "block 3 does not exist",
    );
    check(&["train", "--reward", "big", "--out", path(&out)], "reward model");
    check(
        &[
            "train",
            "--games",
            "1",
            "--out",
            path(&dir.join("no-such-dir").join("m.safetensors")),
        ],
        "cannot write",
    );
    assert!(!out.exists());
}
