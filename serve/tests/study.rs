//! A study's path for its participants, end to end over loopback: consent, the platform's
//! ids, time on every step, the side view's block moves, the end's completion code, a
//! withdrawal, a return; and what the researcher reads: the figures, the CSV, a replay.

use crate::common::*;
use serde_json::{Value, json};
use serve::ServeConfig;

/// A study in `dir` with one top-view and one side-view condition (no model: the
/// untrained stand-ins of each view), `episodes` each, withdrawal `withdrawal`.
fn study(dir: &std::path::Path, episodes: u64, withdrawal: &str) -> ServeConfig {
    let path = dir.join("study.toml");
    std::fs::write(
        &path,
        format!(
            r##"
name = "crowd"
seed = 3
consent = "# Consent\n\nYou agree to **be recorded**. <script>alert(1)</script>"
instructions = "Stack the blocks."
participant_ids = ["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]
completion_code = "C0DE42"
completion_url = "https://app.example.org/done?cc=C0DE42"
withdrawal = "{withdrawal}"

[[condition]]
name = "top"
episodes = {episodes}
goals = "0,1,2"
modes = ["play"]

[[condition]]
name = "side"
view = "side"
episodes = {episodes}
goals = "0,1/2"
modes = ["play"]
"##
        ),
    )
    .unwrap();
    ServeConfig {
        study: Some(path),
        record_dir: Some(dir.join("rec")),
        ..ServeConfig::default()
    }
}

/// Joins with the form `body`; the token or the refusal.
async fn join_form(addr: std::net::SocketAddr, body: &str) -> Result<String, (u16, String)> {
    let (status, response) = http(addr, "POST", "/join", body).await;
    if status != 303 {
        return Err((status, response));
    }
    let location = response.lines().find_map(|l| l.strip_prefix("location: ")).unwrap();
    Ok(location.trim().strip_prefix("/s/").unwrap().to_string())
}

fn ids(pid: &str) -> String {
    format!("consent=agree&PROLIFIC_PID={pid}&STUDY_ID=S1&SESSION_ID=X{pid}")
}

/// Plays the view's episode to the goal by the exact solver's plan (the view's world).
async fn solve_view(socket: &mut Socket, view: &Value) -> Value {
    let (state, goal) = world_of(view);
    let world = sim::EnvConfig {
        view: serde_json::from_value(view["view"].clone()).unwrap(),
        ..sim::EnvConfig::default()
    };
    let plan = oracle::ExactSolver::for_world(&world).solve(&state, &goal).unwrap();
    let mut last = view.clone();
    for a in &plan.actions {
        last = act(socket, &a.to_string()).await;
        assert_eq!(last["type"], "view", "{last}");
    }
    last
}

fn body_of(response: &str) -> &str {
    response.split("\r\n\r\n").nth(1).unwrap_or("")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_crowd_participant_consents_plays_with_time_and_gets_the_completion_code() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, results) = start(study(dir.path(), 1, "mark")).await;
    // The consent form, rendered: its Markdown as HTML, its script as text.
    let (_, response) = http(addr, "GET", "/api/study", "").await;
    let page: Value = serde_json::from_str(body_of(&response)).unwrap();
    let consent = page["consent"].as_str().unwrap();
    assert!(
        consent.contains("<strong>be recorded</strong>") && !consent.contains("<script"),
        "{consent}"
    );
    assert_eq!(
        page["participant_ids"],
        json!(["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"])
    );
    // The completion code is for those who finish, never for a visitor.
    assert!(!response.contains("C0DE42"), "{response}");
    // Without consent, nothing begins; an id the study does not read is refused.
    assert_eq!(join_form(addr, "PROLIFIC_PID=abc").await.unwrap_err().0, 400);
    assert_eq!(join_form(addr, "consent=agree&workerId=abc").await.unwrap_err().0, 400);
    assert_eq!(
        join_form(addr, "consent=agree&PROLIFIC_PID=a%2Fb").await.unwrap_err().0,
        400
    );
    assert!(!dir.path().join("rec").exists() || recordings(&dir.path().join("rec")).is_empty());

    let token = join_form(addr, &ids("5f1a")).await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    let first = receive(&mut socket).await;
    assert_eq!(
        (first["condition"].as_str(), first["withdrawal"].as_bool()),
        (Some("top"), Some(true))
    );
    assert_eq!(first["completion"], Value::Null, "no code before the end");
    // The page's clock is recorded when it is believable.
    tokio::time::sleep(std::time::Duration::from_millis(60)).await;
    let picked = ask(&mut socket, json!({"type": "act", "action": "pick 0", "t_ms": 40})).await;
    assert_eq!(picked["type"], "view");
    let last = solve_view(&mut socket, &picked).await;
    assert_eq!(last["done"], true);
    assert_eq!(
        last["completion"],
        json!({"code": "C0DE42", "url": "https://app.example.org/done?cc=C0DE42"})
    );
    let path = only_recording(&dir.path().join("rec"));
    let lines = lines(&path);
    assert_eq!(
        lines[0]["participant"]["ids"],
        json!({"PROLIFIC_PID": "5f1a", "STUDY_ID": "S1", "SESSION_ID": "X5f1a"})
    );
    assert!(lines[1]["started_ms"].as_u64().unwrap() > 1_700_000_000_000);
    let steps: Vec<&Value> = lines.iter().filter(|l| l["type"] == "step").collect();
    assert_eq!(steps[0]["t_ms"], 40);
    let times: Vec<u64> = steps.iter().map(|s| s["t_ms"].as_u64().unwrap()).collect();
    assert!(times.windows(2).all(|w| w[0] <= w[1]), "monotonic: {times:?}");
    assert!(
        steps
            .iter()
            .all(|s| s["received_ms"].as_u64().unwrap() >= lines[1]["started_ms"].as_u64().unwrap())
    );

    // Returning in the same browser (its cookie): the same session, not a new one. The id
    // alone is no key: a join with it is refused, and /api/resume answers as for anyone.
    let cookie = format!("Cookie: blockstack_session={token}\r\n");
    let (status, response) = http_with(addr, "POST", "/join", &ids("5f1a"), &cookie).await;
    assert_eq!(status, 303, "{response}");
    assert!(response.contains(&format!("/s/{token}")), "{response}");
    assert_eq!(join_form(addr, &ids("5f1a")).await.unwrap_err().0, 409);
    let (status, response) = http_with(addr, "POST", "/api/resume", "PROLIFIC_PID=5f1a", &cookie).await;
    assert_eq!(status, 200);
    assert!(body_of(&response).contains(&token));
    let (_, known) = http(addr, "POST", "/api/resume", "PROLIFIC_PID=5f1a").await;
    let (_, unknown) = http(addr, "POST", "/api/resume", "PROLIFIC_PID=new1").await;
    assert_eq!(body_of(&known), body_of(&unknown));
    assert_eq!(body_of(&known), r#"{"token":null}"#);

    // The researcher's figures, CSV and replay.
    let api = results
        .split_once(&addr.to_string())
        .unwrap()
        .1
        .replace("/results/", "/api/results/");
    let (_, response) = http(addr, "GET", &api, "").await;
    let data: Value = serde_json::from_str(body_of(&response)).unwrap();
    let top = &data["table"]["conditions"][0];
    assert_eq!(
        (top["condition"].as_str(), top["participants"].as_u64()),
        (Some("top"), Some(1))
    );
    assert_eq!(
        (top["episodes"].as_u64(), top["success"].as_f64()),
        (Some(1), Some(1.0))
    );
    assert_eq!(
        top["steps_to_optimum"].as_f64(),
        Some(1.0),
        "played by the shortest plan"
    );
    assert!(top["median_rt_ms"].as_u64().is_some());
    let (status, response) = http(addr, "GET", &format!("{api}/episodes.csv"), "").await;
    assert_eq!(status, 200);
    let csv: Vec<&str> = body_of(&response).lines().collect();
    assert_eq!(csv.len(), 2, "{csv:?}");
    assert!(csv[0].starts_with("participant,code,participant_id,condition,view,goal,episode,"));
    assert!(csv[1].contains(",5f1a,top,top,\"0,1,2\",0,"), "{}", csv[1]);
    let file = path.file_name().unwrap().to_str().unwrap();
    let replay = api.replace("/api/results/", "/api/replay/") + &format!("/{file}/0");
    let (status, response) = http(addr, "GET", &replay, "").await;
    assert_eq!(status, 200);
    let replayed: Value = serde_json::from_str(body_of(&response)).unwrap();
    assert_eq!(replayed["steps"].as_array().unwrap().len(), steps.len());
    assert_eq!(replayed["steps"][0]["action"], "pick 0");
    assert_eq!(
        http(addr, "GET", &replay.replace(file, "../study.toml"), "").await.0,
        404
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_side_view_is_played_by_block_moves_and_falls() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(study(dir.path(), 1, "mark")).await;
    // The first participant gets the top view; the second the side view.
    join_form(addr, &ids("p1")).await.unwrap();
    let token = join_form(addr, &ids("p2")).await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    let view = receive(&mut socket).await;
    assert_eq!(
        (view["condition"].as_str(), view["view"].as_str()),
        (Some("side"), Some("side"))
    );
    // The side view's fewest block moves, each sent as a click on a block and a column.
    let mut last = view.clone();
    for _ in 0..10 {
        if last["over"] == true {
            break;
        }
        let (state, goal) = world_of(&last);
        let grid = sim::Grid::default();
        let plan = oracle::towers::plan_side(oracle::towers::MovePlanner::Exact, grid, &state, &goal).unwrap();
        let mv = oracle::towers::block_move_of(&state, grid, plan.moves[0]).unwrap();
        let (block, to) = match mv {
            sim::BlockMove::Onto { block, target } => (block.0, last["blocks"][target.index()][0].as_u64().unwrap()),
            sim::BlockMove::ToTable { block, column } => (block.0, u64::from(column)),
        };
        last = ask(&mut socket, json!({"type": "move", "block": block, "to": to})).await;
        assert_eq!(last["type"], "view", "{last}");
    }
    assert_eq!(last["outcome"], "goal", "{last}");
    let side = std::fs::read_dir(dir.path().join("rec"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.to_str().unwrap().contains("-side"))
        .unwrap();
    let lines = lines(&side);
    assert_eq!(lines[0]["view"], "side");
    // Every gripper step of every move recorded, each the person's.
    assert!(
        lines
            .iter()
            .filter(|l| l["type"] == "step")
            .all(|s| s["correction"] == true)
    );
    // A move the rules refuse changes nothing.
    let next = ask(&mut socket, json!({"type": "move", "block": 9, "to": 0})).await;
    assert_eq!(next["type"], "error");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_withdrawal_marks_or_deletes_and_leaves_the_participant_out() {
    for how in ["mark", "delete"] {
        let dir = tempfile::tempdir().unwrap();
        let (addr, results) = start(study(dir.path(), 2, how)).await;
        let token = join_form(addr, &ids("w1")).await.unwrap();
        let mut socket = connect(addr, &token, None).await.unwrap();
        receive(&mut socket).await;
        act(&mut socket, "pick 0").await;
        let (status, response) = http(addr, "POST", &format!("/api/withdraw/{token}"), "").await;
        assert_eq!(status, 200, "{response}");
        let files = recordings(&dir.path().join("rec"));
        match how {
            "mark" => {
                let path = only_recording(&dir.path().join("rec"));
                assert_eq!(lines(&path).last().unwrap()["type"], "withdrawn");
                assert!(agent::demos::read_demonstrations(&path, None).unwrap().withdrawn);
            }
            _ => {
                assert!(files.is_empty(), "deleted");
                // Nothing of w1 left but a keyed hash of the id.
                let ledger = std::fs::read_to_string(dir.path().join("rec/.serve-ledger.jsonl")).unwrap();
                assert!(!ledger.contains("w1") && !ledger.contains("p0000"), "{ledger}");
            }
        }
        // The session is gone, the id refused, the figures leave it out, and the place in
        // the balance is free again.
        let after = act(&mut socket, "up").await;
        assert!(after["message"].as_str().unwrap().contains("withdrew"), "{after}");
        assert_eq!(join_form(addr, &ids("w1")).await.unwrap_err().0, 403);
        let api = results
            .split_once(&addr.to_string())
            .unwrap()
            .1
            .replace("/results/", "/api/results/");
        let (_, response) = http(addr, "GET", &api, "").await;
        let data: Value = serde_json::from_str(body_of(&response)).unwrap();
        assert_eq!(data["table"]["episodes"], json!([]), "{how}");
        assert_eq!(data["table"]["conditions"][0]["participants"], 0);
        if how == "mark" {
            // The page says one was left out; its replay says why.
            assert_eq!(data["table"]["withdrawn"], 1);
            let replay = api.replace("/api/results/", "/api/replay/") + "/p0000-top.jsonl/0";
            let (status, response) = http(addr, "GET", &replay, "").await;
            assert_eq!(status, 404);
            assert!(response.contains("withdrew"), "{response}");
        }
        let next = join_form(addr, &ids("w2")).await.unwrap();
        let mut socket = connect(addr, &next, None).await.unwrap();
        assert_eq!(receive(&mut socket).await["condition"], "top", "{how}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_that_reconnects_mid_episode_loses_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(study(dir.path(), 2, "mark")).await;
    let token = join_form(addr, &ids("r1")).await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    receive(&mut socket).await;
    let mut before = Value::Null;
    for a in ["pick 1", "up", "right"] {
        before = act(&mut socket, a).await;
    }
    drop(socket);
    let mut again = connect(addr, &token, None).await.unwrap();
    let after = receive(&mut again).await;
    for key in ["blocks", "held", "steps", "episode", "progress"] {
        assert_eq!(after[key], before[key], "{key}");
    }
    let more = act(&mut again, "down").await;
    assert_eq!(more["steps"], 4);
    let path = only_recording(&dir.path().join("rec"));
    let steps: Vec<u64> = lines(&path)
        .iter()
        .filter(|l| l["type"] == "step")
        .map(|l| l["step"].as_u64().unwrap())
        .collect();
    assert_eq!(steps, [1, 2, 3, 4]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn own_codes_required_ids_and_a_code_for_those_who_withdraw() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("study.toml");
    std::fs::write(
        &path,
        r#"
participant_ids = ["PROLIFIC_PID", "STUDY_ID", "SESSION_ID"]
require_ids = true
code_per_participant = true
completion_url = "https://app.example.org/done?cc={code}"
completion_on_withdrawal = true
withdrawal = "mark"
idle_minutes = 45
joins_per_minute = 5

[[condition]]
name = "top"
episodes = 1
goals = "0,1,2"
modes = ["play"]
"#,
    )
    .unwrap();
    let config = ServeConfig {
        study: Some(path),
        record_dir: Some(dir.path().join("rec")),
        ..ServeConfig::default()
    };
    let (addr, results) = start(config).await;
    // Without every id the study names: refused.
    let (status, response) = http(addr, "POST", "/join", "PROLIFIC_PID=a1").await;
    assert_eq!(status, 400, "{response}");
    assert!(response.contains("STUDY_ID"), "{response}");
    // Two participants finish: each gets a code of their own, in the link too.
    let mut codes = Vec::new();
    for pid in ["a1", "b2"] {
        let token = join_form(addr, &ids(pid)).await.unwrap();
        let mut socket = connect(addr, &token, None).await.unwrap();
        let view = receive(&mut socket).await;
        let last = solve_view(&mut socket, &view).await;
        let code = last["completion"]["code"].as_str().unwrap().to_string();
        assert_eq!(code.len(), 8);
        assert_eq!(
            last["completion"]["url"].as_str().unwrap(),
            format!("https://app.example.org/done?cc={code}")
        );
        codes.push(code);
    }
    assert_ne!(codes[0], codes[1]);
    // The CSV lists each finished participant's code.
    let api = results
        .split_once(&addr.to_string())
        .unwrap()
        .1
        .replace("/results/", "/api/results/");
    let (_, response) = http(addr, "GET", &format!("{api}/episodes.csv"), "").await;
    let csv = body_of(&response);
    assert!(csv.lines().next().unwrap().ends_with(",completion_code"), "{csv}");
    for code in &codes {
        assert_eq!(csv.matches(code.as_str()).count(), 1, "{csv}");
    }
    // One who withdraws is given their code too (the study says so).
    let token = join_form(addr, &ids("c3")).await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    receive(&mut socket).await;
    act(&mut socket, "pick 0").await;
    let (status, response) = http(addr, "POST", &format!("/api/withdraw/{token}"), "").await;
    assert_eq!(status, 200, "{response}");
    let answer: Value = serde_json::from_str(body_of(&response)).unwrap();
    assert_eq!(answer["completion"]["code"].as_str().unwrap().len(), 8, "{answer}");
    // The fifth join from this address within the minute is refused (joins_per_minute = 5:
    // a1, b2, c3 and the refused one above made four).
    assert!(join_form(addr, &ids("d4")).await.is_ok());
    assert_eq!(join_form(addr, &ids("e5")).await.unwrap_err().0, 429);
}
