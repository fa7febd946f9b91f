//! Trained models from Python: every kind of model file (`neural::AnyModel`), its world,
//! its actions and its evaluation, behind `blockstack.load`.

use std::path::PathBuf;

use agent::eval::EvalOverrides;
use agent::rollout::policy_rng;
use neural::AnyModel;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::seeding::SimRng;
use sim::{Goal, Grid, Observation, State, View};

use crate::boundary::{OrValueError, guard, raise_signal, signal_checker, value_error};
use crate::config::World;
use crate::env::state_from;
use crate::observe;

/// A model file of any kind, loaded: `blockstack.Model` wraps it.
#[pyclass(module = "blockstack._native")]
pub struct NativeModel {
    model: AnyModel,
    path: String,
    /// The generator the policy draws from (ties, and random actions when not
    /// deterministic): [`policy_rng`] of the episode's seed after `reset(seed)`, as
    /// `blockstack run` plays an episode reset with that seed.
    rng: SimRng,
}

#[pymethods]
impl NativeModel {
    /// The model file at `path` (`blockstack train` or `blockstack dqn`); a `ValueError`
    /// saying what is wrong with a file that is neither.
    #[new]
    fn new(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let model = py.detach(|| guard(|| AnyModel::load(&path).or_value_error()))?;
        Ok(NativeModel {
            model,
            path: path.display().to_string(),
            rng: policy_rng(0),
        })
    }

