//! `train --checkpoint` and `train --resume`: a run stopped at any checkpoint (on purpose
//! or by `kill -9`) and resumed ends with the same model file, byte for byte, as a run that
//! never stopped.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{BIN, blockstack, cli, file_metadata, path, scratch, stderr, train};

/// The role recipe on two goals, on the grid backend: its final replay makes the
/// checkpoint carry a replay memory.
const ROLE: [&str; 15] = [
    "--repr",
    "role",
    "--reward",
    "step-cost",
    "--goals",
    "0,1,2:2,1,0",
    "--alpha",
    "1",
    "--gamma",
    "1",
    "--epsilon",
    "0.1",
    "--backward-replay",
    "--final-replay",
    "--backend=grid",
];

fn same_bytes(a: &Path, b: &Path) {
    let (a_bytes, b_bytes) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(a_bytes == b_bytes, "{} and {} differ", a.display(), b.display());
}

/// The games a checkpoint has played, read as any program could.
fn games_played(checkpoint: &Path) -> u64 {
    file_metadata(checkpoint, "blockstack-train-checkpoint")["report"]["games"]
        .as_u64()
        .expect("games played")
}

#[test]
fn a_run_resumed_from_its_checkpoint_ends_with_the_same_model() {
    let dir = scratch("checkpoint-resume");
    let (whole, half, resumed, ck) = (
        dir.join("whole.st"),
        dir.join("half.st"),
        dir.join("resumed.st"),
        dir.join("ck"),
    );
    train(&[&ROLE[..], &["--games", "4000", "--out", path(&whole)]].concat());
    train(
        &[
            &ROLE[..],
            &[
                "--games",
                "2000",
                "--checkpoint",
                path(&ck),
                "--checkpoint-every",
                "700",
                "--out",
                path(&half),
            ],
        ]
        .concat(),
    );
    assert_eq!(games_played(&ck), 2000);
    train(&["--games", "4000", "--resume", path(&ck), "--out", path(&resumed)]);
    same_bytes(&whole, &resumed);
    // It went on checkpointing to the same file.
    assert_eq!(games_played(&ck), 4000);

    // The physics backend, the paper's learner; and the authors' schedule, whose table
    // remembers the entries it has seen.
    for (profile, games) in [("spec", 200), ("original", 40)] {
        let (whole, resumed, ck) = (dir.join("w2.st"), dir.join("r2.st"), dir.join("ck2"));
        let run = ["--profile", profile, "--goals", "0,1,2:1,0,2"];
        train(&[&run[..], &["--games", &games.to_string(), "--out", path(&whole)]].concat());
        train(
            &[
                &run[..],
                &[
                    "--games",
                    &(games / 2).to_string(),
                    "--checkpoint",
                    path(&ck),
                    "--out",
                    path(&half),
                ],
            ]
            .concat(),
        );
        train(&[
            "--resume",
            path(&ck),
            "--games",
            &games.to_string(),
            "--out",
            path(&resumed),
        ]);
        same_bytes(&whole, &resumed);
    }
}

#[test]
fn a_run_killed_mid_way_resumes_from_its_last_checkpoint() {
    let dir = scratch("checkpoint-kill");
    let (whole, resumed, ck) = (dir.join("whole.st"), dir.join("resumed.st"), dir.join("ck"));
    let games = "8000";
    let mut child = Command::new(BIN)
        .args(["train"])
        .args(ROLE)
        .args(["--games", games, "--checkpoint", path(&ck), "--checkpoint-every", "500"])
        .args(["--out", path(&dir.join("never.st"))])
        .spawn()
        .expect("the binary runs");
    let clock = Instant::now();
    while !ck.exists() {
        assert!(
            clock.elapsed() < Duration::from_secs(120),
            "no checkpoint after 2 minutes"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before it was killed"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().expect("SIGKILL");
    child.wait().unwrap();
    assert!(!dir.join("never.st").exists());
    let played = games_played(&ck);
    assert!(played > 0 && played.is_multiple_of(500) && played < 8000, "{played}");

    train(&["--games", games, "--resume", path(&ck), "--out", path(&resumed)]);
    train(&[&ROLE[..], &["--games", games, "--out", path(&whole)]].concat());
    same_bytes(&whole, &resumed);
}

#[test]
fn checkpoint_misuse_is_one_line_and_exit_status_2() {
    let dir = scratch("checkpoint-misuse");
    let (model, ck) = (dir.join("m.st"), dir.join("ck"));
    train(&[
        "--goals",
        "0,1,2",
        "--games",
        "20",
        "--backend",
        "grid",
        "--checkpoint",
        path(&ck),
        "--out",
        path(&model),
    ]);
    // What a run killed with SIGKILL mid-write leaves: a hidden temporary file of the
    // checkpoint (no process has this id). The next run on that checkpoint removes it.
    let stale = dir.join(".ck.999999999-0.tmp");
    std::fs::write(&stale, b"half a checkpoint").unwrap();
    let o = cli("train")
        .flag("resume", path(&ck))
        .flag("games", "30")
        .flag("out", path(&dir.join("r.st")))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stale.exists(), "the stale temporary file is removed");
    for (args, message) in [
        (vec!["--resume", path(&ck), "--games", "10"], "--games is the total"),
        (
            vec!["--resume", path(&ck), "--seed", "4"],
            "'--resume <FILE>' cannot be used with '--seed <SEED>'",
        ),
        (
            vec!["--resume", path(&model)],
            "blockstack-q-agent file and not blockstack-train-checkpoint",
        ),
        (vec!["--checkpoint-every", "5"], "--checkpoint"),
        (vec!["--checkpoint", "-"], "it must be a file"),
        (
            vec!["--checkpoint", path(&ck), "--checkpoint-every", "0"],
            "--checkpoint-every",
        ),
    ] {
        let o = blockstack(&[&["train", "--out", path(&dir.join("other.st"))][..], &args].concat());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    let o = cli("train").flag("resume", path(&ck)).flag("out", path(&ck)).run();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("would destroy the input") && err.contains("--out and --resume"),
        "{err}"
    );
    // Both flags named, whether the file exists yet or not.
    for same in [ck.clone(), dir.join("new.st")] {
        let o = cli("train")
            .flag("games", "5")
            .flag("checkpoint", path(&same))
            .flag("out", path(&same))
            .run();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("--out") && err.contains("--checkpoint"), "{err}");
    }
    let o = cli("train")
        .flag("resume", path(&ck))
        .flag("checkpoint", path(&model))
        .flag("out", path(&model))
        .run();
    assert!(stderr(&o).contains("--checkpoint"), "{}", stderr(&o));
}
