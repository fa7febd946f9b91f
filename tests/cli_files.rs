//! Every command's files: special destinations (FIFO, symlink, a character device of the
//! test's own), closed and full standard output, destinations checked before any work,
//! no temporary file left by an error or a signal, outputs that are inputs, bounded and
//! versioned model files, pictures in the format their name says.

use std::fs;
use std::io::Read;
use std::os::unix::fs::FileTypeExt;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use crate::common::{BIN, ROLE_ON_GRID, blockstack, cli, path, scratch, stderr, stdout, train_model};

/// Trains a small role model (grid backend, a few hundred games) at `dir/name`.
fn small_model(dir: &Path, name: &str) -> PathBuf {
    train_model(dir, name, &[&ROLE_ON_GRID[..], &["--games", "300"]].concat())
}

/// The names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Names in `dir` that look like temporary files (ours end in `.tmp`; older builds put
/// `.tmpPID` at the end).
fn temporaries(dir: &Path) -> Vec<String> {
    listing(dir).into_iter().filter(|n| n.contains(".tmp")).collect()
}

/// Waits for `child`, killing it if it takes longer than `limit` (a guard against a hang,
/// not a timing).
fn wait_guarded(mut child: Child, limit: Duration) -> Output {
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > limit {
            child.kill().unwrap();
            panic!("the command did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// Runs `blockstack args` with standard output a pipe whose reader is gone before the
/// command writes (what `| head -1` leaves once `head` has exited).
fn with_closed_stdout(args: &[&str]) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    wait_guarded(child, Duration::from_secs(120))
}

#[test]
fn a_closed_pipe_ends_a_command_quietly_and_after_its_model_is_saved() {
    let dir = scratch("closed-pipe");
    let model = small_model(&dir, "m.safetensors");
    let m = path(&model);
    for args in [
        vec!["eval", "--model", m, "--episodes", "20", "--backend", "grid"],
        vec!["eval", "--model", m, "--episodes", "20", "--backend", "grid", "--json"],
        vec!["run", "--episodes", "20", "--backend", "grid"],
        vec!["run", "--agent", "q", "--model", m, "--episodes", "20", "--json"],
        vec!["solve", "--start", "0,0;3,0;5,2", "--goal", "1,0,2"],
        vec!["render", "--seed", "3"],
    ] {
        let o = with_closed_stdout(&args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{args:?}: {}", stderr(&o));
        assert_eq!(stderr(&o), "", "{args:?}");
    }
    // The model a command saves is on disk before it prints.
    let out = dir.join("trained.safetensors");
    let o = with_closed_stdout(&["train", "--games", "20", "--backend", "grid", "--out", path(&out)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        cli("eval")
            .flag("model", path(&out))
            .flag("episodes", "1")
            .run()
            .status
            .success()
    );
}

#[test]
fn a_full_standard_output_is_one_line_and_status_2() {
    let full = Path::new("/dev/full");
    if !full.exists() {
        println!("skipped: this system has no /dev/full");
        return;
    }
    for args in [
        &["run", "--episodes", "3", "--backend", "grid"][..],
        &["render", "--seed", "1", "--ascii", "--blocks", "3"],
    ] {
        let o = Command::new(BIN)
            .args(args)
            .stdout(fs::OpenOptions::new().write(true).open(full).unwrap())
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("blockstack: cannot write to standard output"), "{err}");
    }
}

#[test]
fn a_fifo_destination_is_written_directly_and_stays_a_fifo() {
    let dir = scratch("fifo");
    let fifo = dir.join("trajectory");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = String::new();
            fs::File::open(&fifo).unwrap().read_to_string(&mut text).unwrap();
            text
        })
    };
    let o = cli("run")
        .flag("goal", "1,0,2")
        .flag("episodes", "2")
        .flag("seed", "7")
        .flag("backend", "grid")
        .flag("trajectory", path(&fifo))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    // Checked before joining the reader: had the FIFO been replaced, its reader would wait
    // for a writer forever.
    assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    let text = reader.join().unwrap();
    assert_eq!(text.lines().filter(|l| l.contains("\"type\":\"episode\"")).count(), 2);
    assert_eq!(listing(&dir), ["trajectory"]);
}

