//! `blockstack learn-from-demos`: apply a recorded demonstration session to a model,
//! headless.

use std::io::Write;
use std::path::PathBuf;

use agent::QAgent;
use agent::demos::{Admission, BadLines, RunWorld, learn_admitted};
use anyhow::{Context, Result};
use clap::Args;
use files::{OutputPath, refuse_same_file};

use super::stdout::line;

/// Arguments of `blockstack learn-from-demos`.
#[derive(Debug, Args)]
pub struct LearnFromDemosArgs {
    /// The recording (JSON Lines, as `demo --record` and `correct --record` write it).
    pub demos: PathBuf,
    /// The model the recorded sessions started from.
    #[arg(long)]
    pub model: PathBuf,
    /// Where to write the model after learning.
    #[arg(long)]
    pub out: PathBuf,
    /// A line that cannot be used: skip (report it with its number and use the rest) or
    /// fail (stop, writing nothing).
    #[arg(long, default_value = "skip")]
    pub on_bad_line: BadLines,
    /// Read a withdrawn participant's recording too, for an audit (by default it is
    /// refused: a withdrawn participant is left out of every analysis).
    #[arg(long)]
    pub include_withdrawn: bool,
}

/// Replays, saves, and reports.
pub fn learn_from_demos(args: LearnFromDemosArgs) -> Result<()> {
    let out = OutputPath::check(&args.out)?;
    super::stdout::claim_for_data(&[Some(&out)])?;
    refuse_same_file(&args.out, &args.demos).context("--out and the recording")?;
    refuse_same_file(&args.out, &args.model).context("--out and --model")?;
    let mut agent = QAgent::load(&args.model)?;
    // The model's view, grid and blocks; the protocol is the session's own (a model is
    // corrected under either profile, and the session line names the rule it learnt by).
    let admission = Admission {
        world: Some(RunWorld {
            protocol: None,
            ..RunWorld::of(&agent::correction::session_world(&agent))
        }),
        include_withdrawn: args.include_withdrawn,
    };
    let admitted = learn_admitted(&mut agent, &args.demos, args.on_bad_line, &admission)?;
    let report = admitted.read;
    {
        // Standard error may be gone: that must not cost the model.
        let mut err = std::io::stderr().lock();
        if let Some(note) = &admitted.note {
            let _ = writeln!(err, "{note}");
        }
        for bad in &report.bad_lines {
            let _ = writeln!(err, "{}:{}: skipped: {}", args.demos.display(), bad.line, bad.reason);
        }
        if report.unchecked_sessions > 0 {
            let _ = writeln!(
                err,
                "{}: {} of {} sessions are of recording version 1, which does not name its model: \
                 not checked to have started from {}",
                args.demos.display(),
                report.unchecked_sessions,
                report.sessions,
                args.model.display()
            );
        }
    }
    agent
        .save(out.path())
        .context("the demonstrations were learnt but the model not saved")?;
    line(format_args!(
        "learnt from {} steps ({} corrections) in {} episodes of {} sessions; {} of {} lines skipped",
        report.steps,
        report.corrections,
        report.episodes,
        report.sessions,
        report.bad_lines.len(),
        report.lines
    ))?;
    line(format_args!("saved {}", args.out.display()))
}
