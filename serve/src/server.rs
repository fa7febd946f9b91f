//! The HTTP side: the routes, the participants' registry, the WebSocket loop and the
//! bounds (docs/serve.md).
//!
//! - `GET /`: the page (a join form); `POST /join` makes a participant session (the next
//!   condition in turn) and sends the browser to `/s/TOKEN`.
//! - `GET /s/TOKEN`: the page; it opens `GET /ws/TOKEN`, the session's WebSocket.
//! - `GET /results/TOKEN` and `GET /api/results/TOKEN`: the researcher's page and its data,
//!   behind a token of its own.
//! - `GET /assets/app.js`, `/assets/style.css`: compiled into the binary.
//!
//! Tokens are 128 bits from the operating system's generator (`rand::rng()`): the one place
//! blockstack draws unseeded randomness, since a token that a seed could reproduce would
//! not be a secret. Everything a participant plays is seeded by the condition.

use std::collections::HashMap;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use agent::DemoWriter;
use axum::Router;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Form, Path, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use files::OutputPath;
use serde::{Deserialize, Serialize};

use crate::config::{Condition, Limits, ServeConfig, check_name, conditions};
use crate::error::{Result, ServeError};
use crate::participant::{Participant, Recorder};
use crate::protocol::{ClientMessage, ErrorMessage, Mode, Progress};

/// The page: one HTML file for every view (join, session, results, curve).
pub(crate) const INDEX_HTML: &str = include_str!("../assets/index.html");
const APP_JS: &str = include_str!("../assets/app.js");
const STYLE_CSS: &str = include_str!("../assets/style.css");

/// The addresses a server answers on, to tell the people who use it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Links {
    /// Where participants begin (`http://HOST:PORT/`).
    pub join: String,
    /// The researcher's page, behind its token.
    pub results: String,
}

/// A bound server, not yet serving.
pub struct Server {
    listener: tokio::net::TcpListener,
    app: Arc<App>,
}

impl Server {
    /// Loads the conditions (models, study), prepares the recording folder and binds the
    /// address: every error a user can make is found here, before anyone connects.
    pub async fn bind(mut config: ServeConfig) -> Result<Server> {
        let (study, conditions) = conditions(&mut config)?;
        let record_dir = match &config.record_dir {
            Some(dir) => {
                files::prepare_folder(dir)?;
                Some(dir.canonicalize()?)
            }
            None => None,
        };
        let addr = SocketAddr::new(config.bind, config.port);
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .map_err(|source| ServeError::Bind {
                addr: addr.to_string(),
                source,
            })?;
        Ok(Server {
            listener,
            app: Arc::new(App {
                study,
                conditions,
                record_dir,
                limits: config.limits,
                researcher: new_token(),
                registry: Mutex::new(Registry::default()),
            }),
        })
    }

    /// The address bound (its port when 0 was asked for).
    pub fn local_addr(&self) -> Result<SocketAddr> {
        Ok(self.listener.local_addr()?)
    }

    /// Where participants begin and where the researcher looks.
    pub fn links(&self) -> Result<Links> {
        let base = format!("http://{}", self.local_addr()?);
        Ok(Links {
            join: format!("{base}/"),
            results: format!("{base}/results/{}", self.app.researcher),
        })
    }

    /// Serves until the process ends. Every recorded line is flushed as it is written, so
    /// killing the process loses none that a page was told of.
    pub async fn serve(self) -> Result<()> {
        Ok(axum::serve(self.listener, router(self.app)).await?)
    }
}

/// Runs `blockstack serve`: binds, calls `announce` with the links, serves until the
/// process is ended.
pub fn run(config: ServeConfig, announce: impl FnOnce(&Links) -> std::io::Result<()>) -> Result<()> {
    let runtime = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
    runtime.block_on(async {
        let server = Server::bind(config).await?;
        announce(&server.links()?)?;
        server.serve().await
    })
}

/// A fresh token: 128 bits from the operating system's generator, as 32 hex digits (the
/// module docs say why this is not seeded).
fn new_token() -> String {
    use rand::RngExt;
    format!("{:032x}", rand::rng().random::<u128>())
}

/// The server's shared state.
struct App {
    study: String,
    conditions: Vec<Arc<Condition>>,
    record_dir: Option<PathBuf>,
    limits: Limits,
    researcher: String,
    registry: Mutex<Registry>,
}

