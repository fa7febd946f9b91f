//! `blockstack dqn --preset general`: the relational policy trained, then played by `run`
//! in the side view (and from a PDDL task's start, `run --pddl`), by `solve --pddl` as a
//! plan in the competitions' format and by `solve-all` over a folder; its flags and worlds
//! refused in one line.

use std::path::{Path, PathBuf};

use crate::common::{blockstack, cli, file_metadata, path, scratch, stderr};

/// A short run (seconds), saved under `name`.
fn train(dir: &Path, name: &str) -> PathBuf {
    let out = dir.join(name);
    let text = cli("dqn")
        .flag("preset", "general")
        // The preset's problems of up to 20 blocks take a minute to label; 6 take seconds.
        .flag("blocks", 6)
        .flag("steps", 20)
        .flag("batch", 16)
        .flag("seed", 3)
        .flag("out", path(&out))
        .ok();
    assert!(
        text.contains("trained relational policy") && text.contains("saved"),
        "{text}"
    );
    out
}

#[test]
fn the_general_preset_trains_a_policy_that_run_solve_and_solve_all_play() {
    let dir = scratch("general");
    let model = train(&dir, "general.safetensors");
    let meta = file_metadata(&model, "blockstack-relational");
    assert_eq!(meta["config"]["max_blocks"], 6);
    assert_eq!(
        meta["report"].as_array().unwrap().len(),
        10,
        "one report per DAgger iteration"
    );

    // The side view, at the model's default world and at another size; the top view refused.
    // `relational` is its kind's name; `dqn`, earlier releases' name for it, plays it too.
    let run = |agent: &str, blocks: usize| {
        cli("run")
            .args(&["--view", "side", "--agent", agent, "--backend", "grid"])
            .flag("model", path(&model))
            .flag("blocks", blocks)
            .flag("episodes", 3)
            .arg("--json")
            .json()
    };
    for (agent, blocks) in [("relational", 3), ("dqn", 6)] {
        let r = run(agent, blocks);
        assert_eq!(r["agent"], "relational", "{r}");
        assert_eq!(r["episodes"], 3, "{r}");
    }
    let top = blockstack(&["run", "--view", "top", "--agent", "dqn", "--model", path(&model)]);
    let e = stderr(&top);
    assert!(
        !top.status.success() && e.contains("side view") && e.lines().count() == 1,
        "{e}"
    );
    let q = blockstack(&["run", "--agent", "q", "--model", path(&model)]);
    assert!(stderr(&q).contains("not what --agent q plays"), "{}", stderr(&q));

    // PDDL problems: a plan in the competitions' format, replayed over the file's facts; a
    // folder planned as the near-optimal planner plans it.
    let tasks = dir.join("tasks");
    cli("generate")
        .flag("blocks", 8)
        .flag("count", 3)
        .flag("seed", 5)
        .flag("out", path(&tasks))
        .ok();
    let plan = cli("solve")
        .flag("pddl", path(&tasks.join("p01.pddl")))
        .flag("model", path(&model))
        .arg("--json")
        .json();
    assert_eq!(plan["actions"].as_u64().unwrap(), 2 * plan["moves"].as_u64().unwrap());
    // `run --pddl` plays the task's episodes with the policy, at the task's size.
    let r = cli("run")
        .flag("pddl", path(&tasks.join("p01.pddl")))
        .args(&["--agent", "dqn", "--backend", "grid", "--episodes", "2", "--json"])
        .flag("model", path(&model))
        .json();
    assert_eq!(
        (&r["agent"], &r["blocks"], &r["start"], &r["episodes"]),
        (&"relational".into(), &8.into(), &"pddl".into(), &2.into()),
        "{r}"
    );
    let all = cli("solve-all")
        .flag("tasks", path(&tasks))
        .flag("model", path(&model))
        .arg("--json")
        .json();
    assert_eq!(all["solver"], "relational policy");
    assert_eq!(all["overall"]["tasks"], 3);
    // A model of another kind is not a policy of block moves.
    let tabular = dir.join("q.safetensors");
    cli("train").flag("games", 10).flag("out", path(&tabular)).ok();
    let wrong = blockstack(&[
        "solve",
        "--pddl",
        path(&tasks.join("p01.pddl")),
        "--model",
        path(&tabular),
    ]);
    let e = stderr(&wrong);
    assert!(
        !wrong.status.success() && e.contains("relational policy") && e.lines().count() == 1,
        "{e}"
    );
}

#[test]
fn flags_the_general_preset_does_not_take_are_refused_in_one_line() {
    let dir = scratch("general-flags");
    for flag in [["--grid", "5x5"], ["--reward", "sparse"], ["--gamma", "0.9"]] {
        let out = dir.join("never.safetensors");
        let o = blockstack(&[&["dqn", "--preset", "general", "--out", path(&out)][..], &flag[..]].concat());
        let e = stderr(&o);
        assert!(!o.status.success() && e.lines().count() == 1, "{e}");
        assert!(
            e.contains(&format!("{} does not apply to --preset general", flag[0])),
            "{e}"
        );
        assert!(!out.exists());
    }
    let o = blockstack(&[
        "dqn",
        "--preset",
        "general",
        "--blocks",
        "65",
        "--out",
        path(&dir.join("x")),
    ]);
    assert!(stderr(&o).contains("choose 2 to 64"), "{}", stderr(&o));
}
