//! A server restarted on the same record folder goes on from what the folder holds:
//! participant numbers, the study's cap and the balance of its conditions.

use crate::common::*;
use serve::ServeConfig;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn numbering_the_cap_and_the_balance_go_on_after_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("study.toml");
    std::fs::write(
        &study,
        "name = \"pilot\"\nmax_participants = 4\n\n[[condition]]\nname = \"a\"\n\n[[condition]]\nname = \"a-b\"\n\n[[condition]]\nname = \"c\"\n",
    )
    .unwrap();
    let record = dir.path().join("out");
    let config = || ServeConfig {
        study: Some(study.clone()),
        record_dir: Some(record.clone()),
        ..ServeConfig::default()
    };
    let (first, _) = start(config()).await;
    join_acting(first, "x").await;
    join_acting(first, "y").await;
    // Joins that never act count for nothing, and leave nothing behind.
    for name in ["bot1", "bot2", "bot3", "bot4"] {
        join(first, name).await.unwrap();
    }
    // A second run on the same folder (the first could have been killed: nothing it held
    // in memory is needed).
    let (second, _) = start(config()).await;
    join_acting(second, "z").await;
    let names: Vec<String> = recordings(&record)
        .iter()
        .map(|p| p.file_name().unwrap().to_str().unwrap().to_string())
        .collect();
    // Numbers go on (never two p0000), and the condition no one has yet comes next.
    assert_eq!(names, ["p0000-a-x.jsonl", "p0001-a-b-y.jsonl", "p0002-c-z.jsonl"]);
    for (name, condition) in [("p0001-a-b-y.jsonl", "a-b"), ("p0002-c-z.jsonl", "c")] {
        let header = &lines(&record.join(name))[0];
        assert_eq!(header["participant"]["condition"], condition);
    }
    // The cap of 4 counts the first run's participants: one more, then no one.
    join_acting(second, "w").await;
    let (status, body) = join(second, "v").await.unwrap_err();
    assert_eq!(status, 503, "{body}");
    assert!(body.contains("takes 4 participants"), "{body}");
    let (third, _) = start(config()).await;
    assert_eq!(join(third, "u").await.unwrap_err().0, 503);
}

/// A study of two conditions (top and side view, stand-in agents), 2 episodes each, with
/// platform ids, in `dir`.
fn crowd(dir: &std::path::Path) -> std::path::PathBuf {
    let study = dir.join("crowd.toml");
    std::fs::write(
        &study,
        "seed = 4\nparticipant_ids = [\"PROLIFIC_PID\"]\n\n[[condition]]\nname = \"top\"\ngoals = \"0,1,2\"\nepisodes = 2\nmodes = [\"play\"]\n\n[[condition]]\nname = \"side\"\nview = \"side\"\ngoals = \"0,1/2\"\nepisodes = 2\nmodes = [\"play\"]\n",
    )
    .unwrap();
    study
}

async fn join_id(addr: std::net::SocketAddr, pid: &str) -> String {
    let (status, response) = http(addr, "POST", "/join", &format!("PROLIFIC_PID={pid}")).await;
    assert_eq!(status, 303, "{response}");
    let location = response.lines().find_map(|l| l.strip_prefix("location: ")).unwrap();
    location.trim().strip_prefix("/s/").unwrap().to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_a_kill_every_acknowledged_line_is_kept_and_returning_participants_resume() {
    let dir = tempfile::tempdir().unwrap();
    let study = crowd(dir.path());
    let record = dir.path().join("rec");
    std::fs::create_dir(&record).unwrap();
    let (mut server, addr) = crate::session::child(&record, Some(&study));
    // The first participant finishes an episode and begins the next; the second plays a
    // little of the side view.
    let first = join_id(addr, "alpha").await;
    let mut socket = connect(addr, &first, None).await.unwrap();
    let view = receive(&mut socket).await;
    let (state, goal) = world_of(&view);
    let plan = oracle::ExactSolver::new(sim::Grid::default())
        .solve(&state, &goal)
        .unwrap();
    let mut last = view;
    for a in &plan.actions {
        last = act(&mut socket, &a.to_string()).await;
    }
    assert_eq!(last["progress"]["episodes_done"], 1);
    ask(&mut socket, serde_json::json!({"type": "next"})).await;
    let mut acknowledged = 0;
    for a in ["pick 0", "up"] {
        acknowledged = act(&mut socket, a).await["progress"]["recorded_lines"]
            .as_u64()
            .unwrap();
    }
    let second = join_id(addr, "beta").await;
    let mut other = connect(addr, &second, None).await.unwrap();
    let side = receive(&mut other).await;
    assert_eq!(side["condition"], "side");
    let pick = side["legal"][0].as_str().unwrap().to_string();
    let other_acknowledged = act(&mut other, &pick).await["progress"]["recorded_lines"]
        .as_u64()
        .unwrap();
    // kill -9: nothing is flushed on the way out.
    server.0.kill().unwrap();
    server.0.wait().unwrap();
    let alpha = record.join("p0000-top.jsonl");
    let beta = record.join("p0001-side.jsonl");
    assert_eq!(lines(&alpha).len() as u64, acknowledged);
    assert_eq!(lines(&beta).len() as u64, other_acknowledged);

    // A restart on the same folder: the first participant returns and goes on (one episode
    // done, the cut one left unfinished on disk); a newcomer gets the next number and the
    // condition the balance asks for.
    let (_server, addr) = crate::session::child(&record, Some(&study));
    // Their platform id is no key to their session: a join with it is refused (409); the
    // token their browser kept takes them back.
    let (status, _) = http(addr, "POST", "/join", "PROLIFIC_PID=alpha").await;
    assert_eq!(status, 409);
    let mut socket = connect(addr, &first, None).await.unwrap();
    let resumed = receive(&mut socket).await;
    assert_eq!(resumed["condition"], "top");
    assert_eq!(resumed["progress"]["episodes_done"], 1);
    assert_eq!(resumed["progress"]["steps"].as_u64().unwrap() as usize, plan.len() + 2);
    assert_eq!(resumed["episode"], 2, "the episode after the cut one");
    act(&mut socket, "pick 1").await;
    let header = lines(&alpha)
        .into_iter()
        .filter(|l| l["type"] == "session")
        .nth(1)
        .expect("a second session line, appended");
    assert_eq!(header["first_episode"], 2);
    assert_eq!(header["participant"]["number"], 0);
    // The whole file replays, both sessions, into the condition's agent.
    let read = agent::demos::read_demonstrations(&alpha, None).unwrap();
    assert_eq!(read.episodes.iter().map(|e| e.episode).collect::<Vec<_>>(), [0, 1, 2]);
    let newcomer = join_id(addr, "gamma").await;
    let mut socket = connect(addr, &newcomer, None).await.unwrap();
    assert_eq!(receive(&mut socket).await["condition"], "top");
    act(&mut socket, "pick 0").await;
    assert!(record.join("p0002-top.jsonl").exists());
    assert_eq!(recordings(&record).len(), 3);
}
