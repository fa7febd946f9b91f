//! `blockstack demo`: watch a trained agent play in the terminal and correct it.

use std::path::{Path, PathBuf};

use agent::correction::{CorrectionRule, CorrectionSession, SessionLabels};
use agent::{DemoWriter, QAgent};
use anyhow::{Context, Result};
use clap::Args;
use files::{OutputPath, refuse_same_file};
use sim::Profile;

use super::profile::{PlayRulesArgs, ProfileArg, session_world};
use super::stdout::line;
use crate::tui::{self, app::DemoApp, app::SavePolicy};

/// Arguments of `blockstack demo`.
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// The trained model to watch and correct.
    #[arg(long)]
    pub model: PathBuf,
    /// Goals to play, in turn, separated by ':', e.g. 0,1,2:1,0,2 [default: every goal; under
    /// the original profile the authors' four, 0,1,2:2,1,0:1,2,0:1,0,2]
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

/// The goals of a correction session in `world`: `text`'s, else every goal of the world, or
/// the authors' demonstrated goals under the original profile (with their 3 blocks).
pub fn demonstration_goals(text: Option<&str>, world: &sim::EnvConfig, profile: Profile) -> Result<Vec<sim::Goal>> {
    match text {
        None => agent::correction::default_goals(world, profile).context("without --goals every goal is used"),
        Some(text) => Ok(sim::Goal::parse_list(text, world.blocks)?),
    }
}

/// `agent.safetensors` -> `agent.corrected.safetensors`.
pub fn default_out(model: &Path) -> PathBuf {
    let stem = model
        .file_stem()
        .map_or("model".into(), |s| s.to_string_lossy().into_owned());
    model.with_file_name(format!("{stem}.corrected.{}", agent::model::MODEL_EXTENSION))
}

/// How the agent proposes and learns during a correction session, and in which world: the
/// flags `demo` and `correct` share.
#[derive(Debug, Args)]
pub struct LearningArgs {
    /// After a correction, the demonstrated action is raised to at least the best other
    /// action's value plus this margin; none: the plain update alone, as the authors coded
    /// it [default: the profile's: 0.8 under spec, none under original]
    #[arg(long, value_parser = parse_margin)]
    pub margin: Option<Margin>,
    /// Learn only from corrections, not from the agent's own steps.
    #[arg(long)]
    pub corrections_only: bool,
    /// Probability that the agent proposes a random legal action (the paper's test policy:
    /// 0.1).
    #[arg(long, default_value_t = agent::profile::TEST_EPSILON)]
    pub epsilon: f64,
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub play: PlayRulesArgs,
    /// The reward the agent learns from: sparse, dense, paper, step-cost or paper-code
    /// [default: the one it was trained with, or the profile's]
    #[arg(long)]
    pub reward: Option<sim::RewardModel>,
}

/// A `--margin`: a number, or none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Margin(pub Option<f64>);

/// Reads `--margin`: `none`, or a number.
fn parse_margin(text: &str) -> Result<Margin, String> {
    if text == "none" {
        return Ok(Margin(None));
    }
    text.parse()
        .map(|m| Margin(Some(m)))
        .map_err(|_| format!("{text:?} is neither a number nor none"))
}

impl LearningArgs {
    /// The learning rule the flags describe, on the rule of `profile`.
    pub fn rule(&self, profile: Profile) -> Result<CorrectionRule> {
        let base = CorrectionRule::for_profile(profile);
        let rule = CorrectionRule {
            margin: self.margin.map_or(base.margin, |m| m.0),
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
    let record = record.as_ref().map(DemoWriter::append).transpose()?;
    let l = &args.learning;
    let (world, profile) = session_world(&agent, l.profile, l.play, l.reward);
    let goals = demonstration_goals(args.goals.as_deref(), &world, profile)?;
    // A person's session keeps time: each step's time since its episode began.
    let labels = SessionLabels {
        demonstrator: "person".into(),
        model: Some(args.model.display().to_string()),
        timed: true,
        ..SessionLabels::default()
    };
    let session = CorrectionSession::labelled(
        agent,
        l.rule(profile)?,
        world,
        goals,
        args.seed,
        args.learning.epsilon,
        labels,
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
