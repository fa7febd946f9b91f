//! A test client of our own over loopback: joins over HTTP, plays over the WebSocket.

#![allow(dead_code, reason = "not every helper is used by every run")]

use std::net::SocketAddr;
use std::path::Path;
use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use serve::{ServeConfig, Server};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;

/// A WebSocket to a session.
pub type Socket = tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<TcpStream>>;

/// Starts a server on a free loopback port; its address and researcher link.
pub async fn start(config: ServeConfig) -> (SocketAddr, String) {
    let server = Server::bind(ServeConfig { port: 0, ..config }).await.unwrap();
    let addr = server.local_addr().unwrap();
    let results = server.links().unwrap().results;
    tokio::spawn(server.serve());
    (addr, results)
}

/// A raw HTTP/1.1 request; the status and the whole response text.
pub async fn http(addr: SocketAddr, method: &str, path: &str, body: &str) -> (u16, String) {
    http_with(addr, method, path, body, "").await
}

/// [`http`] with `headers` (each line ending in `\r\n`) added.
pub async fn http_with(addr: SocketAddr, method: &str, path: &str, body: &str, headers: &str) -> (u16, String) {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\n{headers}Content-Type: application/x-www-form-urlencoded\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut response = String::new();
    stream.read_to_string(&mut response).await.unwrap();
    let status = response.split(' ').nth(1).unwrap().parse().unwrap();
    (status, response)
}

/// Joins as a participant (`name`: the form's field); the session token, or the status and
/// response of a refusal.
pub async fn join(addr: SocketAddr, name: &str) -> Result<String, (u16, String)> {
    let (status, response) = http(addr, "POST", "/join", &format!("name={name}")).await;
    if status != 303 {
        return Err((status, response));
    }
    let location = response
        .lines()
        .find_map(|l| l.strip_prefix("location: ").or_else(|| l.strip_prefix("Location: ")))
        .unwrap();
    Ok(location.trim().strip_prefix("/s/").unwrap().to_string())
}

/// Joins as a participant (`name`) and takes a step (`pick 0`), so that they count; the
/// session token.
pub async fn join_acting(addr: SocketAddr, name: &str) -> String {
    let token = join(addr, name).await.unwrap();
    let mut socket = connect(addr, &token, None).await.unwrap();
    receive(&mut socket).await;
    let view = act(&mut socket, "pick 0").await;
    assert_eq!(view["type"], "view", "{view}");
    token
}

/// Opens the session `token`'s WebSocket, with the browser's `origin` if given.
pub async fn connect(addr: SocketAddr, token: &str, origin: Option<&str>) -> Result<Socket, String> {
    let mut request = format!("ws://{addr}/ws/{token}").into_client_request().unwrap();
    if let Some(origin) = origin {
        request.headers_mut().insert("origin", origin.parse().unwrap());
    }
    tokio_tungstenite::connect_async(request)
        .await
        .map(|(s, _)| s)
        .map_err(|e| e.to_string())
}

/// The next text message, as JSON.
pub async fn receive(socket: &mut Socket) -> Value {
    loop {
        let message = tokio::time::timeout(Duration::from_secs(10), socket.next())
            .await
            .expect("an answer within 10 s")
            .expect("the connection is open")
            .expect("a message");
        if let Message::Text(text) = message {
            return serde_json::from_str(text.as_str()).unwrap();
        }
    }
}

/// Sends `message` and returns the answer.
pub async fn ask(socket: &mut Socket, message: Value) -> Value {
    socket.send(Message::Text(message.to_string().into())).await.unwrap();
    receive(socket).await
}

/// Sends the person's `action`.
pub async fn act(socket: &mut Socket, action: &str) -> Value {
    ask(socket, json!({"type": "act", "action": action})).await
}

