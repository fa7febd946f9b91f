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

/// The world an environment is made of, from the Python keyword arguments: the profile's
/// world (its action protocol, start rule and reward) with the given grid, blocks, goal,
/// horizon and backend, and the reward, protocol and start rule given by name, if any.
#[allow(clippy::too_many_arguments)]
pub fn env_config(
    blocks: usize,
    goal: Option<&str>,
    grid: (usize, usize),
    reward: Option<&str>,
    backend: &str,
    horizon: u32,
    profile: &str,
    rules: PlayRules<'_>,
) -> PyResult<EnvConfig> {
    let parts = ProfileParts::of(Profile::Spec).overridden(
        Some(self::profile(profile)?),
        rules.protocol.map(str::parse).transpose().or_value_error()?,
        rules.start.map(str::parse).transpose().or_value_error()?,
        reward.map(RewardModel::from_name).transpose().or_value_error()?,
    );
    let config = parts.apply(EnvConfig {
        grid: Grid::new(grid.0, grid.1).or_value_error()?,
        blocks,
        goal: match goal {
            Some(text) => GoalSpec::Fixed(Goal::parse(text, Some(blocks)).or_value_error()?),
            None => GoalSpec::Random,
        },
        horizon,
        backend: backend.parse::<Backend>().or_value_error()?,
        view: match rules.view {
            Some(name) => name.parse().or_value_error()?,
            None => sim::View::default(),
        },
        ..EnvConfig::default()
    });
    config.validate().or_value_error()?;
    Ok(config)
}

/// The rules of play a profile sets, named one by one (`None`: the profile's).
#[derive(Clone, Copy, Debug, Default)]
pub struct PlayRules<'a> {
    /// The action protocol's name (`free` or `paper`).
    pub protocol: Option<&'a str>,
    /// The start rule's name (`uniform` or `paper`).
    pub start: Option<&'a str>,
    /// The world's name (`top` or `side`).
    pub view: Option<&'a str>,
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