#[derive(Default)]
struct Registry {
    by_token: HashMap<String, Arc<Slot>>,
    /// In order of arrival, for the researcher's page.
    all: Vec<Arc<Slot>>,
}

/// One participant's place on the server.
struct Slot {
    number: usize,
    name: Option<String>,
    recording: Option<String>,
    /// A page is connected (one at a time).
    connected: AtomicBool,
    inner: Mutex<Inner>,
}

struct Inner {
    participant: Participant,
    bucket: Bucket,
}

/// Messages a session may still send now: refilled at the limit's rate up to one
/// second's worth.
struct Bucket {
    tokens: f64,
    last: Instant,
}

impl Bucket {
    fn take(&mut self, rate: u32) -> bool {
        let now = Instant::now();
        let rate = f64::from(rate);
        self.tokens = (self.tokens + now.duration_since(self.last).as_secs_f64() * rate).min(rate);
        self.last = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl App {
    /// A new participant, in the next condition in turn; its token.
    fn join(&self, name: Option<String>) -> std::result::Result<String, (StatusCode, String)> {
        if let Some(n) = &name {
            check_name(n).map_err(|e| (StatusCode::BAD_REQUEST, format!("participant name: {e}")))?;
        }
        let mut registry = lock(&self.registry);
        if registry.all.len() >= self.limits.max_sessions {
            return Err((
                StatusCode::SERVICE_UNAVAILABLE,
                format!(
                    "this server takes at most {} sessions, and has them all",
                    self.limits.max_sessions
                ),
            ));
        }
        let number = registry.all.len();
        // Balanced: participant k gets condition k mod n, so the counts never differ by more
        // than one.
        let condition = self.conditions[number % self.conditions.len()].clone();
        let fail = |e: String| (StatusCode::INTERNAL_SERVER_ERROR, e);
        let (writer, recording) = match &self.record_dir {
            None => (None, None),
            Some(dir) => {
                let (path, file) = recording_path(dir, number, &condition.name, name.as_deref());
                let out = OutputPath::check(&path).map_err(|e| fail(e.to_string()))?;
                (
                    Some(DemoWriter::append(&out).map_err(|e| fail(e.to_string()))?),
                    Some(file),
                )
            }
        };
        let participant = Participant::new(condition, Recorder::new(writer)).map_err(|e| fail(e.to_string()))?;
        let token = new_token();
        let slot = Arc::new(Slot {
            number,
            name,
            recording,
            connected: AtomicBool::new(false),
            inner: Mutex::new(Inner {
                participant,
                bucket: Bucket {
                    tokens: f64::from(self.limits.actions_per_second),
                    last: Instant::now(),
                },
            }),
        });
        registry.by_token.insert(token.clone(), slot.clone());
        registry.all.push(slot);
        Ok(token)
    }

    fn find(&self, token: &str) -> Option<Arc<Slot>> {
        lock(&self.registry).by_token.get(token).cloned()
    }

    fn is_researcher(&self, token: &str) -> bool {
        // Compared in constant time: the token is the page's only lock.
        let (a, b) = (token.as_bytes(), self.researcher.as_bytes());
        a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
    }

    /// The answer to one text message of a session's page.
    fn answer(&self, slot: &Slot, text: &str) -> String {
        let mut inner = lock(&slot.inner);
        let id = message_id(text);
        if !inner.bucket.take(self.limits.actions_per_second) {
            return error_line(
                id,
                format!(
                    "too many messages: at most {} a second; nothing was done",
                    self.limits.actions_per_second
                ),
            );
        }
        if text.len() > self.limits.max_message_bytes {
            return error_line(
                id,
                format!(
                    "a message of {} bytes is longer than the {} allowed; nothing was done",
                    text.len(),
                    self.limits.max_message_bytes
                ),
            );
        }
        let message: ClientMessage = match serde_json::from_str(text) {
            Ok(m) => m,
            Err(e) => return error_line(id, format!("not a message of the protocol ({e}); nothing was done")),
        };
        match inner.participant.handle(&message) {
            Ok(view) => serde_json::to_string(&view).expect("views serialise"),
            Err(e) => error_line(id, format!("{e}; nothing was done")),
        }
    }
}

/// The recording of participant `number` under `dir`: `pNNNN-CONDITION[-NAME].jsonl`, the
/// first such name not taken (an earlier run's recordings are never appended to). Every
/// part is checked to be a plain name, so the path stays in `dir`.
fn recording_path(dir: &std::path::Path, number: usize, condition: &str, name: Option<&str>) -> (PathBuf, String) {
    let mut n = number;
    loop {
        let file = match name {
            Some(name) => format!("p{n:04}-{condition}-{name}.jsonl"),
            None => format!("p{n:04}-{condition}.jsonl"),
        };
        let path = dir.join(&file);
        if std::fs::symlink_metadata(&path).is_err() {
            return (path, file);
        }
        n += 1;
    }
}

/// The `id` of a message, when it is a JSON object with a whole-number `id`.
fn message_id(text: &str) -> Option<u64> {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()?
        .get("id")?
        .as_u64()
}

fn error_line(id: Option<u64>, message: String) -> String {
    serde_json::to_string(&ErrorMessage::new(id, message)).expect("errors serialise")
}

fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/join", post(join))
        .route("/s/{token}", get(page))
        .route("/results/{token}", get(results_page))
        .route("/api/results/{token}", get(results))
        .route("/ws/{token}", get(socket))
        .merge(asset_routes())
        .with_state(app)
}

/// The script and style sheet, compiled in.
pub(crate) fn asset_routes<S: Clone + Send + Sync + 'static>() -> Router<S> {
    Router::new()
        .route(
            "/assets/app.js",
            get(|| async { ([(header::CONTENT_TYPE, "text/javascript")], APP_JS) }),
        )
        .route(
            "/assets/style.css",
            get(|| async { ([(header::CONTENT_TYPE, "text/css")], STYLE_CSS) }),
        )
}

