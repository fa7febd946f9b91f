//! `blockstack correct` and `learn-from-demos` end to end: replay gives the live session's
//! model, a killed session leaves only whole lines, bad lines are reported or fatal.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use agent::DemoRecord;

use crate::common::{blockstack, cli, path, scratch, stderr, train_model};

/// The paper's learner, briefly trained on two goals on the grid backend.
fn base_model(dir: &Path) -> PathBuf {
    train_model(
        dir,
        "base.safetensors",
        &["--goals", "0,1,2:1,0,2", "--games", "300", "--backend", "grid"],
    )
}

#[test]
fn replaying_a_recorded_correction_session_gives_the_same_model() {
    let dir = scratch("replay");
    let base = base_model(&dir);
    let (live, demos, replayed) = (
        dir.join("live.safetensors"),
        dir.join("demos.jsonl"),
        dir.join("replayed.safetensors"),
    );
    for demonstrator in ["1", "3"] {
        let o = cli("correct")
            .flag("model", path(&base))
            .flag("demonstrator", demonstrator)
            .flag("demos", "6")
            .flag("goals", "0,1,2:2,1,0")
            .flag("seed", "3")
            .flag("out", path(&live))
            .flag("record", path(&demos))
            .run();
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("corrections"));
        // Each session is replayed from a file of its own (recordings are appended to).
        let o = cli("learn-from-demos")
            .arg(path(&demos))
            .flag("model", path(&base))
            .flag("out", path(&replayed))
            .flag("on-bad-line", "fail")
            .run();
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(std::fs::read(&live).unwrap(), std::fs::read(&replayed).unwrap());
        std::fs::remove_file(&demos).unwrap();
    }
    // A bad demonstrator number is refused by name.
    let o = cli("correct")
        .flag("model", path(&base))
        .flag("demonstrator", "4")
        .flag("out", path(&live))
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("demonstrator"), "{}", stderr(&o));
}

#[test]
fn a_killed_session_leaves_a_recording_whose_complete_lines_all_parse() {
    let dir = scratch("kill");
    let base = base_model(&dir);
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
    let o = cli("learn-from-demos")
        .arg(path(&demos))
        .flag("model", path(&base))
        .flag("out", path(&dir.join("from-killed.safetensors")))
        .run();
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
    let base = base_model(&dir);
    let demos = dir.join("demos.jsonl");
    let o = cli("correct")
        .flag("model", path(&base))
        .flag("demonstrator", "2")
        .flag("demos", "2")
        .flag("out", path(&dir.join("live.safetensors")))
        .flag("record", path(&demos))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&demos).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[3] = "this is not json".into();
    lines[4] = lines[4].replace("\"type\":", "\"tpye\":");
    std::fs::write(&demos, lines.join("\n") + "\n").unwrap();
    let out = dir.join("out.safetensors");
    let o = cli("learn-from-demos")
        .arg(path(&demos))
        .flag("model", path(&base))
        .flag("out", path(&out))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("demos.jsonl:4: skipped") && err.contains("demos.jsonl:5: skipped"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("2 of"));
    assert!(out.exists());
    std::fs::remove_file(&out).unwrap();
    let o = cli("learn-from-demos")
        .arg(path(&demos))
        .flag("model", path(&base))
        .flag("out", path(&out))
        .flag("on-bad-line", "fail")
        .run();
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("line 4") && err.lines().count() == 1, "{err}");
    assert!(!out.exists(), "nothing is written when the command fails");
    // A missing file is one clear line too.
    let o = cli("learn-from-demos")
        .arg(path(&dir.join("missing.jsonl")))
        .flag("model", path(&base))
        .flag("out", path(&out))
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("missing.jsonl"));
}

#[test]
fn learn_from_demos_refuses_what_cannot_be_learnt_from() {
    let dir = scratch("refusals");
    let base = base_model(&dir);
    let demos = dir.join("demos.jsonl");
    let o = cli("correct")
        .flag("model", path(&base))
        .flag("demonstrator", "1")
        .flag("demos", "2")
        .flag("out", path(&dir.join("live.safetensors")))
        .flag("record", path(&demos))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let lines: Vec<String> = std::fs::read_to_string(&demos)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    // Another model: the same settings, fewer games.
    let other = train_model(
        &dir,
        "other.safetensors",
        &["--goals", "0,1,2:1,0,2", "--games", "20", "--backend", "grid"],
    );
    let write = |name: &str, lines: &[String]| {
        let file = dir.join(name);
        std::fs::write(&file, lines.iter().map(|l| format!("{l}\n")).collect::<String>()).unwrap();
        file
    };
    let empty = write("empty.jsonl", &[]);
    // The fourth line (the second step) written twice.
    let twice = write("twice.jsonl", &[&lines[..4], &lines[3..]].concat());
    // The first step's next state with block 0 on another free cell, which no action gives.
    let mut impossible = lines.clone();
    let mut step: serde_json::Value = serde_json::from_str(&impossible[2]).unwrap();
    let taken: Vec<serde_json::Value> = [&step["state"]["blocks"], &step["next"]["blocks"]]
        .iter()
        .flat_map(|b| b.as_array().unwrap().clone())
        .collect();
    let free = (0..7)
        .flat_map(|x| (0..7).map(move |y| serde_json::json!([x, y])))
        .find(|c| !taken.contains(c))
        .unwrap();
    step["next"]["blocks"][0] = free;
    impossible[2] = step.to_string();
    let impossible = write("impossible.jsonl", &impossible);
    let out = dir.join("out.safetensors");
    let cases: &[(&Path, &Path, &[&str], &str)] = &[
        (&empty, &base, &[], "empty"),
        (&base, &base, &[], "model file"),
        (&demos, &other, &[], "identity"),
        (&twice, &base, &["--on-bad-line", "fail"], "written twice"),
        (&impossible, &base, &["--on-bad-line", "fail"], "rules"),
    ];
    for (recording, model, extra, needle) in cases {
        let o = blockstack(
            &[
                &[
                    "learn-from-demos",
                    path(recording),
                    "--model",
                    path(model),
                    "--out",
                    path(&out),
                ][..],
                extra,
            ]
            .concat(),
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{needle}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{needle}: {err}");
        assert!(err.contains(needle), "{needle}: {err}");
        assert!(!out.exists(), "{needle}: nothing is written");
    }
    // Skipping, the line written twice is reported and the rest learnt.
    let o = cli("learn-from-demos")
        .arg(path(&twice))
        .flag("model", path(&base))
        .flag("out", path(&out))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("twice.jsonl:5: skipped"), "{}", stderr(&o));
}
