//! `blockstack correct` and `learn-from-demos` end to end: replay gives the live session's
//! model, a killed session leaves only whole lines, bad lines are reported or fatal.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use agent::DemoRecord;

mod common;
use common::{blockstack, path, scratch, stderr};

/// The paper's learner, briefly trained on two goals on the grid backend.
fn train(dir: &Path) -> PathBuf {
    let out = dir.join("base.safetensors");
    let o = blockstack(&[
        "train",
        "--goals",
        "0,1,2:1,0,2",
        "--games",
        "300",
        "--backend",
        "grid",
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

#[test]
fn replaying_a_recorded_correction_session_gives_the_same_model() {
    let dir = scratch("replay");
    let base = train(&dir);
    let (live, demos, replayed) = (
        dir.join("live.safetensors"),
        dir.join("demos.jsonl"),
        dir.join("replayed.safetensors"),
    );
    for demonstrator in ["1", "3"] {
        let o = blockstack(&[
            "correct",
            "--model",
            path(&base),
            "--demonstrator",
            demonstrator,
            "--demos",
            "6",
            "--goals",
            "0,1,2:2,1,0",
            "--seed",
            "3",
            "--out",
            path(&live),
            "--record",
            path(&demos),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("corrections"));
        // Each session is replayed from a file of its own (recordings are appended to).
        let o = blockstack(&[
            "learn-from-demos",
            path(&demos),
            "--model",
            path(&base),
            "--out",
            path(&replayed),
            "--on-bad-line",
            "fail",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(std::fs::read(&live).unwrap(), std::fs::read(&replayed).unwrap());
        std::fs::remove_file(&demos).unwrap();
    }
    // A bad demonstrator number is refused by name.
    let o = blockstack(&[
        "correct",
        "--model",
        path(&base),
        "--demonstrator",
        "4",
        "--out",
        path(&live),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("demonstrator"), "{}", stderr(&o));
}

#[test]
fn a_killed_session_leaves_a_recording_whose_complete_lines_all_parse() {
    let dir = scratch("kill");
    let base = train(&dir);
    let demos = dir.join("demos.jsonl");
    let mut child = Command::new(env!("CARGO_BIN_EXE_blockstack"))
        .args([
            "correct",
            "--model",
            path(&base),
            "--demonstrator",
            "3",
            "--demos",
            "1000000",
            "--seed",
            "9",
            "--out",
            path(&dir.join("never.safetensors")),
            "--record",
            path(&demos),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while std::fs::read(&demos).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count()) < 2000 {
        assert!(Instant::now() < deadline, "the session wrote too little");
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let bytes = std::fs::read(&demos).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    let complete = &text[..text.rfind('\n').unwrap() + 1];
    let mut steps = 0;
    for (i, line) in complete.lines().enumerate() {
        let record: DemoRecord =
            serde_json::from_str(line).unwrap_or_else(|e| panic!("line {} does not parse: {e}", i + 1));
        steps += usize::from(matches!(record, DemoRecord::Step(_)));
    }
    assert!(steps > 1000);
    assert!(!dir.join("never.safetensors").exists());
    // The recording is usable as it is: a cut-off last line, if any, is skipped and named.
    let o = blockstack(&[
        "learn-from-demos",
        path(&demos),
        "--model",
        path(&base),
        "--out",
        path(&dir.join("from-killed.safetensors")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    if complete.len() < text.len() {
        assert!(stderr(&o).contains("cut off"), "{}", stderr(&o));
    } else {
        assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    }
}

#[test]
fn malformed_lines_are_skipped_by_number_or_stop_the_command() {
    let dir = scratch("malformed");
    let base = train(&dir);
    let demos = dir.join("demos.jsonl");
    let o = blockstack(&[
        "correct",
        "--model",
        path(&base),
        "--demonstrator",
        "2",
        "--demos",
        "2",
        "--out",
        path(&dir.join("live.safetensors")),
        "--record",
        path(&demos),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&demos).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[3] = "this is not json".into();
    lines[4] = lines[4].replace("\"type\":", "\"tpye\":");
    std::fs::write(&demos, lines.join("\n") + "\n").unwrap();
    let out = dir.join("out.safetensors");
    let o = blockstack(&[
        "learn-from-demos",
        path(&demos),
        "--model",
        path(&base),
        "--out",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("demos.jsonl:4: skipped") && err.contains("demos.jsonl:5: skipped"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("2 of"));
    assert!(out.exists());
    std::fs::remove_file(&out).unwrap();
    let o = blockstack(&[
        "learn-from-demos",
        path(&demos),
        "--model",
        path(&base),
        "--out",
        path(&out),
        "--on-bad-line",
        "fail",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("line 4") && err.lines().count() == 1, "{err}");
    assert!(!out.exists(), "nothing is written when the command fails");
    // A missing file is one clear line too.
    let o = blockstack(&[
        "learn-from-demos",
        path(&dir.join("missing.jsonl")),
        "--model",
        path(&base),
        "--out",
        path(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("missing.jsonl"));
}
