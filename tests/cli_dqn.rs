//! `blockstack dqn`, and `eval` / `run --agent dqn` playing its network files, end to end,
//! with their answers to bad input.

use std::path::{Path, PathBuf};

use crate::common::{blockstack, cli, file_metadata, path, scratch, stderr, stdout};

/// A tiny DQfD run on 2 blocks (seconds), saved under `name`.
fn train(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec![
        "dqn",
        "--blocks",
        "2",
        "--demos",
        "exact:100",
        "--pretrain",
        "300",
        "--steps",
        "200",
        "--hidden",
        "64",
        "--seed",
        "4",
        "--out",
        path(&out),
    ];
    args.extend(extra);
    let o = blockstack(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    // Not a terminal: no progress bar, nothing on stderr.
    assert_eq!(stderr(&o), "");
    let text = stdout(&o);
    assert!(text.contains("trained dqn-small") && text.contains("saved"), "{text}");
    out
}

#[test]
fn a_trained_network_is_evaluated_and_played_like_a_tabular_model() {
    let dir = scratch("dqn-eval");
    let net = train(&dir, "net.safetensors", &[]);
    let v: serde_json::Value = cli("eval")
        .flag("model", path(&net))
        .flag("episodes", "20")
        .flag("epsilon", "0")
        .flag("backend", "grid")
        .arg("--json")
        .json();
    assert_eq!(v["agent"], "dqn-small");
    assert_eq!(v["episodes"], 40);
    assert_eq!(v["per_goal"].as_array().unwrap().len(), 2);
    let o = cli("run")
        .flag("agent", "dqn")
        .flag("model", path(&net))
        .flag("blocks", "2")
        .flag("goal", "1,0")
        .flag("episodes", "5")
        .flag("epsilon", "0")
        .arg("--json")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("\"agent\":\"dqn-small\""), "{}", stdout(&o));
    // The same seed gives the same tensors, byte for byte (the file's metadata is a map
    // that safetensors writes in no fixed order).
    let again = train(&dir, "again.safetensors", &[]);
    let tensors = |p: &Path| {
        let bytes = std::fs::read(p).unwrap();
        let header = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
        bytes[8 + header..].to_vec()
    };
    assert_eq!(tensors(&net), tensors(&again));
}

