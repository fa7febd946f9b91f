//! The server end to end over loopback: a person plays an episode, corrects the agent and
//! watches it; bad input changes nothing; sessions cannot reach each other; a study hands
//! out conditions in turn; a killed server keeps every acknowledged line.

use crate::common::*;
use futures_util::SinkExt;
use serde_json::{Value, json};
use serve::ServeConfig;
use sim::Action;

fn config(record_dir: &std::path::Path) -> ServeConfig {
    ServeConfig {
        record_dir: Some(record_dir.to_path_buf()),
        ..ServeConfig::default()
    }
}

/// Plays the view's episode to the goal by the exact solver's plan; the actions sent and
/// the last view.
async fn solve(socket: &mut Socket, view: &Value) -> (Vec<Action>, Value) {
    let (state, goal) = world_of(view);
    let protocol = if view["legal"].as_array().unwrap().len() == 8 {
        sim::ActionProtocol::Free
    } else {
        sim::ActionProtocol::Paper
    };
    let plan = oracle::ExactSolver::new(sim::Grid::default())
        .with_protocol(protocol)
        .solve(&state, &goal)
        .unwrap();
    let mut last = view.clone();
    for &a in &plan.actions {
        last = act(socket, &a.to_string()).await;
        assert_eq!(last["type"], "view", "{last}");
    }
    (plan.actions, last)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_person_plays_an_episode_and_every_step_is_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(config(dir.path())).await;
    let token = join(addr, "P01").await.unwrap();
    assert_eq!(token.len(), 32);
    let mut socket = connect(addr, &token, Some(&format!("http://{addr}"))).await.unwrap();
    let first = receive(&mut socket).await;
    assert_eq!(first["mode"], "play");
    assert_eq!(first["modes"], json!(["play"]));
    assert_eq!(first["colours"][0], "#dc322f", "sim::render's palette");
    let (actions, last) = solve(&mut socket, &first).await;
    assert!(last["over"].as_bool().unwrap());
    assert_eq!(last["outcome"], "goal");
    assert_eq!(last["shortest"].as_u64().unwrap() as usize, actions.len());
    assert_eq!(last["steps"].as_u64().unwrap() as usize, actions.len());
    assert!(last["message"].as_str().unwrap().contains("Goal reached"), "{last}");
    assert_eq!(last["progress"]["episodes_done"], 1);

    let path = only_recording(dir.path());
    assert!(
        path.file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .ends_with("-default-P01.jsonl")
    );
    let lines = lines(&path);
    assert_eq!(
        last["progress"]["recorded_lines"].as_u64().unwrap() as usize,
        lines.len()
    );
    assert_eq!(lines[0]["type"], "session");
    assert_eq!(lines[0]["version"], agent::demos::DEMOS_VERSION);
    assert_eq!(lines[0]["demonstrator"], "person");
    assert_eq!(lines[1]["type"], "episode");
    let steps: Vec<&Value> = lines[2..].iter().collect();
    assert_eq!(steps.len(), actions.len());
    for (i, (line, a)) in steps.iter().zip(&actions).enumerate() {
        assert_eq!(line["type"], "step");
        assert_eq!(line["step"].as_u64().unwrap() as usize, i + 1);
        assert_eq!(line["action"], a.to_string());
        assert_eq!(line["correction"], true);
    }
    // The reader of recordings takes it as it is, every line checked against the rules.
    let episodes = agent::demos::read_episodes(&path, None).unwrap();
    assert_eq!(episodes.len(), 1);
    assert_eq!(episodes[0].steps.len(), actions.len());

    // An action after the end is refused; n begins the next episode.
    let refused = act(&mut socket, "up").await;
    assert_eq!(refused["type"], "error");
    let next = ask(&mut socket, json!({"type": "next", "id": 9})).await;
    assert_eq!((next["episode"].as_u64(), next["id"].as_u64()), (Some(1), Some(9)));
    assert_eq!(next["steps"], 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_gets_one_line_and_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(config(dir.path())).await;
    let token = join(addr, "").await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    receive(&mut socket).await;
    // A step first: the recording is made with it.
    let first = act(&mut socket, "pick 0").await;
    let path = only_recording(dir.path());
    let before = std::fs::read(&path).unwrap();
    let bad = [
        "not json".to_string(),
        "{\"type\":\"act\"}".to_string(),
        json!({"type": "act", "action": "jump"}).to_string(),
        json!({"type": "act", "action": "pick 7"}).to_string(),
        json!({"type": "act", "action": "up", "extra": 1}).to_string(),
        json!({"type": "fly", "id": 3}).to_string(),
        json!({"type": "accept", "id": 4}).to_string(),
        json!({"type": "step"}).to_string(),
        json!({"type": "mode", "mode": "watch"}).to_string(),
        json!({"type": "mode", "mode": "../../etc"}).to_string(),
        json!({"type": "act", "action": "x".repeat(5000)}).to_string(),
        "[1,2,3]".to_string(),
    ];
    for text in &bad {
        socket
            .send(tokio_tungstenite::tungstenite::Message::Text(text.clone().into()))
            .await
            .unwrap();
        let answer = receive(&mut socket).await;
        assert_eq!(answer["type"], "error", "{text} -> {answer}");
        let message = answer["message"].as_str().unwrap();
        assert!(
            !message.contains('\n') && message.contains("nothing was done"),
            "{message}"
        );
    }
    socket
        .send(tokio_tungstenite::tungstenite::Message::Binary(vec![1, 2, 3].into()))
        .await
        .unwrap();
    assert_eq!(receive(&mut socket).await["type"], "error");
    // The ids of refused messages come back when they could be read.
    let fly = ask(&mut socket, json!({"type": "fly", "id": 77})).await;
    assert_eq!(fly["id"], 77);
    assert_eq!(std::fs::read(&path).unwrap(), before, "the recording is untouched");
    // A move with nothing held is no error under the free protocol; the state is as it was
    // before the bad messages.
    let now = ask(&mut socket, json!({"type": "mode", "mode": "play"})).await;
    assert_eq!(
        (now["blocks"].clone(), now["steps"].clone()),
        (first["blocks"].clone(), json!(1))
    );

    // A message larger than the frame bound ends the connection.
    let huge = "y".repeat(100 * 1024);
    let _ = socket
        .send(tokio_tungstenite::tungstenite::Message::Text(huge.into()))
        .await;
    use futures_util::StreamExt;
    let end = tokio::time::timeout(std::time::Duration::from_secs(5), async {
        loop {
            match socket.next().await {
                None | Some(Err(_)) => return true,
                Some(Ok(tokio_tungstenite::tungstenite::Message::Close(_))) => return true,
                Some(Ok(_)) => {}
            }
        }
    })
    .await;
    assert_eq!(end, Ok(true));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sessions_are_isolated_and_tokens_checked() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, results) = start(config(dir.path())).await;
    let a = join(addr, "alice").await.unwrap();
    let b = join(addr, "bob").await.unwrap();
    assert_ne!(a, b);
    // A name with a path in it is refused, and nothing is written anywhere.
    for name in ["..%2Fevil", "a%2Fb", "x%00y", &"n".repeat(40)] {
        let (status, body) = join(addr, name).await.unwrap_err();
        assert_eq!(status, 400, "{body}");
        assert!(body.contains("not a name"), "{body}");
    }
    assert_eq!(recordings(dir.path()).len(), 0, "nothing is on disk before a step");

    // A stale or made-up token: one clear error, then the connection closes with the
    // policy code (1008), never a second copy of the message.
    let mut stale = connect(addr, &"0".repeat(32), None).await.unwrap();
    let answer = receive(&mut stale).await;
    assert_eq!(answer["type"], "error");
    assert!(answer["message"].as_str().unwrap().contains("not known"));
    assert_eq!(close_code(&mut stale).await, Some(1008));
    // Another site's page may not open a session.
    let foreign = connect(addr, &a, Some("http://evil.example")).await;
    assert!(foreign.unwrap_err().contains("403"));
    let (status, _) = http_with(addr, "POST", "/join", "name=x", "Origin: http://evil.example\r\n").await;
    assert_eq!(status, 403);
    let (status, _) = http_with(addr, "POST", "/join", "name=x", &format!("Origin: http://{addr}\r\n")).await;
    assert_eq!(status, 303);
    // One page per session: the newest has it (a frozen or lost page locks nothing), and
    // the one before is told at its next message, then closed.
    let mut first = connect(addr, &a, None).await.unwrap();
    let view_a = receive(&mut first).await;
    let mut second = connect(addr, &a, None).await.unwrap();
    assert_eq!(receive(&mut second).await["blocks"], view_a["blocks"]);
    let told = act(&mut first, "up").await;
    assert!(told["message"].as_str().unwrap().contains("another window"), "{told}");
    assert_eq!(close_code(&mut first).await, Some(4001));
    // Bob's moves never reach Alice's recording.
    let mut bob = connect(addr, &b, None).await.unwrap();
    let view_b = receive(&mut bob).await;
    let pick = format!("pick {}", 0);
    act(&mut bob, &pick).await;
    act(&mut bob, "up").await;
    let files: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    let alice_file = files.iter().find(|p| p.to_str().unwrap().ends_with("alice.jsonl"));
    let bob_file = files
        .iter()
        .find(|p| p.to_str().unwrap().ends_with("bob.jsonl"))
        .unwrap();
    assert!(alice_file.is_none(), "Alice took no step: no recording of hers");
    assert_eq!(lines(bob_file).len(), 4);
    // Both play the condition's seeded starts: the same first episode.
    assert_eq!(view_a["blocks"], view_b["blocks"]);

    // The researcher's page is behind its own token; a participant's does not open it.
    let path = results.split_once(&addr.to_string()).unwrap().1.to_string();
    let api = path.replace("/results/", "/api/results/");
    let (status, body) = http(addr, "GET", &api, "").await;
    assert_eq!(status, 200);
    assert!(
        body.contains("\"name\":\"bob\"") && body.contains("\"steps\":2"),
        "{body}"
    );
    assert_eq!(http(addr, "GET", &format!("/api/results/{a}"), "").await.0, 404);
    assert_eq!(http(addr, "GET", &format!("/results/{a}"), "").await.0, 404);
    assert_eq!(http(addr, "GET", &path, "").await.0, 200);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn too_many_messages_a_second_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(config(dir.path())).await;
    let token = join(addr, "").await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    receive(&mut socket).await;
    // 200 cheap steps (a move with nothing held changes nothing but is a step) as fast as
    // the answers come: far more than the 20 a second allowed.
    let clock = std::time::Instant::now();
    let mut refused = 0;
    for _ in 0..200 {
        let answer = act(&mut socket, "up").await;
        if answer["type"] == "error" {
            assert!(answer["message"].as_str().unwrap().contains("too many messages"));
            refused += 1;
        }
    }
    let allowed = 20.0 + 20.0 * clock.elapsed().as_secs_f64();
    assert!((200 - refused) as f64 <= allowed + 1.0, "{refused} of 200 refused");
    assert!(refused > 0);
    // Every accepted step is recorded; the refused ones are not.
    let path = only_recording(dir.path());
    let steps = lines(&path).iter().filter(|l| l["type"] == "step").count();
    assert_eq!(steps, 200 - refused);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_person_corrects_the_agent_and_watches_it() {
    let dir = tempfile::tempdir().unwrap();
    let model = tabular_model(dir.path());
    let record = dir.path().join("recordings");
    let (addr, _) = start(ServeConfig {
        model: Some(model.clone()),
        goals: Some("0,1,2".into()),
        ..config(&record)
    })
    .await;
    let token = join(addr, "").await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    let first = receive(&mut socket).await;
    assert_eq!(first["modes"], json!(["play", "watch", "correct"]));
    let view = ask(&mut socket, json!({"type": "mode", "mode": "correct"})).await;
    assert_eq!(view["mode"], "correct");
    assert_eq!(view["episode"], 1, "correct mode begins an episode of its own");
    let proposal = view["proposal"].as_str().unwrap().to_string();
    assert_eq!(view["q"].as_array().unwrap().len(), 8);
    // Accept twice, then override with a pick of block 2 and a move.
    let mut expected = vec![];
    let mut v = view;
    for _ in 0..2 {
        let p = v["proposal"].as_str().unwrap().to_string();
        v = ask(&mut socket, json!({"type": "accept"})).await;
        expected.push((p.clone(), p, false));
    }
    let p = v["proposal"].as_str().unwrap().to_string();
    v = act(&mut socket, "pick 2").await;
    expected.push((p, "pick 2".to_string(), true));
    let p = v["proposal"].as_str().unwrap().to_string();
    v = act(&mut socket, "right").await;
    expected.push((p, "right".to_string(), true));
    assert_eq!(v["progress"]["corrections"], 2);
    assert!(!proposal.is_empty());

    let path = only_recording(&record);
    let lines = lines(&path);
    let steps: Vec<(String, String, bool)> = lines
        .iter()
        .filter(|l| l["type"] == "step")
        .map(|l| {
            (
                l["proposed"].as_str().unwrap().into(),
                l["action"].as_str().unwrap().into(),
                l["correction"].as_bool().unwrap(),
            )
        })
        .collect();
    assert_eq!(steps, expected);
    assert_eq!(lines[0]["model"], model.display().to_string());
    // learn-from-demos replays it into the model it started from.
    let mut agent = agent::QAgent::load(&model).unwrap();
    let report = agent::demos::learn_from_file(&mut agent, &path, agent::BadLines::Fail).unwrap();
    assert_eq!((report.steps, report.corrections), (4, 2));

    // Watch: the greedy choice and the legal actions' values; steps at the person's pace.
    let w = ask(&mut socket, json!({"type": "mode", "mode": "watch"})).await;
    assert_eq!(w["mode"], "watch");
    let greedy = w["greedy"].as_str().unwrap().to_string();
    assert!(
        w["q"]
            .as_array()
            .unwrap()
            .iter()
            .any(|q| q["action"] == greedy.as_str())
    );
    let after = ask(&mut socket, json!({"type": "step"})).await;
    assert_eq!(after["steps"], 1);
    assert!(after["message"].as_str().unwrap().contains(&greedy), "{after}");
    assert_eq!(self::lines(&path).len(), lines.len(), "watching records nothing");
    // Moves of one's own are not part of watch mode.
    assert_eq!(act(&mut socket, "up").await["type"], "error");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_study_hands_out_conditions_in_turn_and_counts_progress() {
    let dir = tempfile::tempdir().unwrap();
    let model = tabular_model(dir.path());
    let study = dir.path().join("study.toml");
    std::fs::write(
        &study,
        format!(
            r#"
name = "pilot"
seed = 5
max_participants = 3

[[condition]]
name = "solo"
episodes = 1
modes = ["play"]

[[condition]]
name = "teach"
model = "{}"
profile = "original"
episodes = 2
modes = ["correct", "play"]
"#,
            model.file_name().unwrap().to_str().unwrap()
        ),
    )
    .unwrap();
    let record = dir.path().join("out");
    let (addr, results) = start(ServeConfig {
        study: Some(study.clone()),
        ..config(&record)
    })
    .await;
    let mut views = vec![];
    for name in ["a", "b", "c"] {
        let token = join(addr, name).await.unwrap();
        let mut socket = connect(addr, &token, None).await.unwrap();
        views.push((receive(&mut socket).await, socket));
    }
    let conditions: Vec<&str> = views.iter().map(|(v, _)| v["condition"].as_str().unwrap()).collect();
    assert_eq!(conditions, ["solo", "teach", "solo"]);
    assert_eq!(views[1].0["mode"], "correct");
    // Under the original profile a move with nothing held is refused, naming what is allowed.
    let refused = act(&mut views[1].1, "up").await;
    assert!(refused["message"].as_str().unwrap().contains("only pick"), "{refused}");
    // A refused action is no step: b does not count yet; b and c act now.
    for k in [1, 2] {
        assert_eq!(act(&mut views[k].1, "pick 0").await["type"], "view");
    }
    // Participant a finishes the one episode asked for.
    let (first, socket) = &mut views[0];
    let first = first.clone();
    let (_, last) = solve(socket, &first).await;
    assert_eq!(last["done"], true);
    // Three acted: the fourth is turned away.
    let (status, body) = join(addr, "d").await.unwrap_err();
    assert_eq!(status, 503, "{body}");
    let after = ask(socket, json!({"type": "next"})).await;
    assert!(after["message"].as_str().unwrap().contains("finished"), "{after}");
    let api = results
        .split_once(&addr.to_string())
        .unwrap()
        .1
        .replace("/results/", "/api/results/");
    let (_, body) = http(addr, "GET", &api, "").await;
    let json: Value = serde_json::from_str(body.split("\r\n\r\n").nth(1).unwrap()).unwrap();
    assert_eq!(json["study"], "pilot");
    let rows = json["sessions"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[0]["done"], true);
    assert_eq!(rows[0]["recording"], "p0000-solo-a.jsonl");
    assert_eq!(rows[1]["recording"], "p0001-teach-b.jsonl");
    assert_eq!(recordings(&record).len(), 3);
}

#[tokio::test]
async fn a_study_that_cannot_work_is_refused_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study.toml");
    let cases = [
        ("max_participants = 0\n[[condition]]\nname = \"a\"\n", "admits no one"),
        (
            "[[condition]]\nname = \"a\"\nmodes = [\"play\", \"play\"]\n",
            "listed twice",
        ),
        ("[[condition]]\nname = \"a\"\ngoals = \"0,1/2\"\n", "condition a"),
        ("[[condition]]\nname = \"a\"\nmodes = [\"watch\"]\n", "needs a model"),
        ("[[condition]]\nname = \"../a\"\n", "not a name"),
        ("[[condition]]\nname = \"a\"\ncolour = 1\n", "unknown field"),
        ("name = \"x\"\n", "missing field"),
        ("[[condition]]\nname = \"a\"\nprofile = \"paper\"\n", "profile"),
    ];
    for (text, expected) in cases {
        std::fs::write(&study, text).unwrap();
        let error = serve::Server::bind(ServeConfig {
            study: Some(study.clone()),
            port: 0,
            ..config(dir.path())
        })
        .await
        .err()
        .unwrap()
        .to_string();
        assert!(error.contains(expected), "{text} -> {error}");
        // The condition is named once (P22: "condition a: condition a: ..." before).
        assert!(error.matches("condition a:").count() <= 1, "{error}");
    }
}

/// The server of the kill test, run in a child process (this test binary again): prints
/// its port, then serves until killed.
#[test]
#[ignore = "run by recordings_survive_a_kill in a child process"]
fn child_server() {
    let Ok(dir) = std::env::var("SERVE_CHILD_DIR") else {
        return;
    };
    let study = std::env::var("SERVE_CHILD_STUDY").ok().map(Into::into);
    let config = ServeConfig {
        study,
        ..config(std::path::Path::new(&dir)).with_port0()
    };
    serve::run(config, |links| {
        println!("{}", links.join);
        Ok(())
    })
    .unwrap();
}

trait Port0 {
    fn with_port0(self) -> Self;
}

impl Port0 for ServeConfig {
    fn with_port0(self) -> Self {
        ServeConfig { port: 0, ..self }
    }
}

/// A server in a child process (this test binary again, [`child_server`]) recording into
/// `dir`, with the study at `study` if given: killed however the test ends.
pub struct Child(pub std::process::Child);

impl Drop for Child {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Starts a [`Child`] server; it and its address.
pub fn child(dir: &std::path::Path, study: Option<&std::path::Path>) -> (Child, std::net::SocketAddr) {
    use std::io::BufRead;
    let mut command = std::process::Command::new(std::env::current_exe().unwrap());
    command
        .args([
            "session::child_server",
            "--exact",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("SERVE_CHILD_DIR", dir)
        .stdout(std::process::Stdio::piped());
    if let Some(study) = study {
        command.env("SERVE_CHILD_STUDY", study);
    }
    let mut process = command.spawn().unwrap();
    let mut out = std::io::BufReader::new(process.stdout.take().unwrap());
    let child = Child(process);
    let addr = loop {
        let mut line = String::new();
        assert_ne!(out.read_line(&mut line).unwrap(), 0, "the child ended before serving");
        // libtest writes "test child_server ... " before the child's own line.
        if let Some((_, rest)) = line.trim().split_once("http://") {
            break rest.trim_end_matches('/').parse().unwrap();
        }
    };
    (child, addr)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn recordings_survive_a_kill() {
    let dir = tempfile::tempdir().unwrap();
    let (mut child, addr) = child(dir.path(), None);
    let token = join(addr, "").await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    let mut acknowledged = receive(&mut socket).await["progress"]["recorded_lines"]
        .as_u64()
        .unwrap();
    for a in ["pick 0", "up", "right", "drop", "pick 1", "left"] {
        acknowledged = act(&mut socket, a).await["progress"]["recorded_lines"]
            .as_u64()
            .unwrap();
    }
    child.0.kill().unwrap();
    child.0.wait().unwrap();
    let path = only_recording(dir.path());
    let lines = lines(&path);
    assert_eq!(lines.len() as u64, acknowledged);
    assert_eq!(lines.len(), 2 + 6);
    agent::demos::read_episodes(&path, None).unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_side_view_shows_goals_of_towers_and_its_own_shortest_plans() {
    let dir = tempfile::tempdir().unwrap();
    let model = side_model(dir.path());
    let record = dir.path().join("recordings");
    let (addr, _) = start(ServeConfig {
        model: Some(model.clone()),
        goals: Some("0,1/2:0/1/2".into()),
        ..config(&record)
    })
    .await;
    let token = join(addr, "").await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    let first = receive(&mut socket).await;
    assert_eq!(first["view"], "side");
    // Two goals that one flat list would make the same stack.
    assert_eq!(first["goal"], json!({"towers": [[0, 1], [2]], "blocks": 3}));
    let (state, goal) = world_of(&first);
    let world = sim::EnvConfig {
        view: sim::View::Side,
        ..sim::EnvConfig::default()
    };
    // The side view's shortest plan (gripper steps), not the top view's.
    let plan = oracle::ExactSolver::for_world(&world).solve(&state, &goal).unwrap();
    let mut last = first.clone();
    for a in &plan.actions {
        last = act(&mut socket, &a.to_string()).await;
        assert_eq!(last["type"], "view", "{last}");
    }
    assert_eq!(last["outcome"], "goal");
    assert_eq!(last["shortest"].as_u64().unwrap() as usize, plan.len());
    let next = ask(&mut socket, json!({"type": "next"})).await;
    assert_eq!(next["goal"], json!({"towers": [[0], [1], [2]], "blocks": 3}));
    // The recording names its view and replays under the side view's rules.
    let path = only_recording(&record);
    assert_eq!(lines(&path)[0]["view"], "side");
    let mut agent = agent::QAgent::load(&model).unwrap();
    let report = agent::demos::learn_from_file(&mut agent, &path, agent::BadLines::Fail).unwrap();
    assert_eq!(report.steps, plan.len());
    let episodes = agent::demos::read_episodes(&path, None).unwrap();
    assert_eq!(episodes[0].view, sim::View::Side);
}
