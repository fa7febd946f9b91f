//! The HTTP side: the routes, the WebSocket loop and the bounds (docs/serve.md).
//!
//! - `GET /`: the page: a study's consent and instructions (`GET /api/study`: never the
//!   completion code), or a join form; `POST /join` makes a participant session (the
//!   condition with the fewest participants), gives the browser its token in a cookie
//!   (HttpOnly, SameSite=Strict) and sends it to `/s/TOKEN`; `POST /api/resume` answers the
//!   token of the session the browser's cookie reaches, the same for every id it names.
//! - `POST /api/withdraw/TOKEN`: the participant withdraws.
//! - `GET /s/TOKEN`: the page (the cookie set for a token that reaches a session); it opens
//!   `GET /ws/TOKEN`, the session's WebSocket.
//! - `GET /results/TOKEN` and `GET /api/results/TOKEN`: the researcher's page and its data,
//!   behind a token of its own; `.../episodes.csv` one row per episode; `POST
//!   .../resume` a resume link for a participant; `GET /replay/TOKEN/FILE/EPISODE` (and
//!   `/api/replay/...`) an episode step by step.
//! - `GET /assets/app.js`, `/assets/style.css`: compiled into the binary.
//!
//! Every answer carries a Content-Security-Policy that lets the page run only its own
//! script and style, `X-Frame-Options: DENY` and `Referrer-Policy: no-referrer` (a session
//! link never leaves in a `Referer`).
//!
//! Tokens are 128 bits from the operating system's generator (`rand::rng()`): the one place
//! blockstack draws unseeded randomness, since a token that a seed could reproduce would
//! not be a secret. Everything a participant plays is seeded by the condition.
//!
//! Connections are served by hyper directly (not `axum::serve`) so that each has bounds:
//! a request's head must arrive within [`Limits::request_timeout`](crate::Limits::request_timeout), a handler must finish
//! within it, and at most [`Limits::max_connections`](crate::Limits::max_connections) are open at once. A participant's
//! work (a session begun, a message carried out: the exact solver may take seconds on many
//! blocks) runs on tokio's blocking threads, never on the async workers that every other
//! participant's messages need.

use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Router;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Form, Path, Request, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::middleware::Next;
use axum::response::{Html, IntoResponse, Redirect, Response};
use axum::routing::{get, post};
use serde::Serialize;

use crate::config::{ServeConfig, plan};
use crate::error::{Result, ServeError};
use crate::protocol::{ClientMessage, ErrorMessage};
use crate::registry::{Arrival, Bucket, JoinRefused, Registry, Seating, SessionRow, Slot, SlotState, lock};
use crate::results::{Figures, Table};

/// The page: one HTML file for every view (join, session, results, curve).
pub(crate) const INDEX_HTML: &str = include_str!("../assets/index.html");
const APP_JS: &str = include_str!("../assets/app.js");
const STYLE_CSS: &str = include_str!("../assets/style.css");

/// WebSocket close codes the server uses (RFC 6455 section 7.4; 4000-4999 are the
/// application's own). The page reconnects after [`close::GOING_AWAY`] and a dropped
/// connection, and not after the others, which say why in their reason.
pub mod close {
    /// The server let an idle page go (it answered no ping): the page may come back.
    pub const GOING_AWAY: u16 = 1001;
    /// A session link that is not known here (mistyped, stale, or let go).
    pub const UNKNOWN_SESSION: u16 = 1008;
    /// A frame or message over the size bound.
    pub const TOO_BIG: u16 = 1009;
    /// The session was opened in another window, which now has it.
    pub const OPENED_ELSEWHERE: u16 = 4001;
}

/// The addresses a server answers on, to tell the people who use it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Links {
    /// Where participants begin (`http://HOST:PORT/`).
    pub join: String,
    /// The researcher's page, behind its token.
    pub results: String,
    /// A line to print after the links, when there is something to say about them.
    pub note: Option<String>,
}

/// A bound server, not yet serving.
pub struct Server {
    listener: tokio::net::TcpListener,
    app: Arc<App>,
}

impl Server {
    /// Loads the conditions (models, study), prepares the recording folder, reads what it
    /// already holds (numbering, balance and the study's cap go on from it) and binds the
    /// address: every error a user can make is found here, before anyone connects.
    pub async fn bind(config: ServeConfig) -> Result<Server> {
        let plan = plan(&config)?;
        let limits = crate::Limits {
            session_idle: plan.idle.unwrap_or(config.limits.session_idle),
            joins_per_minute: plan.joins_per_minute.unwrap_or(config.limits.joins_per_minute),
            ..config.limits
        };
        let record_dir = match &config.record_dir {
            Some(dir) => {
                files::prepare_folder(dir)?;
                Some(dir.canonicalize()?)
            }
            None => None,
        };
        let public = config.public_url.as_deref().map(PublicUrl::parse).transpose()?;
        let addr = SocketAddr::new(config.bind, config.port);
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .map_err(|source| ServeError::Bind {
                addr: addr.to_string(),
                source,
            })?;
        let seating = Seating {
            conditions: plan.conditions.clone(),
            record_dir: record_dir.clone(),
            limits,
            max_participants: plan.max_participants,
            study: Arc::new(plan.path),
            keeps_ledger: config.study.is_some(),
        };
        let registry = Registry::new(&seating).map_err(ServeError::Config)?;
        let figures = Figures::new(
            record_dir,
            plan.conditions,
            limits.solver_budget,
            seating.study.participant_ids.first().cloned(),
            registry.codes(&seating.study),
        );
        Ok(Server {
            listener,
            app: Arc::new(App {
                seating,
                public,
                researcher: crate::registry::new_token(),
                registry: Mutex::new(registry),
                figures,
                connections: AtomicU64::new(0),
                joins: Mutex::new(HashMap::new()),
            }),
        })
    }

