//! `train --checkpoint` / `--resume` and `dqn --checkpoint` / `--resume`: a run stopped at
//! any checkpoint (on purpose or by `kill -9`) and resumed ends with the same model file,
//! byte for byte, as a run that never stopped.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{BIN, blockstack, cli, file_metadata, path, scratch, stderr, stdout, train};

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
        // A checkpoint file each: one run's checkpoint is not written over by another's.
        let (whole, resumed, ck) = (dir.join("w2.st"), dir.join("r2.st"), dir.join(format!("ck-{profile}")));
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

/// A small network run: DQN on 2 blocks and one goal, a narrow network.
const DQN: [&str; 10] = [
    "--preset",
    "dqn-planes",
    "--blocks",
    "2",
    "--goals",
    "0,1",
    "--hidden",
    "64",
    "--steps",
    "30000",
];

fn dqn(args: &[&str]) -> std::process::Output {
    let o = blockstack(&[&["dqn"][..], args].concat());
    assert!(o.status.success(), "dqn {args:?}: {}", stderr(&o));
    o
}

/// The steps a network checkpoint has done, read as any program could.
fn steps_done(checkpoint: &Path) -> u64 {
    file_metadata(checkpoint, "blockstack-dqn-checkpoint")["report"]["steps"]
        .as_u64()
        .expect("steps done")
}

#[test]
fn a_network_run_killed_after_a_checkpoint_resumes_to_the_same_file() {
    let dir = scratch("dqn-checkpoint-kill");
    let (whole, resumed, ck) = (dir.join("whole.st"), dir.join("resumed.st"), dir.join("ck"));
    let mut child = Command::new(BIN)
        .arg("dqn")
        .args(DQN)
        .args(["--checkpoint", path(&ck), "--checkpoint-every", "500"])
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
    let done = steps_done(&ck);
    assert!(done > 0 && done.is_multiple_of(500) && done < 30000, "{done}");

    let o = dqn(&["--resume", path(&ck), "--out", path(&resumed)]);
    assert!(
        stdout(&o).contains(&format!("resumed at step {done}")),
        "{}",
        stdout(&o)
    );
    dqn(&[&DQN[..], &["--out", path(&whole)]].concat());
    assert!(
        std::fs::read(&whole).unwrap() == std::fs::read(&resumed).unwrap(),
        "the resumed run's network differs from the undisturbed run's"
    );
    // It went on checkpointing to the same file, to the end.
    assert_eq!(steps_done(&ck), 30000);
}

