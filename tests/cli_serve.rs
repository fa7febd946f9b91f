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
