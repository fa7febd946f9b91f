//! One environment: `sim::Env` with its observation kind, behind `blockstack.StackEnv`.

use oracle::{ExactSolver, Oracle, Planner};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyTuple};
use sim::{Action, BlockId, BlockMove, Cell, Env, Observation, State, Termination, View};

use crate::boundary::{OrValueError, guard, value_error};
use crate::config::{self, ObsKind, World, goal_from};
use crate::observe;

/// The most block moves `actions="moves"` numbers: its mask is one byte per move at every
/// step (`N * (N + W)`: 2,000 blocks on their default grid, 8 million).
const MAX_MOVE_ACTIONS: usize = 1 << 23;

/// One blockstack environment; the Gymnasium class `blockstack.StackEnv` wraps it.
#[pyclass(module = "blockstack._native")]
pub struct NativeEnv {
    env: Env,
    kind: ObsKind,
    /// `actions="moves"`: an action is a block move (`sim::BlockMove`'s index), carried out
    /// as the gripper steps it takes.
    moves: bool,
}

/// The index of `action`, one integer (a Python int, a numpy integer or a 0-d integer
/// array) in `0..count`; a `ValueError` naming what is wrong otherwise.
pub fn action_index(action: &Bound<'_, PyAny>, blocks: usize) -> PyResult<usize> {
    let bad = || {
        let shape = action
            .getattr("shape")
            .map_or_else(|_| String::new(), |s| format!(" of shape {s}"));
        let dtype = action
            .getattr("dtype")
            .map_or_else(|_| String::new(), |d| format!(" and dtype {d}"));
        let type_name = action
            .get_type()
            .name()
            .map_or_else(|_| "?".to_string(), |n| n.to_string());
        value_error(format!(
            "an action is one integer (an int, a numpy integer or a 0-d integer array), not a {type_name}{shape}{dtype}"
        ))
    };
    if action.is_instance_of::<PyBool>() {
        return Err(bad());
    }
    let index: i64 = action.extract().map_err(|_| bad())?;
    let index = usize::try_from(index).map_err(|_| {
        value_error(format!(
            "action {index} is out of range: with {blocks} blocks the actions are 0..{}",
            Action::count(blocks)
        ))
    })?;
    Action::from_index(index, blocks).or_value_error()?;
    Ok(index)
}

impl NativeEnv {
    fn planner_action(&self, planner: &dyn Planner) -> PyResult<usize> {
        let obs = self.env.observation();
        guard(|| Ok(planner.next_action(&obs.state, &obs.goal).or_value_error()?.index()))
    }

    fn obs_info<'py>(
        &self,
        py: Python<'py>,
        obs: &Observation,
        blocked: bool,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let info = observe::info(py, obs, blocked)?;
        if self.moves {
            // The legal block moves replace the gripper's mask.
            let legal: Vec<i8> = self.env.legal_moves().into_iter().map(i8::from).collect();
            info.set_item("action_mask", numpy::PyArray1::from_vec(py, legal))?;
        }
        Ok((observe::to_python(py, self.kind, obs)?, info.into_any()))
    }

    /// Number of actions: `5 + N` gripper actions, or `N * (N + W)` block moves.
    fn count(&self) -> usize {
        let config = self.env.config();
        if self.moves {
            BlockMove::count(config.blocks, config.grid)
        } else {
            Action::count(config.blocks)
        }
    }
}

#[pymethods]
impl NativeEnv {
    /// An environment of `world` (the world keywords, [`World`]) showing `obs`, acting with
    /// `actions`; a `ValueError` with the crate's message for a config that cannot make one.
    #[new]
    #[pyo3(signature = (world, obs="planes", actions="gripper"))]
    fn new(world: World, obs: &str, actions: &str) -> PyResult<Self> {
        let kind = config::obs_kind(obs)?;
        let config = world.config()?;
        let moves = match actions {
            "gripper" => false,
            "moves" if config.view == View::Side => true,
            "moves" => return Err(value_error("actions=\"moves\" (block moves) needs view=\"side\"")),
            _ => {
                return Err(value_error(format!(
                    "cannot read actions from {actions:?}: choose gripper or moves"
                )));
            }
        };
        kind.check(config.grid, config.blocks).or_value_error()?;
        let move_count = BlockMove::count(config.blocks, config.grid);
        if moves && move_count > MAX_MOVE_ACTIONS {
            return Err(value_error(format!(
                "actions=\"moves\" numbers every block move, {move_count} with {} blocks on a {} grid, more than the {MAX_MOVE_ACTIONS} an action space and its mask hold: use fewer blocks or a narrower grid",
                config.blocks, config.grid
            )));
        }
        Ok(NativeEnv {
            env: guard(|| Env::new(config).or_value_error())?,
            kind,
            moves,
        })
    }

    /// Number of actions: `5 + N` gripper actions, or `N * (N + W)` block moves.
    #[getter]
    fn action_count(&self) -> usize {
        self.count()
    }