#[test]
fn network_checkpoint_misuse_is_one_line_and_exit_status_2() {
    let dir = scratch("dqn-checkpoint-misuse");
    let (model, ck) = (dir.join("m.st"), dir.join("ck"));
    dqn(&[
        "--preset",
        "dqn-planes",
        "--blocks",
        "2",
        "--steps",
        "50",
        "--checkpoint",
        path(&ck),
        "--out",
        path(&model),
    ]);
    for (args, message) in [
        (
            vec!["--resume", path(&ck), "--seed", "4"],
            "'--resume <FILE>' cannot be used with '--seed <SEED>'",
        ),
        (
            vec!["--resume", path(&ck), "--steps", "80"],
            "'--resume <FILE>' cannot be used with '--steps <STEPS>'",
        ),
        (
            vec!["--resume", path(&model)],
            "blockstack-dqn file and not blockstack-dqn-checkpoint",
        ),
        (vec!["--steps", "10", "--checkpoint-every", "5"], "--checkpoint"),
        (vec!["--steps", "10", "--checkpoint", "-"], "it must be a file"),
        (
            vec!["--steps", "10", "--checkpoint", path(&ck), "--checkpoint-every", "0"],
            "--checkpoint-every",
        ),
    ] {
        let o = blockstack(&[&["dqn", "--out", path(&dir.join("other.st"))][..], &args].concat());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(message), "{args:?}: {err}");
    }
    let o = cli("dqn").flag("resume", path(&ck)).flag("out", path(&ck)).run();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--out and --resume"), "{}", stderr(&o));
    let o = cli("dqn")
        .flag("steps", "5")
        .flag("checkpoint", path(&model))
        .flag("out", path(&model))
        .run();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--out") && stderr(&o).contains("--checkpoint"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn checkpoint_writes_only_over_nothing_or_a_checkpoint_of_the_same_run() {
    let dir = scratch("checkpoint-destination");
    let (network, ck, text) = (dir.join("net.st"), dir.join("ck"), dir.join("notes.txt"));
    let run = |steps: &str, checkpoint: &Path, out: &Path| {
        blockstack(&[
            "dqn",
            "--preset",
            "dqn-planes",
            "--blocks",
            "2",
            "--steps",
            steps,
            "--checkpoint",
            path(checkpoint),
            "--out",
            path(out),
        ])
    };
    assert!(run("50", &ck, &network).status.success());
    std::fs::write(&text, "not a checkpoint").unwrap();
    let tabular = dir.join("q.st");
    train(&["--games", "5", "--backend", "grid", "--out", path(&tabular)]);
    // A trained network, another run's checkpoint, a tabular model, a file of text: each
    // refused in one line naming it and what it holds, and left as it was.
    for (target, steps, says) in [
        (&network, "50", "a blockstack-dqn file (a trained network)"),
        (&ck, "60", "a checkpoint of another run"),
        (&tabular, "50", "a blockstack-q-agent file (a trained tabular model)"),
        (&text, "50", "not a checkpoint"),
    ] {
        let before = std::fs::read(target).unwrap();
        let o = run(steps, target, &dir.join("new.st"));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(path(target)) && err.contains(says), "{err}");
        assert!(
            std::fs::read(target).unwrap() == before,
            "{} was changed",
            target.display()
        );
        assert!(!dir.join("new.st").exists());
    }
    // The same run's checkpoint is written over; so is the resumed run's own file.
    assert!(run("50", &ck, &dir.join("again.st")).status.success());
    let o = blockstack(&["dqn", "--resume", path(&ck), "--out", path(&dir.join("resumed.st"))]);
    assert!(o.status.success(), "{}", stderr(&o));
    // `train` keeps the same rule with the same flags.
    let o = blockstack(&[
        "train",
        "--games",
        "5",
        "--checkpoint",
        path(&network),
        "--out",
        path(&dir.join("q2.st")),
    ]);
    let err = stderr(&o);
    assert!(
        o.status.code() == Some(2) && err.contains("a trained network") && err.lines().count() == 1,
        "{err}"
    );
    let o = blockstack(&[
        "train",
        "--games",
        "5",
        "--checkpoint",
        path(&ck),
        "--out",
        path(&dir.join("q2.st")),
    ]);
    assert!(stderr(&o).contains("another learner's checkpoint"), "{}", stderr(&o));
}

#[test]
fn a_device_or_a_checkpoint_where_a_model_belongs_is_named_for_what_it_is() {
    let dir = scratch("checkpoint-readers");
    let ck = dir.join("ck");
    dqn(&[
        "--preset",
        "dqn-planes",
        "--blocks",
        "2",
        "--steps",
        "20",
        "--checkpoint",
        path(&ck),
        "--out",
        path(&dir.join("m.st")),
    ]);
    let o = blockstack(&["dqn", "--resume", "/dev/zero", "--out", path(&dir.join("z.st"))]);
    let err = stderr(&o);
    assert!(
        o.status.code() == Some(2) && err.contains("a pipe or a device") && err.lines().count() == 1,
        "{err}"
    );
    for agent in ["dqn", "q"] {
        let o = blockstack(&["run", "--agent", agent, "--model", path(&ck)]);
        let err = stderr(&o);
        assert!(
            err.contains("a training checkpoint (blockstack-dqn-checkpoint), not a model")
                && !err.contains("blockstack-q-agent"),
            "{err}"
        );
    }
}