    /// The address bound (its port when 0 was asked for).
    pub fn local_addr(&self) -> Result<SocketAddr> {
        Ok(self.listener.local_addr()?)
    }

    /// Where participants begin and where the researcher looks: the `--public-url` when
    /// given, else the address bound (loopback's when bound to every address, with a note
    /// saying so).
    pub fn links(&self) -> Result<Links> {
        let addr = self.local_addr()?;
        let (base, note) = match &self.app.public {
            Some(public) => (public.base.clone(), None),
            None if addr.ip().is_unspecified() => {
                let here = SocketAddr::new(IpAddr::from([127, 0, 0, 1]), addr.port());
                (
                    format!("http://{here}"),
                    Some(format!(
                        "listening on every address ({addr}): participants on other machines open this machine's \
                         IP address at port {}, or a name given with --public-url",
                        addr.port()
                    )),
                )
            }
            None => (format!("http://{addr}"), None),
        };
        Ok(Links {
            join: format!("{base}/"),
            results: format!("{base}/results/{}", self.app.researcher),
            note,
        })
    }

    /// Serves until the process ends. Every recorded line is flushed as it is written, so
    /// killing the process loses none that a page was told of.
    pub async fn serve(self) -> Result<()> {
        let app = self.app;
        let router = router(app.clone());
        let limits = app.seating.limits;
        let slots = Arc::new(tokio::sync::Semaphore::new(limits.max_connections));
        tokio::spawn(expire_sessions(app.clone()));
        loop {
            let permit = slots
                .clone()
                .acquire_owned()
                .await
                .expect("the semaphore is never closed");
            let (stream, peer) = match self.listener.accept().await {
                Ok(accepted) => accepted,
                Err(_) => {
                    // Out of file descriptors, or a connection reset before it was
                    // accepted: wait a moment rather than spin.
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            };
            // Each request knows the address it came from (joins are bounded per address).
            let service =
                hyper_util::service::TowerToHyperService::new(router.clone().layer(axum::Extension(Peer(peer.ip()))));
            let app = app.clone();
            tokio::spawn(async move {
                app.connections.fetch_add(1, Ordering::SeqCst);
                let mut builder = hyper::server::conn::http1::Builder::new();
                builder
                    .timer(hyper_util::rt::TokioTimer::new())
                    .header_read_timeout(limits.request_timeout);
                let connection = builder
                    .serve_connection(hyper_util::rt::TokioIo::new(stream), service)
                    .with_upgrades();
                let _ = connection.await;
                app.connections.fetch_sub(1, Ordering::SeqCst);
                drop(permit);
            });
        }
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

/// Lets idle sessions go, now and then ([`Registry::expire_idle`]).
async fn expire_sessions(app: Arc<App>) {
    let limits = app.seating.limits;
    let every = (limits.session_idle / 4).clamp(Duration::from_millis(20), Duration::from_secs(60));
    loop {
        tokio::time::sleep(every).await;
        Registry::expire_idle(&app.registry, &limits);
    }
}

/// `--public-url`: the base participants use, its host name and its origin.
struct PublicUrl {
    /// `http://host[:port]`, no trailing slash.
    base: String,
    /// The host, lower case, without port.
    host: String,
    /// The origin its pages have ([`origin_of`]).
    origin: String,
}

impl PublicUrl {
    fn parse(text: &str) -> Result<PublicUrl> {
        let bad = |why: &str| ServeError::Config(format!("--public-url {text:?}: {why}"));
        let rest = text
            .strip_prefix("http://")
            .or_else(|| text.strip_prefix("https://"))
            .ok_or_else(|| bad("give a URL beginning with http:// or https://"))?;
        let authority = rest.trim_end_matches('/');
        if authority.is_empty() || authority.contains(['/', '?', '#', '@', ' ']) {
            return Err(bad("give the address alone: a scheme, a host and perhaps a port"));
        }
        let host = host_name(authority).to_ascii_lowercase();
        let scheme = if text.starts_with("https://") { "https" } else { "http" };
        Ok(PublicUrl {
            base: text.trim_end_matches('/').to_string(),
            host,
            origin: origin_of(scheme, authority),
        })
    }
}

/// An origin as compared: `scheme://host[:port]`, lower case, the scheme's default port
/// left out (a browser leaves it out of `Origin`, and `Host` may name it).
fn origin_of(scheme: &str, authority: &str) -> String {
    let (scheme, authority) = (scheme.to_ascii_lowercase(), authority.to_ascii_lowercase());
    let default = if scheme == "https" { ":443" } else { ":80" };
    let authority = authority.strip_suffix(default).unwrap_or(&authority);
    format!("{scheme}://{authority}")
}

/// Whether a request (a WebSocket, a form) comes from our own page: a browser names the
/// page's origin, whose scheme, host and port must be this server's as the browser reached
/// it: `http://` and its `Host` (itself checked by [`guard`]), or the `--public-url`'s
/// origin (a proxy serving https in front). A client that sends no `Origin` is not a
/// browser, and no other site's page can make it act.
///
/// Our pages' `Referrer-Policy: no-referrer` makes a browser send `Origin: null` on their
/// own POSTs (the Fetch standard's rule); such a request passes when the browser's fetch
/// metadata says it is same-origin (`Sec-Fetch-Site`, which another site's page cannot
/// set).
fn same_origin(public: Option<&PublicUrl>, headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    if origin == "null" {
        return headers.get("sec-fetch-site").is_some_and(|site| site == "same-origin");
    }
    let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
    let (Ok(origin), Some(host)) = (origin.to_str(), host) else {
        return false;
    };
    let Some((scheme, authority)) = origin.split_once("://") else {
        return false;
    };
    let origin = origin_of(scheme, authority);
    origin == origin_of("http", host) || public.is_some_and(|p| p.origin == origin)
}

/// The session token a request's cookie holds, if any.
fn cookie_token(headers: &HeaderMap) -> Option<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .find_map(|pair| pair.trim().strip_prefix(COOKIE)?.strip_prefix('=').map(str::to_string))
        .filter(|t| !t.is_empty())
}

/// The host of an `authority` (`name:port`, `[v6]:port`), without the port.
fn host_name(authority: &str) -> &str {
    if let Some(v6) = authority.strip_prefix('[') {
        return v6.split(']').next().unwrap_or(v6);
    }
    authority.rsplit_once(':').map_or(authority, |(h, _)| h)
}

/// The address a request came from.
#[derive(Clone, Copy, Debug)]
struct Peer(IpAddr);

/// The server's shared state.
struct App {
    seating: Seating,
    public: Option<PublicUrl>,
    researcher: String,
    registry: Mutex<Registry>,
    figures: Figures,
    /// Connections open now.
    connections: AtomicU64,
    /// Joins each client address may still make ([`crate::Limits::joins_per_minute`]).
    joins: Mutex<HashMap<IpAddr, Bucket>>,
}

/// The cookie that keeps a participant's session token in their browser.
const COOKIE: &str = "blockstack_session";

/// The page's security headers (module docs): its own script and style only (the consent's
/// HTML is the server's, and nothing in it runs), no framing, no referrer.
const SECURITY_HEADERS: [(&str, &str); 4] = [
    (
        "content-security-policy",
        "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self'; connect-src 'self'; \
         form-action 'self'; base-uri 'none'; frame-ancestors 'none'",
    ),
    ("x-frame-options", "DENY"),
    ("referrer-policy", "no-referrer"),
    ("x-content-type-options", "nosniff"),
];

impl App {
    /// Takes one of `peer`'s joins from its bucket; false when it has none left.
    fn may_join(&self, peer: IpAddr) -> bool {
        let capacity = self.seating.limits.joins_per_minute;
        let per_second = f64::from(capacity) / 60.0;
        let mut joins = lock(&self.joins);
        // Forget the addresses whose buckets are full again: the map stays as small as the
        // addresses that joined in the last minute.
        if joins.len() > 10_000 {
            joins.retain(|_, b| !b.is_full(capacity, per_second));
        }
        joins
            .entry(peer)
            .or_insert_with(|| Bucket::full(capacity))
            .take(capacity, per_second)
    }

    /// Whether a request comes from our own page ([`same_origin`]).
    fn same_origin(&self, headers: &HeaderMap) -> bool {
        same_origin(self.public.as_ref(), headers)
    }

    /// The cookie that gives a browser the session `token`.
    fn cookie(&self, token: &str) -> String {
        let secure = if self.public.as_ref().is_some_and(|p| p.origin.starts_with("https://")) {
            "; Secure"
        } else {
            ""
        };
        format!("{COOKIE}={token}; Path=/; Max-Age=2592000; HttpOnly; SameSite=Strict{secure}")
    }

    fn is_researcher(&self, token: &str) -> bool {
        // Compared in constant time: the token is the page's only lock.
        let (a, b) = (token.as_bytes(), self.researcher.as_bytes());
        a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
    }

    /// Whether a request's `Host` names this server: an IP address, `localhost`, or the
    /// `--public-url`'s host. A page of another site whose name was made to point at this
    /// machine (DNS rebinding) sends its own name, and is refused.
    fn serves_host(&self, host: Option<&str>) -> bool {
        let Some(host) = host else {
            return false;
        };
        let name = host_name(host);
        name.parse::<IpAddr>().is_ok()
            || name.eq_ignore_ascii_case("localhost")
            || self.public.as_ref().is_some_and(|p| p.host.eq_ignore_ascii_case(name))
    }

    /// The answer to one text message of a session's page (runs on a blocking thread).
    /// A participant's first step is counted before it is carried out (the study's cap
    /// may refuse it) and noted in the ledger once it is on disk. The registry's lock is
    /// never taken while the session's is held.
    fn answer(&self, slot: &Slot, text: &str) -> std::result::Result<String, String> {
        if slot.expired.load(Ordering::SeqCst) {
            let withdrawn = matches!(*lock(&slot.state), SlotState::Expired { withdrawn: true, .. });
            return Err(if withdrawn { WITHDRAWN } else { EXPIRED }.into());
        }
        slot.touch();
        let id = message_id(text);
        let limits = &self.seating.limits;
        let parsed = (text.len() <= limits.max_message_bytes)
            .then(|| serde_json::from_str::<ClientMessage>(text))
            .transpose();
        let first = !slot.has_acted()
            && matches!(
                parsed,
                Ok(Some(
                    ClientMessage::Act { .. } | ClientMessage::Move { .. } | ClientMessage::Accept { .. }
                ))
            );
        if first && let Err(full) = Registry::first_step(&self.registry, &self.seating, slot) {
            return Ok(error_line(id, format!("{full}; nothing was done")));
        }
        let (answer, stepped) = {
            let mut state = lock(&slot.state);
            let live = match &mut *state {
                SlotState::Live(live) => live,
                SlotState::Expired { withdrawn, .. } => {
                    let gone = if *withdrawn { WITHDRAWN } else { EXPIRED };
                    drop(state);
                    if first {
                        Registry::no_first_step(&self.registry, slot);
                    }
                    return Err(gone.into());
                }
            };
            let steps = live.participant.progress().steps;
            let answer = self.carry_out(live, id, text, parsed);
            (answer, live.participant.progress().steps > steps)
        };
        if first {
            if stepped {
                if let Err(e) = Registry::recorded(&self.registry, slot) {
                    return Ok(error_line(
                        id,
                        format!("your step is recorded, but the way back to this session could not be noted: {e}"),
                    ));
                }
            } else {
                Registry::no_first_step(&self.registry, slot);
            }
        }
        Ok(answer)
    }

    /// The answer to a message of a session held, `parsed` from `text` (`None`: too long).
    fn carry_out(
        &self,
        live: &mut crate::registry::Live,
        id: Option<u64>,
        text: &str,
        parsed: serde_json::Result<Option<ClientMessage>>,
    ) -> String {
        let limits = &self.seating.limits;
        let rate = limits.actions_per_second;
        if !live.bucket.take(rate, f64::from(rate)) {
            return error_line(
                id,
                format!("too many messages: at most {rate} a second; nothing was done"),
            );
        }
        let message = match parsed {
            Ok(Some(m)) => m,
            Ok(None) => {
                return error_line(
                    id,
                    format!(
                        "a message of {} bytes is longer than the {} allowed; nothing was done",
                        text.len(),
                        limits.max_message_bytes
                    ),
                );
            }
            Err(e) => return error_line(id, format!("not a message of the protocol ({e}); nothing was done")),
        };
        match live.participant.handle(&message) {
            Ok(view) => serde_json::to_string(&view).expect("views serialise"),
            Err(e) => error_line(id, format!("{e}; nothing was done")),
        }
    }
}

const UNKNOWN: &str =
    "this session link is not known here: it is mistyped, or from an earlier run of the server; ask for a new one";
const WITHDRAWN: &str = "you withdrew from this study: nothing more is recorded for you";
const EXPIRED: &str =
    "this session was closed after a long time without a page; its recording is kept: ask for a new link";

/// The `id` of a message, when it is a JSON object with a whole-number `id`.
fn message_id(text: &str) -> Option<u64> {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()?
        .get("id")?
        .as_u64()
}

/// `value` as a JSON response.
fn json(value: &impl Serialize) -> Response {
    (
        [(header::CONTENT_TYPE, "application/json")],
        serde_json::to_string(value).expect("answers serialise"),
    )
        .into_response()
}

fn error_line(id: Option<u64>, message: String) -> String {
    serde_json::to_string(&ErrorMessage::new(id, message)).expect("errors serialise")
}

fn router(app: Arc<App>) -> Router {
    Router::new()
        .route("/", get(page))
        .route("/api/study", get(study))
        .route("/join", post(join))
        .route("/api/resume", post(resume))
        .route("/api/withdraw/{token}", post(withdraw))
        .route("/s/{token}", get(session_page))
        .route("/results/{token}", get(results_page))
        .route("/replay/{token}/{file}/{episode}", get(replay_page))
        .route("/api/results/{token}", get(results))
        .route("/api/results/{token}/episodes.csv", get(episodes_csv))
        .route("/api/results/{token}/resume", post(resume_link))
        .route("/api/replay/{token}/{file}/{episode}", get(replay))
        .route("/ws/{token}", get(socket))
        .merge(asset_routes())
        .layer(axum::middleware::from_fn_with_state(app.clone(), guard))
        .with_state(app)
}

/// Every request: its `Host` must name this server ([`App::serves_host`]), and its handler
/// must answer within [`Limits::request_timeout`] (a body sent slowly is cut off).
async fn guard(State(app): State<Arc<App>>, request: Request, next: Next) -> Response {
    let host = request.headers().get(header::HOST).and_then(|h| h.to_str().ok());
    if !app.serves_host(host) {
        let host = host.unwrap_or("(none)");
        return (
            StatusCode::FORBIDDEN,
            format!(
                "this server does not answer to the host {host}: open it by its IP address, or start it with --public-url naming this host"
            ),
        )
            .into_response();
    }
    let mut response = match tokio::time::timeout(app.seating.limits.request_timeout, next.run(request)).await {
        Ok(response) => response,
        Err(_) => (StatusCode::REQUEST_TIMEOUT, "the request took too long to arrive").into_response(),
    };
    let headers = response.headers_mut();
    for (name, value) in SECURITY_HEADERS {
        headers.insert(name, header::HeaderValue::from_static(value));
    }
    response
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

/// A session's page; a token that reaches a session is given to the browser as its
/// cookie, so that the participant comes back to it from the study's link (a resume link
/// the researcher issued does this in another browser).
async fn session_page(State(app): State<Arc<App>>, Path(token): Path<String>) -> Response {
    let found = tokio::task::spawn_blocking({
        let (app, token) = (app.clone(), token.clone());
        move || Registry::session(&app.registry, &app.seating, &token, None)
    })
    .await;
    match found {
        Ok(Ok(Some(_))) => ([(header::SET_COOKIE, app.cookie(&token))], Html(INDEX_HTML)).into_response(),
        _ => Html(INDEX_HTML).into_response(),
    }
}

/// What the page needs to lead a participant: the study's path (consent and
/// instructions as safe HTML, the id parameters, what withdrawing does); never the
/// completion code or link.
async fn study(State(app): State<Arc<App>>) -> Response {
    json(app.seating.study.as_ref())
}

/// Who arrives, from a form's fields: `name` (the code typed), `consent` (`agree`), and the
/// study's id parameters; an error line for any other field.
fn arrival(fields: HashMap<String, String>) -> std::result::Result<Arrival, String> {
    let mut arrival = Arrival::default();
    for (key, value) in fields {
        match key.as_str() {
            "name" => arrival.name = Some(value.trim().to_string()).filter(|n| !n.is_empty()),
            "consent" => arrival.consent = value == "agree",
            _ => {
                if !value.is_empty() {
                    arrival.ids.insert(key, value);
                }
            }
        }
    }
    Ok(arrival)
}

const WITHDREW: &str = "you withdrew from this study: nothing more is recorded for you";
const EXISTS: &str = "a session of this study already exists for this participant id, begun in another browser \
     or window: go on in the browser where you began it (open the study's link there again), or write to the \
     researcher for a link that takes you back to it";

fn refused(refusal: JoinRefused) -> Response {
    match refusal {
        JoinRefused::BadRequest(m) => (StatusCode::BAD_REQUEST, m).into_response(),
        JoinRefused::Full(m) => (StatusCode::SERVICE_UNAVAILABLE, m).into_response(),
        JoinRefused::Withdrawn => (StatusCode::FORBIDDEN, WITHDREW).into_response(),
        JoinRefused::Exists => (StatusCode::CONFLICT, EXISTS).into_response(),
        JoinRefused::Failed(m) => (StatusCode::INTERNAL_SERVER_ERROR, m).into_response(),
    }
}

async fn join(
    State(app): State<Arc<App>>,
    axum::Extension(Peer(peer)): axum::Extension<Peer>,
    headers: HeaderMap,
    Form(form): Form<HashMap<String, String>>,
) -> Response {
    // Another site's page may not fill the server with sessions through its own form.
    if !app.same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "a page of another origin may not begin a session",
        )
            .into_response();
    }
    let mut arrival = match arrival(form) {
        Ok(a) => a,
        Err(m) => return (StatusCode::BAD_REQUEST, m).into_response(),
    };
    arrival.token = cookie_token(&headers);
    if !app.may_join(peer) {
        return (
            StatusCode::TOO_MANY_REQUESTS,
            format!(
                "too many sessions were begun from your address: at most {} a minute; wait a minute and try again",
                app.seating.limits.joins_per_minute
            ),
        )
            .into_response();
    }
    let joined = tokio::task::spawn_blocking({
        let app = app.clone();
        move || Registry::join(&app.registry, &app.seating, arrival)
    })
    .await;
    match joined {
        Ok(Ok(token)) => (
            [(header::SET_COOKIE, app.cookie(&token))],
            Redirect::to(&format!("/s/{token}")),
        )
            .into_response(),
        Ok(Err(refusal)) => refused(refusal),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}

/// A participant who arrives with the platform's ids: the token of the session their
/// browser's cookie reaches, when it is theirs (`{"token": ...}`), else `{"token": null}`,
/// the same answer for an id that took part and one never seen (an id is no key to a
/// session). `{"withdrawn": true}` when the cookie's participant withdrew.
async fn resume(
    State(app): State<Arc<App>>,
    headers: HeaderMap,
    Form(form): Form<HashMap<String, String>>,
) -> Response {
    if !app.same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "a page of another origin may not resume a session",
        )
            .into_response();
    }
    let arrival = match arrival(form) {
        Ok(a) => a,
        Err(m) => return (StatusCode::BAD_REQUEST, m).into_response(),
    };
    let Some(token) = cookie_token(&headers) else {
        return json(&serde_json::json!({ "token": null }));
    };
    let found = tokio::task::spawn_blocking(move || {
        let id = app
            .seating
            .study
            .participant_ids
            .first()
            .and_then(|key| arrival.ids.get(key).cloned());
        Registry::session(&app.registry, &app.seating, &token, id.as_deref())
    })
    .await;
    match found {
        Ok(Ok(Some(slot))) => json(&serde_json::json!({ "token": slot.token })),
        Ok(Err(JoinRefused::Withdrawn)) => json(&serde_json::json!({ "token": null, "withdrawn": true })),
        _ => json(&serde_json::json!({ "token": null })),
    }
}

