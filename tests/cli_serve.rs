//! `blockstack serve` from the command line: loopback by default, the links printed, and a
//! setting that cannot work refused in one line before anything is served (the server
//! itself is tested in serve/tests).

use std::io::BufRead;
use std::process::{Command, Stdio};

fn blockstack() -> Command {
    Command::new(env!("CARGO_BIN_EXE_blockstack"))
}

#[test]
fn serve_listens_on_loopback_and_prints_both_links() {
    let mut child = blockstack()
        .args(["serve", "--port", "0"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut lines = vec![String::new(), String::new()];
    for line in &mut lines {
        out.read_line(line).unwrap();
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(lines[0].starts_with("participants: http://127.0.0.1:"), "{lines:?}");
    assert!(lines[1].starts_with("researcher:   http://127.0.0.1:"), "{lines:?}");
    let token = lines[1].trim().rsplit('/').next().unwrap();
    assert_eq!(token.len(), 32);
}

#[test]
fn a_setting_that_cannot_work_is_one_line_and_status_2() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study.toml");
    std::fs::write(&study, "[[condition]]\nname = \"a\"\n").unwrap();
    let cases: [(&[&str], &str); 3] = [
        (&["--study", study.to_str().unwrap()], "give --record-dir"),
        (&["--model", "/nonexistent/model.safetensors"], "model.safetensors"),
        (&["--goals", "0,1"], "goal"),
    ];
    for (args, expected) in cases {
        let out = blockstack().args(["serve", "--port", "0"]).args(args).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}

#[test]
fn a_pilot_of_the_example_study_fills_the_researchers_page() {
    let dir = tempfile::tempdir().unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/study");
    for file in ["crowd.toml", "consent.md", "instructions.md"] {
        std::fs::copy(root.join(file), dir.path().join(file)).unwrap();
    }
    // The study's two models, small (the example's commands with fewer games).
    for args in [
        &["--goals", "0,1,2:2,1,0", "--out", "top.safetensors"][..],
        &["--view", "side", "--out", "side.safetensors"][..],
    ] {
        let o = blockstack()
            .current_dir(dir.path())
            .args(["train", "--games", "200"])
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let record = dir.path().join("pilot");
    let o = blockstack()
        .current_dir(dir.path())
        .args([
            "pilot",
            "--study",
            "crowd.toml",
            "--participants",
            "4",
            "--record-dir",
            "pilot",
            "--seed",
            "2",
        ])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{out}{}", String::from_utf8_lossy(&o.stderr));
    // A demonstrator finished with the code, one withdrew, a random player gave up.
    assert!(
        out.contains("demonstrator (careful expert)") && out.contains("completion code C7Q2XK"),
        "{out}"
    );
    assert_eq!(out.matches("; withdrew").count(), 1, "{out}");
    assert!(
        out.contains("random player") && out.contains("left without finishing"),
        "{out}"
    );
    // The researcher's page counts the three who stayed, of the study's 60; the withdrawn
    // one is left out.
    assert!(
        out.contains("the researcher's page: 3 participants of at most 60; 1 withdrawn left out"),
        "{out}"
    );
    let recordings = std::fs::read_dir(&record)
        .unwrap()
        .filter(|e| e.as_ref().unwrap().file_name().to_str().unwrap().starts_with('p'))
        .count();
    assert_eq!(
        recordings, 4,
        "the withdrawn one marked, not deleted (withdrawal = \"mark\")"
    );
}
