//! `blockstack serve`: parses the flags and hands them to [`serve::run`].

use std::net::IpAddr;
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use sim::Profile;

use super::stdout::line;

/// Arguments of `blockstack serve`.
#[derive(Debug, Args)]
pub struct ServeArgs {
    /// The port to listen on (0: any free port, printed at start).
    #[arg(long, default_value_t = 8080)]
    pub port: u16,
    /// The address to listen on: loopback unless told otherwise (0.0.0.0 lets other machines in).
    #[arg(long, default_value = "127.0.0.1")]
    pub bind: IpAddr,
    /// The model to watch and correct: a tabular model (watch, correct) or a network (watch).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// The world and correction rule of play and correct mode: spec or original [default: the model's]
    #[arg(long)]
    pub profile: Option<Profile>,
    /// Goals played in turn, separated by ':' [default: every goal; under the original profile the authors' four]
    #[arg(long)]
    pub goals: Option<String>,
    /// Write one recording per participant into this folder (made if missing).
    #[arg(long)]
    pub record_dir: Option<PathBuf>,
    /// A study file (TOML): its conditions, handed to participants in turn (needs --record-dir).
    #[arg(long)]
    pub study: Option<PathBuf>,
    /// Seed of the starts (a study's own seed wins).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The most participant sessions held at once; a session with no page for 30 minutes
    /// is let go, its recording kept (a study's max_participants caps the participants in all).
    #[arg(long, default_value_t = serve::Limits::default().max_sessions)]
    pub max_sessions: usize,
    /// The address participants reach the server at, e.g. http://lab.example.org:8080/, when
    /// it is not the one bound: printed as the link, and the only host name answered (DNS
    /// rebinding is refused; IP addresses and localhost are always answered).
    #[arg(long)]
    pub public_url: Option<String>,
}

/// Serves until the process is ended (Ctrl-C).
pub fn serve(args: ServeArgs) -> Result<()> {
    let config = serve::ServeConfig {
        bind: args.bind,
        port: args.port,
        model: args.model,
        profile: args.profile,
        goals: args.goals,
        record_dir: args.record_dir,
        study: args.study,
        public_url: args.public_url,
        seed: args.seed,
        limits: serve::Limits {
            max_sessions: args.max_sessions,
            ..serve::Limits::default()
        },
    };
    serve::run(config, |links| {
        line(format_args!("participants: {}", links.join))
            .and_then(|()| line(format_args!("researcher:   {}", links.results)))
            .and_then(|()| {
                links
                    .note
                    .as_ref()
                    .map_or(Ok(()), |note| line(format_args!("note: {note}")))
            })
            .and_then(|()| super::flush_stdout())
            .map_err(std::io::Error::other)
    })?;
    Ok(())
}