/// The participant of `token` withdraws (the study says whether their recording is deleted
/// or marked, and whether they get the completion code and link all the same).
async fn withdraw(State(app): State<Arc<App>>, Path(token): Path<String>, headers: HeaderMap) -> Response {
    if !app.same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "a page of another origin may not withdraw anyone",
        )
            .into_response();
    }
    let done = tokio::task::spawn_blocking(move || Registry::withdraw(&app.registry, &app.seating, &token)).await;
    match done {
        Ok(Ok((how, completion))) => json(&serde_json::json!({ "withdrawal": how, "completion": completion })),
        Ok(Err(m)) => (StatusCode::BAD_REQUEST, m).into_response(),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}

/// A resume link for the participant numbered by the form's `participant` (the
/// researcher's page): `{"link": ...}`, a fresh token that reaches their recording.
async fn resume_link(
    State(app): State<Arc<App>>,
    Path(token): Path<String>,
    headers: HeaderMap,
    Form(form): Form<HashMap<String, String>>,
) -> Response {
    if !app.is_researcher(&token) {
        return (StatusCode::NOT_FOUND, "unknown results link").into_response();
    }
    if !app.same_origin(&headers) {
        return (StatusCode::FORBIDDEN, "a page of another origin may not ask for a link").into_response();
    }
    let Some(number) = form.get("participant").and_then(|n| n.trim().parse::<u64>().ok()) else {
        return (StatusCode::BAD_REQUEST, "give the participant's number").into_response();
    };
    let base = match &app.public {
        Some(public) => public.base.clone(),
        None => format!(
            "http://{}",
            headers
                .get(header::HOST)
                .and_then(|h| h.to_str().ok())
                .unwrap_or("127.0.0.1")
        ),
    };
    let issued = tokio::task::spawn_blocking(move || Registry::resume_link(&app.registry, &app.seating, number)).await;
    match issued {
        Ok(Ok(Some(token))) => json(&serde_json::json!({ "link": format!("{base}/s/{token}") })),
        Ok(Ok(None)) => (
            StatusCode::NOT_FOUND,
            format!("participant {number} has no recording here (they took no step)"),
        )
            .into_response(),
        Ok(Err(m)) => (StatusCode::BAD_REQUEST, m).into_response(),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}

async fn results_page(State(app): State<Arc<App>>, Path(token): Path<String>) -> Response {
    if app.is_researcher(&token) {
        Html(INDEX_HTML).into_response()
    } else {
        (StatusCode::NOT_FOUND, "unknown results link").into_response()
    }
}

/// The researcher's page's data.
#[derive(Serialize)]
struct Results {
    study: String,
    conditions: Vec<String>,
    max_sessions: usize,
    max_participants: Option<u64>,
    /// Participants admitted in all, over every run on the record folder.
    admitted: u64,
    /// This run's sessions.
    sessions: Vec<SessionRow>,
    /// The figures of every recording on disk.
    table: Table,
}

async fn results(State(app): State<Arc<App>>, Path(token): Path<String>) -> Response {
    if !app.is_researcher(&token) {
        return (StatusCode::NOT_FOUND, "unknown results link").into_response();
    }
    let (slots, admitted) = {
        let r = lock(&app.registry);
        (r.all(), r.admitted())
    };
    let results = tokio::task::spawn_blocking(move || Results {
        study: app.seating.study.name.clone(),
        conditions: app.seating.conditions.iter().map(|c| c.name.clone()).collect(),
        max_sessions: app.seating.limits.max_sessions,
        max_participants: app.seating.max_participants,
        admitted,
        sessions: slots.iter().map(|slot| slot.row()).collect(),
        table: app.figures.table(),
    })
    .await
    .expect("the rows are made without panicking");
    (
        [(header::CONTENT_TYPE, "application/json")],
        serde_json::to_string(&results).expect("results serialise"),
    )
        .into_response()
}

/// Every episode of every recording, one row each, as CSV.
async fn episodes_csv(State(app): State<Arc<App>>, Path(token): Path<String>) -> Response {
    if !app.is_researcher(&token) {
        return (StatusCode::NOT_FOUND, "unknown results link").into_response();
    }
    let text = tokio::task::spawn_blocking(move || crate::results::csv(&app.figures.table()))
        .await
        .expect("the table is made without panicking");
    (
        [
            (header::CONTENT_TYPE, "text/csv; charset=utf-8"),
            (header::CONTENT_DISPOSITION, "attachment; filename=\"episodes.csv\""),
        ],
        text,
    )
        .into_response()
}

async fn replay_page(State(app): State<Arc<App>>, Path((token, _, _)): Path<(String, String, u64)>) -> Response {
    if app.is_researcher(&token) {
        Html(INDEX_HTML).into_response()
    } else {
        (StatusCode::NOT_FOUND, "unknown results link").into_response()
    }
}

/// Episode `episode` of the recording `file`, step by step.
async fn replay(State(app): State<Arc<App>>, Path((token, file, episode)): Path<(String, String, u64)>) -> Response {
    if !app.is_researcher(&token) {
        return (StatusCode::NOT_FOUND, "unknown results link").into_response();
    }
    let found = tokio::task::spawn_blocking(move || app.figures.replay(&file, episode))
        .await
        .expect("the replay is read without panicking");
    match found {
        Ok(replay) => json(&replay),
        Err(why) => (StatusCode::NOT_FOUND, why).into_response(),
    }
}

async fn socket(
    State(app): State<Arc<App>>,
    Path(token): Path<String>,
    headers: HeaderMap,
    upgrade: WebSocketUpgrade,
) -> Response {
    if !app.same_origin(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "a page of another origin may not open this session",
        )
            .into_response();
    }
    let limit = app.seating.limits.max_frame_bytes;
    upgrade
        .max_message_size(limit)
        .max_frame_size(limit)
        .on_upgrade(move |socket| session_socket(socket, app, token))
}

