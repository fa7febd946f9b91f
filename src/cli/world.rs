//! The flags that describe a world, one set shared by every command that plays, trains or
//! draws one (`run`, `render`, `train`, `dqn`, `eval`), each parsed by clap into `sim`'s own
//! types.
//!
//! Every flag is optional: a command fills what is not given from its own starting point (a
//! model's world, a preset, `sim`'s defaults), and says so in its help (`mut_arg` on the
//! command). A command that plays a model refuses a size or view other than the model's.

use anyhow::Result;
use clap::Args;
use sim::{Backend, EnvConfig, Goal, GoalSpec, Grid, ProfileParts, RewardModel, View};

/// The world's size, length, reward, backend and view (the rules a profile sets come with
/// [`ProfileParts`]).
#[derive(Debug, Clone, Copy, Default, Args)]
pub struct WorldArgs {
    /// Number of blocks [default: 3, or a model's own]
    #[arg(long)]
    pub blocks: Option<usize>,
    /// Grid size, WxH [default: a model's own, or 7x7; in the side view, 7x7 up to 7
    /// blocks and N x (N+1) beyond]
    #[arg(long)]
    pub grid: Option<Grid>,
    /// Steps before an episode is cut off [default: 1000]
    #[arg(long)]
    pub horizon: Option<u32>,
    /// Reward model: sparse, dense, paper, step-cost or paper-code [default: the profile's:
    /// sparse under spec, paper-code under original]
    #[arg(long)]
    pub reward: Option<RewardModel>,
    /// World backend: physics (rapier2d) or grid (occupancy model) [default: physics]
    #[arg(long)]
    pub backend: Option<Backend>,
    /// The world: top (the paper's, seen from above) or side (the classic Blocks World:
    /// towers on a table, gravity, only clear blocks picked) [default: a model's own, else
    /// top]
    #[arg(long)]
    pub view: Option<View>,
}

/// `--goal`: one goal for every episode (`run`, `render`).
#[derive(Debug, Clone, Default, Args)]
pub struct GoalArg {
    /// The goal, bottom to top, e.g. 1,0,2; or towers separated by '/', e.g. 0,1/2 (blocks
    /// no tower names are free) (default: one tower drawn at random every episode).
    #[arg(long)]
    pub goal: Option<String>,
}

impl WorldArgs {
    /// `base` with every part these flags give in its place; the rules (protocol, start,
    /// reward unless `--reward`) are `rules`'. Not checked: see [`EnvConfig::validate`].
    pub fn over(&self, base: EnvConfig, rules: &ProfileParts) -> EnvConfig {
        let blocks = self.blocks.unwrap_or(base.blocks);
        let view = self.view.unwrap_or(base.view);
        let grid = default_grid(base.grid, view, blocks);
        EnvConfig {
            grid: self.grid.unwrap_or(grid),
            blocks,
            horizon: self.horizon.unwrap_or(base.horizon),
            backend: self.backend.unwrap_or(base.backend),
            view,
            ..rules.apply(base)
        }
    }

    /// The environment config these flags describe over `base` (a model's world, or
    /// `sim`'s default) under `rules` (whose reward is already this command's), with the
    /// goal `goal` (drawn every episode when `None`), checked. Episodes end at the goal.
    pub fn config(&self, base: EnvConfig, rules: &ProfileParts, goal: Option<&str>) -> Result<EnvConfig> {
        let mut config = self.over(base, rules);
        config.goal = match goal {
            Some(text) => GoalSpec::Fixed(Goal::parse(text, Some(config.blocks))?),
            None => GoalSpec::Random,
        };
        config.termination = sim::Termination::Goal;
        config.validate()?;
        Ok(config)
    }
}

/// The grid when `--grid` is absent: `base` (a model's own), or when `base` is the default
/// grid, the view's default for `blocks` blocks: 7 x 7 in the top view,
/// [`Grid::side_default`] in the side view (docs/world.md, "The side view at any size").
pub fn default_grid(base: Grid, view: View, blocks: usize) -> Grid {
    if view == View::Side && base == Grid::default() {
        Grid::side_default(blocks)
    } else {
        base
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Debug, Parser)]
    struct Flags {
        #[command(flatten)]
        world: WorldArgs,
    }

    #[test]
    fn flags_are_parsed_into_the_worlds_types_and_replace_the_base() {
        let flags = Flags::try_parse_from([
            "x",
            "--grid",
            "5x6",
            "--backend",
            "grid",
            "--view",
            "side",
            "--reward",
            "dense",
        ])
        .unwrap();
        let rules = ProfileParts::of(sim::Profile::Spec);
        let base = EnvConfig {
            blocks: 2,
            ..EnvConfig::default()
        };
        let config = flags.world.over(base, &rules);
        assert_eq!(
            (config.grid, config.blocks, config.backend, config.view),
            (Grid::new(5, 6).unwrap(), 2, Backend::Grid, View::Side)
        );
        // The rules' reward; `--reward` goes into the rules (`profile::played`).
        assert_eq!(config.reward, rules.reward);
        for bad in [
            ["x", "--grid", "7by7"],
            ["x", "--backend", "rapier"],
            ["x", "--view", "front"],
        ] {
            let err = Flags::try_parse_from(bad).unwrap_err().to_string();
            assert!(err.contains(bad[2]), "{err}");
        }
    }
}
