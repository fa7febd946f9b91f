//! Bounds checked up front: too many goals, the exact solver's budget, grids one cell wide
//! (played through), and flags that do not apply, each answered in one line with exit
//! status 2.

use crate::common::{blockstack, cli, stderr, stdout};

#[test]
fn too_many_goals_are_refused_in_one_short_line() {
    for (blocks, grid, goals) in [("12", "12x12", "479001600"), ("8", "8x9", "40320")] {
        let o = cli("train")
            .flag("blocks", blocks)
            .flag("grid", grid)
            .flag("out", "unused.st")
            .run();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.len() < 300, "{err}");
        assert!(err.contains(goals) && err.contains("--goals"), "{err}");
    }
}

#[test]
fn the_exact_solver_budget_is_a_flag_named_when_it_runs_out() {
    let o = cli("solve")
        .flag("start", "0,0;3,0;5,2")
        .flag("goal", "1,0,2")
        .flag("solver-budget", "2")
        .run();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.starts_with("blockstack: --solver-budget 2: "), "{err}");
    assert!(err.contains("raise the budget"), "{err}");
    let o = cli("solve")
        .flag("start", "0,0;3,0;5,2")
        .flag("goal", "1,0,2")
        .flag("solver-budget", "100000")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));

    let o = cli("run")
        .flag("agent", "exact")
        .flag("episodes", "3")
        .flag("solver-budget", "2")
        .run();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--solver-budget 2"), "{err}");

    for (args, message) in [
        (
            &["solve", "--start", "0,0;1,0", "--goal", "0,1", "--solver-budget", "0"][..],
            "--solver-budget",
        ),
        (
            &[
                "solve",
                "--start",
                "0,0;1,0",
                "--goal",
                "0,1",
                "--solver-budget",
                "1000000000",
            ],
            "--solver-budget",
        ),
        (
            &[
                "solve",
                "--start",
                "0,0;1,0",
                "--goal",
                "0,1",
                "--solver",
                "oracle",
                "--solver-budget",
                "9",
            ],
            "--solver oracle",
        ),
        (
            &["run", "--agent", "random", "--solver-budget", "9"],
            "--solver-budget does not apply to --agent random: it is for --agent exact only",
        ),
    ] {
        let o = blockstack(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
}

#[test]
fn the_oracle_plays_every_episode_on_a_grid_one_cell_wide() {
    for oracle in ["astar", "paper"] {
        let o = cli("run")
            .flag("agent", "oracle")
            .flag("oracle", oracle)
            .flag("grid", "1x6")
            .flag("blocks", "3")
            .flag("episodes", "200")
            .arg("--json")
            .run();
        assert!(o.status.success(), "{oracle}: {}", stderr(&o));
        let report: serde_json::Value = serde_json::from_str(&stdout(&o)).expect("json");
        assert_eq!(report["episodes"], 200, "{report}");
        assert_eq!(report["failures"], 0, "{report}");
    }
}

#[test]
fn flags_that_do_not_apply_are_refused_naming_the_flag() {
    for (args, message) in [
        (&["render", "--horizon", "5"][..], "--horizon does not apply to render"),
        (&["render", "--reward", "sparse"], "--reward does not apply to render"),
        (
            &["run", "--agent", "random", "--epsilon", "5"],
            "--epsilon does not apply to --agent random: it is for --agent q, dqn or relational only",
        ),
        (
            &["run", "--agent", "oracle", "--model", "m.st"],
            "--model does not apply to --agent oracle",
        ),
        (
            &["run", "--agent", "exact", "--oracle", "paper"],
            "--oracle does not apply to --agent exact",
        ),
    ] {
        let o = blockstack(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    // Where they apply, they are taken.
    for args in [
        &["render", "--seed", "3"][..],
        &["run", "--agent", "random", "--horizon", "5", "--episodes", "2"],
    ] {
        let o = blockstack(args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    }
}