/// Ids of page connections, so that a session knows which page has it.
static NEXT_PAGE: AtomicU64 = AtomicU64::new(1);

/// Marks a session's page as gone when its connection ends, however it ends, unless a
/// newer page has taken the session over.
struct Connected {
    slot: Arc<Slot>,
    page: u64,
}

impl Drop for Connected {
    fn drop(&mut self) {
        let mut page = lock(&self.slot.page);
        if *page == self.page {
            *page = 0;
        }
        drop(page);
        self.slot.touch();
    }
}

/// Sends one error line, then closes with `code` and a short `reason`.
async fn refuse(socket: &mut WebSocket, code: u16, message: &str) {
    let _ = socket
        .send(Message::Text(error_line(None, message.into()).into()))
        .await;
    close(socket, code, message).await;
}

async fn close(socket: &mut WebSocket, code: u16, reason: &str) {
    // A close frame's reason holds at most 123 bytes.
    let mut end = reason.len().min(120);
    while !reason.is_char_boundary(end) {
        end -= 1;
    }
    let _ = socket
        .send(Message::Close(Some(CloseFrame {
            code,
            reason: reason[..end].into(),
        })))
        .await;
}

/// Sends `message`, or gives up after the request timeout (a page that does not read).
async fn send_within(socket: &mut WebSocket, limit: Duration, message: Message) -> bool {
    matches!(tokio::time::timeout(limit, socket.send(message)).await, Ok(Ok(())))
}

