//! The field's files from the command line: `generate` writes PDDL problems, `solve --pddl`
//! prints plans in the competitions' format, `solve-all` plans a folder against best known
//! costs; bad files are refused in one line.

use crate::common::{Cli, blockstack, cli, path, scratch, stderr};

/// The IPC actions of a plan printed by `solve --pddl`, checked to be of the format.
fn actions(plan: &str) -> Vec<String> {
    let mut lines: Vec<&str> = plan.lines().collect();
    let cost = lines.pop().expect("a cost line");
    let actions: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    assert_eq!(cost, format!("; cost = {} (unit cost)", actions.len()));
    for a in &actions {
        let words: Vec<&str> = a.trim_start_matches('(').trim_end_matches(')').split(' ').collect();
        let arity = match words[0] {
            "pickup" | "putdown" => 1,
            "stack" | "unstack" => 2,
            other => panic!("{other} in {plan}"),
        };
        assert_eq!(words.len(), arity + 1, "{a}");
    }
    actions
}

#[test]
fn generate_writes_problems_that_solve_and_solve_all_plans_a_folder() {
    let dir = scratch("pddl");
    let uniform = dir.join("tasks/uniform");
    let ipc = dir.join("tasks/ipc");
    let gen_ = |out: &std::path::Path, shape: &str| {
        cli("generate")
            .args(&["--view", "side"])
            .flag("blocks", 12)
            .flag("count", 3)
            .flag("seed", 7)
            .flag("shape", shape)
            .flag("out", path(out))
            .ok()
    };
    assert!(gen_(&uniform, "uniform").contains("wrote 3 problems of 12 blocks"));
    gen_(&ipc, "ipc");
    let p01 = std::fs::read_to_string(uniform.join("p01.pddl")).unwrap();
    assert!(p01.starts_with(";; blockstack generate --blocks 12 --seed 7 --shape uniform: problem 01 of 3\n"));
    assert!(p01.contains("(:objects b1 b2 b3 b4 b5 b6 b7 b8 b9 b10 b11 b12 - object)"));
    // Same seed, same files; the shapes differ.
    let again = dir.join("again");
    gen_(&again, "uniform");
    assert_eq!(
        std::fs::read_to_string(again.join("p03.pddl")).unwrap(),
        std::fs::read_to_string(uniform.join("p03.pddl")).unwrap()
    );
    assert_ne!(std::fs::read_to_string(ipc.join("p01.pddl")).unwrap(), p01);

    // The exact and near-optimal plans of one problem: the format, two actions a move, and
    // the exact plan never longer.
    let solve = |solver: &str| {
        cli("solve")
            .flag("pddl", path(&uniform.join("p02.pddl")))
            .flag("solver", solver)
            .arg("--json")
    };
    let exact = solve("exact").json();
    let near = solve("near-optimal").json();
    for j in [&exact, &near] {
        assert_eq!(j["actions"].as_u64().unwrap(), 2 * j["moves"].as_u64().unwrap());
        assert_eq!(
            j["plan"].as_array().unwrap().len() as u64,
            j["actions"].as_u64().unwrap()
        );
    }
    assert!(exact["moves"].as_u64() <= near["moves"].as_u64());
    let text = cli("solve").flag("pddl", path(&uniform.join("p02.pddl"))).ok();
    let printed = actions(&text);
    assert_eq!(serde_json::json!(printed), near["plan"]);

    // A bounds file keyed by path suffix; a bad file is a row with its error, not the end.
    std::fs::write(
        dir.join("bounds.json"),
        format!(
            r#"{{"tasks/uniform/p02.pddl": {}, "ipc/p01.pddl": 1000}}"#,
            exact["actions"]
        ),
    )
    .unwrap();
    std::fs::write(dir.join("tasks/domain.pddl"), "(define (domain blocksworld))").unwrap();
    std::fs::write(dir.join("tasks/uniform/p09.pddl"), "(define (problem x)").unwrap();
    let all = cli("solve-all")
        .flag("tasks", path(&dir.join("tasks")))
        .flag("bounds", path(&dir.join("bounds.json")))
        .arg("--json")
        .json();
    let tasks = all["tasks"].as_array().unwrap();
    assert_eq!(tasks.len(), 7, "{all}");
    assert_eq!(tasks[0]["task"], "ipc/p01.pddl");
    assert_eq!(tasks[0]["bound"], 1000);
    let p02 = tasks.iter().find(|t| t["task"] == "uniform/p02.pddl").unwrap();
    assert_eq!(
        p02["ratio"].as_f64().unwrap(),
        near["actions"].as_f64().unwrap() / exact["actions"].as_f64().unwrap()
    );
    let bad = tasks.iter().find(|t| t["task"] == "uniform/p09.pddl").unwrap();
    assert!(bad["error"].as_str().unwrap().contains("never closed"), "{bad}");
    assert_eq!(all["overall"]["tasks"], 7);
    assert_eq!(all["overall"]["solved"], 6);
    assert_eq!(all["overall"]["bounded"], 2);
    let groups: Vec<&str> = all["groups"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["group"].as_str().unwrap())
        .collect();
    assert_eq!(groups, ["ipc", "uniform"]);
    let table = cli("solve-all").flag("tasks", path(&dir.join("tasks"))).ok();
    assert!(
        table.contains("near-optimal plans, each replayed over its file's facts"),
        "{table}"
    );
}