/// The state and goal a view shows.
pub fn world_of(view: &Value) -> (sim::State, sim::Goal) {
    let cells: Vec<sim::Cell> = view["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| sim::Cell::new(c[0].as_u64().unwrap() as u16, c[1].as_u64().unwrap() as u16))
        .collect();
    let held = view["held"].as_u64().map(|b| sim::BlockId::of(b as usize));
    let goal: sim::Goal = serde_json::from_value(view["goal"].clone()).unwrap();
    (sim::State::new(&cells, held).unwrap(), goal)
}

/// The recording's lines, as JSON.
pub fn lines(path: &Path) -> Vec<Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The recordings in `dir` (a study's ledger, a dot file, left out).
pub fn recordings(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !p.file_name().unwrap().to_str().unwrap().starts_with('.'))
        .collect();
    files.sort();
    files
}

/// The only recording in `dir`.
pub fn only_recording(dir: &Path) -> std::path::PathBuf {
    let files = recordings(dir);
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}

/// A tabular model of 3 blocks on the default grid, untrained, saved in `dir`.
pub fn tabular_model(dir: &Path) -> std::path::PathBuf {
    let agent = agent::QAgent::new(
        agent::ReprKind::Chasing,
        sim::Grid::default(),
        3,
        agent::QParams::default(),
    )
    .unwrap();
    let path = dir.join("agent.safetensors");
    agent.save(&path).unwrap();
    path
}

/// A tabular model of the side view (3 blocks, `role-towers`, a few games on the grid
/// backend), saved in `dir` as `side.safetensors`.
pub fn side_model(dir: &Path) -> std::path::PathBuf {
    let config = agent::TrainConfig::resolve(&agent::TrainOverrides {
        view: Some(sim::View::Side),
        backend: Some(sim::Backend::Grid),
        games: Some(20),
        ..agent::TrainOverrides::default()
    })
    .unwrap();
    let trained = agent::train(&config, None).unwrap();
    let path = dir.join("side.safetensors");
    trained.agent.save(&path).unwrap();
    path
}

/// A tabular model of `blocks` blocks on the default grid, untrained, saved in `dir`.
pub fn tabular_model_of(dir: &Path, blocks: usize) -> std::path::PathBuf {
    let agent = agent::QAgent::new(
        agent::ReprKind::Chasing,
        sim::Grid::default(),
        blocks,
        agent::QParams::default(),
    )
    .unwrap();
    let path = dir.join(format!("agent{blocks}.safetensors"));
    agent.save(&path).unwrap();
    path
}

/// Whether the server closes the raw connection `stream` within `limit` (it reads to the
/// end; any bytes the server sent first are skipped).
pub async fn closed_within(stream: &mut TcpStream, limit: Duration) -> bool {
    let mut buf = [0u8; 4096];
    tokio::time::timeout(limit, async {
        loop {
            match stream.read(&mut buf).await {
                Ok(0) | Err(_) => return,
                Ok(_) => {}
            }
        }
    })
    .await
    .is_ok()
}

/// The code of the close frame that ends `socket` (after any other messages), or `None`
/// when it ends without one.
pub async fn close_code(socket: &mut Socket) -> Option<u16> {
    loop {
        match tokio::time::timeout(Duration::from_secs(10), socket.next())
            .await
            .expect("the end within 10 s")
        {
            Some(Ok(Message::Close(frame))) => return frame.map(|f| u16::from(f.code)),
            Some(Ok(_)) => {}
            None | Some(Err(_)) => return None,
        }
    }
}

/// A raw HTTP/1.1 request naming `host` in its `Host` header (and `origin`, if given, in
/// its `Origin`); the status.
pub async fn http_as(addr: SocketAddr, method: &str, path: &str, body: &str, host: &str, origin: Option<&str>) -> u16 {
    let mut stream = TcpStream::connect(addr).await.unwrap();
    let origin = origin.map_or(String::new(), |o| format!("Origin: {o}\r\n"));
    let request = format!(
        "{method} {path} HTTP/1.1\r\nHost: {host}\r\n{origin}Content-Type: application/x-www-form-urlencoded\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
        body.len()
    );
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut response = String::new();
    stream.read_to_string(&mut response).await.unwrap();
    response.split(' ').nth(1).unwrap().parse().unwrap()
}
