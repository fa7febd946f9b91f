//! The commands that read demonstrations (`dqn --demos-file`, `learn-from-demos`) run the
//! one checked reader of each file format: what it refuses is one line and exit 2, and the
//! files the previous release wrote (testkit/fixtures/) still read.

use std::path::{Path, PathBuf};

use crate::common::{cli, path, scratch, stderr, stdout};

fn fixture(name: &str) -> PathBuf {
    testkit::fixture(name)
}

/// `blockstack dqn --demos-file FILE` on the default 3-block world, with a tiny network.
fn dqn(demos: &Path, out: &Path) -> std::process::Output {
    cli("dqn")
        .flag("demos-file", path(demos))
        .flag("pretrain", "20")
        .flag("steps", "20")
        .flag("hidden", "16")
        .flag("out", path(out))
        .run()
}

/// The run was refused with exit 2 and one line naming `needle`.
fn refused_in_one_line(o: &std::process::Output, needle: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains(needle), "{err}");
}

#[test]
fn a_step_after_a_terminated_step_is_refused_in_one_line() {
    let dir = scratch("readers-after-end");
    let text = std::fs::read_to_string(fixture("trajectory.jsonl")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let end = lines.iter().position(|l| l.contains("\"terminated\":true")).unwrap();
    let mut after: serde_json::Value = serde_json::from_str(lines[end]).unwrap();
    after["step"] = (after["step"].as_u64().unwrap() + 1).into();
    // Picking the held block again: the rules allow it and change nothing.
    after["action"] = 7.into();
    let broken = dir.join("t.jsonl");
    let body: String = lines[..=end].iter().map(|l| format!("{l}\n")).collect();
    std::fs::write(&broken, body + &after.to_string() + "\n").unwrap();
    let out = dir.join("net.safetensors");
    refused_in_one_line(&dqn(&broken, &out), &format!("line {}", end + 2));
    assert!(!out.exists());
}

#[test]
fn a_device_given_as_demonstrations_is_refused_before_it_is_read() {
    let dir = scratch("readers-dev-zero");
    let out = dir.join("net.safetensors");
    refused_in_one_line(
        &dqn(Path::new("/dev/zero"), &out),
        "a pipe or a device, not a regular file",
    );
    assert!(!out.exists());
}

#[test]
fn files_written_by_the_previous_release_still_read() {
    let dir = scratch("readers-fixtures");
    let out = dir.join("learnt.safetensors");
    let o = cli("learn-from-demos")
        .arg(path(&fixture("recording-v2.jsonl")))
        .flag("model", path(&fixture("model.safetensors")))
        .flag("on-bad-line", "fail")
        .flag("out", path(&out))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("in 2 episodes of 1 sessions; 0 of 24 lines skipped"),
        "{}",
        stdout(&o)
    );
    for demos in ["trajectory.jsonl", "recording-v2.jsonl"] {
        let net = dir.join("net.safetensors");
        let o = dqn(&fixture(demos), &net);
        assert!(o.status.success(), "{demos}: {}", stderr(&o));
        assert!(net.exists(), "{demos}");
    }
}
