//! The field's files from the command line: `generate` writes PDDL problems, `solve --pddl`
//! prints plans in the competitions' format, `solve-all` plans a folder against best known
//! costs; bad files are refused in one line.

use crate::common::{Cli, blockstack, cli, path, scratch, stderr};

/// The IPC actions of a plan printed by `solve --pddl`, checked to be of the format: the
/// actions, the cost, the lower bound, and `; optimal` if it is proven.
fn actions(plan: &str) -> Vec<String> {
    let mut lines: Vec<&str> = plan.lines().collect();
    let mut last = lines.pop().expect("a bound line");
    let proven = last == "; optimal";
    if proven {
        last = lines.pop().expect("a bound line");
    }
    let bound: usize = last.strip_prefix("; lower bound = ").expect(plan).parse().unwrap();
    let cost = lines.pop().expect("a cost line");
    let actions: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    assert_eq!(cost, format!("; cost = {} (unit cost)", actions.len()));
    assert!(bound <= actions.len());
    assert_eq!(proven, bound == actions.len());
    for a in &actions {
        let words: Vec<&str> = a.trim_start_matches('(').trim_end_matches(')').split(' ').collect();
        let arity = match words[0] {
            "pickup" | "putdown" | "pick-up" | "put-down" => 1,
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
    // The optimal solver proves the exact solver's optimum; every plan carries its bound.
    let optimal = solve("optimal").json();
    assert_eq!(optimal["moves"], exact["moves"]);
    assert_eq!(optimal["optimal"], true);
    assert_eq!(optimal["lower_bound"], optimal["actions"]);
    assert_eq!(exact["lower_bound"], exact["actions"]);
    assert!(near["lower_bound"].as_u64() <= near["actions"].as_u64());
    let c = &optimal["certificate"];
    let parts = c["misplaced"].as_u64().unwrap() + c["forced"].as_u64().unwrap() + c["breakers"].as_u64().unwrap();
    assert_eq!(2 * parts, optimal["lower_bound"].as_u64().unwrap());
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
    assert_eq!(tasks[0]["best_known"], 1000);
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
    let proven = cli("solve-all")
        .flag("tasks", path(&dir.join("tasks")))
        .flag("solver", "optimal")
        .flag("time-limit", 30)
        .arg("--json")
        .json();
    assert_eq!(proven["solver"], "optimal");
    assert_eq!(proven["overall"]["optimal"], 6, "{proven}");
    assert!(
        proven["tasks"]
            .as_array()
            .unwrap()
            .iter()
            .all(|t| t["error"].is_string() || t["gap"] == 0)
    );
    // Each task's CPU time on the one thread that planned it, beside its wall time.
    for t in proven["tasks"].as_array().unwrap() {
        let (cpu, wall) = (t["cpu_seconds"].as_f64().unwrap(), t["seconds"].as_f64().unwrap());
        assert!((0.0..=wall + 1e-3).contains(&cpu), "{t}");
    }
    // The optimal solver's report is the optima another planner is set against.
    let optima = dir.join("optima.json");
    std::fs::write(&optima, proven.to_string()).unwrap();
    let against = cli("solve-all")
        .flag("tasks", path(&dir.join("tasks")))
        .flag("optima", path(&optima))
        .arg("--json")
        .json();
    for t in against["tasks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|t| t["error"].is_null())
    {
        assert!(t["optimum"].as_u64().is_some(), "{t}");
        assert!(t["over_optimum"].as_f64().unwrap() >= 1.0, "{t}");
    }
    assert!(against["overall"]["mean_over_optimum"].as_f64().unwrap() >= 1.0);
    let table = cli("solve-all").flag("tasks", path(&dir.join("tasks"))).ok();
    assert!(
        table.contains("near-optimal plans, each replayed over its file's facts")
            && table.lines().next().unwrap().ends_with("seconds    cpu s."),
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
        "--solver-budget: the search budget is the exact solver's",
    );
    refused(
        cli("solve")
            .flag("pddl", path(&file))
            .flag("solver", "exact")
            .flag("time-limit", 1),
        "--time-limit: the time limit is the optimal solver's",
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

/// `run --pddl` on the grid backend, as JSON, with `extra` flags.
fn run_pddl(problem: &std::path::Path, agent: &str, extra: &[&str]) -> Cli {
    cli("run")
        .flag("pddl", path(problem))
        .flag("agent", agent)
        .args(&["--backend", "grid", "--episodes", "3", "--json"])
        .args(extra)
}

#[test]
fn run_plays_a_problem_from_its_start_towards_its_goal() {
    let dir = scratch("pddl-run");
    cli("generate")
        .args(&["--view", "side"])
        .flag("blocks", 4)
        .flag("count", 1)
        .flag("seed", 11)
        .flag("out", path(&dir))
        .ok();
    let problem = dir.join("p01.pddl");
    // Every planner agent reaches the task's goal in every episode.
    let mut steps = std::collections::BTreeMap::new();
    for agent in ["exact", "exact-moves", "near-optimal", "oracle"] {
        let r = run_pddl(&problem, agent, &[]).json();
        assert_eq!(
            (r["blocks"].as_u64(), r["grid"].as_str(), r["start"].as_str()),
            (Some(4), Some("7x7"), Some("pddl")),
            "{r}"
        );
        assert_eq!(
            (r["episodes"].as_u64(), r["failures"].as_u64()),
            (Some(3), Some(0)),
            "{agent}: {r}"
        );
        steps.insert(agent, r["mean_steps"].as_f64().unwrap());
        // The report names the task, not its towers (a big task's goal is kilobytes).
        assert_eq!(
            r["goal"].as_str(),
            Some(format!("the task's ({})", path(&problem)).as_str()),
            "{r}"
        );
    }
    // Every episode starts from the task's start, and the exact agent takes as few gripper
    // steps as the exact solver finds from there.
    let trajectory = dir.join("exact.jsonl");
    run_pddl(&problem, "exact", &["--trajectory", path(&trajectory)]).ok();
    let text = std::fs::read_to_string(&trajectory).unwrap();
    let episodes: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|v| v.get("start").is_some())
        .collect();
    assert_eq!(episodes.len(), 3);
    // The episode's goal, as `--goal` writes it: towers bottom to top, `/` between them.
    let towers: Vec<String> = episodes[0]["goal"]["towers"]
        .as_array()
        .expect("the episode's goal")
        .iter()
        .map(|t| {
            t.as_array()
                .unwrap()
                .iter()
                .map(|b| b.to_string())
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect();
    let goal = towers.join("/");
    assert!(episodes.iter().all(|e| e["start"] == episodes[0]["start"]), "{text}");
    let start: Vec<String> = episodes[0]["start"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| format!("{},{}", c[0], c[1]))
        .collect();
    let optimum = cli("solve")
        .args(&["--view", "side", "--cost", "steps", "--solver", "exact", "--json"])
        .flag("start", start.join(";"))
        .flag("goal", &goal)
        .json();
    assert_eq!(steps["exact"], optimum["length"].as_f64().unwrap(), "{optimum}");
    assert!(steps.values().all(|&s| s >= steps["exact"]), "{steps:?}");

    // A random agent plays from the same start too (its own draws differ by episode).
    let random = dir.join("random.jsonl");
    run_pddl(&problem, "random", &["--trajectory", path(&random), "--horizon", "20"]).ok();
    let starts: Vec<serde_json::Value> = std::fs::read_to_string(&random)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter_map(|v| v.get("start").cloned())
        .collect();
    assert_eq!(starts, vec![episodes[0]["start"].clone(); 3]);

    // A tabular model plays the task of its own size, and refuses another in one line.
    let model = dir.join("q.safetensors");
    cli("train")
        .args(&["--view", "side", "--backend", "grid", "--games", "50"])
        .flag("out", path(&model))
        .ok();
    cli("generate")
        .args(&["--view", "side"])
        .flag("blocks", 3)
        .flag("count", 1)
        .flag("out", path(&dir.join("three")))
        .ok();
    let r = run_pddl(&dir.join("three/p01.pddl"), "q", &["--model", path(&model)]).json();
    assert_eq!(
        (r["blocks"].as_u64(), r["episodes"].as_u64()),
        (Some(3), Some(3)),
        "{r}"
    );
    let o = run_pddl(&problem, "q", &["--model", path(&model)]).run();
    let e = stderr(&o);
    assert!(
        !o.status.success() && e.contains("3 blocks") && e.contains("4 blocks") && e.trim_end().lines().count() == 1,
        "{e}"
    );
}

#[test]
fn run_refuses_a_problem_with_flags_of_another_world_in_one_line() {
    let dir = scratch("pddl-run-bad");
    cli("generate")
        .args(&["--view", "side"])
        .flag("blocks", 3)
        .flag("count", 1)
        .flag("out", path(&dir))
        .ok();
    let problem = dir.join("p01.pddl");
    for (flag, value) in [("goal", "0,1,2"), ("blocks", "3"), ("grid", "7x7")] {
        let o = blockstack(&["run", "--pddl", path(&problem), &format!("--{flag}"), value]);
        let e = stderr(&o);
        assert!(
            o.status.code() == Some(2) && e.contains("cannot be used with") && e.contains(&format!("--{flag}")),
            "{e}"
        );
    }
    let o = blockstack(&["run", "--pddl", path(&problem), "--view", "top"]);
    let e = stderr(&o);
    assert!(e.contains("--view top") && e.trim_end().lines().count() == 1, "{e}");
    let o = blockstack(&["run", "--pddl", path(&dir.join("missing.pddl"))]);
    let e = stderr(&o);
    assert!(e.contains("missing.pddl") && e.trim_end().lines().count() == 1, "{e}");
    // More blocks than the side view holds.
    let big = dir.join("big.pddl");
    let names: Vec<String> = (1..=10_001).map(|i| format!("b{i}")).collect();
    let init: String = names.iter().map(|n| format!("(on-table {n}) (clear {n}) ")).collect();
    std::fs::write(
        &big,
        format!(
            "(define (problem big) (:domain blocksworld) (:objects {}) (:init (arm-empty) {init}) (:goal (and (on b1 b2) (on-table b2))))",
            names.join(" ")
        ),
    )
    .unwrap();
    let o = blockstack(&["run", "--pddl", path(&big)]);
    let e = stderr(&o);
    assert!(
        e.contains("big.pddl") && e.contains("10001") && e.trim_end().lines().count() == 1,
        "{e}"
    );
}

/// A fixture of the Python package's tests (`python/tests/fixtures`), shared here.
fn fixture(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("python/tests/fixtures")
        .join(name)
}

#[test]
fn a_domain_file_names_the_plans_actions_and_anything_else_is_refused() {
    let problem = fixture("problem-pick-up.pddl");
    let plain = cli("solve").flag("pddl", path(&problem)).ok();
    let hyphenated = cli("solve")
        .flag("pddl", path(&problem))
        .flag("domain", path(&fixture("domain-pick-up.pddl")))
        .ok();
    let (plain, hyphenated) = (actions(&plain), actions(&hyphenated));
    assert!(plain.iter().any(|a| a.starts_with("(pickup ")), "{plain:?}");
    assert!(hyphenated.iter().any(|a| a.starts_with("(pick-up ")), "{hyphenated:?}");
    assert!(hyphenated.iter().any(|a| a.starts_with("(put-down ")), "{hyphenated:?}");
    let renamed: Vec<String> = plain
        .iter()
        .map(|a| a.replace("(pickup", "(pick-up").replace("(putdown", "(put-down"))
        .collect();
    assert_eq!(renamed, hyphenated);
    // The other spelling's domain, and its problem.
    let json = cli("solve")
        .flag("pddl", path(&fixture("problem-pickup.pddl")))
        .flag("domain", path(&fixture("domain-pickup.pddl")))
        .args(&["--json", "--solver", "optimal"])
        .json();
    assert_eq!(json["optimal"], true, "{json}");
    let refused = |c: Cli, expect: &str| {
        let o = c.run();
        let err = stderr(&o);
        assert!(o.status.code() == Some(2) && err.contains(expect), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    };
    refused(
        cli("solve")
            .flag("pddl", path(&fixture("problem-pickup.pddl")))
            .flag("domain", path(&fixture("domain-gripper.pddl"))),
        "the predicate (at-robby ?r) is not one of the 4-operator Blocks World's",
    );
    refused(
        cli("solve")
            .flag("pddl", path(&fixture("problem-pickup.pddl")))
            .flag("domain", path(&fixture("domain-pick-up.pddl"))),
        "the problem is of the domain blocksworld, but the domain file defines BLOCKS",
    );
    refused(
        cli("solve").flag("pddl", path(&fixture("problem-gripper.pddl"))),
        "(:domain gripper) is not the Blocks World",
    );
    refused(
        cli("solve")
            .flag("pddl", path(&fixture("domain-pickup.pddl")))
            .flag("domain", path(&fixture("domain-pickup.pddl"))),
        "this is a domain file: give the problem file",
    );
    let o = blockstack(&[
        "solve",
        "--domain",
        path(&fixture("domain-pickup.pddl")),
        "--start",
        "0,0",
        "--goal",
        "0",
    ]);
    assert!(stderr(&o).contains("--domain goes with --pddl"), "{}", stderr(&o));
}

#[test]
fn the_plan_file_holds_what_solve_prints_and_only_a_regular_file_is_written() {
    let dir = scratch("pddl-plan-file");
    let problem = fixture("problem-pick-up.pddl");
    let domain = fixture("domain-pick-up.pddl");
    let printed = cli("solve")
        .flag("pddl", path(&problem))
        .flag("domain", path(&domain))
        .ok();
    let plan = dir.join("plan.txt");
    std::fs::write(&plan, "an older plan").unwrap();
    let said = cli("solve")
        .flag("pddl", path(&problem))
        .flag("domain", path(&domain))
        .flag("plan-file", path(&plan))
        .ok();
    assert_eq!(std::fs::read_to_string(&plan).unwrap(), printed);
    assert!(
        said.starts_with(&format!("wrote the plan to {}: cost ", path(&plan))),
        "{said}"
    );
    assert_eq!(said.lines().count(), 1, "{said}");
    // --json prints its report as without the file.
    let json = cli("solve")
        .flag("pddl", path(&problem))
        .flag("plan-file", path(&dir.join("p.txt")))
        .arg("--json")
        .json();
    let written = std::fs::read_to_string(dir.join("p.txt")).unwrap();
    assert_eq!(json["plan"].as_array().unwrap().len(), actions(&written).len());
    let refused = |c: Cli, expect: &str| {
        let o = c.run();
        let err = stderr(&o);
        assert!(o.status.code() == Some(2) && err.contains(expect), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    };
    let fifo = dir.join("pipe");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    refused(
        cli("solve").flag("pddl", path(&problem)).flag("plan-file", path(&fifo)),
        "it is a named pipe, not a regular file",
    );
    refused(
        cli("solve").flag("pddl", path(&problem)).flag("plan-file", path(&dir)),
        "--plan-file",
    );
    let copy = dir.join("copy.pddl");
    std::fs::copy(&problem, &copy).unwrap();
    refused(
        cli("solve").flag("pddl", path(&copy)).flag("plan-file", path(&copy)),
        "is also the input",
    );
    assert_eq!(std::fs::read(&copy).unwrap(), std::fs::read(&problem).unwrap());
}

#[test]
fn what_other_tools_write_in_a_problem_is_read_or_refused_by_name() {
    let dir = scratch("pddl-other-tools");
    let write = |name: &str, text: &str| {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        file
    };
    let metric = write(
        "metric.pddl",
        "(define (problem m) (:domain blocksworld) (:objects a - block b - (either block thing))
          (:init (= (total-cost) 0) (arm-empty) (clear a) (on a b) (on-table b))
          (:goal (and (on b a) (on-table a))) (:metric minimize (total-cost)))",
    );
    assert_eq!(actions(&cli("solve").flag("pddl", path(&metric)).ok()).len(), 4);
    let synonyms = write(
        "ipc2000.pddl",
        "(define (problem s) (:domain BLOCKS) (:objects a b)
          (:init (handempty) (clear a) (on a b) (ontable b)) (:goal (and (on b a) (ontable a))))",
    );
    assert_eq!(actions(&cli("solve").flag("pddl", path(&synonyms)).ok()).len(), 4);
    let logistics = write(
        "logistics.pddl",
        "(define (problem l) (:domain logistics) (:objects a) (:init (arm-empty) (clear a) (on-table a)) (:goal (and (on-table a))))",
    );
    let o = cli("solve").flag("pddl", path(&logistics)).run();
    assert!(
        stderr(&o).contains("line 1: (:domain logistics) is not the Blocks World"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_task_with_nothing_to_play_is_solved_by_the_empty_plan_and_not_played() {
    let dir = scratch("pddl-nothing");
    let head = "(define (problem p) (:domain blocksworld) (:objects b1 b2)
      (:init (arm-empty) (clear b2) (on b2 b1) (on-table b1))";
    for (name, goal, says) in [
        (
            "met.pddl",
            "(:goal (and (on b2 b1) (on-table b1))))",
            "its goal, so there is no episode to play",
        ),
        (
            "empty.pddl",
            "(:goal (and)))",
            "its goal (which places no block), so there is no episode to play",
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, format!("{head} {goal}")).unwrap();
        let plan = cli("solve").flag("pddl", path(&file)).ok();
        assert_eq!(plan, "; cost = 0 (unit cost)\n; lower bound = 0\n; optimal\n");
        let o = run_pddl(&file, "near-optimal", &[]).run();
        let e = stderr(&o);
        assert!(
            o.status.code() == Some(2) && e.contains(&format!("{name}: the task's start already meets")),
            "{e}"
        );
        assert!(e.contains(says) && e.trim_end().lines().count() == 1, "{e}");
    }
}

#[test]
fn run_refuses_a_start_rule_and_says_when_the_horizon_is_too_short() {
    let problem = fixture("problem-pickup.pddl");
    let o = blockstack(&["run", "--pddl", path(&problem), "--start", "uniform"]);
    let e = stderr(&o);
    assert!(
        o.status.code() == Some(2) && e.contains("cannot be used with") && e.contains("--start"),
        "{e}"
    );
    let o = run_pddl(&problem, "near-optimal", &["--horizon", "5"]).run();
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("the horizon of 5 steps is shorter than the near-optimal plan of this task (")
            && e.contains("give --horizon "),
        "{e}"
    );
    let o = run_pddl(&problem, "near-optimal", &[]).run();
    assert!(!stderr(&o).contains("horizon"), "{}", stderr(&o));
}
