//! A pilot of a study before it is launched: simulated participants sent through the real
//! server and its protocol, so that the researcher sees the recordings, the researcher's
//! figures and the CSV fill as they will with people (`blockstack pilot`, docs/serve.md).
//!
//! The server is this crate's own, bound on loopback at a free port, with the study file
//! and record folder given. Each participant is a client of it as a browser is: it opens
//! the study's link with platform ids, reads the study (`GET /api/study`), asks whether its
//! browser has a session (`POST /api/resume`), agrees and begins (`POST /join`, its token
//! in the cookie), and plays over the session's WebSocket, one message at a time at a
//! person's pace (under the server's message bound), from its own loopback address
//! (`127.0.0.2`, `127.0.0.3`, ...: the per-address join bound holds as for a crowd).
//!
//! Who takes part, in turn:
//!
//! - **simulated demonstrators** (`agent::Demonstrator`'s presets 1, 2 and 3 in turn): in
//!   the top view's correct mode the demonstrator reviews each proposal and corrects it or
//!   accepts it; in play mode, and in the side view, it plays the exact solver's plan. It
//!   plays every episode the condition asks for and reads its completion code;
//! - **random players** (every third, from the third): random legal actions, leaving after
//!   20 steps without finishing (a participant who gives up);
//! - **one withdrawal** (the second participant): three steps, then the study's withdrawal.
//!
//! Everything is seeded by the pilot's seed (the study's seed sets the starts): the same
//! seed, the same recordings but for their times.

use std::collections::BTreeMap;
use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use agent::{Demonstrator, DemonstratorProfile};
use futures_util::{SinkExt, StreamExt};
use oracle::ExactSolver;
use rand::RngExt;
use serde::Serialize;
use serde_json::{Value, json};
use sim::seeding::{SimRng, episode_seed, rng};
use sim::{Action, BlockId, Cell, EnvConfig, Goal, Observation, State, View};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;

use crate::config::{Condition, ServeConfig, plan};
use crate::error::{Result, ServeError};
use crate::server::Server;

/// A random player leaves after this many steps.
const RANDOM_STEPS: u64 = 20;
/// The withdrawing participant withdraws after this many steps.
const STEPS_BEFORE_WITHDRAWING: u64 = 3;
/// The time between two messages of a participant: about 14 a second, under the server's
/// bound of 20.
const PACE: Duration = Duration::from_millis(70);

/// What a pilot is told.
#[derive(Clone, Debug)]
pub struct PilotConfig {
    /// The study file.
    pub study: PathBuf,
    /// Simulated participants.
    pub participants: u64,
    /// Where the recordings go (a folder of its own: the pilot's participants count
    /// towards a study's cap there).
    pub record_dir: PathBuf,
    /// The seed of the participants' choices.
    pub seed: u64,
}

/// Who a simulated participant is.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase", tag = "kind", content = "name")]
pub enum Role {
    /// A simulated demonstrator (its profile's name).
    Demonstrator(String),
    /// A random player who gives up.
    Random,
    /// A participant who withdraws.
    Withdraws,
}

impl Role {
    /// The role of participant `k` (module docs).
    fn of(k: u64) -> Role {
        match k {
            1 => Role::Withdraws,
            k if k % 3 == 2 => Role::Random,
            k => Role::Demonstrator(
                DemonstratorProfile::preset((k % 3) as u8 + 1)
                    .map(|p| p.name)
                    .unwrap_or_default(),
            ),
        }
    }
}

/// What one simulated participant did.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PilotParticipant {
    /// Their platform id.
    pub id: String,
    /// Who they were.
    pub role: Role,
    /// The condition the server gave them.
    pub condition: String,
    /// Episodes they ended.
    pub episodes_done: u64,
    /// Steps taken.
    pub steps: u64,
    /// Of those, their own choices.
    pub corrections: u64,
    /// The completion code their last view gave them.
    pub code: Option<String>,
    /// They withdrew.
    pub withdrew: bool,
}

