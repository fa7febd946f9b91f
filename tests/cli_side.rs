//! `--view side` end to end: the side view drawn, played by the random agent with a goal of
//! towers into a trajectory file that records the view, and the agents that play only the
//! top view refusing it with one line.

use crate::common::{ROLE_ON_GRID, blockstack, cli, path, scratch, stderr, stdout, train_model};

#[test]
fn render_draws_the_side_view_over_a_table() {
    let o = cli("render")
        .flag("view", "side")
        .flag("blocks", "4")
        .flag("goal", "0,1/2,3")
        .flag("seed", "3")
        .arg("--ascii")
        .run();
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
    let v: serde_json::Value = cli("run")
        .flag("view", "side")
        .flag("blocks", "3")
        .flag("goal", "0,1/2")
        .flag("episodes", "3")
        .flag("seed", "5")
        .arg("--json")
        .flag("trajectory", traj.to_str().unwrap())
        .json();
    assert_eq!(v["goal"], "0,1/2");
    let first = std::fs::read_to_string(&traj).unwrap();
    let header: serde_json::Value = serde_json::from_str(first.lines().next().unwrap()).unwrap();
    assert_eq!(header["view"], "side");
    assert_eq!(header["goal"]["towers"], serde_json::json!([[0, 1], [2]]));
}