async fn page() -> Html<&'static str> {
    Html(INDEX_HTML)
}

/// The join form's fields.
#[derive(Deserialize)]
struct JoinForm {
    #[serde(default)]
    name: String,
}

async fn join(State(app): State<Arc<App>>, headers: HeaderMap, Form(form): Form<JoinForm>) -> Response {
    // Another site's page may not fill the server with sessions through its own form.
    if !same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "a page of another origin may not begin a session",
        )
            .into_response();
    }
    let name = Some(form.name.trim().to_string()).filter(|n| !n.is_empty());
    match app.join(name) {
        Ok(token) => Redirect::to(&format!("/s/{token}")).into_response(),
        Err((status, message)) => (status, message).into_response(),
    }
}

async fn results_page(State(app): State<Arc<App>>, Path(token): Path<String>) -> Response {
    if app.is_researcher(&token) {
        Html(INDEX_HTML).into_response()
    } else {
        (StatusCode::NOT_FOUND, "unknown results link").into_response()
    }
}

/// One participant on the researcher's page.
#[derive(Serialize)]
struct SessionRow {
    number: usize,
    name: Option<String>,
    condition: String,
    mode: Mode,
    connected: bool,
    done: bool,
    recording: Option<String>,
    progress: Progress,
}

/// The researcher's page's data.
#[derive(Serialize)]
struct Results {
    study: String,
    conditions: Vec<String>,
    max_sessions: usize,
    sessions: Vec<SessionRow>,
}

async fn results(State(app): State<Arc<App>>, Path(token): Path<String>) -> Response {
    if !app.is_researcher(&token) {
        return (StatusCode::NOT_FOUND, "unknown results link").into_response();
    }
    let slots = lock(&app.registry).all.clone();
    let sessions = slots
        .iter()
        .map(|slot| {
            let inner = lock(&slot.inner);
            let p = &inner.participant;
            SessionRow {
                number: slot.number,
                name: slot.name.clone(),
                condition: p.condition().name.clone(),
                mode: p.mode(),
                connected: slot.connected.load(Ordering::SeqCst),
                done: p.is_done(),
                recording: slot.recording.clone(),
                progress: p.view(None).progress,
            }
        })
        .collect();
    let results = Results {
        study: app.study.clone(),
        conditions: app.conditions.iter().map(|c| c.name.clone()).collect(),
        max_sessions: app.limits.max_sessions,
        sessions,
    };
    (
        [(header::CONTENT_TYPE, "application/json")],
        serde_json::to_string(&results).expect("results serialise"),
    )
        .into_response()
}

/// Whether a request (a WebSocket, the join form) comes from our own page: a browser names the page's origin,
/// which must be this server as the browser reached it (its `Host`). A client that sends
/// no `Origin` is not a browser, and no other site's page can make it act.
fn same_origin(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
    let origin = origin.to_str().ok();
    match (origin, host) {
        (Some(origin), Some(host)) => origin
            .strip_prefix("http://")
            .or_else(|| origin.strip_prefix("https://"))
            .is_some_and(|o| o.eq_ignore_ascii_case(host)),
        _ => false,
    }
}