/// What a pilot found: each participant, and what the researcher's page and CSV show.
#[derive(Clone, Debug, Serialize)]
pub struct PilotReport {
    /// The study's name.
    pub study: String,
    /// The participants, in order.
    pub participants: Vec<PilotParticipant>,
    /// Participants the server counts (those who acted, withdrawn ones left out).
    pub admitted: u64,
    /// The study's cap.
    pub max_participants: Option<u64>,
    /// The researcher's figures per condition, as the page shows them.
    pub conditions: Value,
    /// Rows of `episodes.csv` (one per episode), its header left out.
    pub csv_rows: usize,
    /// Recordings left out because their participant withdrew.
    pub withdrawn_left_out: u64,
}

/// Runs the pilot (module docs).
pub fn pilot(config: &PilotConfig) -> Result<PilotReport> {
    if config.participants == 0 {
        return Err(ServeError::Config(
            "--participants 0 pilots no one: give at least 1".into(),
        ));
    }
    let serve = ServeConfig {
        study: Some(config.study.clone()),
        record_dir: Some(config.record_dir.clone()),
        port: 0,
        ..ServeConfig::default()
    };
    // The conditions' worlds, for the simulated participants' planners.
    let conditions = plan(&serve)?.conditions;
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async {
        let server = Server::bind(serve).await?;
        let addr = server.local_addr()?;
        let researcher = server.links()?.results;
        tokio::spawn(server.serve());
        let mut tasks = Vec::new();
        for k in 0..config.participants {
            let conditions = conditions.clone();
            let seed = config.seed;
            tasks.push(tokio::spawn(
                async move { participant(addr, k, seed, &conditions).await },
            ));
        }
        let mut participants = Vec::new();
        for task in tasks {
            participants.push(task.await.map_err(|e| ServeError::Config(e.to_string()))??);
        }
        let path = researcher
            .split_once(&addr.to_string())
            .map_or(researcher.as_str(), |(_, p)| p)
            .replace("/results/", "/api/results/");
        let (_, _, body) = request(addr, local(0), "GET", &path, "", "").await?;
        let results: Value = serde_json::from_str(&body).map_err(|e| failed(format!("the researcher's data: {e}")))?;
        let (_, _, csv) = request(addr, local(0), "GET", &format!("{path}/episodes.csv"), "", "").await?;
        Ok(PilotReport {
            study: results["study"].as_str().unwrap_or_default().to_string(),
            participants,
            admitted: results["admitted"].as_u64().unwrap_or(0),
            max_participants: results["max_participants"].as_u64(),
            conditions: results["table"]["conditions"].clone(),
            csv_rows: csv.lines().count().saturating_sub(1),
            withdrawn_left_out: results["table"]["withdrawn"].as_u64().unwrap_or(0),
        })
    })
}

fn failed(reason: String) -> ServeError {
    ServeError::Config(format!("the pilot failed: {reason}"))
}

/// The loopback address of participant `k`'s machine.
fn local(k: u64) -> IpAddr {
    IpAddr::V4(Ipv4Addr::new(127, 0, 0, 2 + (k % 250) as u8))
}

/// One HTTP/1.1 request from `source`: the status, the head and the body.
async fn request(
    addr: SocketAddr,
    source: IpAddr,
    method: &str,
    path: &str,
    body: &str,
    headers: &str,
) -> Result<(u16, String, String)> {
    let socket = tokio::net::TcpSocket::new_v4()?;
    // Another loopback address where the system has it (Linux: all of 127/8), else the
    // usual one.
    if socket.bind(SocketAddr::new(source, 0)).is_err() {
        socket.bind(SocketAddr::new(IpAddr::V4(Ipv4Addr::LOCALHOST), 0))?;
    }
    let mut stream = socket.connect(addr).await?;
    let text = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\nOrigin: http://{addr}\r\n{headers}Content-Type: \
         application/x-www-form-urlencoded\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(text.as_bytes()).await?;
    let mut response = String::new();
    stream.read_to_string(&mut response).await?;
    let (head, body) = response.split_once("\r\n\r\n").unwrap_or((&response, ""));
    let status = head
        .split(' ')
        .nth(1)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| failed(format!("{method} {path}: no status in {head:?}")))?;
    Ok((status, head.to_string(), body.to_string()))
}

