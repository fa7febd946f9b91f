//! `blockstack demo`: watch a trained agent play in the terminal and correct it.

use std::path::{Path, PathBuf};

use agent::correction::{CorrectionRule, CorrectionSession, DEFAULT_MARGIN, SessionWorld};
use agent::{DemoWriter, QAgent};
use anyhow::{Context, Result};
use clap::Args;
use files::{OutputPath, refuse_same_file};

use super::stdout::line;
use super::train::parse_goals;
use crate::tui::{self, app::DemoApp, app::SavePolicy};

/// Arguments of `blockstack demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// The trained model to watch and correct.
    #[arg(long)]
    pub model: PathBuf,
    /// Goals to play, in turn, separated by ':', e.g. 0,1,2:1,0,2 (default: every goal).
    #[arg(long)]
    pub goals: Option<String>,
    /// Append every step of the session to this JSON Lines file, as it happens.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Where to save the corrected model (default: the model's name with `.corrected`
    /// before `.safetensors`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Save the corrected model after every this many corrections (0: only on quitting).
    #[arg(long, default_value_t = 5)]
    pub save_every: u64,
    #[command(flatten)]
    pub learning: LearningArgs,
    /// Seed of the starts and of the agent's random proposals.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// `agent.safetensors` -> `agent.corrected.safetensors`.
pub fn default_out(model: &Path) -> PathBuf {
    let stem = model
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().into_owned());
    model.with_file_name(format!("{stem}.corrected.{}", agent::model::MODEL_EXTENSION))
}

/// How the agent proposes and learns during a correction session: the flags `demo` and
/// `correct` share.
#[derive(Debug, Args)]
pub struct LearningArgs {
    /// After a correction, the demonstrated action is raised to at least the best other
    /// action's value plus this margin.
    #[arg(long, default_value_t = DEFAULT_MARGIN)]
    pub margin: f64,
    /// Learn only from corrections, not from the agent's own steps.
    #[arg(long)]
    pub corrections_only: bool,
    /// Probability that the agent proposes a random action (the paper's test policy: 0.1).
    #[arg(long, default_value_t = 0.1)]
    pub epsilon: f64,
}

impl LearningArgs {
    /// The learning rule the flags describe.
    pub fn rule(&self) -> Result<CorrectionRule> {
        let rule = CorrectionRule {
            margin: self.margin,
            learn_agent_steps: !self.corrections_only,
        };
        rule.validate()?;
        Ok(rule)
    }
}

/// Runs the terminal UI, then says what was saved.
pub fn demo(args: DemoArgs) -> Result<()> {
    let out = args.out.clone().unwrap_or_else(|| default_out(&args.model));
    let record = args.record.as_deref().map(OutputPath::check).transpose()?;
    anyhow::ensure!(
        !OutputPath::check(&out)?.is_stdout() && !record.as_ref().is_some_and(OutputPath::is_stdout),
        "demo draws on the terminal, so its --out and --record cannot be standard output (-): give file names"
    );
    refuse_same_file(&out, &args.model).context("--out and --model")?;
    if let Some(record) = &args.record {
        refuse_same_file(record, &args.model).context("--record and --model")?;
        refuse_same_file(record, &out).context("--record and --out")?;
    }
    let agent = QAgent::load(&args.model)?;
    let goals = parse_goals(args.goals.as_deref(), agent.blocks())?;
    let record = record.as_ref().map(DemoWriter::append).transpose()?;
    let world = SessionWorld::of(&agent);
    let session = CorrectionSession::new(
        agent,
        args.learning.rule()?,
        world,
        goals,
        args.seed,
        args.learning.epsilon,
        "person",
        Some(&args.model.display().to_string()),
        record,
    )?;
    let mut app = DemoApp::new(
        session,
        SavePolicy {
            path: out.clone(),
            every: args.save_every,
        },
    )?;
    let outcome = tui::run(&mut app);
    if outcome.is_err() && !app.should_quit() {
        // Keep what was learnt whatever went wrong.
        app.save_model()
            .with_context(|| format!("and the corrected model could not be saved to {}", out.display()))?;
    }
    outcome?;
    let (_, _, report) = app.finish();
    line(format_args!(
        "{} episodes, {} steps, {} corrections; corrected model saved to {}",
        report.episodes,
        report.steps,
        report.corrections,
        out.display()
    ))?;
    if let Some(path) = &args.record {
        line(format_args!("recorded to {}", path.display()))?;
    }
    Ok(())
}
