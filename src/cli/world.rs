//! Arguments that describe a world, shared by the subcommands.

use anyhow::Result;
use clap::Args;
use sim::{Backend, EnvConfig, Goal, GoalSpec, Grid, View};

use sim::ProfileParts;

/// The world: grid, blocks, goal, horizon, reward, backend (the rules a profile sets come
/// with [`ProfileParts`]).
#[derive(Debug, Clone, Args)]
pub struct WorldArgs {
    /// Number of blocks.
    #[arg(long, default_value_t = 3)]
    pub blocks: usize,
    /// The goal, bottom to top, e.g. 1,0,2; or towers separated by '/', e.g. 0,1/2 (blocks
    /// no tower names are free) (default: one tower drawn at random every episode).
    #[arg(long)]
    pub goal: Option<String>,
    /// Grid size, WxH [default: 7x7; in the side view, 7x7 up to 7 blocks and N x (N+1)
    /// beyond]
    #[arg(long)]
    pub grid: Option<String>,
    /// Steps before an episode is cut off [default: 1000]
    #[arg(long)]
    pub horizon: Option<u32>,
    /// Reward model: sparse, dense, paper, step-cost or paper-code [default: the profile's:
    /// sparse under spec, paper-code under original]
    #[arg(long)]
    pub reward: Option<String>,
    /// World backend: physics (rapier2d) or grid (occupancy model).
    #[arg(long, default_value = "physics")]
    pub backend: String,
    /// The world: top (the paper's, seen from above) or side (the classic Blocks World:
    /// towers on a table, gravity, only clear blocks picked) [default: a model's own, else
    /// top]
    #[arg(long)]
    pub view: Option<String>,
}

impl WorldArgs {
    /// The environment config these arguments describe under `rules` (whose reward is
    /// already this command's), in `view` unless `--view` says otherwise, checked. Episodes
    /// end at the goal.
    pub fn config(&self, rules: &ProfileParts, view: View) -> Result<EnvConfig> {
        let view: View = self.view.as_deref().map_or(Ok(view), str::parse)?;
        let grid = grid_or_default(self.grid.as_deref(), view, self.blocks)?;
        let goal = match &self.goal {
            Some(text) => GoalSpec::Fixed(Goal::parse(text, Some(self.blocks))?),
            None => GoalSpec::Random,
        };
        let backend: Backend = self.backend.parse()?;
        let config = EnvConfig {
            grid,
            blocks: self.blocks,
            goal,
            horizon: self.horizon.unwrap_or(sim::DEFAULT_HORIZON),
            reward: rules.reward,
            backend,
            protocol: rules.protocol,
            start: rules.start,
            termination: sim::Termination::Goal,
            obs: sim::ObsKind::default(),
            view,
        };
        config.validate()?;
        Ok(config)
    }
}

/// The grid `--grid` names, or the view's default for `blocks` blocks: 7 x 7 in the top
/// view, [`Grid::side_default`] in the side view (docs/world.md, "The side view at any size").
pub fn grid_or_default(text: Option<&str>, view: View, blocks: usize) -> Result<Grid> {
    Ok(match text {
        Some(text) => text.parse()?,
        None if view == View::Side => Grid::side_default(blocks),
        None => Grid::default(),
    })
}