type Socket = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// Participant `k` takes part (module docs).
async fn participant(addr: SocketAddr, k: u64, seed: u64, conditions: &[Arc<Condition>]) -> Result<PilotParticipant> {
    let source = local(k);
    let role = Role::of(k);
    let (_, _, study) = request(addr, source, "GET", "/api/study", "", "").await?;
    let study: Value = serde_json::from_str(&study).map_err(|e| failed(format!("/api/study: {e}")))?;
    let keys: Vec<String> = study["participant_ids"]
        .as_array()
        .map(|ids| ids.iter().filter_map(|i| i.as_str().map(String::from)).collect())
        .unwrap_or_default();
    let id = format!("pilot{seed}-{k}");
    let ids: BTreeMap<String, String> = keys
        .iter()
        .enumerate()
        .map(|(i, key)| (key.clone(), if i == 0 { id.clone() } else { format!("pilot{seed}") }))
        .collect();
    let query = ids
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join("&");
    request(addr, source, "GET", &format!("/?{query}"), "", "").await?;
    let (_, _, resumed) = request(addr, source, "POST", "/api/resume", &query, "").await?;
    if !resumed.contains("\"token\":null") {
        return Err(failed(format!("{id}: a new browser was given a session: {resumed}")));
    }
    let form = if query.is_empty() {
        "consent=agree".to_string()
    } else {
        format!("consent=agree&{query}")
    };
    let (status, head, body) = request(addr, source, "POST", "/join", &form, "").await?;
    if status != 303 {
        return Err(failed(format!("{id} could not join ({status}): {body}")));
    }
    let token = head
        .lines()
        .find_map(|l| l.to_ascii_lowercase().strip_prefix("location: /s/").map(str::to_string))
        .ok_or_else(|| failed(format!("{id}: no session link in {head:?}")))?;
    let mut request_ws = format!("ws://{addr}/ws/{token}")
        .into_client_request()
        .map_err(|e| failed(e.to_string()))?;
    request_ws.headers_mut().insert(
        "origin",
        format!("http://{addr}").parse().map_err(|_| failed("origin".into()))?,
    );
    let (mut socket, _) = tokio_tungstenite::connect_async(request_ws)
        .await
        .map_err(|e| failed(format!("{id}: {e}")))?;
    let mut view = receive(&mut socket).await?;
    let condition = view["condition"].as_str().unwrap_or_default().to_string();
    let world = conditions
        .iter()
        .find(|c| c.name == condition)
        .map(|c| c.world.clone())
        .ok_or_else(|| {
            failed(format!(
                "{id} was given the condition {condition:?}, which the study does not have"
            ))
        })?;
    let mut choices = rng(episode_seed(seed, k));
    let mut demonstrator = match &role {
        Role::Demonstrator(_) => Some(Demonstrator::new(
            DemonstratorProfile::preset((k % 3) as u8 + 1)?,
            world.grid,
        )),
        _ => None,
    };
    let mut episode = None;
    let mut withdrew = false;
    loop {
        if view["done"] == true {
            break;
        }
        let steps = view["progress"]["steps"].as_u64().unwrap_or(0);
        if role == Role::Withdraws && steps >= STEPS_BEFORE_WITHDRAWING {
            let (status, _, body) = request(addr, source, "POST", &format!("/api/withdraw/{token}"), "", "").await?;
            if status != 200 {
                return Err(failed(format!("{id} could not withdraw ({status}): {body}")));
            }
            withdrew = true;
            break;
        }
        if role == Role::Random && steps >= RANDOM_STEPS {
            break;
        }
        let message = if view["over"] == true {
            json!({"type": "next"})
        } else {
            let obs = observation(&view, &world)?;
            if let Some(d) = demonstrator.as_mut()
                && episode != view["episode"].as_u64()
            {
                episode = view["episode"].as_u64();
                d.begin_episode(&obs, episode_seed(seed, episode.unwrap_or(0)));
            }
            choose(&view, &obs, &world, &role, demonstrator.as_mut(), &mut choices)?
        };
        tokio::time::sleep(PACE).await;
        socket
            .send(Message::Text(message.to_string().into()))
            .await
            .map_err(|e| failed(format!("{id}: {e}")))?;
        let answer = receive(&mut socket).await?;
        if answer["type"] == "view" {
            view = answer;
        } else if role != Role::Random {
            return Err(failed(format!("{id}: {message} was refused: {}", answer["message"])));
        }
    }
    let progress = &view["progress"];
    Ok(PilotParticipant {
        id,
        role,
        condition,
        episodes_done: progress["episodes_done"].as_u64().unwrap_or(0),
        steps: progress["steps"].as_u64().unwrap_or(0),
        corrections: progress["corrections"].as_u64().unwrap_or(0),
        code: view["completion"]["code"].as_str().map(String::from),
        withdrew,
    })
}

