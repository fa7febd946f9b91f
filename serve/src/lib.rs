//! `blockstack serve`: a page in the browser where a person plays, watches and corrects the
//! agent, and studies with many participants at once (docs/serve.md).
//!
//! Terminal tools (`blockstack demo`) leave out the people a study needs; a page reaches
//! them. Nothing here re-implements a rule: play and correct mode drive the library's
//! [`agent::CorrectionSession`] (the session `blockstack demo` drives) and record through
//! its [`agent::DemoWriter`], watch mode plays a [`neural::AnyModel`], the shortest plan is
//! [`oracle::ExactSolver`]'s, and the page's colours and labels are `sim::render`'s.
//!
//! - [`protocol`]: the messages between page and server.
//! - [`participant`]: one participant's state machine, with no network in it.
//! - `registry`: the participants held, numbered and balanced across restarts; only those
//!   who act count, and a session is reached by its token only.
//! - `ledger`: what a study's record folder keeps beside the recordings: tokens and
//!   withdrawn ids as keyed hashes, and the key of per-participant completion codes.
//! - [`config`]: settings, the study file and the conditions it makes.
//! - [`server`]: the routes, the WebSocket loop and the bounds.
//! - [`results`]: the researcher's figures, CSV and replay, from the recordings on disk.
//! - [`markdown`]: a study's consent and instructions, rendered safely.
//! - [`curve`]: a training run's learning curve, live (`blockstack train ... --serve`).
//! - [`pilot`](mod@pilot): simulated participants sent through the real server before a launch
//!   (`blockstack pilot`).

pub mod config;
pub mod curve;
pub mod error;
mod ledger;
pub mod markdown;
pub mod participant;
pub mod pilot;
pub mod protocol;
mod registry;
pub mod results;
pub mod server;

pub use config::{ConditionSpec, Limits, ServeConfig, StudyFile};
pub use curve::{CurveHandle, CurvePoint, serve_curve};
pub use error::{Result, ServeError};
pub use pilot::{PilotConfig, PilotReport, pilot};
pub use server::{Links, Server, run};