async fn session_socket(mut socket: WebSocket, app: Arc<App>, token: String) {
    // Held, or taken up again from the recording the token reaches (let go, or an earlier
    // run's).
    let held = lock(&app.registry).find(&token);
    let found = match held {
        Some(slot) => Ok(Some(slot)),
        None => {
            let app = app.clone();
            tokio::task::spawn_blocking(move || Registry::session(&app.registry, &app.seating, &token, None))
                .await
                .unwrap_or(Ok(None))
        }
    };
    let slot = match found {
        Ok(Some(slot)) => slot,
        Ok(None) => return refuse(&mut socket, close::UNKNOWN_SESSION, UNKNOWN).await,
        Err(JoinRefused::Withdrawn) => return refuse(&mut socket, close::UNKNOWN_SESSION, WITHDRAWN).await,
        Err(JoinRefused::Full(m) | JoinRefused::Failed(m)) => {
            return refuse(&mut socket, close::UNKNOWN_SESSION, &m).await;
        }
        Err(other) => return refuse(&mut socket, close::UNKNOWN_SESSION, &format!("{other:?}")).await,
    };
    // The newest page has the session: one that was frozen or lost keeps no lock on it.
    let page = NEXT_PAGE.fetch_add(1, Ordering::SeqCst);
    *lock(&slot.page) = page;
    let _connected = Connected {
        slot: slot.clone(),
        page,
    };
    slot.touch();
    let limits = app.seating.limits;
    let first = {
        let state = lock(&slot.state);
        match &*state {
            SlotState::Live(live) => {
                Some(serde_json::to_string(&live.participant.view(None)).expect("views serialise"))
            }
            SlotState::Expired { .. } => None,
        }
    };
    let Some(first) = first else {
        return refuse(&mut socket, close::UNKNOWN_SESSION, EXPIRED).await;
    };
    if !send_within(&mut socket, limits.request_timeout, Message::Text(first.into())).await {
        return;
    }
    let mut ping = tokio::time::interval(limits.socket_idle / 3);
    ping.tick().await;
    let mut heard = tokio::time::Instant::now();
    loop {
        let message = tokio::select! {
            m = socket.recv() => m,
            _ = ping.tick() => {
                if *lock(&slot.page) != page {
                    refuse(&mut socket, close::OPENED_ELSEWHERE, "this session was opened in another window, which has it now").await;
                    return;
                }
                if heard.elapsed() >= limits.socket_idle {
                    close(&mut socket, close::GOING_AWAY, "no answer for a long time").await;
                    return;
                }
                if !send_within(&mut socket, limits.request_timeout, Message::Ping(Vec::new().into())).await {
                    return;
                }
                continue;
            }
        };
        heard = tokio::time::Instant::now();
        let Some(message) = message else {
            return;
        };
        if *lock(&slot.page) != page {
            refuse(
                &mut socket,
                close::OPENED_ELSEWHERE,
                "this session was opened in another window, which has it now",
            )
            .await;
            return;
        }
        let answer = match message {
            Ok(Message::Text(text)) => {
                let (app, slot) = (app.clone(), slot.clone());
                let done = tokio::task::spawn_blocking(move || app.answer(&slot, text.as_str())).await;
                match done {
                    Ok(Ok(answer)) => answer,
                    Ok(Err(expired)) => return refuse(&mut socket, close::UNKNOWN_SESSION, &expired).await,
                    Err(e) => error_line(
                        None,
                        format!("the server failed to carry this out ({e}); nothing was done"),
                    ),
                }
            }
            Ok(Message::Binary(_)) => error_line(
                None,
                "binary messages are not part of the protocol: send JSON text; nothing was done".into(),
            ),
            Ok(Message::Close(_)) => return,
            Ok(_) => continue,
            Err(e) => {
                // Past the frame bound (the one error the socket can still hear about);
                // a broken connection gets no answer.
                let text = e.to_string();
                if text.contains("too long") || text.contains("too big") || text.contains("Space limit") {
                    close(&mut socket, close::TOO_BIG, &text).await;
                }
                return;
            }
        };
        if !send_within(&mut socket, limits.request_timeout, Message::Text(answer.into())).await {
            return;
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
    fn only_the_servers_own_origin_passes_by_scheme_host_and_port() {
        let plain = |origin, host| same_origin(None, &headers(origin, host));
        assert!(plain(None, "127.0.0.1:8080"));
        assert!(plain(Some("http://127.0.0.1:8080"), "127.0.0.1:8080"));
        assert!(plain(Some("http://LOCALHOST"), "localhost:80"));
        // An https page is not this http server's (P22), nor another port or site.
        assert!(!plain(Some("https://127.0.0.1:8080"), "127.0.0.1:8080"));
        assert!(!plain(Some("https://Example.org"), "example.org"));
        assert!(!plain(Some("http://127.0.0.1:8081"), "127.0.0.1:8080"));
        assert!(!plain(Some("http://evil.example"), "127.0.0.1:8080"));
        assert!(!plain(Some("null"), "127.0.0.1:8080"));
        // A page of ours under no-referrer: null, and same-origin by the fetch metadata.
        let mut ours = headers(Some("null"), "127.0.0.1:8080");
        ours.insert("sec-fetch-site", "same-origin".parse().unwrap());
        assert!(same_origin(None, &ours));
        ours.insert("sec-fetch-site", "cross-site".parse().unwrap());
        assert!(!same_origin(None, &ours));
        // Behind a proxy serving https: the public URL's origin, its default port left out.
        let public = PublicUrl::parse("https://Example.org/").unwrap();
        let proxied = |origin, host| same_origin(Some(&public), &headers(origin, host));
        assert!(proxied(Some("https://example.org"), "example.org"));
        assert!(proxied(Some("https://example.org:443"), "127.0.0.1:8080"));
        assert!(!proxied(Some("http://example.org:443"), "example.org"));
        assert!(!proxied(Some("https://example.org:8443"), "example.org"));
    }

    #[test]
    fn the_cookie_gives_back_the_session_token_only() {
        let mut h = HeaderMap::new();
        h.insert(header::COOKIE, "a=1; blockstack_session=abc123; b=2".parse().unwrap());
        assert_eq!(cookie_token(&h).as_deref(), Some("abc123"));
        h.insert(
            header::COOKIE,
            "blockstack_sessionx=1; blockstack_session=".parse().unwrap(),
        );
        assert_eq!(cookie_token(&h), None);
    }

    #[test]
    fn hosts_are_names_of_this_server_only() {
        assert_eq!(host_name("127.0.0.1:8080"), "127.0.0.1");
        assert_eq!(host_name("[::1]:8080"), "::1");
        assert_eq!(host_name("lab.example.org"), "lab.example.org");
        let public = PublicUrl::parse("https://Lab.Example.org:8443/").unwrap();
        assert_eq!(
            (public.base.as_str(), public.host.as_str()),
            ("https://Lab.Example.org:8443", "lab.example.org")
        );
        for bad in ["lab.example.org", "ftp://x", "http://x/study", "http://a@b"] {
            assert!(PublicUrl::parse(bad).is_err(), "{bad}");
        }
    }
}
