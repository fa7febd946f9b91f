//! A training run's learning curve, live in the browser (`blockstack train ... --serve`).
//!
//! The trainer pushes a point every so many games ([`CurveHandle::push`]); a small server
//! on a thread of its own serves the page at `/curve`, which asks `/api/curve` for the
//! points every second and draws them. The curve is the run's own progress, read-only,
//! on loopback unless told otherwise: no token guards it. The server ends with the process.

use std::net::{IpAddr, SocketAddr};
use std::sync::{Arc, Mutex};

use axum::Router;
use axum::extract::State;
use axum::http::header;
use axum::response::{Html, IntoResponse, Redirect};
use axum::routing::get;
use serde::Serialize;

use crate::error::{Result, ServeError};

/// One point of the curve.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CurvePoint {
    /// Games played so far.
    pub games: u64,
    /// The share of recent games that reached the goal, in `[0, 1]`.
    pub success_rate: f64,
    /// Mean steps of the recent games that reached the goal.
    pub mean_steps: Option<f64>,
}

/// The curve so far and what the run is.
#[derive(Debug, Default, Serialize)]
struct Curve {
    title: String,
    target: u64,
    points: Vec<CurvePoint>,
}

/// Where a trainer sends its points.
#[derive(Clone, Debug)]
pub struct CurveHandle {
    curve: Arc<Mutex<Curve>>,
    /// The page's address.
    pub url: String,
}

impl CurveHandle {
    /// Adds a point.
    pub fn push(&self, point: CurvePoint) {
        self.curve.lock().unwrap_or_else(|e| e.into_inner()).points.push(point);
    }
}

/// Serves the curve of a run called `title` of `target` games on `bind:port`, on a thread
/// of its own; the handle to push points to.
pub fn serve_curve(bind: IpAddr, port: u16, title: &str, target: u64) -> Result<CurveHandle> {
    let listener = std::net::TcpListener::bind(SocketAddr::new(bind, port)).map_err(|source| ServeError::Bind {
        addr: SocketAddr::new(bind, port).to_string(),
        source,
    })?;
    listener.set_nonblocking(true)?;
    let url = format!("http://{}/curve", listener.local_addr()?);
    let curve = Arc::new(Mutex::new(Curve {
        title: title.into(),
        target,
        points: Vec::new(),
    }));
    let runtime = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    let shared = curve.clone();
    std::thread::spawn(move || {
        runtime.block_on(async move {
            let Ok(listener) = tokio::net::TcpListener::from_std(listener) else {
                return;
            };
            let app = Router::new()
                .route("/", get(|| async { Redirect::to("/curve") }))
                .route("/curve", get(|| async { Html(crate::server::INDEX_HTML) }))
                .route("/api/curve", get(points))
                .merge(crate::server::asset_routes())
                .with_state(shared);
            let _ = axum::serve(listener, app).await;
        });
    });
    Ok(CurveHandle { curve, url })
}

async fn points(State(curve): State<Arc<Mutex<Curve>>>) -> impl IntoResponse {
    let text = serde_json::to_string(&*curve.lock().unwrap_or_else(|e| e.into_inner())).expect("curves serialise");
    ([(header::CONTENT_TYPE, "application/json")], text)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Read, Write};

    #[test]
    fn the_page_reads_the_points_pushed_so_far() {
        let handle = serve_curve(IpAddr::from([127, 0, 0, 1]), 0, "run", 100).unwrap();
        handle.push(CurvePoint {
            games: 64,
            success_rate: 0.25,
            mean_steps: Some(12.5),
        });
        let addr = handle
            .url
            .trim_start_matches("http://")
            .trim_end_matches("/curve")
            .to_string();
        let mut stream = std::net::TcpStream::connect(&addr).unwrap();
        write!(
            stream,
            "GET /api/curve HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut response = String::new();
        stream.read_to_string(&mut response).unwrap();
        assert!(response.starts_with("HTTP/1.1 200"), "{response}");
        assert!(
            response.contains(r#""points":[{"games":64,"success_rate":0.25,"mean_steps":12.5}]"#),
            "{response}"
        );
        assert!(response.contains(r#""target":100"#));
    }
}
