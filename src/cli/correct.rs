//! `blockstack correct`: a simulated demonstrator corrects a trained agent, headless.

use std::path::PathBuf;

use agent::correction::CorrectionConfig;
use agent::{DemoWriter, DemonstratorProfile, QAgent};
use anyhow::{Context, Result};
use clap::Args;
use files::{OutputPath, refuse_same_file};
use sim::Goal;

use super::demo::LearningArgs;
use super::demo::demonstration_goals;
use super::profile::session_world;
use super::stdout::line;

/// Arguments of `blockstack correct`.
#[derive(Debug, Args)]
pub struct CorrectArgs {
    /// The trained model to correct.
    #[arg(long)]
    pub model: PathBuf,
    /// The simulated demonstrator: 1 (careful expert), 2 (attentive amateur) or 3
    /// (distracted); see the agent crate's `demonstrator` docs for their parameters.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=3))]
    pub demonstrator: u8,
    /// Demonstrations (episodes) to give.
    #[arg(long, default_value_t = 10)]
    pub demos: u64,
    /// Goals to demonstrate on, in turn, separated by ':' [default: every goal; under the
    /// original profile the authors' four, 0,1,2:2,1,0:1,2,0:1,0,2]
    #[arg(long)]
    pub goals: Option<String>,
    /// Seed of the starts, the agent's proposals and the demonstrator's choices.
    #[arg(long, default_value_t = 3)]
    pub seed: u64,
    /// Where to write the corrected model.
    #[arg(long)]
    pub out: PathBuf,
    /// Append every step to this JSON Lines file, as it happens (in place, line by line).
    #[arg(long)]
    pub record: Option<PathBuf>,
    #[command(flatten)]
    pub learning: LearningArgs,
}

/// Corrects, saves, and reports.
pub fn correct(args: CorrectArgs) -> Result<()> {
    let out = OutputPath::check(&args.out)?;
    let record = args.record.as_deref().map(OutputPath::check).transpose()?;
    super::stdout::claim_for_data(&[Some(&out), record.as_ref()])?;
    refuse_same_file(&args.out, &args.model).context("--out and --model")?;
    if let Some(record) = &args.record {
        refuse_same_file(record, &args.model).context("--record and --model")?;
        refuse_same_file(record, &args.out).context("--record and --out")?;
    }
    let agent = QAgent::load(&args.model)?;
    let profile = DemonstratorProfile::preset(args.demonstrator)?;
    let l = &args.learning;
    let (world, rules_of) = session_world(&agent, l.profile, l.play, l.reward);
    let goals = demonstration_goals(args.goals.as_deref(), &world, rules_of)?;
    let config = CorrectionConfig {
        rule: Some(l.rule(rules_of)?),
        world: Some(world),
        epsilon: l.epsilon,
        model: Some(args.model.display().to_string()),
        ..CorrectionConfig::new(profile.clone(), goals.clone(), args.demos, args.seed)
    };
    let record = record.as_ref().map(DemoWriter::append).transpose()?;
    let bar = super::progress::bar(args.demos, "demonstrations");
    let sink = super::progress::TickingSink { sink: record, bar };
    let corrected = agent::correct(agent, &config, sink)?;
    corrected.sink.bar.finish_and_clear();
    corrected
        .agent
        .save(out.path())
        .context("the agent was corrected but not saved")?;
    let r = corrected.report;
    let goals: Vec<String> = goals.iter().map(Goal::to_string).collect();
    line(format_args!(
        "demonstrator {} ({}) gave {} demonstrations on {} (seed {}): {} steps, {} corrections, {} reached the goal",
        args.demonstrator,
        profile.name,
        r.episodes,
        goals.join(":"),
        args.seed,
        r.steps,
        r.corrections,
        r.successes
    ))?;
    line(format_args!("saved {}", args.out.display()))?;
    if let Some(path) = &args.record {
        line(format_args!("recorded to {}", path.display()))?;
    }
    Ok(())
}