#[test]
fn bad_problems_and_flags_are_refused_in_one_line() {
    let dir = scratch("pddl-bad");
    let file = dir.join("p.pddl");
    std::fs::write(
        &file,
        "(define (problem p) (:domain blocksworld) (:objects b1 b2)\n (:init (arm-empty) (clear b1) (on b1 b2) (on-table b2))\n (:goal (and (on b2 b1))))",
    )
    .unwrap();
    let refused = |c: Cli, expect: &str| {
        let o = c.run();
        assert_eq!(o.status.code(), Some(2), "{:?}", c.argv());
        let err = stderr(&o);
        assert!(err.contains(expect), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    };
    refused(
        cli("solve").flag("pddl", path(&file)),
        "line 3: the goal puts b2 on b1 but does not say what b1 stands on",
    );
    refused(
        cli("solve").flag("pddl", path(&dir.join("missing.pddl"))),
        "missing.pddl",
    );
    refused(
        cli("solve")
            .flag("pddl", path(&file))
            .flag("solver", "near-optimal")
            .flag("solver-budget", 10),
        "--solver-budget is the exact solver's",
    );
    refused(
        cli("generate")
            .flag("blocks", 3)
            .flag("view", "top")
            .flag("out", path(&dir)),
        "--view top",
    );
    refused(cli("solve-all").flag("tasks", path(&dir.join("nothing"))), "--tasks");
    // clap's own refusals name the flags.
    let o = blockstack(&["solve", "--pddl", path(&file), "--start", "0,0"]);
    assert!(stderr(&o).contains("cannot be used with"), "{}", stderr(&o));
}

#[test]
fn the_exact_solver_refuses_what_its_budget_cannot_finish() {
    let dir = scratch("pddl-budget");
    cli("generate")
        .flag("blocks", 20)
        .flag("seed", 3)
        .flag("out", path(&dir))
        .ok();
    let o = cli("solve")
        .flag("pddl", path(&dir.join("p01.pddl")))
        .flag("solver", "exact")
        .flag("solver-budget", 1000)
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("--solver-budget 1000: the exact block-move search generated its budget"),
        "{}",
        stderr(&o)
    );
    let o = cli("generate").flag("blocks", 30).flag("out", path(&dir)).ok();
    assert!(o.contains("30 blocks"));
    let o = cli("solve")
        .flag("pddl", path(&dir.join("p01.pddl")))
        .flag("solver", "exact")
        .run();
    assert!(stderr(&o).contains("takes at most 25 blocks, not 30"), "{}", stderr(&o));
}
