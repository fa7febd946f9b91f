//! `blockstack demo` in a real terminal, driven through tmux (send-keys, capture-pane): it
//! starts and shows the grid and the goal, an override key changes the state shown, `q`
//! quits, the recording holds the corrections and replays to the saved model, a session
//! killed with SIGKILL leaves a recording whose complete lines all parse, blocks 10 to 15
//! are picked by their labels A to F, and the agent waits while the terminal is too small;
//! and `eval`, `run` and `correct` draw a progress bar on a terminal, and none elsewhere.
//!
//! Skips, saying so, when tmux is not installed (`.ci/run` installs it).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use agent::DemoRecord;

use crate::common::{BIN, blockstack, cli, path, scratch, stderr, train_model};

/// A tmux server of our own (its socket in the test's folder), killed when dropped.
struct Tmux {
    socket: PathBuf,
}

impl Tmux {
    fn new(dir: &Path) -> Tmux {
        Tmux {
            socket: dir.join("tmux.sock"),
        }
    }

    fn run(&self, args: &[&str]) -> Output {
        Command::new("tmux")
            .arg("-S")
            .arg(&self.socket)
            .args(args)
            .env("TERM", "xterm-256color")
            .output()
            .expect("tmux runs")
    }

    /// Starts `command` in a detached 80 x 24 session named `session`.
    fn start(&self, session: &str, command: &str) {
        self.start_sized(session, (80, 24), command);
    }

