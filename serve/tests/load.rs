//! The load test of docs/serve.md: simulated participants on loopback, each sending
//! actions at a steady rate; every recording checked line by line, and the latency from
//! action to new state measured. Ignored by default (it takes a minute or more):
//!
//! ```text
//! SERVE_LOAD_SECONDS=60 cargo test -p serve --release --test integration load:: -- --ignored --nocapture
//! ```
//!
//! `SERVE_LOAD_PARTICIPANTS` (default 50) and `SERVE_LOAD_RATE` (actions per second each,
//! default 10) change the load.

use std::time::{Duration, Instant};

use crate::common::*;
use serde_json::json;
use serve::{Limits, ServeConfig};

fn env(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "a minute of load; run it by name (module docs)"]
async fn fifty_participants_at_ten_actions_a_second() {
    let participants = env("SERVE_LOAD_PARTICIPANTS", 50);
    let rate = env("SERVE_LOAD_RATE", 10);
    let seconds = env("SERVE_LOAD_SECONDS", 60);
    let dir = tempfile::tempdir().unwrap();
    let (addr, _) = start(ServeConfig {
        record_dir: Some(dir.path().to_path_buf()),
        limits: Limits {
            max_sessions: participants as usize,
            // Every simulated participant joins from this one address.
            joins_per_minute: participants as u32,
            ..Limits::default()
        },
        ..ServeConfig::default()
    })
    .await;
    let mut tasks = Vec::new();
    for p in 0..participants {
        let token = join(addr, &format!("load{p}")).await.unwrap();
        tasks.push(tokio::spawn(async move {
            let mut socket = connect(addr, &token, None).await.unwrap();
            let mut view = receive(&mut socket).await;
            let mut latencies = Vec::new();
            let mut errors = 0u64;
            let start = Instant::now();
            let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / rate as f64));
            let mut k = p as usize;
            while start.elapsed() < Duration::from_secs(seconds) {
                tick.tick().await;
                // A person's actions: a legal one, varied; the next episode once one ends.
                let message = if view["over"] == true {
                    json!({"type": "next"})
                } else {
                    let legal = view["legal"].as_array().unwrap();
                    k = k.wrapping_mul(31).wrapping_add(7);
                    json!({"type": "act", "action": legal[k % legal.len()]})
                };
                let sent = Instant::now();
                let answer = ask(&mut socket, message).await;
                latencies.push(sent.elapsed());
                if answer["type"] == "view" {
                    view = answer;
                } else {
                    errors += 1;
                }
            }
            let acknowledged = view["progress"]["recorded_lines"].as_u64().unwrap();
            (token, latencies, errors, acknowledged)
        }));
    }
    let mut all = Vec::new();
    let mut errors = 0;
    let mut acknowledged = 0;
    for t in tasks {
        let (_, latencies, e, a) = t.await.unwrap();
        all.extend(latencies);
        errors += e;
        acknowledged += a;
    }
    // Every recording: every acknowledged line there, none twice, each episode's steps
    // numbered 1, 2, ... and the whole file valid under the world's rules.
    let mut on_disk = 0;
    for entry in std::fs::read_dir(dir.path()).unwrap() {
        let path = entry.unwrap().path();
        let lines = lines(&path);
        on_disk += lines.len() as u64;
        let mut expected = 0;
        for line in &lines {
            match line["type"].as_str().unwrap() {
                "episode" => expected = 1,
                "step" => {
                    assert_eq!(line["step"].as_u64().unwrap(), expected, "{}", path.display());
                    expected += 1;
                }
                _ => {}
            }
        }
        agent::demos::read_episodes(&path, None).unwrap();
    }
    all.sort();
    let pct = |p: f64| all[((all.len() as f64 * p) as usize).min(all.len() - 1)];
    println!(
        "{participants} participants x {rate} actions/s for {seconds} s: {} actions, {errors} refused, \
         {on_disk} lines on disk ({acknowledged} acknowledged); latency p50 {:?}, p99 {:?}, max {:?}",
        all.len(),
        pct(0.5),
        pct(0.99),
        all.last().unwrap()
    );
    assert_eq!(on_disk, acknowledged, "no line lost, none written twice");
    assert_eq!(errors, 0);
}
