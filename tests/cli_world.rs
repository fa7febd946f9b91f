//! `blockstack run` and `render` end to end, and their answers to bad input.

use crate::common::{blockstack, cli, path, scratch, stderr, stdout};

#[test]
fn run_reports_failures_and_steps_as_json() {
    let base = cli("run")
        .flag("blocks", 2)
        .flag("goal", "0,1")
        .flag("episodes", 20)
        .flag("seed", 7)
        .arg("--json");
    let o = base.clone().flag("agent", "random").run();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["episodes"], 20);
    assert!(v["failures"].as_u64().unwrap() <= 20);
    assert!(v["mean_steps"].as_f64().unwrap() > 1.0);
    assert!(v["median_steps"].as_f64().unwrap() > 1.0);
    assert_eq!(v["agent"], "random");
    // Same seed, same figures; both backends play the same episodes.
    assert_eq!(base.ok(), stdout(&o));
    let grid = base.flag("backend", "grid").run();
    let g: serde_json::Value = serde_json::from_str(&stdout(&grid)).unwrap();
    assert_eq!((&g["failures"], &g["mean_steps"]), (&v["failures"], &v["mean_steps"]));
}

#[test]
fn run_prints_a_readable_summary() {
    let o = cli("run")
        .flag("blocks", "3")
        .flag("episodes", "5")
        .flag("seed", "1")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for label in ["failures", "mean steps", "median steps"] {
        assert!(out.contains(label), "{out}");
    }
}