/// The next message of a participant of `role` in `view` (`obs` in the condition's
/// `world`).
fn choose(
    view: &Value,
    obs: &Observation,
    world: &EnvConfig,
    role: &Role,
    demonstrator: Option<&mut Demonstrator>,
    choices: &mut SimRng,
) -> Result<Value> {
    let legal: Vec<&str> = view["legal"]
        .as_array()
        .map(|a| a.iter().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    if *role == Role::Random {
        let action = legal
            .get(choices.random_range(0..legal.len().max(1)))
            .copied()
            .unwrap_or("drop");
        return Ok(json!({"type": "act", "action": action}));
    }
    let expert = ExactSolver::for_world(world)
        .solve(&obs.state, &obs.goal)
        .map_err(|e| failed(format!("no plan from the view: {e}")))?
        .actions
        .first()
        .copied();
    let Some(expert) = expert else {
        return Ok(json!({"type": "next"}));
    };
    if view["mode"] != "correct" {
        return Ok(json!({"type": "act", "action": expert.to_string()}));
    }
    let proposal = view["proposal"]
        .as_str()
        .and_then(|p| Action::parse(p, obs.state.block_count()).ok());
    let correction = match (demonstrator, proposal) {
        // The simulated demonstrators review proposals of the top view's world.
        (Some(d), Some(p)) if obs.view == View::Top => d.review(obs, p)?,
        (_, Some(p)) if p == expert => None,
        _ => Some(expert),
    };
    Ok(match correction {
        Some(a) => json!({"type": "act", "action": a.to_string()}),
        None => json!({"type": "accept"}),
    })
}

/// The observation a view shows, in the condition's `world`.
fn observation(view: &Value, world: &EnvConfig) -> Result<Observation> {
    let bad = || failed(format!("a view the pilot cannot read: {view}"));
    let cells: Vec<Cell> = view["blocks"]
        .as_array()
        .ok_or_else(bad)?
        .iter()
        .map(|c| Some(Cell::new(c[0].as_u64()? as u16, c[1].as_u64()? as u16)))
        .collect::<Option<_>>()
        .ok_or_else(bad)?;
    let held = view["held"].as_u64().map(|b| BlockId(b as u16));
    let goal: Goal = serde_json::from_value(view["goal"].clone()).map_err(|_| bad())?;
    Ok(Observation {
        grid: world.grid,
        state: State::new(&cells, held)?,
        goal,
        protocol: world.protocol,
        view: world.view,
    })
}

/// The next text message, as JSON.
async fn receive(socket: &mut Socket) -> Result<Value> {
    loop {
        let message = tokio::time::timeout(Duration::from_secs(30), socket.next())
            .await
            .map_err(|_| failed("no answer within 30 s".into()))?
            .ok_or_else(|| failed("the connection closed".into()))?
            .map_err(|e| failed(e.to_string()))?;
        if let Message::Text(text) = message {
            return serde_json::from_str(text.as_str()).map_err(|e| failed(e.to_string()));
        }
    }
}
