//! `blockstack render`: draw a start state.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use files::OutputPath;
use sim::Env;
use sim::render::{self, Colour};

use super::profile::{ProfileArg, StartArg, overridden};
use super::stdout;
use super::world::{GoalArg, WorldArgs};

/// Arguments of `blockstack render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub goal: GoalArg,
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub start: StartArg,
    /// The seed of the start state (as `reset(seed)` draws it).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write a picture here, in the format its name says: .png, or .jpg / .jpeg (`-`: a
    /// PNG on standard output).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the world as text (the default when no --out is given).
    #[arg(long)]
    pub ascii: bool,
    /// Pixels per cell in the picture (at least 4; the picture is at most 16384 pixels a
    /// side and 2^25 pixels in all).
    #[arg(long, default_value_t = render::CELL_PIXELS)]
    pub cell: u32,
}

/// Draws the start state of `reset(seed)`.
pub fn render(args: RenderArgs) -> Result<()> {
    // A picture of a start plays no episode: flags about episodes would be ignored.
    for (flag, given) in [
        ("--horizon", args.world.horizon.is_some()),
        ("--reward", args.world.reward.is_some()),
    ] {
        anyhow::ensure!(
            !given,
            "{flag} does not apply to render: it draws a start and plays no episode"
        );
    }
    let out = args.out.as_deref().map(OutputPath::check).transpose()?;
    stdout::claim_for_data(&[out.as_ref()])?;
    let rules = overridden(
        sim::ProfileParts::of(sim::Profile::Spec),
        args.profile,
        None,
        args.start.start,
        args.world.reward,
    );
    let config = args
        .world
        .config(sim::EnvConfig::default(), &rules, args.goal.goal.as_deref())?;
    if let Some(out) = &out {
        render::PictureFormat::of(out.path())?;
        anyhow::ensure!(
            args.cell >= 4,
            "--cell {} is too small to draw: use at least 4 pixels",
            args.cell
        );
        render::picture_size(config.grid, config.blocks, args.cell)?;
    }
    let mut env = Env::new(config)?;
    let obs = env.reset(args.seed);
    if let Some(out) = &out {
        render::save_picture(&obs, out, args.cell)?;
    }
    if args.ascii || out.is_none() {
        stdout::text(&render::ascii(&obs, Colour::for_stdout()))?;
    }
    Ok(())
}