    /// Starts an episode, as `sim::Env::reset(seed)` does (`None` continues the generator);
    /// `(observation, info)`.
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(&mut self, py: Python<'py>, seed: Option<u64>) -> PyResult<Bound<'py, PyTuple>> {
        let obs = guard(|| Ok(self.env.reset(seed)))?;
        let (o, i) = self.obs_info(py, &obs, false)?;
        PyTuple::new(py, [o, i])
    }

    /// Starts an episode from a given state: `cells` lists `(x, y)` by block id, `held` is
    /// a block id or `None`, `goal` text or a sequence (the current goal if `None`).
    #[pyo3(signature = (cells, held=None, goal=None))]
    fn reset_to<'py>(
        &mut self,
        py: Python<'py>,
        cells: Vec<(u16, u16)>,
        held: Option<u16>,
        goal: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyTuple>> {
        let blocks = self.env.config().blocks;
        let goal = match goal {
            Some(g) => goal_from(g, Some(blocks))?,
            None => self.env.goal().clone(),
        };
        let state = state_from(&cells, held)?;
        // Refused before the reset: a refused start leaves the episode as it was.
        if matches!(self.env.config().termination, Termination::Goal) && goal.holds_in(self.env.config().view, &state) {
            return Err(value_error(format!(
                "goal {goal} already holds in that state: an episode needs a start where it does not"
            )));
        }
        let obs = guard(|| self.env.reset_to(state, goal).or_value_error())?;
        let (o, i) = self.obs_info(py, &obs, false)?;
        PyTuple::new(py, [o, i])
    }

    /// Takes one action; `(observation, reward, terminated, truncated, info)`.
    fn step<'py>(&mut self, py: Python<'py>, action: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyTuple>> {
        let config = self.env.config().clone();
        let (step, gripper_steps) = if self.moves {
            let index: i64 = action
                .extract()
                .map_err(|_| value_error("a block move is one whole number"))?;
            let mv = usize::try_from(index)
                .map_err(|_| {
                    value_error(format!(
                        "block move {index} is out of range: the moves are 0..{}",
                        self.count()
                    ))
                })
                .and_then(|i| BlockMove::from_index(i, config.blocks, config.grid).or_value_error())?;
            let m = guard(|| self.env.step_block_move(mv).or_value_error())?;
            (m.step, m.gripper_steps)
        } else {
            let index = action_index(action, config.blocks)?;
            (guard(|| self.env.step_index(index).or_value_error())?, 1)
        };
        let (o, i) = self.obs_info(py, &step.observation, step.info.blocked)?;
        if self.moves {
            i.cast::<pyo3::types::PyDict>()?
                .set_item("gripper_steps", gripper_steps)?;
        }
        PyTuple::new(
            py,
            [
                o,
                step.reward.into_pyobject(py)?.into_any(),
                PyBool::new(py, step.terminated).to_owned().into_any(),
                PyBool::new(py, step.truncated).to_owned().into_any(),
                i,
            ],
        )
    }

    /// The current observation, as `reset` and `step` return it.
    fn observation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        observe::to_python(py, self.kind, &self.env.observation())
    }

    /// The rendered frame, `uint8`, height x width x 3.
    fn render_rgb<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        observe::to_python(py, ObsKind::Frame, &self.env.observation())
    }

    /// The world as text, top row first (`sim::render::ascii`, no colour).
    fn render_ansi(&self) -> String {
        sim::render::ascii(&self.env.observation(), sim::render::Colour::Never)
    }

    /// The exact solver's next action from the current state: the first of a shortest plan.
    fn expert_action(&self) -> PyResult<usize> {
        self.planner_action(&ExactSolver::new(self.env.config().grid).with_view(self.env.config().view))
    }

    /// The oracle's next action from the current state.
    fn oracle_action(&self) -> PyResult<usize> {
        self.planner_action(&Oracle::new(self.env.config().grid))
    }

    /// The length of a shortest plan from the current state to the goal.
    fn optimal_steps(&self) -> PyResult<u32> {
        let obs = self.env.observation();
        guard(|| {
            ExactSolver::new(self.env.config().grid)
                .with_view(self.env.config().view)
                .distance(&obs.state, &obs.goal)
                .or_value_error()
        })
    }

    /// `(cells, held, goal)`: every block's `(x, y)`, the held block or `None`, the goal.
    fn state(&self) -> (Vec<(u32, u32)>, Option<u32>, Vec<u32>) {
        let obs = self.env.observation();
        (
            obs.blocks().iter().map(|c| (u32::from(c.x), u32::from(c.y))).collect(),
            obs.held_block().map(|b| u32::from(b.0)),
            obs.goal.order().iter().map(|b| u32::from(b.0)).collect(),
        )
    }

    /// Number of blocks.
    #[getter]
    fn blocks(&self) -> usize {
        self.env.config().blocks
    }

    /// `(width, height)`.
    #[getter]
    fn grid(&self) -> (usize, usize) {
        let g = self.env.config().grid;
        (g.width(), g.height())
    }

    /// Steps before an episode is truncated.
    #[getter]
    fn horizon(&self) -> u32 {
        self.env.config().horizon
    }

    /// Steps taken in the current episode.
    #[getter]
    fn steps(&self) -> u32 {
        self.env.steps()
    }
}

/// A state from Python's cells and held block, checked by `sim`.
pub fn state_from(cells: &[(u16, u16)], held: Option<u16>) -> PyResult<State> {
    let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
    State::new(&cells, held.map(BlockId)).or_value_error()
}
