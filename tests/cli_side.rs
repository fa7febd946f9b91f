//! `--view side` end to end: the side view drawn, played by the random agent with a goal of
//! towers into a trajectory file that records the view, and the agents that play only the
//! top view refusing it with one line.

use crate::common::{blockstack, scratch, stderr, stdout};

#[test]
fn render_draws_the_side_view_over_a_table() {
    let o = blockstack(&[
        "render", "--view", "side", "--blocks", "4", "--goal", "0,1/2,3", "--seed", "3", "--ascii",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.lines().any(|l| l == "=".repeat(21)), "{text}");
    // Every block stands: the row above the table holds a block in every column that has one.
    let rows: Vec<&str> = text.lines().take(7).collect();
    assert!(rows[6].chars().any(|c| c.is_ascii_digit()), "{text}");
}

#[test]
fn run_plays_the_side_view_and_records_it() {
    let dir = scratch("side");
    let traj = dir.join("side.jsonl");
    let o = blockstack(&[
        "run",
        "--view",
        "side",
        "--blocks",
        "3",
        "--goal",
        "0,1/2",
        "--episodes",
        "3",
        "--seed",
        "5",
        "--json",
        "--trajectory",
        traj.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["goal"], "0,1/2");
    let first = std::fs::read_to_string(&traj).unwrap();
    let header: serde_json::Value = serde_json::from_str(first.lines().next().unwrap()).unwrap();
    assert_eq!(header["view"], "side");
    assert_eq!(header["goal"]["towers"], serde_json::json!([[0, 1], [2]]));
}

#[test]
fn top_view_agents_and_rules_refuse_the_side_view_in_one_line() {
    for (args, says) in [
        (
            vec!["run", "--view", "side", "--agent", "oracle"],
            "--agent oracle plays the top view only",
        ),
        (
            vec!["run", "--agent", "exact", "--goal", "0,1/2"],
            "goal 0,1/2 is not one tower of every block",
        ),
        (
            vec!["render", "--view", "side", "--start", "paper"],
            "the side view starts from random towers",
        ),
        (vec!["render", "--view", "front"], "choose one of top, side"),
    ] {
        let o = blockstack(&args);
        assert!(!o.status.success(), "{args:?}");
        let err = stderr(&o);
        assert!(err.contains(says) && err.lines().count() == 1, "{args:?}: {err}");
    }
}
