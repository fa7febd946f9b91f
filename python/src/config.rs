//! Python arguments into the crates' configs, checked by the crates themselves.

use pyo3::prelude::*;
use sim::{Backend, EnvConfig, Goal, GoalSpec, Grid, Profile, ProfileParts, RewardModel};

use crate::boundary::{OrValueError, value_error};

pub use sim::ObsKind;

/// The observation kind called `name` (`sim::ObsKind`: planes, role-planes, frame,
/// paper-screen or state); a `ValueError` naming the choices otherwise, and naming the new
/// names for the old, ambiguous `pixels`.
pub fn obs_kind(name: &str) -> PyResult<ObsKind> {
    name.parse::<ObsKind>().or_value_error()
}

/// The shape of the `uint8` array of observation kind `obs` in a world of `blocks` blocks on
/// a `grid` (width, height) grid, or `None` for `state` (a dict of arrays).
#[pyfunction]
pub fn observation_shape(obs: &str, blocks: usize, grid: (usize, usize)) -> PyResult<Option<[usize; 3]>> {
    let grid = Grid::new(grid.0, grid.1).or_value_error()?;
    let kind = obs_kind(obs)?;
    kind.check(grid, blocks).or_value_error()?;
    Ok(kind.shape(grid, blocks))
}

/// The world keywords, one set taken the same way by `StackEnv`, `BlocksWorldEnv`,
/// `StackVectorEnv`, `StackGoalEnv` and `demonstrations`: Python's `blockstack.world.World`
/// (a dataclass that checks their types and ranges first) read by attribute.
#[derive(Clone, Debug, FromPyObject)]
pub struct World {
    /// Number of blocks.
    pub blocks: usize,
    /// The goal as text (`"1,0,2"`, `"0,1/2"`), or `None` to draw one each episode.
    pub goal: Option<String>,
    /// `(width, height)`.
    pub grid: (usize, usize),
    /// The reward's name, or `None` for the profile's.
    pub reward: Option<String>,
    /// The backend's name.
    pub backend: String,
    /// Steps before an episode is truncated.
    pub horizon: u32,
    /// The profile's name.
    pub profile: String,
    /// The action protocol's name, or `None` for the profile's.
    pub protocol: Option<String>,
    /// The start rule's name, or `None` for the profile's.
    pub start: Option<String>,
    /// The view's name.
    pub view: String,
}

impl World {
    /// The world these keywords describe: the profile's rules (its action protocol, start
    /// rule and reward) with each rule named in its place ([`ProfileParts::overridden`]), on
    /// the grid, blocks, goal, horizon, backend and view given; checked by `sim`.
    pub fn config(&self) -> PyResult<EnvConfig> {
        let parts = ProfileParts::of(Profile::Spec).overridden(
            Some(profile(&self.profile)?),
            self.protocol.as_deref().map(str::parse).transpose().or_value_error()?,
            self.start.as_deref().map(str::parse).transpose().or_value_error()?,
            self.reward
                .as_deref()
                .map(RewardModel::from_name)
                .transpose()
                .or_value_error()?,
        );
        let config = parts.apply(EnvConfig {
            grid: Grid::new(self.grid.0, self.grid.1).or_value_error()?,
            blocks: self.blocks,
            goal: match &self.goal {
                Some(text) => GoalSpec::Fixed(Goal::parse(text, Some(self.blocks)).or_value_error()?),
                None => GoalSpec::Random,
            },
            horizon: self.horizon,
            backend: self.backend.parse::<Backend>().or_value_error()?,
            view: self.view.parse().or_value_error()?,
            ..EnvConfig::default()
        });
        config.validate().or_value_error()?;
        Ok(config)
    }
}

/// A grid from Python: text such as `"7x7"` or a `(width, height)` pair, as every function
/// of the package takes it.
pub fn grid_from(grid: &Bound<'_, PyAny>) -> PyResult<Grid> {
    if let Ok(text) = grid.extract::<String>() {
        return text.parse::<Grid>().or_value_error();
    }
    // A list as well as a tuple: grids often come from JSON or TOML.
    let pair: Vec<usize> = grid.extract().unwrap_or_default();
    let [w, h] = pair[..] else {
        return Err(value_error(
            "a grid is text such as \"7x7\" or a (width, height) pair of whole numbers",
        ));
    };
    Grid::new(w, h).or_value_error()
}

/// `(width, height)` of a grid given as text such as `"7x7"` or a `(width, height)` pair
/// ([`grid_from`]): the one reading of a grid argument, for the Python classes and
/// functions to call before they build anything. No grid (`None`) is the view's default for
/// `blocks` blocks: 7 x 7 from above, `sim::Grid::side_default` from the side.
#[pyfunction]
#[pyo3(signature = (grid, view=None, blocks=3))]
pub fn grid_size(grid: Option<&Bound<'_, PyAny>>, view: Option<&str>, blocks: usize) -> PyResult<(usize, usize)> {
    let grid = match grid {
        Some(grid) => grid_from(grid)?,
        None if view.map(str::parse::<sim::View>).transpose().or_value_error()? == Some(sim::View::Side) => {
            Grid::side_default(blocks)
        }
        None => Grid::default(),
    };
    Ok((grid.width(), grid.height()))
}

/// The profile called `name` (`spec` or `original`; `sim::Profile`).
pub fn profile(name: &str) -> PyResult<Profile> {
    name.parse::<Profile>().or_value_error()
}

/// A goal from Python: text such as `"1,0,2"` or a sequence of block ids.
pub fn goal_from(goal: &Bound<'_, PyAny>, blocks: Option<usize>) -> PyResult<Goal> {
    if let Ok(text) = goal.extract::<String>() {
        return Goal::parse(&text, blocks).or_value_error();
    }
    let order: Vec<usize> = goal
        .extract()
        .map_err(|_| value_error("a goal is text such as \"1,0,2\" or a sequence of block ids, bottom to top"))?;
    let g = Goal::from_indices(&order).or_value_error()?;
    match blocks {
        Some(n) if n != g.block_count() => Err(value_error(format!(
            "goal {g} has {} blocks but the world has {n}",
            g.block_count()
        ))),
        _ => Ok(g),
    }
}

/// The seed of episode `index` of a run with seed `base`: `sim::seeding::episode_seed`,
/// the seeds the CLI's `run --seed` resets its episodes with.
#[pyfunction]
pub fn episode_seed(base: u64, index: u64) -> u64 {
    sim::seeding::episode_seed(base, index)
}