async fn socket(
    State(app): State<Arc<App>>,
    Path(token): Path<String>,
    headers: HeaderMap,
    upgrade: WebSocketUpgrade,
) -> Response {
    if !same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "a page of another origin may not open this session",
        )
            .into_response();
    }
    let limit = app.limits.max_frame_bytes;
    upgrade
        .max_message_size(limit)
        .max_frame_size(limit)
        .on_upgrade(move |socket| session_socket(socket, app, token))
}

/// Marks a session's page as gone when its connection ends, however it ends.
struct Connected(Arc<Slot>);

impl Drop for Connected {
    fn drop(&mut self) {
        self.0.connected.store(false, Ordering::SeqCst);
    }
}

async fn refuse(mut socket: WebSocket, message: &str) {
    let _ = socket
        .send(Message::Text(error_line(None, message.into()).into()))
        .await;
    let _ = socket.send(Message::Close(None)).await;
}

async fn session_socket(mut socket: WebSocket, app: Arc<App>, token: String) {
    let Some(slot) = app.find(&token) else {
        return refuse(
            socket,
            "this session link is not known here: it is mistyped, or from an earlier run of the server; ask for a new one",
        )
        .await;
    };
    if slot.connected.swap(true, Ordering::SeqCst) {
        return refuse(socket, "this session is open in another window: close that one first").await;
    }
    let _connected = Connected(slot.clone());
    let first = serde_json::to_string(&lock(&slot.inner).participant.view(None)).expect("views serialise");
    if socket.send(Message::Text(first.into())).await.is_err() {
        return;
    }
    while let Some(message) = socket.recv().await {
        let answer = match message {
            Ok(Message::Text(text)) => app.answer(&slot, text.as_str()),
            Ok(Message::Binary(_)) => error_line(
                None,
                "binary messages are not part of the protocol: send JSON text; nothing was done".into(),
            ),
            Ok(Message::Close(_)) => break,
            Ok(_) => continue,
            Err(e) => {
                // Past the frame bound, or a broken connection: say why if it can still hear.
                let _ = socket
                    .send(Message::Close(Some(CloseFrame {
                        code: 1009,
                        reason: format!("{e}").chars().take(100).collect::<String>().into(),
                    })))
                    .await;
                break;
            }
        };
        if socket.send(Message::Text(answer.into())).await.is_err() {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headers(origin: Option<&str>, host: &str) -> HeaderMap {
        let mut h = HeaderMap::new();
        h.insert(header::HOST, host.parse().unwrap());
        if let Some(o) = origin {
            h.insert(header::ORIGIN, o.parse().unwrap());
        }
        h
    }

    #[test]
    fn only_the_servers_own_origin_passes() {
        assert!(same_origin(&headers(None, "127.0.0.1:8080")));
        assert!(same_origin(&headers(Some("http://127.0.0.1:8080"), "127.0.0.1:8080")));
        assert!(same_origin(&headers(Some("https://Example.org"), "example.org")));
        assert!(!same_origin(&headers(Some("http://127.0.0.1:8081"), "127.0.0.1:8080")));
        assert!(!same_origin(&headers(Some("http://evil.example"), "127.0.0.1:8080")));
        assert!(!same_origin(&headers(Some("null"), "127.0.0.1:8080")));
    }

    #[test]
    fn the_bucket_allows_a_seconds_worth_then_refills() {
        let mut b = Bucket {
            tokens: 5.0,
            last: Instant::now(),
        };
        assert_eq!((0..10).filter(|_| b.take(5)).count(), 5);
        b.last -= std::time::Duration::from_millis(400);
        assert_eq!((0..10).filter(|_| b.take(5)).count(), 2);
    }

    #[test]
    fn tokens_are_fresh_128_bit_hex() {
        let (a, b) = (new_token(), new_token());
        assert_eq!(a.len(), 32);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
    }

    #[test]
    fn a_recording_never_reuses_a_name_and_stays_in_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        let (path, file) = recording_path(dir.path(), 3, "c", Some("P1"));
        assert_eq!(file, "p0003-c-P1.jsonl");
        assert_eq!(path.parent().unwrap(), dir.path());
        std::fs::write(&path, "").unwrap();
        assert_eq!(recording_path(dir.path(), 3, "c", Some("P1")).1, "p0004-c-P1.jsonl");
    }
}