#[test]
fn a_character_device_destination_stays_a_device() {
    let dir = scratch("device");
    // A null device of the test's own (major 1, minor 3): never the real /dev/null.
    let null = dir.join("null");
    match Command::new("mknod").arg(&null).args(["c", "1", "3"]).output() {
        Ok(o) if o.status.success() => {}
        other => {
            println!("skipped: cannot make a character device here ({other:?})");
            return;
        }
    }
    let model = small_model(&dir, "m.safetensors");
    for args in [
        vec![
            "run",
            "--episodes",
            "3",
            "--backend",
            "grid",
            "--trajectory",
            path(&null),
        ],
        vec!["render", "--out", path(&null)],
        vec!["train", "--games", "10", "--backend", "grid", "--out", path(&null)],
        vec![
            "correct",
            "--model",
            path(&model),
            "--demonstrator",
            "1",
            "--demos",
            "1",
            "--out",
            path(&null),
        ],
    ] {
        let o = blockstack(&args);
        // `render --out` needs a picture name; the others write into the device.
        if args[0] == "render" {
            assert_eq!(o.status.code(), Some(2));
            assert!(stderr(&o).contains(".png or .jpg"), "{}", stderr(&o));
        } else {
            assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        }
        assert!(
            fs::symlink_metadata(&null).unwrap().file_type().is_char_device(),
            "{args:?}"
        );
        assert!(temporaries(&dir).is_empty(), "{args:?}");
    }
}

#[test]
fn a_symlink_destination_is_followed_and_stays_a_link() {
    let dir = scratch("symlink");
    fs::create_dir(dir.join("models")).unwrap();
    let link = dir.join("latest.safetensors");
    std::os::unix::fs::symlink("models/m1.safetensors", &link).unwrap();
    for games in ["20", "40"] {
        let o = cli("train")
            .flag("games", games)
            .flag("backend", "grid")
            .flag("out", path(&link))
            .run();
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        let eval = cli("eval")
            .flag("model", path(&dir.join("models/m1.safetensors")))
            .flag("episodes", "1")
            .run();
        assert!(eval.status.success(), "{}", stderr(&eval));
    }
    assert_eq!(listing(&dir.join("models")), ["m1.safetensors"]);
}

#[test]
fn bad_destinations_fail_before_any_work() {
    let dir = scratch("destinations");
    let model = small_model(&dir, "m.safetensors");
    let demos = dir.join("demos.jsonl");
    let o = cli("correct")
        .flag("model", path(&model))
        .flag("demonstrator", "1")
        .flag("demos", "1")
        .flag("out", path(&dir.join("c.safetensors")))
        .flag("record", path(&demos))
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let missing = dir.join("no-such-folder").join("out.safetensors");
    let ok = dir.join("ok.safetensors");
    let (m, mi) = (path(&model), path(&missing));
    let d = path(&demos);
    // Commands given work that would take hours: they must fail at once.
    let cases: Vec<Vec<&str>> = vec![
        vec!["train", "--games", "100000000", "--out", mi],
        vec!["train", "--games", "100000000", "--out", path(&dir)],
        vec!["run", "--episodes", "100000000", "--trajectory", mi],
        vec!["render", "--out", mi],
        vec![
            "correct",
            "--model",
            m,
            "--demonstrator",
            "1",
            "--demos",
            "100000000",
            "--out",
            mi,
        ],
        vec![
            "correct",
            "--model",
            m,
            "--demonstrator",
            "1",
            "--demos",
            "100000000",
            "--out",
            path(&ok),
            "--record",
            mi,
        ],
        vec!["learn-from-demos", d, "--model", m, "--out", mi],
        vec!["demo", "--model", m, "--out", mi],
        vec!["reproduce", "--out", m],
    ];
    for args in &cases {
        let child = Command::new(BIN)
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let o = wait_guarded(child, Duration::from_secs(60));
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.contains("does not exist") || err.contains("is a directory") || err.contains("not a folder"),
            "{args:?}: {err}"
        );
        assert_eq!(stdout(&o), "", "{args:?}");
    }
    assert!(!dir.join("no-such-folder").exists());
    assert!(temporaries(&dir).is_empty());
}

