//! `blockstack solve` and `run --agent oracle|exact` end to end, and their answers to bad
//! input.

use std::process::Output;

use sim::{Action, Cell, Goal, Grid, GridWorld, State, View, World};

use crate::common::{blockstack, cli, stderr, stdout};

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_str(&stdout(o)).unwrap()
}

/// Replays action indices from `start` and says whether the goal holds at the end.
fn reaches(start: &[(u16, u16)], held: Option<u16>, goal: &str, actions: &[usize]) -> bool {
    let cells: Vec<Cell> = start.iter().map(|&(x, y)| Cell::new(x, y)).collect();
    let goal: Goal = goal.parse().unwrap();
    let state = State::new(&cells, held.map(sim::BlockId)).unwrap();
    let mut world = GridWorld::new(Grid::default(), state).unwrap();
    for &i in actions {
        world.act(Action::from_index(i, cells.len()).unwrap()).unwrap();
    }
    goal.holds(world.state_ref())
}

#[test]
fn solve_prints_a_shortest_plan_as_json() {
    let o = cli("solve")
        .flag("start", "0,0;3,0;5,2")
        .flag("goal", "1,0,2")
        .arg("--json")
        .run();
    let v = json(&o);
    assert_eq!(v["solver"], "exact");
    let actions: Vec<usize> = v["actions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(v["length"].as_u64().unwrap() as usize, actions.len());
    assert_eq!(actions.len(), 8);
    assert!(reaches(&[(0, 0), (3, 0), (5, 2)], None, "1,0,2", &actions));
}

#[test]
fn solve_with_a_held_block_and_the_oracle() {
    let args = ["solve", "--start", "0,0;3,0;5,2", "--goal", "1,0,2", "--held", "2"];
    let exact = json(&blockstack(&[&args[..], &["--json"]].concat()));
    let oracle = json(&blockstack(&[&args[..], &["--json", "--solver", "oracle"]].concat()));
    assert_eq!(oracle["solver"], "oracle");
    assert!(oracle["length"].as_u64() >= exact["length"].as_u64());
    for v in [exact, oracle] {
        let actions: Vec<usize> = v["actions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_u64().unwrap() as usize)
            .collect();
        assert!(reaches(&[(0, 0), (3, 0), (5, 2)], Some(2), "1,0,2", &actions));
    }
}

#[test]
fn solve_prints_action_names_and_length() {
    let o = cli("solve")
        .flag("start", "0,0;3,0")
        .flag("goal", "1,0")
        .flag("grid", "7x7")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("exact plan, goal 1,0, grid 7x7: 5 actions"), "{out}");
    assert!(out.contains("pick 0, "), "{out}");
}

#[test]
fn solve_rejects_bad_input_with_one_line_and_exit_2() {
    for (args, message) in [
        (
            &["--start", "0,0;0,0", "--goal", "0,1"][..],
            "both stand on cell (0, 0)",
        ),
        (
            &["--start", "0,0;9,0", "--goal", "0,1"],
            "cell (9, 0) is outside the 7x7 grid",
        ),
        (&["--start", "0,0;1,0", "--goal", "0,0"], "not a permutation"),
        (&["--start", "0,0;1,0;2,0", "--goal", "0,1"], "not a permutation"),
        (
            &["--start", "0,0;1,0;2,0", "--goal", "0,1,2", "--grid", "3x2"],
            "taller than the grid",
        ),
        (&["--start", "0,0;1", "--goal", "0,1"], "cannot read cell from \"1\""),
        (
            &["--start", "0,0;1,0", "--goal", "0,1", "--held", "256"],
            "block 256 does not exist",
        ),
        (
            &["--start", "0,0;1,0", "--goal", "0,1", "--held", "5"],
            "block 5 does not exist",
        ),
        (
            &["--start", "0,0;0,1", "--goal", "1,0", "--grid", "1x4"],
            "cannot be reached",
        ),
    ] {
        let o = blockstack(&[&["solve"][..], args].concat());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(stdout(&o).is_empty());
    }
}

#[test]
fn run_plays_the_planners_in_the_physics_world() {
    let run = |agent: &str| {
        json(
            &cli("run")
                .flag("agent", agent)
                .flag("blocks", "3")
                .flag("goal", "2,0,1")
                .flag("episodes", "20")
                .flag("seed", "4")
                .arg("--json")
                .run(),
        )
    };
    let (exact, oracle) = (run("exact"), run("oracle"));
    for (v, name) in [(&exact, "exact"), (&oracle, "oracle")] {
        assert_eq!(v["agent"], name);
        assert_eq!(v["backend"], "physics");
        assert_eq!(v["failures"], 0);
    }
    assert!(oracle["mean_steps"].as_f64() >= exact["mean_steps"].as_f64());
}

/// Replays action indices from the side-view state `start` on `grid`: the end state.
fn replay_side(grid: Grid, start: State, actions: &[usize]) -> State {
    let mut world = GridWorld::new_in(View::Side, grid, start.clone()).unwrap();
    for &i in actions {
        world.act(Action::from_index(i, start.block_count()).unwrap()).unwrap();
    }
    world.state_ref().clone()
}

fn indices(v: &serde_json::Value) -> Vec<usize> {
    v["actions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_u64().unwrap() as usize)
        .collect()
}

/// `solve --view side --cost steps`: the fewest gripper steps by the exact solver, and the
/// near-optimal block-move plan carried out by the gripper (also `--solver oracle`).
#[test]
fn solve_counts_gripper_steps_in_the_side_view() {
    // 1 on 0, 2 on 1; 3 alone. Goal: 1 on the table, 3 on 1, 2 on 3 (0 free).
    let grid = Grid::default();
    let start = State::new(
        &[Cell::new(0, 0), Cell::new(0, 1), Cell::new(0, 2), Cell::new(1, 0)],
        None,
    )
    .unwrap();
    let goal = Goal::parse("1,3,2/", Some(4)).unwrap();
    let base = cli("solve")
        .flag("view", "side")
        .flag("start", "0,0;0,1;0,2;1,0")
        .flag("goal", "1,3,2/")
        .flag("cost", "steps");
    let exact = json(&base.clone().arg("--json").run());
    let optimum = oracle::ExactSolver::new(grid)
        .with_view(View::Side)
        .distance(&start, &goal)
        .unwrap();
    assert_eq!(exact["length"], optimum);
    assert_eq!(
        (exact["cost"].as_str(), exact["solver"].as_str()),
        (Some("steps"), Some("exact"))
    );
    let actions = indices(&exact);
    assert_eq!(actions.len() as u32, optimum);
    assert!(goal.holds_in(View::Side, &replay_side(grid, start.clone(), &actions)));
    // The near-optimal plan, 4 block moves, carried out: no shorter than the optimum, and
    // the oracle of the side view is the same plan.
    let near = json(&base.clone().flag("solver", "near-optimal").arg("--json").run());
    let oracle = json(&base.clone().flag("solver", "oracle").arg("--json").run());
    assert_eq!(indices(&near), indices(&oracle));
    assert_eq!(oracle["solver"], "oracle");
    let carried = indices(&near);
    assert!(carried.len() >= actions.len() && near["length"] == carried.len());
    assert!(goal.holds_in(View::Side, &replay_side(grid, start, &carried)));
    let picks = carried.iter().filter(|&&i| i >= 5).count();
    assert_eq!(picks, 4, "one pick per block move");
    // Text: the count, then the gripper actions.
    let text = base.clone().ok();
    assert!(
        text.starts_with(&format!(
            "exact plan, goal 1,3,2/, grid 7x7, side view: {optimum} gripper steps\npick 2, "
        )),
        "{text}"
    );
    // From a held block, by the exact solver.
    let held = json(
        &cli("solve")
            .flag("view", "side")
            .flag("start", "0,0;0,1;0,2;1,3")
            .flag("held", 3)
            .flag("goal", "1,3,2/")
            .flag("cost", "steps")
            .arg("--json")
            .run(),
    );
    let cells = [Cell::new(0, 0), Cell::new(0, 1), Cell::new(0, 2), Cell::new(1, 3)];
    let held_start = State::new(&cells, Some(sim::BlockId(3))).unwrap();
    assert!(goal.holds_in(View::Side, &replay_side(grid, held_start, &indices(&held))));
    // What is refused, in one line.
    for (args, message) in [
        (
            base.clone().flag("solver-budget", 5),
            "use --solver near-optimal or --cost moves",
        ),
        (
            base.clone().flag("solver", "near-optimal").flag("held", 2),
            "starts with nothing held",
        ),
        (
            cli("solve")
                .flag("view", "side")
                .flag("start", "0,0;0,1;0,2;1,0")
                .flag("goal", "1,3,2/")
                .flag("solver-budget", 100),
            "only with --cost steps --solver exact",
        ),
    ] {
        let o = args.run();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}