    /// `q` (a tabular Q-agent), `dqn` (a network) or `relational` (a relational policy of
    /// block moves, `blockstack dqn --preset general`).
    #[getter]
    fn kind(&self) -> &'static str {
        match self.model {
            AnyModel::Q(_) => "q",
            AnyModel::Dqn(_) => "dqn",
            AnyModel::Relational(_) => "relational",
        }
    }

    /// The probability of a random legal action the model plays with unless told otherwise
    /// (`neural::AnyModel::default_epsilon`, as `blockstack run` and `eval` play it): its
    /// profile's test policy (0.1) for a tabular model or a network, 0 for a relational
    /// policy.
    #[getter]
    fn default_epsilon(&self) -> f64 {
        self.model.default_epsilon()
    }

    /// The environment observation a network on pixels reads (`paper-screen`, or `screen`
    /// for the `conv` network on its default screen), `None` otherwise.
    #[getter]
    fn picture(&self) -> Option<String> {
        match &self.model {
            AnyModel::Dqn(d) => d.picture().map(|k| k.to_string()),
            AnyModel::Q(_) | AnyModel::Relational(_) => None,
        }
    }

    /// The model's name in reports (as `blockstack eval` prints it).
    #[getter]
    fn name(&self) -> String {
        self.model.name()
    }

    /// The world it was trained in, as keyword arguments of `blockstack.StackEnv`:
    /// `blocks`, `grid`, `reward`, `backend`, `profile`, `protocol`, `start`, `horizon`.
    fn world<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let w = self.model.world();
        let d = PyDict::new(py);
        d.set_item("blocks", w.blocks)?;
        d.set_item("grid", (w.grid.width(), w.grid.height()))?;
        d.set_item("reward", w.reward.to_string())?;
        d.set_item("backend", w.backend.to_string())?;
        d.set_item("profile", self.model.profile().to_string())?;
        d.set_item("protocol", w.protocol.to_string())?;
        d.set_item("start", w.start.to_string())?;
        d.set_item("horizon", w.horizon)?;
        d.set_item("view", w.view.to_string())?;
        Ok(d)
    }

    /// A `ValueError` unless `world` (the world keywords) is one the model plays: its grid,
    /// blocks and view, as `blockstack run --model` refuses any other.
    fn check_world(&self, world: World) -> PyResult<()> {
        let config = world.config()?;
        self.model.check_world(config.grid, config.blocks).or_value_error()?;
        self.model.check_view(config.view).or_value_error()
    }

    /// Starts the policy's generator for an episode reset with `seed`, as `blockstack run`
    /// does: from then on the model breaks ties (and draws random actions) as the CLI would
    /// in that episode.
    fn reset(&mut self, seed: u64) {
        self.rng = policy_rng(seed);
    }

    /// The action for a `state` observation (`cells` by block id, `held` a block id or
    /// `None`, `goal` and `goal_tower` as the observation has them): greedy with `epsilon`
    /// 0, else a random legal action with probability `epsilon`.
    #[pyo3(signature = (cells, held, goal, goal_tower, epsilon=0.0))]
    fn act(
        &mut self,
        cells: Vec<(u16, u16)>,
        held: Option<u16>,
        goal: Vec<i64>,
        goal_tower: Vec<i64>,
        epsilon: f64,
    ) -> PyResult<usize> {
        if matches!(self.model, AnyModel::Relational(_)) {
            return Err(value_error(
                "a relational policy chooses block moves, not gripper actions: play it in an environment with \
                 actions=\"moves\" (model.make_env() makes one)",
            ));
        }
        let state: State = state_from(&cells, held)?;
        let world = self.model.world();
        self.model
            .check_world(world.grid, state.block_count())
            .or_value_error()?;
        let goal = observe::read_goal(&goal, &goal_tower, state.block_count())?;
        let obs = Observation {
            grid: world.grid,
            state,
            goal,
            protocol: world.protocol,
            view: world.view,
        };
        let (model, rng) = (&self.model, &mut self.rng);
        guard(|| {
            let mut policy = model.policy(epsilon).or_value_error()?;
            Ok(policy.act(&obs, rng).or_value_error()?.index())
        })
    }

    /// The block move a relational policy makes from a side-view `state` observation on a
    /// grid of `(width, height)`: its index among the actions of an environment with
    /// `actions="moves"` (`sim::BlockMove::index`); greedy with `epsilon` 0, else a random
    /// legal block move with probability `epsilon`. A `ValueError` for a model of another
    /// kind.
    #[pyo3(signature = (cells, held, goal, goal_tower, grid, epsilon=0.0))]
    #[allow(clippy::too_many_arguments)]
    fn act_move(
        &mut self,
        cells: Vec<(u16, u16)>,
        held: Option<u16>,
        goal: Vec<i64>,
        goal_tower: Vec<i64>,
        grid: (usize, usize),
        epsilon: f64,
    ) -> PyResult<usize> {
        let AnyModel::Relational(model) = &self.model else {
            return Err(value_error(
                "this model chooses gripper actions: predict plays it; block moves are a relational policy's",
            ));
        };
        let state: State = state_from(&cells, held)?;
        let grid = Grid::new(grid.0, grid.1).or_value_error()?;
        let goal = observe::read_goal(&goal, &goal_tower, state.block_count())?;
        let obs = Observation {
            grid,
            state,
            goal,
            protocol: sim::ActionProtocol::Free,
            view: View::Side,
        };
        let rng = &mut self.rng;
        guard(|| {
            let mut policy = model.policy(epsilon).or_value_error()?;
            let mv = policy.block_move(&obs, rng).or_value_error()?;
            Ok(mv.index(obs.state.block_count(), grid))
        })
    }

    /// The action for a picture observation of the kind the network reads (`paper-screen`,
    /// or `screen`), as `uint8` bytes, with the episode's `goal` and `goal_tower` (the
    /// environment's `info`) and `action_mask` (its legal actions): greedy among the legal
    /// actions with `epsilon` 0, else a random legal action with probability `epsilon`.
    #[pyo3(signature = (picture, goal, goal_tower, action_mask, epsilon=0.0))]
    fn act_on_picture(
        &mut self,
        picture: numpy::PyReadonlyArrayDyn<'_, u8>,
        goal: Vec<i64>,
        goal_tower: Vec<i64>,
        action_mask: Vec<i64>,
        epsilon: f64,
    ) -> PyResult<usize> {
        let AnyModel::Dqn(dqn) = &self.model else {
            return Err(value_error(
                "a tabular model reads the state observation, not a picture: make the environment with obs='state'",
            ));
        };
        let blocks = dqn.blocks();
        let goal = observe::read_goal(&goal, &goal_tower, blocks)?;
        if action_mask.len() != sim::Action::count(blocks) {
            return Err(value_error(format!(
                "action_mask has {} values; with {blocks} blocks there are {} actions",
                action_mask.len(),
                sim::Action::count(blocks)
            )));
        }
        let allowed = neural::mask::ActionSet::from_indices(
            action_mask.iter().enumerate().filter(|(_, m)| **m != 0).map(|(a, _)| a),
        );
        let picture = picture
            .as_slice()
            .map_err(|_| value_error("the picture must be a contiguous uint8 array"))?;
        let rng = &mut self.rng;
        guard(|| {
            Ok(dqn
                .act_on_picture(picture, &goal, allowed, epsilon, rng)
                .or_value_error()?
                .index())
        })
    }

    /// Evaluates the model in its own world as `blockstack eval --json` does with the same
    /// settings, and returns that JSON text: `episodes` seeded starts from base seed `seed`
    /// on each goal (`goals` `:`-separated, default every goal), with `epsilon` (default the
    /// model's own, as `eval`'s), on the
    /// `backend`, games cut at `horizon`. The GIL is released.
    #[pyo3(signature = (episodes=500, seed=2, goals=None, epsilon=None, backend="physics", horizon=1000))]
    #[allow(clippy::too_many_arguments)]
    fn evaluate(
        &self,
        py: Python<'_>,
        episodes: u64,
        seed: u64,
        goals: Option<&str>,
        epsilon: Option<f64>,
        backend: &str,
        horizon: u32,
    ) -> PyResult<String> {
        let overrides = EvalOverrides {
            goals: goals
                .map(|text| Goal::parse_list(text, self.model.blocks()))
                .transpose()
                .or_value_error()?,
            episodes,
            seed,
            backend: Some(backend.parse().or_value_error()?),
            horizon: Some(horizon),
            ..EvalOverrides::default()
        };
        let plan = self.model.eval_plan_with(&overrides).or_value_error()?;
        py.detach(|| {
            guard(|| {
                let mut signal = None;
                let evaluated = self.model.evaluate(
                    &plan,
                    &self.path,
                    epsilon.unwrap_or(self.model.default_epsilon()),
                    &mut signal_checker(&mut signal),
                );
                let evaluation = evaluated.map_err(|e| raise_signal(signal, e))?;
                serde_json::to_string(&evaluation.report).or_value_error()
            })
        })
    }
}