#[test]
fn the_same_seed_writes_the_same_trajectory_byte_for_byte() {
    let dir = scratch("trajectory");
    let (a, b) = (dir.join("a.jsonl"), dir.join("b.jsonl"));
    for path in [&a, &b] {
        let o = cli("run")
            .flag("blocks", "3")
            .flag("goal", "1,0,2")
            .flag("episodes", "3")
            .flag("seed", "11")
            .flag("horizon", "50")
            .flag("trajectory", path.to_str().unwrap())
            .run();
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let (ta, tb) = (std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    assert_eq!(ta, tb);
    // The documented format: a header per episode, then one line per step counted from 1.
    let lines: Vec<serde_json::Value> = String::from_utf8(ta)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines[0]["type"], "episode");
    assert_eq!(lines[0]["grid"], serde_json::json!([7, 7]));
    assert_eq!(lines[0]["goal"], serde_json::json!([1, 0, 2]));
    assert_eq!(lines[0]["horizon"], 50);
    assert_eq!(lines[0]["start"].as_array().unwrap().len(), 3);
    assert_eq!(lines[1]["type"], "step");
    assert_eq!(lines[1]["step"], 1);
    for key in [
        "episode",
        "action",
        "blocks",
        "held",
        "reward",
        "terminated",
        "truncated",
    ] {
        assert!(lines[1].get(key).is_some(), "missing {key}");
    }
    assert_eq!(lines.iter().filter(|l| l["type"] == "episode").count(), 3);
    // Each episode ends with a terminated or truncated step.
    let ends = lines
        .iter()
        .filter(|l| l["terminated"] == true || l["truncated"] == true)
        .count();
    assert_eq!(ends, 3);
}

#[test]
fn render_writes_a_png_and_prints_ascii() {
    let dir = scratch("render");
    let png = dir.join("world.png");
    let o = cli("render")
        .flag("blocks", "3")
        .flag("goal", "0,1,2")
        .flag("seed", "7")
        .flag("out", png.to_str().unwrap())
        .arg("--ascii")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(&png).unwrap().to_rgb8();
    assert!(img.width() >= 7 * 48 && img.height() >= 7 * 48);
    assert!(stdout(&o).contains("goal"));
    assert_eq!(stdout(&o).lines().count(), 8);
}

#[test]
fn bad_input_gets_one_line_and_exit_status_2() {
    let cases: &[(&[&str], &str)] = &[
        (&["run", "--goal", "0,0,1"], "appears twice"),
        (&["run", "--goal", "0,1"], "goal 0,1"),
        (&["run", "--goal", "0,1,x"], "not a block number"),
        (&["run", "--blocks", "8"], "taller than the grid"),
        (
            &["run", "--blocks", "3", "--grid", "1x3"],
            "at least one cell must stay free",
        ),
        (&["run", "--blocks", "1"], "1 blocks is not allowed"),
        (&["run", "--grid", "0x7"], "grid 0x7"),
        (&["run", "--grid", "seven"], "WxH"),
        (&["run", "--horizon", "0"], "horizon"),
        (&["run", "--reward", "lots"], "reward model"),
        (&["run", "--backend", "box2d"], "physics or grid"),
        (
            &["run", "--episodes", "1", "--trajectory", "/nonexistent-dir/t.jsonl"],
            "cannot write /nonexistent-dir/t.jsonl",
        ),
        (
            &["render", "--out", "/nonexistent-dir/w.png"],
            "cannot write /nonexistent-dir/w.png",
        ),
    ];
    for (args, needle) in cases {
        let o = blockstack(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// The world flags are one set, parsed into the world's own types by every command that
/// describes a world: a bad value is the same one line whichever command is given it.
#[test]
fn every_command_reads_the_world_flags_alike() {
    let commands: [&[&str]; 5] = [
        &["run"],
        &["render"],
        &["train", "--out", "unused.safetensors"],
        &["dqn", "--out", "unused.safetensors"],
        &["eval", "--model", "missing.safetensors"],
    ];
    for (flag, value, says) in [
        ("--grid", "7by7", "--grid 7by7: cannot read grid"),
        ("--backend", "box2d", "--backend box2d: cannot read backend"),
        (
            "--view",
            "front",
            "--view front: cannot read view from \"front\": choose one of top, side",
        ),
        ("--reward", "lots", "--reward lots: "),
        ("--blocks", "many", "--blocks many: "),
        ("--horizon", "0x10", "--horizon 0x10: "),
    ] {
        for command in commands {
            let args = [command, &[flag, value]].concat();
            let o = blockstack(&args);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
            assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
            assert!(err.contains(says), "{args:?}: {err}");
        }
    }
    // Malformed goals of towers are refused, not read as something else.
    for goal in ["0,1//2", "+0,1/2", "/0,1,2"] {
        let o = blockstack(&["run", "--view", "side", "--goal", goal]);
        assert_eq!(o.status.code(), Some(2), "{goal}");
        assert!(
            stderr(&o).contains(&format!("cannot read goal from \"{goal}\"")),
            "{}",
            stderr(&o)
        );
    }
}

/// `eval` plays the model's own world: a size or view other than the model's is refused
/// with the words `run --model` uses.
#[test]
fn eval_refuses_a_world_the_model_never_learnt() {
    let dir = scratch("eval-world");
    let model = dir.join("m.safetensors");
    let o = cli("train")
        .flag("repr", "role")
        .flag("goals", "0,1,2")
        .flag("games", 5)
        .flag("backend", "grid")
        .flag("out", path(&model))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    for (flag, value, says) in [
        ("grid", "5x5", "the world has 3 blocks on a 5x5 grid"),
        ("blocks", "2", "the world has 2 blocks"),
        (
            "view",
            "side",
            "the model learnt the top view; it cannot play the side view",
        ),
    ] {
        let o = cli("eval")
            .flag("model", path(&model))
            .flag(flag, value)
            .flag("episodes", 1)
            .run();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{flag}: {err}");
        assert!(
            err.contains(says) && err.trim_end().lines().count() == 1,
            "{flag}: {err}"
        );
    }
    let v = cli("eval")
        .flag("model", path(&model))
        .flag("episodes", 2)
        .flag("backend", "grid")
        .flag("reward", "dense")
        .flag("horizon", 50)
        .arg("--json")
        .json();
    assert_eq!((v["horizon"].as_u64(), v["backend"].as_str()), (Some(50), Some("grid")));
}
