//! `blockstack run` and `render` end to end, and their answers to bad input.

use crate::common::{blockstack, cli, scratch, stderr, stdout};

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
