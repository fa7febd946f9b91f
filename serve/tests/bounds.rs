//! The server's bounds against clients that misbehave or simply go away: requests sent
//! half or slowly, pages that never answer, sessions nobody comes back to, another site's
//! name pointed at this machine, a participant whose episode takes long to begin, and
//! odd study files.

use std::time::Duration;

use crate::common::*;
use serde_json::json;
use serve::{Limits, ServeConfig};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;

fn quick(record_dir: &std::path::Path, limits: Limits) -> ServeConfig {
    ServeConfig {
        record_dir: Some(record_dir.to_path_buf()),
        limits,
        ..ServeConfig::default()
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_request_sent_half_or_slowly_is_cut_off() {
    let dir = tempfile::tempdir().unwrap();
    let limits = Limits {
        request_timeout: Duration::from_millis(300),
        ..Limits::default()
    };
    let (addr, _) = start(quick(dir.path(), limits)).await;
    // A connection that says nothing, one that stops in the middle of its head, and one
    // whose body never comes: each closed, not held open.
    let mut silent = TcpStream::connect(addr).await.unwrap();
    let mut half = TcpStream::connect(addr).await.unwrap();
    half.write_all(b"GET / HTTP/1.1\r\nHost: 127.0").await.unwrap();
    let mut slow = TcpStream::connect(addr).await.unwrap();
    slow.write_all(
        format!("POST /join HTTP/1.1\r\nHost: {addr}\r\nContent-Type: application/x-www-form-urlencoded\r\nContent-Length: 100\r\n\r\nname=")
            .as_bytes(),
    )
    .await
    .unwrap();
    for stream in [&mut silent, &mut half, &mut slow] {
        assert!(closed_within(stream, Duration::from_secs(5)).await);
    }
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "no session was begun"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_that_answers_no_ping_is_let_go() {
    let dir = tempfile::tempdir().unwrap();
    let limits = Limits {
        socket_idle: Duration::from_millis(300),
        ..Limits::default()
    };
    let (addr, _) = start(quick(dir.path(), limits)).await;
    let token = join(addr, "").await.unwrap();
    // A client that reads nothing (so answers no ping) for a while.
    let mut socket = connect(addr, &token, None).await.unwrap();
    tokio::time::sleep(Duration::from_millis(1500)).await;
    // The server has said goodbye (1001) and gone: the client's pong to the pings it
    // buffered may fail first, so the end may come as an error.
    use futures_util::StreamExt;
    let end = tokio::time::timeout(Duration::from_secs(5), async {
        loop {
            match socket.next().await {
                Some(Ok(tokio_tungstenite::tungstenite::Message::Close(frame))) => {
                    return frame.map(|f| u16::from(f.code));
                }
                Some(Ok(_)) => {}
                None | Some(Err(_)) => return Some(1001),
            }
        }
    })
    .await;
    assert_eq!(end, Ok(Some(1001)), "the page is let go");
    // The session is still there: a page that comes back goes on where it was.
    let mut again = connect(addr, &token, None).await.unwrap();
    assert_eq!(receive(&mut again).await["type"], "view");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_session_no_page_comes_back_to_is_let_go_and_frees_its_place() {
    let dir = tempfile::tempdir().unwrap();
    let limits = Limits {
        max_sessions: 1,
        session_idle: Duration::from_millis(200),
        ..Limits::default()
    };
    let (addr, _) = start(quick(dir.path(), limits)).await;
    // A participant who acted, then whose page went away.
    let first = join_acting(addr, "a").await;
    // Held: the one place is taken.
    let (status, body) = join(addr, "b").await.unwrap_err();
    assert_eq!(status, 503, "{body}");
    tokio::time::sleep(Duration::from_millis(800)).await;
    // Let go: its place is free, its recording kept.
    join(addr, "b").await.unwrap();
    assert_eq!(recordings(dir.path()).len(), 1, "b took no step: nothing of b on disk");
    // A session that never acted gives its place to a newcomer at once.
    join(addr, "c").await.unwrap();
    // The first participant's link takes their session up again from its recording.
    let mut back = connect(addr, &first, None).await.unwrap();
    let answer = receive(&mut back).await;
    assert_eq!(answer["type"], "view", "{answer}");
    assert_eq!(answer["progress"]["steps"], 1, "{answer}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_session_that_never_acts_is_let_go_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let limits = Limits {
        session_idle: Duration::from_millis(200),
        ..Limits::default()
    };
    let (addr, _) = start(quick(dir.path(), limits)).await;
    let token = join(addr, "idle").await.unwrap();
    // Its page stays connected: no step is what counts.
    let mut socket = connect(addr, &token, None).await.unwrap();
    receive(&mut socket).await;
    tokio::time::sleep(Duration::from_millis(800)).await;
    let answer = act(&mut socket, "pick 0").await;
    assert_eq!(answer["type"], "error", "{answer}");
    assert_eq!(recordings(dir.path()).len(), 0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn another_sites_name_for_this_machine_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(quick(dir.path(), Limits::default())).await;
    let port = addr.port();
    // DNS rebinding: evil.example made to resolve to 127.0.0.1; its page's requests name
    // evil.example as both host and origin, so the origin check alone lets them through.
    let evil = format!("evil.example:{port}");
    let origin = format!("http://{evil}");
    assert_eq!(
        http_as(addr, "POST", "/join", "name=x", &evil, Some(&origin)).await,
        403
    );
    assert_eq!(http_as(addr, "GET", "/", "", &evil, None).await, 403);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // The server's own names pass.
    for host in [format!("127.0.0.1:{port}"), format!("localhost:{port}")] {
        assert_eq!(http_as(addr, "GET", "/", "", &host, None).await, 200, "{host}");
    }
    // A name given with --public-url passes.
    let dir = tempfile::tempdir().unwrap();
    let (addr, results) = start(ServeConfig {
        public_url: Some("http://lab.example.org:8080/".into()),
        ..quick(dir.path(), Limits::default())
    })
    .await;
    assert!(results.starts_with("http://lab.example.org:8080/results/"), "{results}");
    let host = "lab.example.org:8080";
    assert_eq!(
        http_as(
            addr,
            "POST",
            "/join",
            "name=x",
            host,
            Some("http://lab.example.org:8080")
        )
        .await,
        303
    );
}

#[tokio::test]
async fn the_links_of_a_server_on_every_address_can_be_opened() {
    let server = serve::Server::bind(ServeConfig {
        bind: "0.0.0.0".parse().unwrap(),
        port: 0,
        ..ServeConfig::default()
    })
    .await
    .unwrap();
    let links = server.links().unwrap();
    assert!(!links.join.contains("0.0.0.0"), "{}", links.join);
    assert!(links.note.unwrap().contains("every address"));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 1)]
async fn a_participant_whose_episode_takes_long_to_begin_stalls_no_other() {
    // One async worker: anything run on it stops every other message until it ends. The
    // shortest plan of a 12-block start on 12 x 12 takes the exact solver its whole budget.
    let dir = tempfile::tempdir().unwrap();
    let model = {
        let agent = agent::QAgent::new(
            agent::ReprKind::Chasing,
            sim::Grid::new(12, 12).unwrap(),
            12,
            agent::QParams::default(),
        )
        .unwrap();
        let path = dir.path().join("twelve.safetensors");
        agent.save(&path).unwrap();
        path
    };
    let limits = Limits {
        solver_budget: 300_000,
        ..Limits::default()
    };
    let (addr, _) = start(ServeConfig {
        model: Some(model),
        goals: Some("0,1,2,3,4,5,6,7,8,9,10,11".into()),
        ..quick(&dir.path().join("rec"), limits)
    })
    .await;
    let slow = join(addr, "slow").await.unwrap();
    let quick_one = join(addr, "quick").await.unwrap();
    let mut slow = connect(addr, &slow, None).await.unwrap();
    let mut other = connect(addr, &quick_one, None).await.unwrap();
    receive(&mut slow).await;
    receive(&mut other).await;
    // The slow participant begins an episode (a new start: its shortest plan is searched);
    // meanwhile the other acts.
    use futures_util::SinkExt;
    slow.send(tokio_tungstenite::tungstenite::Message::Text(
        json!({"type": "next"}).to_string().into(),
    ))
    .await
    .unwrap();
    tokio::time::sleep(Duration::from_millis(30)).await;
    let begun = std::time::Instant::now();
    let answer = act(&mut other, "pick 0").await;
    let other_answered = begun.elapsed();
    assert_eq!(answer["type"], "view");
    let next = receive(&mut slow).await;
    let slow_answered = begun.elapsed();
    assert_eq!(next["episode"], 1);
    assert!(
        other_answered < slow_answered,
        "the other participant waited {other_answered:?}, until the slow one's episode began ({slow_answered:?})"
    );
}

#[cfg(unix)]
#[tokio::test]
async fn a_study_file_that_is_a_pipe_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("study.toml");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let bound = tokio::time::timeout(
        Duration::from_secs(5),
        serve::Server::bind(ServeConfig {
            study: Some(fifo),
            record_dir: Some(dir.path().join("rec")),
            port: 0,
            ..ServeConfig::default()
        }),
    )
    .await
    .expect("refused at once, not blocked waiting for a writer");
    let error = bound.err().unwrap().to_string();
    assert!(error.contains("not a regular file"), "{error}");
}

#[tokio::test]
async fn a_condition_that_cannot_run_is_refused_at_start() {
    let dir = tempfile::tempdir().unwrap();
    let side = side_model(dir.path());
    let cases = [
        // A goal of towers in the top view (no model: the spec profile's world).
        (None, None, Some("0,1/2")),
        // A top-view model with a goal of towers.
        (Some(tabular_model(dir.path())), None, Some("0,1/2")),
        // The original profile's start rule in the side view.
        (Some(side), Some(sim::Profile::Original), None),
    ];
    for (model, profile, goals) in cases {
        let error = serve::Server::bind(ServeConfig {
            model: model.clone(),
            profile,
            goals: goals.map(Into::into),
            port: 0,
            record_dir: Some(dir.path().join("rec")),
            ..ServeConfig::default()
        })
        .await
        .err()
        .unwrap_or_else(|| panic!("{model:?} {profile:?} {goals:?} was accepted"))
        .to_string();
        assert!(error.contains("condition default"), "{error}");
    }
    assert!(
        std::fs::read_dir(dir.path().join("rec")).map_or(true, |d| d.count() == 0),
        "no recording was begun"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_answer_carries_the_pages_security_headers() {
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(quick(dir.path(), Limits::default())).await;
    for path in ["/", "/assets/app.js", "/s/00000000000000000000000000000000", "/nowhere"] {
        let (_, response) = http(addr, "GET", path, "").await;
        let head = response.split("\r\n\r\n").next().unwrap().to_ascii_lowercase();
        for header in [
            "content-security-policy: default-src 'none'; script-src 'self'; style-src 'self'",
            "x-frame-options: deny",
            "referrer-policy: no-referrer",
        ] {
            assert!(head.contains(header), "{path}: {header} missing in {head}");
        }
    }
    // An https page is not this http server's (P22): refused by scheme, as another port is.
    let (status, _) = http_with(addr, "POST", "/join", "name=x", &format!("Origin: https://{addr}\r\n")).await;
    assert_eq!(status, 403);
}
