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

/// The fixture recording with `edit` applied to its session line, and with a `withdrawn`
/// line appended when `withdrawn`, written into `dir` as `name`.
fn recording_as(dir: &Path, name: &str, edit: impl Fn(&mut serde_json::Value), withdrawn: bool) -> PathBuf {
    let text = std::fs::read_to_string(fixture("recording-v2.jsonl")).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut session: serde_json::Value = serde_json::from_str(&lines[0]).unwrap();
    edit(&mut session);
    lines[0] = session.to_string();
    if withdrawn {
        lines.push(r#"{"type":"withdrawn","at_ms":1764800009999}"#.into());
    }
    let file = dir.join(name);
    std::fs::write(&file, lines.join("\n") + "\n").unwrap();
    file
}

#[test]
fn a_withdrawn_participants_recording_is_refused_by_every_reader_unless_audited() {
    let dir = scratch("readers-withdrawn");
    let withdrawn = recording_as(&dir, "w.jsonl", |_| {}, true);
    let net = dir.join("net.safetensors");
    refused_in_one_line(&dqn(&withdrawn, &net), "withdrew");
    assert!(!net.exists());
    let out = dir.join("learnt.safetensors");
    let learn = cli("learn-from-demos")
        .arg(path(&withdrawn))
        .flag("model", path(&fixture("model.safetensors")))
        .flag("out", path(&out));
    refused_in_one_line(&learn.clone().run(), "--include-withdrawn");
    assert!(!out.exists(), "nothing saved");
    // An audit reads it, and says so in one line.
    let o = learn.arg("--include-withdrawn").run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.exists());
    let err = stderr(&o);
    assert_eq!(err.lines().filter(|l| l.contains("withdrew")).count(), 1, "{err}");
}

#[test]
fn a_recording_of_another_world_is_refused_naming_both() {
    let dir = scratch("readers-other-world");
    // The same steps said to be of the side view, and of the paper's protocol.
    let side = recording_as(&dir, "side.jsonl", |s| s["view"] = "side".into(), false);
    let paper = recording_as(
        &dir,
        "paper.jsonl",
        |s| {
            s["version"] = 3.into();
            s["world"] = serde_json::json!({"reward": "sparse", "protocol": "paper", "horizon": 1000});
        },
        false,
    );
    let net = dir.join("net.safetensors");
    refused_in_one_line(&dqn(&side, &net), "the recording is of the side view");
    refused_in_one_line(&dqn(&side, &net), "this run is of the top view");
    refused_in_one_line(&dqn(&paper, &net), "the paper protocol; this run is of");
    assert!(!net.exists());
    let out = dir.join("learnt.safetensors");
    let o = cli("learn-from-demos")
        .arg(path(&side))
        .flag("model", path(&fixture("model.safetensors")))
        .flag("out", path(&out))
        .run();
    refused_in_one_line(&o, "the recording is of the side view");
}