    /// Starts `command` in a detached session of `size` (columns, rows).
    fn start_sized(&self, session: &str, size: (u16, u16), command: &str) {
        let (x, y) = (size.0.to_string(), size.1.to_string());
        let o = self.run(&["new-session", "-d", "-s", session, "-x", &x, "-y", &y, command]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }

    /// Resizes the session's window to `size` (columns, rows).
    fn resize(&self, session: &str, size: (u16, u16)) {
        let (x, y) = (size.0.to_string(), size.1.to_string());
        let o = self.run(&["resize-window", "-t", session, "-x", &x, "-y", &y]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }

    fn screen(&self, session: &str) -> String {
        String::from_utf8_lossy(&self.run(&["capture-pane", "-p", "-t", session]).stdout).into_owned()
    }

    fn keys(&self, session: &str, keys: &[&str]) {
        let mut args = vec!["send-keys", "-t", session];
        args.extend_from_slice(keys);
        assert!(self.run(&args).status.success());
    }

    /// Waits until the screen satisfies `ok`, and returns it.
    fn wait_for(&self, session: &str, what: &str, ok: impl Fn(&str) -> bool) -> String {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let screen = self.screen(session);
            if ok(&screen) {
                return screen;
            }
            assert!(Instant::now() < deadline, "the screen never showed {what}:\n{screen}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    fn alive(&self, session: &str) -> bool {
        self.run(&["has-session", "-t", session]).status.success()
    }
}

impl Tmux {
    /// Waits until `session`'s program has ended (its pane closes with it: the commands are
    /// started with `exec`).
    fn wait_gone(&self, session: &str, what: &str) {
        let deadline = Instant::now() + Duration::from_secs(20);
        while self.alive(session) {
            assert!(Instant::now() < deadline, "{what}");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        // The programs still running in our panes: a demo saves its model as it ends, so the
        // scratch folder may be removed only once they are gone (else the late file keeps
        // the folder in the system's temp dir).
        let panes = self.run(&["list-panes", "-a", "-F", "#{pane_pid}"]);
        let pids: Vec<String> = String::from_utf8_lossy(&panes.stdout)
            .split_whitespace()
            .map(str::to_string)
            .collect();
        // Only our own server, by its socket.
        let _ = self.run(&["kill-server"]);
        let deadline = Instant::now() + Duration::from_secs(20);
        for pid in pids {
            while Path::new("/proc").join(&pid).exists() && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        let _ = std::fs::remove_file(&self.socket);
    }
}

fn tmux_missing() -> bool {
    Command::new("tmux").arg("-V").output().is_err()
}

/// The paper's learner, briefly trained on one goal on the grid backend.
fn base_model(dir: &Path) -> PathBuf {
    train_model(
        dir,
        "base.safetensors",
        &["--goals", "1,0,2", "--games", "300", "--backend", "grid"],
    )
}

/// The value after `label` on the screen, e.g. `held: 2` -> `2`.
fn field<'a>(screen: &'a str, label: &str) -> &'a str {
    let at = screen
        .find(label)
        .unwrap_or_else(|| panic!("no {label:?} on\n{screen}"))
        + label.len();
    screen[at..].split_whitespace().next().unwrap()
}

fn records(path: &Path) -> Vec<DemoRecord> {
    let text = std::fs::read_to_string(path).unwrap();
    let complete = &text[..text.rfind('\n').map_or(0, |i| i + 1)];
    complete
        .lines()
        .enumerate()
        .map(|(i, l)| serde_json::from_str(l).unwrap_or_else(|e| panic!("line {} does not parse: {e}: {l}", i + 1)))
        .collect()
}

#[test]
fn a_person_corrects_the_agent_in_the_terminal_and_quits() {
    if tmux_missing() {
        eprintln!("SKIPPED: tmux is not installed, so the terminal UI cannot be driven (.ci/run installs it)");
        return;
    }
    let dir = scratch("session");
    let base = base_model(&dir);
    let (demos, corrected) = (dir.join("demos.jsonl"), dir.join("corrected.safetensors"));
    let tmux = Tmux::new(&dir);
    tmux.start(
        "demo",
        &format!(
            "exec {BIN} demo --model {} --goals 1,0,2 --record {} --out {} --seed 5",
            path(&base),
            path(&demos),
            path(&corrected)
        ),
    );
    let screen = tmux.wait_for("demo", "the grid and the goal", |s| {
        s.contains("goal 1,0,2") && s.contains("world") && s.contains("q quit")
    });
    assert!(screen.lines().filter(|l| l.contains(" .")).count() >= 7, "{screen}");
    tmux.keys("demo", &["Space"]);
    let screen = tmux.wait_for("demo", "the pause", |s| s.contains("PAUSED"));
    // Pick a block that is not held: the screen must show it held, in brackets.
    let held = field(&screen, "held: ");
    let pick = if held == "2" { "1" } else { "2" };
    let step: u32 = field(&screen, "step: ").parse().unwrap();
    tmux.keys("demo", &[pick]);
    let screen = tmux.wait_for("demo", "the picked block held", |s| {
        s.contains(&format!("held: {pick}")) && s.contains(&format!("[{pick}]"))
    });
    assert_eq!(field(&screen, "step: ").parse::<u32>().unwrap(), step + 1, "{screen}");
    assert!(screen.contains("corrections: 1"), "{screen}");
    // An arrow key takes a step too.
    tmux.keys("demo", &["Right"]);
    tmux.wait_for("demo", "the second step", |s| {
        field(s, "step: ") == (step + 2).to_string()
    });
    tmux.keys("demo", &["q"]);
    tmux.wait_gone("demo", "q did not quit");
    // The recording holds both corrections, with what the agent proposed.
    let lines = records(&demos);
    let corrections: Vec<(String, String)> = lines
        .iter()
        .filter_map(|r| match r {
            DemoRecord::Step(s) if s.correction => Some((s.action.clone(), s.proposed.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(
        corrections.iter().map(|(a, _)| a.as_str()).collect::<Vec<_>>(),
        [format!("pick {pick}").as_str(), "right"]
    );
    // Replaying the recording gives the model the session saved on quitting.
    let replayed = dir.join("replayed.safetensors");
    let o = cli("learn-from-demos")
        .arg(path(&demos))
        .flag("model", path(&base))
        .flag("out", path(&replayed))
        .flag("on-bad-line", "fail")
        .run();
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&corrected).unwrap(), std::fs::read(&replayed).unwrap());
}

#[test]
fn a_demo_killed_mid_episode_leaves_whole_lines() {
    if tmux_missing() {
        eprintln!("SKIPPED: tmux is not installed, so the terminal UI cannot be driven (.ci/run installs it)");
        return;
    }
    let dir = scratch("kill");
    let base = base_model(&dir);
    let demos = dir.join("demos.jsonl");
    let tmux = Tmux::new(&dir);
    tmux.start(
        "demo",
        &format!(
            "exec {BIN} demo --model {} --record {} --out {} --seed 8",
            path(&base),
            path(&demos),
            path(&dir.join("corrected.safetensors"))
        ),
    );
    tmux.wait_for("demo", "the grid", |s| s.contains("world"));
    // Fastest pace, and a few corrections on the way.
    tmux.keys("demo", &["+", "+", "+", "+", "+", "+", "Left", "0", "Up"]);
    let deadline = Instant::now() + Duration::from_secs(30);
    while records(&demos).len() < 40 {
        assert!(Instant::now() < deadline, "the session recorded too little");
        std::thread::sleep(Duration::from_millis(50));
    }
    let pid = String::from_utf8_lossy(&tmux.run(&["display-message", "-p", "-t", "demo", "#{pane_pid}"]).stdout)
        .trim()
        .to_string();
    assert!(Command::new("kill").args(["-KILL", &pid]).status().unwrap().success());
    tmux.wait_gone("demo", "the killed demo is still running");
    let lines = records(&demos);
    assert!(matches!(lines[0], DemoRecord::Session(_)));
    assert!(
        lines
            .iter()
            .filter(|r| matches!(r, DemoRecord::Step(s) if s.correction))
            .count()
            >= 3
    );
}

#[test]
fn blocks_past_9_are_picked_by_letter_and_a_small_terminal_stops_the_agent() {
    if tmux_missing() {
        eprintln!("SKIPPED: tmux is not installed, so the terminal UI cannot be driven (.ci/run installs it)");
        return;
    }
    let dir = scratch("sixteen");
    let goal: Vec<String> = (0..16).map(|b| b.to_string()).collect();
    let goal = goal.join(",");
    let run = [
        "--blocks",
        "16",
        "--grid",
        "16x16",
        "--goals",
        &goal,
        "--games",
        "2",
        "--horizon",
        "20",
        "--backend",
        "grid",
    ];
    let model = train_model(&dir, "sixteen.safetensors", &run);
    let demos = dir.join("demos.jsonl");
    let tmux = Tmux::new(&dir);
    // A 16 x 16 grid needs more than 80 columns.
    let roomy = (100, 30);
    tmux.start_sized(
        "demo",
        roomy,
        &format!(
            "exec {BIN} demo --model {} --goals {goal} --record {} --out {} --seed 2",
            path(&model),
            path(&demos),
            path(&dir.join("corrected.safetensors"))
        ),
    );
    tmux.wait_for("demo", "the grid and the help", |s| {
        s.contains("world") && s.contains("0-9 A-F pick")
    });
    tmux.keys("demo", &["Space"]);
    tmux.wait_for("demo", "the pause", |s| s.contains("PAUSED"));
    for label in ["F", "A"] {
        tmux.keys("demo", &[label]);
        tmux.wait_for("demo", &format!("block {label} held"), |s| {
            s.contains(&format!("held: {label}")) && s.contains(&format!("[{label}]"))
        });
    }
    let picks: Vec<String> = records(&demos)
        .iter()
        .filter_map(|r| match r {
            DemoRecord::Step(s) if s.correction => Some(s.action.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(picks, ["pick 15", "pick 10"]);
    // Resumed at the fastest pace, the agent steps...
    tmux.keys("demo", &["Space", "+", "+", "+", "+", "+", "+"]);
    let stepping = |n: usize| {
        let deadline = Instant::now() + Duration::from_secs(30);
        while records(&demos).len() <= n {
            assert!(Instant::now() < deadline, "the agent does not step");
            std::thread::sleep(Duration::from_millis(50));
        }
    };
    stepping(records(&demos).len());
    // ...and not while the terminal is too small to show the world.
    tmux.resize("demo", (40, 10));
    tmux.wait_for("demo", "the polite message", |s| s.contains("too small"));
    // A step already under way when the message came may still land: wait until the
    // recording has been still for half a second (however loaded the machine), then check
    // that it stays still.
    let mut shown = records(&demos).len();
    let (deadline, mut still_since) = (Instant::now() + Duration::from_secs(30), Instant::now());
    while still_since.elapsed() < Duration::from_millis(500) {
        assert!(Instant::now() < deadline, "the agent keeps stepping behind the message");
        std::thread::sleep(Duration::from_millis(50));
        let now = records(&demos).len();
        if now != shown {
            (shown, still_since) = (now, Instant::now());
        }
    }
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(records(&demos).len(), shown, "the agent stepped behind the message");
    tmux.resize("demo", roomy);
    tmux.wait_for("demo", "the world again", |s| s.contains("world"));
    stepping(shown);
    tmux.keys("demo", &["q"]);
    // It saves its model as it quits: into the scratch folder, which must still be there.
    tmux.wait_gone("demo", "q did not quit");
    assert!(dir.join("corrected.safetensors").exists());
}

#[test]
fn eval_run_and_correct_show_a_progress_bar_on_a_terminal_only() {
    if tmux_missing() {
        eprintln!("skipped: tmux is not installed");
        return;
    }
    let dir = scratch("tmux-progress");
    let model = base_model(&dir);
    let out = dir.join("corrected.safetensors");
    let tmux = Tmux::new(&dir);
    // Keeps the server up while the sessions below come and go.
    tmux.start("keep", "sleep 600");
    for (session, args, bar) in [
        (
            "run",
            vec!["run", "--agent", "random", "--episodes", "1000000"],
            "/1000000 episodes",
        ),
        (
            "eval",
            vec!["eval", "--model", path(&model), "--episodes", "100000"],
            "/1200000 episodes played and solved",
        ),
        (
            "correct",
            vec![
                "correct",
                "--model",
                path(&model),
                "--demonstrator",
                "1",
                "--demos",
                "100000",
                "--out",
                path(&out),
            ],
            "/100000 demonstrations",
        ),
    ] {
        let command = format!("{BIN} {}", args.join(" "));
        tmux.start(session, &command);
        tmux.wait_for(session, bar, |s| s.contains(bar));
        let _ = tmux.run(&["kill-session", "-t", session]);
        // Not on a terminal: no bar, nothing on stderr.
        let short: Vec<&str> = args
            .iter()
            .map(|&a| if a.starts_with("1000") { "2" } else { a })
            .collect();
        let o = blockstack(&short);
        assert!(o.status.success(), "{short:?}: {}", stderr(&o));
        assert_eq!(stderr(&o), "", "{short:?}");
    }
}