#[test]
fn bad_files_and_arguments_are_one_line_and_status_2() {
    let dir = scratch("dqn-bad");
    let net = train(&dir, "net.safetensors", &["--loss", "dqn"]);
    let mut bytes = std::fs::read(&net).unwrap();
    let n = bytes.len();
    bytes[n - 5] ^= 0x10;
    let corrupt = dir.join("corrupt.safetensors");
    std::fs::write(&corrupt, &bytes).unwrap();
    let truncated = dir.join("truncated.safetensors");
    std::fs::write(&truncated, &bytes[..n / 2]).unwrap();
    for (file, says) in [(&corrupt, "checksum"), (&truncated, "truncated")] {
        let o = cli("eval").flag("model", path(file)).flag("episodes", "1").run();
        assert_eq!(o.status.code(), Some(2));
        let err = stderr(&o);
        assert!(err.contains(says) && err.lines().count() == 1, "{err}");
    }
    // A network is not what --agent q plays, and a 2-block network does not play 3 blocks.
    let o = cli("run")
        .flag("agent", "q")
        .flag("model", path(&net))
        .flag("blocks", "2")
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not what --agent q plays"), "{}", stderr(&o));
    let o = cli("run")
        .flag("agent", "dqn")
        .flag("model", path(&net))
        .flag("blocks", "3")
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("does not fit"), "{}", stderr(&o));
    let x = dir.join("x.safetensors");
    for (args, says) in [
        (vec!["--preset", "nope"], "unknown preset"),
        (vec!["--obs", "role-planes", "--net", "paper"], "reads paper-screen"),
        (vec!["--obs", "planes"], "called role-planes now"),
        (vec!["--obs", "pixels"], "paper-screen"),
        (vec!["--net", "small", "--screen", "strip"], "only the conv network"),
        (vec!["--net", "conv", "--obs", "paper-screen"], "`--screen paper`"),
        (
            vec!["--preset", "pixels", "--screen", "paper", "--grid", "7x5"],
            "square grid",
        ),
        (
            vec!["--preset", "pixels", "--screen", "corner"],
            "choose one of colours, strip",
        ),
        (vec!["--demos", "people:3"], "exact:K"),
        (
            vec!["--pretrain", "5", "--demos", "none"],
            "pre-training needs demonstrations",
        ),
    ] {
        let mut all = vec!["dqn", "--out", path(&x)];
        all.extend(args);
        let o = blockstack(&all);
        assert_eq!(o.status.code(), Some(2), "{all:?}");
        assert!(stderr(&o).contains(says), "{all:?}: {}", stderr(&o));
    }
    // Sizes too large to allocate are refused before anything is, in one line (these
    // aborted, or grew to 19 GB).
    for (args, says) in [
        (vec!["--demos", "exact:1000000000"], "--demos exact:1000000000"),
        (vec!["--batch", "1000000000000"], "--batch 1000000000000"),
        (vec!["--batch", "1000000", "--buffer", "1000000"], "--batch 1000000"),
        (vec!["--batch", "1000000"], "larger than the buffer"),
        (vec!["--buffer", "10", "--batch", "64"], "--buffer 10"),
    ] {
        let mut all = vec!["dqn", "--out", path(&x)];
        all.extend(args);
        let o = blockstack(&all);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{all:?}: {err}");
        assert!(err.contains(says) && err.lines().count() == 1, "{all:?}: {err}");
    }
    assert!(!x.exists());
}

#[test]
fn demonstrations_come_from_a_trajectory_file_too() {
    let dir = scratch("dqn-demos-file");
    let trajectory = dir.join("t.jsonl");
    let o = cli("run")
        .flag("agent", "exact")
        .flag("blocks", "2")
        .flag("episodes", "30")
        .flag("backend", "grid")
        .flag("trajectory", path(&trajectory))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.join("net.safetensors");
    let o = cli("dqn")
        .flag("blocks", "2")
        .flag("demos-file", path(&trajectory))
        .flag("pretrain", "50")
        .flag("steps", "50")
        .flag("hidden", "32")
        .flag("out", path(&out))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("30 demonstrated episodes"), "{}", stdout(&o));
    let missing = dir.join("missing.jsonl");
    let o = cli("dqn")
        .flag("blocks", "2")
        .flag("demos-file", path(&missing))
        .flag("out", path(&out))
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("missing.jsonl"), "{}", stderr(&o));
}

#[test]
fn an_untrained_network_is_warned_about_and_marked_in_its_file() {
    let dir = scratch("dqn-untrained");
    // No steps at all, and fewer steps than self-play's learning start: no gradient step.
    for steps in ["0", "50"] {
        let out = dir.join(format!("untrained-{steps}.safetensors"));
        let o = cli("dqn")
            .flag("blocks", "2")
            .flag("loss", "dqn")
            .flag("steps", steps)
            .flag("hidden", "16")
            .flag("out", path(&out))
            .run();
        assert!(o.status.success(), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(err.contains("warning: the network is untrained"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        let warnings = &file_metadata(&out, "blockstack-dqn")["warnings"];
        assert!(warnings[0].as_str().unwrap().contains("untrained"), "{warnings}");
        // The file still reads and plays.
        let o = cli("eval").flag("model", path(&out)).flag("episodes", "1").run();
        assert!(o.status.success(), "{}", stderr(&o));
    }
    // A trained network carries no warnings (and its metadata no such field).
    let net = train(&dir, "net.safetensors", &[]);
    assert!(file_metadata(&net, "blockstack-dqn").get("warnings").is_none());
}
