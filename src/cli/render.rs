//! `blockstack render`: draw a start state.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use sim::Env;
use sim::render::{self, Colour};

use super::profile::{ProfileArg, Rules, StartArg};
use super::world::WorldArgs;

/// Arguments of `blockstack render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub start: StartArg,
    /// The seed of the start state (as `reset(seed)` draws it).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write a PNG picture here.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print the world as text (the default when no --out is given).
    #[arg(long)]
    pub ascii: bool,
    /// Pixels per cell in the PNG.
    #[arg(long, default_value_t = render::CELL_PIXELS)]
    pub cell: u32,
}

/// Draws the start state of `reset(seed)`.
pub fn render(args: RenderArgs) -> Result<()> {
    let rules =
        Rules::of(sim::Profile::Spec).overridden(args.profile, None, args.start.start, args.world.reward.as_deref())?;
    let mut env = Env::new(args.world.config(&rules)?)?;
    let obs = env.reset(args.seed);
    if let Some(path) = &args.out {
        anyhow::ensure!(
            args.cell >= 4,
            "--cell {} is too small to draw: use at least 4 pixels",
            args.cell
        );
        render::save_png(&obs, path, args.cell)?;
    }
    if args.ascii || args.out.is_none() {
        print!("{}", render::ascii(&obs, Colour::for_stdout()));
    }
    Ok(())
}