#[test]
fn an_output_that_is_an_input_is_refused() {
    let dir = scratch("same-file");
    let model = small_model(&dir, "m.safetensors");
    let before = fs::read(&model).unwrap();
    let demos = dir.join("demos.jsonl");
    let record = cli("correct")
        .flag("model", path(&model))
        .flag("demonstrator", "2")
        .flag("demos", "1")
        .flag("out", path(&dir.join("c.safetensors")))
        .flag("record", path(&demos))
        .run();
    assert!(record.status.success(), "{}", stderr(&record));
    let recorded = fs::read(&demos).unwrap();
    let alias = dir.join("alias.safetensors");
    std::os::unix::fs::symlink(&model, &alias).unwrap();
    let (m, d, a) = (path(&model), path(&demos), path(&alias));
    let dotted = format!("{}/./m.safetensors", dir.display());
    let x = dir.join("x.safetensors");
    let cases: Vec<Vec<&str>> = vec![
        vec![
            "correct",
            "--model",
            m,
            "--demonstrator",
            "1",
            "--out",
            path(&x),
            "--record",
            m,
        ],
        vec!["correct", "--model", m, "--demonstrator", "1", "--out", a],
        vec!["correct", "--model", m, "--demonstrator", "1", "--out", &dotted],
        vec!["learn-from-demos", d, "--model", m, "--out", d],
        vec!["learn-from-demos", d, "--model", m, "--out", m],
        vec!["run", "--agent", "q", "--model", m, "--trajectory", m],
        vec!["demo", "--model", m, "--record", m],
    ];
    for args in &cases {
        let o = blockstack(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains("is also the input"), "{args:?}: {err}");
    }
    assert!(fs::read(&model).unwrap() == before, "the model is untouched");
    assert!(fs::read(&demos).unwrap() == recorded, "the recording is untouched");
}

