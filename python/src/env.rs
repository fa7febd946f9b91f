//! One environment: `sim::Env` with its observation kind, behind `blockstack.StackEnv`.

use agent::{Policy, PolicyKind, PolicyOptions};
use oracle::towers::{MovePlanner, next_block_move, plan_side};
use oracle::{ExactSolver, PlannerKind};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyTuple};
use sim::{Action, BlockId, BlockMove, Cell, Effect, Env, Observation, Refusal, State, Termination, View};

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
    /// The exact solver and the world's oracle as agents (`[exact, oracle]`), made when
    /// first asked: each follows its plan and replans only when the world left it, so an
    /// episode played by `expert_action` plans once. (A mutex only because a Python class
    /// must be `Sync`; calls on one environment take turns anyway.)
    experts: [std::sync::Mutex<Option<Box<dyn Policy + Send>>>; 2],
    /// How the experts play this world: its profile's oracle ([`PolicyOptions::of_profile`]).
    options: PolicyOptions,
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
    /// The next action of `kind`'s plan from here under the world's rules (its grid, view
    /// and action protocol): a block move's index with `actions="moves"` (the exact solver's
    /// fewest moves, or the near-optimal planner for the oracle), else a gripper action's.
    fn expert_index(&self, kind: PlannerKind) -> PyResult<usize> {
        let config = self.env.config();
        let obs = self.env.current_observation();
        if self.moves {
            return guard(|| {
                let mv = next_block_move(kind.move_planner(), config.grid, &obs.state, &obs.goal).or_value_error()?;
                Ok(mv.index(config.blocks, config.grid))
            });
        }
        let mut slot = self.experts[usize::from(kind != PlannerKind::Exact)]
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let slot = &mut *slot;
        guard(|| {
            let policy = match slot {
                Some(policy) => policy,
                None => slot.insert(PolicyKind::from(kind).expert(config, &self.options).or_value_error()?),
            };
            // The planners draw nothing: the generator is only the trait's argument.
            let action = policy.act(obs, &mut sim::seeding::rng(0)).or_value_error()?;
            Ok(action.index())
        })
    }

    fn obs_info<'py>(
        &self,
        py: Python<'py>,
        obs: &Observation,
        blocked: bool,
        illegal: bool,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let info = observe::info(py, obs, blocked)?;
        info.set_item("illegal", illegal)?;
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
    /// An action the world's rules refuse is a step that changes nothing
    /// (`sim::Refusal::Step`, `info["illegal"]`), or with `strict` a `ValueError` that
    /// changes nothing.
    #[new]
    #[pyo3(signature = (world, obs="planes", actions="gripper", strict=false))]
    fn new(world: World, obs: &str, actions: &str, strict: bool) -> PyResult<Self> {
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
        let refusal = if strict { Refusal::Error } else { Refusal::Step };
        let options = PolicyOptions::of_profile(config::profile(&world.profile)?);
        Ok(NativeEnv {
            env: guard(|| Ok(Env::new(config).or_value_error()?.with_refusal(refusal)))?,
            kind,
            moves,
            experts: Default::default(),
            options,
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
        let (o, i) = self.obs_info(py, &obs, false, false)?;
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
        let (o, i) = self.obs_info(py, &obs, false, false)?;
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
        let illegal = step.info.effect == Effect::Refused;
        let (o, i) = self.obs_info(py, &step.observation, step.info.blocked, illegal)?;
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

    /// The exact solver's next action from the current state, under the world's rules: the
    /// first of a shortest legal plan (with `actions="moves"`, of the fewest block moves).
    fn expert_action(&self) -> PyResult<usize> {
        self.expert_index(PlannerKind::Exact)
    }

    /// The world's oracle's next action from the current state, under its rules (from the
    /// side, the near-optimal block-move planner's).
    fn oracle_action(&self) -> PyResult<usize> {
        self.expert_index(PlannerKind::Oracle)
    }

    /// The length of a shortest legal plan from the current state to the goal, in this
    /// environment's actions (gripper steps, or block moves with `actions="moves"`).
    fn optimal_steps(&self) -> PyResult<u32> {
        let config = self.env.config();
        let obs = self.env.current_observation();
        guard(|| {
            if self.moves {
                let plan = plan_side(MovePlanner::Exact, config.grid, &obs.state, &obs.goal).or_value_error()?;
                return Ok(plan.len() as u32);
            }
            ExactSolver::for_world(config)
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