#[test]
fn top_view_agents_and_rules_refuse_the_side_view_in_one_line() {
    let dir = scratch("side-refusals");
    let model = train_model(&dir, "q.safetensors", &[&ROLE_ON_GRID[..], &["--games", "5"]].concat());
    for (args, says) in [
        (
            vec!["run", "--view", "side", "--agent", "q", "--model", path(&model)],
            "the model learnt the top view; it cannot play the side view",
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

/// `solve --view side`: block-move plans by the exact solver and the near-optimal planner.
#[test]
fn solve_plans_block_moves_in_the_side_view() {
    // 1 on 0, 2 on 1; 3 alone. Goal: 1 on the table, 3 on 1, 2 on 3 (0 free): 2 must leave
    // 1 before 1 moves and come back after 3, so the optimum is 4 moves.
    let base = cli("solve")
        .flag("view", "side")
        .flag("start", "0,0;0,1;0,2;1,0")
        .flag("goal", "1,3,2/");
    let exact: serde_json::Value = serde_json::from_str(&base.clone().arg("--json").ok()).unwrap();
    assert_eq!(exact["length"], 4);
    assert_eq!(exact["cost"], "moves");
    assert_eq!(exact["moves"][0], serde_json::json!({"block": 2, "onto": "table"}));
    assert_eq!(exact["moves"][3], serde_json::json!({"block": 2, "onto": 3}));
    let near = base.clone().flag("solver", "near-optimal").ok();
    assert!(
        near.starts_with("near-optimal plan, goal 1,3,2/, grid 7x7, side view: 4 block moves"),
        "{near}"
    );
    // Two towers, one move.
    let two: serde_json::Value = serde_json::from_str(
        &cli("solve")
            .flag("view", "side")
            .flag("start", "0,0;0,1;0,2;1,0")
            .flag("goal", "0,1/3,2")
            .arg("--json")
            .ok(),
    )
    .unwrap();
    assert_eq!(two["length"], 1);
    // What the side view does not plan is refused in one line.
    for (args, message) in [
        (base.clone().flag("held", 2), "starts with nothing held"),
        (
            cli("solve")
                .flag("view", "side")
                .flag("start", "0,0;0,2")
                .flag("goal", "0,1"),
            "floats",
        ),
        (
            cli("solve")
                .flag("start", "0,0;0,2")
                .flag("goal", "0,1")
                .flag("cost", "moves"),
            "add --view side",
        ),
    ] {
        let o = args.run();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}

/// The side view's planners play it as agents (`--agent exact`: the fewest gripper steps,
/// `exact-moves`: the fewest block moves, `oracle` and `near-optimal`: the near-optimal
/// planner), on the physics backend, to the goal every time.
#[test]
fn the_planners_play_the_side_view() {
    for agent in ["exact", "exact-moves", "near-optimal", "oracle"] {
        let out = cli("run")
            .flag("view", "side")
            .flag("agent", agent)
            .flag("blocks", 4)
            .flag("goal", "0,1/2,3")
            .flag("episodes", 10)
            .flag("seed", 5)
            .arg("--json")
            .ok();
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["episodes"], 10, "{agent}");
        assert_eq!(v["failures"], 0, "{agent}: {out}");
    }
}

#[test]
fn train_eval_and_run_a_side_view_learner() {
    let dir = scratch("side-learner");
    let model = dir.join("side.safetensors");
    let o = cli("train")
        .flag("view", "side")
        .flag("backend", "grid")
        .flag("out", path(&model))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("q-role-towers"), "{}", stdout(&o));
    // eval plays the model's own world: every goal of towers, from the side.
    let v: serde_json::Value = cli("eval")
        .flag("model", path(&model))
        .flag("episodes", "20")
        .flag("epsilon", "0")
        .flag("backend", "grid")
        .arg("--json")
        .json();
    assert_eq!(v["per_goal"].as_array().unwrap().len(), 13);
    assert_eq!(v["failures"], 0, "{v}");
    assert!(v["mean_ratio_to_optimum"].as_f64().unwrap() <= 1.05, "{v}");
    let v: serde_json::Value = cli("run")
        .flag("agent", "q")
        .flag("model", path(&model))
        .flag("goal", "2/0,1")
        .flag("episodes", "5")
        .flag("epsilon", "0")
        .arg("--json")
        .json();
    assert_eq!(v["failures"], 0, "{v}");
    // A side-view model does not play the top view, and one-tower learners refuse towers.
    let o = cli("run")
        .flag("agent", "q")
        .flag("model", path(&model))
        .flag("view", "top")
        .run();
    assert!(stderr(&o).contains("learnt the side view"), "{}", stderr(&o));
    let o = cli("train")
        .flag("view", "side")
        .flag("repr", "role")
        .flag("out", path(&dir.join("x.safetensors")))
        .run();
    assert!(stderr(&o).contains("--repr role-towers"), "{}", stderr(&o));
}

/// `--agent exact` means the fewest gripper steps in both views: in the side view it takes
/// the exact solver's optimum from every start (what `eval` measures against), where the
/// fewest block moves (`--agent exact-moves`, what `exact` played before) take more on some.
/// It says where the old meaning went.
#[test]
fn exact_is_the_fewest_gripper_steps_in_the_side_view_and_exact_moves_the_fewest_moves() {
    let run = |agent: &str| {
        cli("run")
            .flag("view", "side")
            .flag("agent", agent)
            .flag("blocks", 4)
            .flag("goal", "1,3,2/")
            .flag("episodes", 12)
            .flag("seed", 3)
            .flag("backend", "grid")
            .arg("--json")
            .run()
    };
    let (exact, moves) = (run("exact"), run("exact-moves"));
    assert!(exact.status.success() && moves.status.success(), "{}", stderr(&exact));
    let mean = |o: &std::process::Output| -> f64 {
        let v: serde_json::Value = serde_json::from_str(&stdout(o)).unwrap();
        assert_eq!(v["failures"], 0);
        v["mean_steps"].as_f64().unwrap()
    };
    assert!(mean(&exact) < mean(&moves), "{} against {}", mean(&exact), mean(&moves));
    let v: serde_json::Value = serde_json::from_str(&stdout(&moves)).unwrap();
    assert_eq!(v["agent"], "exact-moves");
    assert!(
        stderr(&exact).contains("--agent exact-moves plays the fewest block moves"),
        "{}",
        stderr(&exact)
    );
    assert!(stderr(&moves).is_empty(), "{}", stderr(&moves));
}
