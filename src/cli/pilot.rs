//! `blockstack pilot`: parses the flags, hands them to [`serve::pilot`] and prints what it
//! found.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use serve::pilot::Role;

use super::stdout::line;

/// Arguments of `blockstack pilot`.
#[derive(Debug, Args)]
pub struct PilotArgs {
    /// The study file (TOML), as `blockstack serve --study` takes it.
    #[arg(long)]
    pub study: PathBuf,
    /// Simulated participants (demonstrators, random players who give up, one withdrawal).
    #[arg(long)]
    pub participants: u64,
    /// Where their recordings go: a folder of the pilot's own, not the study's (its
    /// participants count towards the study's cap there).
    #[arg(long)]
    pub record_dir: PathBuf,
    /// Seed of the participants' choices (the study's seed sets the starts).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Runs the pilot and prints a line per participant, then the researcher's figures.
pub fn pilot(args: PilotArgs) -> Result<()> {
    let report = serve::pilot(&serve::PilotConfig {
        study: args.study,
        participants: args.participants,
        record_dir: args.record_dir.clone(),
        seed: args.seed,
    })?;
    line(format_args!(
        "pilot of {}: {} simulated participants through the server and its protocol",
        report.study,
        report.participants.len()
    ))?;
    for p in &report.participants {
        let who = match &p.role {
            Role::Demonstrator(name) => format!("demonstrator ({name})"),
            Role::Random => "random player".to_string(),
            Role::Withdraws => "withdraws".to_string(),
        };
        let end = match (&p.code, p.withdrew) {
            (_, true) => "withdrew".to_string(),
            (Some(code), _) => format!("completion code {code}"),
            (None, _) => "left without finishing".to_string(),
        };
        line(format_args!(
            "  {} {}: {who}; {} episodes, {} steps ({} their own); {end}",
            p.id, p.condition, p.episodes_done, p.steps, p.corrections
        ))?;
    }
    let cap = report
        .max_participants
        .map_or(String::new(), |max| format!(" of at most {max}"));
    line(format_args!(
        "the researcher's page: {} participants{cap}; {} withdrawn left out; episodes.csv: {} rows",
        report.admitted, report.withdrawn_left_out, report.csv_rows
    ))?;
    for c in report.conditions.as_array().into_iter().flatten() {
        let share = c["success"]
            .as_f64()
            .map_or("-".to_string(), |s| format!("{:.0}%", 100.0 * s));
        line(format_args!(
            "  {}: {} participants, {} episodes ended, {share} reached the goal, {} corrections",
            c["condition"].as_str().unwrap_or_default(),
            c["participants"],
            c["episodes"],
            c["corrections"]
        ))?;
    }
    line(format_args!(
        "recordings in {}; `blockstack serve --study ... --record-dir {}` shows them on the researcher's page",
        args.record_dir.display(),
        args.record_dir.display()
    ))
}