#[test]
fn model_files_that_cannot_be_read_are_one_line_errors() {
    let dir = scratch("bad-models");
    let check = |model: &str, needle: &str| {
        let child = Command::new(BIN)
            .args(["eval", "--model", model, "--episodes", "1"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let o = wait_guarded(child, Duration::from_secs(10));
        assert_eq!(o.status.code(), Some(2), "{model}");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(model) && err.contains(needle), "{err}");
    };
    // A device that never ends is refused at once, not read until memory runs out.
    check("/dev/zero", "a pipe or a device is not supported");
    // A model of the JSON format this blockstack wrote before.
    let v1 = dir.join("old.json");
    fs::write(
        &v1,
        r#"{"format":"blockstack-q-agent","version":1,"grid":{"width":7,"height":7},"blocks":3,"repr":"role","params":{"alpha":1.0,"gamma":0.1,"epsilon":0.1,"initial_q":0.0},"training":null,"table":{"keys":470596,"columns":8,"initial":0.0,"rows":[],"checksum":0}}"#,
    )
    .unwrap();
    check(path(&v1), "version-1 model file (JSON)");
    let model = small_model(&dir, "m.safetensors");
    let mut bytes = fs::read(&model).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x40;
    let corrupt = dir.join("corrupt.safetensors");
    fs::write(&corrupt, &bytes).unwrap();
    check(path(&corrupt), "checksum");
}

#[test]
fn values_the_table_cannot_hold_are_refused_up_front() {
    let dir = scratch("float-guard");
    let out = dir.join("m.safetensors");
    let o = cli("train").flag("initial-q", "1e300").flag("out", path(&out)).run();
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("1e300") && err.contains("32-bit floats"), "{err}");
    assert!(!out.exists());
    let model = small_model(&dir, "base.safetensors");
    let o = cli("correct")
        .flag("model", path(&model))
        .flag("demonstrator", "1")
        .flag("margin", "1e39")
        .flag("out", path(&out))
        .run();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("the margin 1e39 does not fit"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn pictures_are_written_in_the_format_their_name_says() {
    let dir = scratch("pictures");
    for (name, magic) in [
        ("w.png", &b"\x89PNG"[..]),
        ("w.jpg", &b"\xff\xd8\xff"[..]),
        ("w.jpeg", &b"\xff\xd8\xff"[..]),
    ] {
        let out = dir.join(name);
        let o = cli("render").flag("seed", "2").flag("out", path(&out)).run();
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(fs::read(&out).unwrap().starts_with(magic), "{name}");
    }
    for (args, needle) in [
        (vec!["render", "--out", path(&dir.join("w.bmp"))], ".png or .jpg"),
        (
            vec!["render", "--out", path(&dir.join("w.png")), "--cell", "100000"],
            "100000-pixel cells",
        ),
        (
            vec!["render", "--out", path(&dir.join("w.png")), "--cell", "4294967295"],
            "use smaller cells",
        ),
    ] {
        let o = blockstack(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    }
    assert!(!dir.join("w.bmp").exists());
    assert_eq!(listing(&dir), ["w.jpeg", "w.jpg", "w.png"]);
}

#[test]
fn an_error_mid_run_leaves_no_temporary_file() {
    let dir = scratch("error-mid-run");
    let out = dir.join("t.jsonl");
    // On a one-cell-wide grid some starts cannot reach the goal: the oracle gives up on
    // one of them after earlier episodes were written.
    let o = cli("run")
        .flag("agent", "oracle")
        .flag("grid", "1x5")
        .flag("blocks", "2")
        .flag("goal", "0,1")
        .flag("episodes", "50")
        .flag("trajectory", path(&out))
        .run();
    assert!(temporaries(&dir).is_empty(), "{:?}", listing(&dir));
    if o.status.code() == Some(2) {
        assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
    }
}

#[test]
fn a_signal_mid_run_leaves_no_temporary_file() {
    for (signal, number) in [("TERM", 15), ("INT", 2)] {
        let dir = scratch(&format!("signal-{signal}"));
        let out = dir.join("t.jsonl");
        let child = Command::new(BIN)
            .args([
                "run",
                "--episodes",
                "100000000",
                "--backend",
                "grid",
                "--trajectory",
                path(&out),
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Wait until the trajectory is being written.
        let start = Instant::now();
        while temporaries(&dir).is_empty() {
            assert!(start.elapsed() < Duration::from_secs(60), "no temporary file appeared");
            std::thread::sleep(Duration::from_millis(20));
        }
        let kill = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let o = wait_guarded(child, Duration::from_secs(60));
        // It died of the signal, as a process without handlers would.
        assert_eq!(o.status.signal(), Some(number), "{signal}: {:?}", o.status);
        assert!(listing(&dir).is_empty(), "{signal}: {:?}", listing(&dir));
    }
}

#[test]
fn standard_output_as_a_destination_carries_the_data_alone() {
    let dir = scratch("stdout-data");
    // The trajectory on standard output, the report on standard error.
    let o = cli("run")
        .flag("goal", "1,0,2")
        .flag("episodes", "2")
        .flag("seed", "7")
        .flag("backend", "grid")
        .arg("--json")
        .arg("--trajectory")
        .arg("-")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    let file = dir.join("t.jsonl");
    let to_file = cli("run")
        .flag("goal", "1,0,2")
        .flag("episodes", "2")
        .flag("seed", "7")
        .flag("backend", "grid")
        .arg("--json")
        .flag("trajectory", path(&file))
        .run();
    assert_eq!(stdout(&o), fs::read_to_string(&file).unwrap());
    assert_eq!(stderr(&o), stdout(&to_file), "the report moved to standard error");
    // A model on standard output is the file's bytes.
    let model = dir.join("m.safetensors");
    let train = |out: &str| {
        cli("train")
            .flag("games", "30")
            .flag("backend", "grid")
            .flag("out", out)
            .run()
    };
    let piped = train("-");
    assert!(piped.status.success(), "{}", stderr(&piped));
    assert!(train(path(&model)).status.success());
    assert!(piped.stdout == fs::read(&model).unwrap(), "the same model");
    // Two outputs cannot share it, and demo draws on the terminal.
    for args in [
        vec![
            "correct",
            "--model",
            path(&model),
            "--demonstrator",
            "1",
            "--out",
            "-",
            "--record",
            "-",
        ],
        vec!["demo", "--model", path(&model), "--out", "-"],
    ] {
        let o = blockstack(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains("standard output (-)"), "{}", stderr(&o));
    }
}

/// Runs `script` in bash with `$BIN` set to the binary (for process substitution).
fn bash(script: &str) -> Output {
    Command::new("bash")
        .args(["-c", script])
        .env("BIN", BIN)
        .output()
        .expect("bash runs")
}

#[test]
fn pipes_from_process_substitution_are_written_or_refused_in_one_line() {
    let dir = scratch("process-substitution");
    // `>(cat > t)`: /dev/fd/N, a link to "pipe:[...]", is a writable pipe.
    let t = dir.join("t.jsonl");
    let o = bash(&format!(
        "\"$BIN\" run --goal 1,0,2 --episodes 2 --seed 7 --backend grid --trajectory >(cat > '{}'); \
         status=$?; wait $!; exit $status",
        t.display()
    ));
    assert!(o.status.success(), "{}", stderr(&o));
    let text = fs::read_to_string(&t).unwrap();
    assert_eq!(text.lines().filter(|l| l.contains("\"type\":\"episode\"")).count(), 2);
    // `<(cat m)`: a model is read twice, so a pipe is refused, naming the flag.
    let model = small_model(&dir, "m.st");
    for command in ["eval --episodes 1", "run --agent q --episodes 1"] {
        let o = bash(&format!("\"$BIN\" {command} --model <(cat '{}')", model.display()));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{command}: {err}");
        assert_eq!(err.lines().count(), 1, "{command}: {err}");
        assert!(err.contains("--model") && err.contains("pipe"), "{command}: {err}");
    }
}

#[test]
fn no_episodes_is_refused_in_one_line() {
    let dir = scratch("no-episodes");
    let t = dir.join("t.jsonl");
    for args in [
        vec!["run", "--episodes", "0"],
        vec!["run", "--episodes", "0", "--json", "--trajectory", path(&t)],
    ] {
        let o = blockstack(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains("--episodes 0"), "{args:?}: {err}");
        assert_eq!(stdout(&o), "", "{args:?}");
    }
    assert!(!t.exists());
}

#[test]
fn generate_refuses_a_link_in_its_folder_and_a_run_too_large_before_writing() {
    let dir = scratch("generate-link");
    let out = dir.join("problems");
    fs::create_dir(&out).unwrap();
    let outside = dir.join("outside.txt");
    fs::write(&outside, "keep me").unwrap();
    std::os::unix::fs::symlink(&outside, out.join("p02.pddl")).unwrap();
    let o = cli("generate")
        .flag("blocks", 4)
        .flag("count", 3)
        .flag("out", path(&out))
        .run();
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("p02.pddl is a link") && err.lines().count() == 1, "{err}");
    assert_eq!(fs::read_to_string(&outside).unwrap(), "keep me");
    assert_eq!(listing(&out), ["p02.pddl"], "nothing written, not even p01");
    let o = cli("generate")
        .flag("blocks", 100000)
        .flag("count", 100000)
        .flag("out", path(&dir.join("huge")))
        .run();
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(err.contains("10000000 blocks in one run"), "{err}");
    assert!(!dir.join("huge").exists());
}
