//! A batch of environments stepped in one call: `sim::VecEnv` with the GIL released,
//! writing every result into numpy arrays allocated once, behind
//! `blockstack.vector.StackVectorEnv`.

use numpy::{
    PyArray1, PyArray2, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods, PyReadwriteArray1, PyReadwriteArray2,
    PyReadwriteArrayDyn, PyUntypedArray, PyUntypedArrayMethods,
};
use std::ops::Range;

use pyo3::prelude::*;
use pyo3::types::{IntoPyDict, PyDict, PyList};
use sim::{Action, Autoreset, Effect, Observation, VecEnv, VecStepRef};

use crate::boundary::{OrValueError, guard, value_error};
use crate::config::{self, ObsKind, World};
use crate::observe;

/// The observation buffer(s) of a batch: one array for `planes` and `pixels`, three for
/// `state`.
enum ObsBuffers {
    /// `(num_envs, *shape)` bytes.
    Bytes(Py<PyArrayDyn<u8>>),
    /// Block cells `(num_envs, N, 2)`, held block `(num_envs,)`, goal and its towers
    /// `(num_envs, N)` each.
    State {
        blocks: Py<PyArrayDyn<i64>>,
        held: Py<PyArray1<i64>>,
        goal: Py<PyArray2<i64>>,
        goal_tower: Py<PyArray2<i64>>,
    },
}

/// One environment's part of the buffers, written on the thread that stepped it.
struct Slot<'a> {
    obs: ObsSlot<'a>,
    reward: &'a mut f64,
    terminated: &'a mut bool,
    truncated: &'a mut bool,
    mask: &'a mut [i8],
    blocked: &'a mut bool,
    illegal: &'a mut bool,
    pairs: &'a mut i64,
    goal: &'a mut [i64],
    goal_tower: &'a mut [i64],
}

enum ObsSlot<'a> {
    Bytes(&'a mut [u8]),
    State {
        blocks: &'a mut [i64],
        held: &'a mut i64,
        goal: &'a mut [i64],
        goal_tower: &'a mut [i64],
    },
}

impl Slot<'_> {
    /// Writes `result`'s observation, its legal actions (the step's mask: not recomputed
    /// from the observation, a cost a batch of thousands notices) and its pairs in place.
    fn write_obs(&mut self, kind: ObsKind, result: &VecStepRef<'_>) {
        let obs = result.observation;
        match &mut self.obs {
            ObsSlot::Bytes(out) => kind
                .write(obs, out)
                .expect("the buffers are shaped by the kind's shape"),
            ObsSlot::State {
                blocks,
                held,
                goal,
                goal_tower,
            } => {
                observe::write_state(
                    obs,
                    blocks,
                    observe::GoalOut {
                        goal,
                        tower: goal_tower,
                    },
                );
                **held = observe::held_index(obs);
            }
        }
        observe::write_mask(&result.action_mask, self.mask);
        observe::write_goal(
            obs,
            observe::GoalOut {
                goal: self.goal,
                tower: self.goal_tower,
            },
        );
        *self.pairs = result.pairs_in_place() as i64;
    }

    /// Writes `result`; returns, under same-step autoreset, the last observation of an
    /// episode that ended in this step and that step's flags (`blocked`, `illegal`).
    fn write(&mut self, kind: ObsKind, result: &VecStepRef<'_>) -> Option<(Observation, Flags)> {
        self.write_obs(kind, result);
        let Some(outcome) = result.outcome else {
            (*self.reward, *self.terminated, *self.truncated) = (0.0, false, false);
            (*self.blocked, *self.illegal) = (false, false);
            return None;
        };
        *self.reward = outcome.reward;
        *self.terminated = outcome.terminated;
        *self.truncated = outcome.truncated;
        let flags = Flags {
            blocked: outcome.blocked(),
            illegal: outcome.effect == Effect::Refused,
        };
        // The step's info is the reset's; the ended step's goes with its last observation,
        // as Gymnasium's same-step mode reports them.
        let own = result.final_observation.is_none();
        *self.blocked = flags.blocked && own;
        *self.illegal = flags.illegal && own;
        let last = result.final_observation?;
        Some((last.clone(), flags))
    }
}

/// A step's flags in its info.
#[derive(Clone, Copy)]
struct Flags {
    /// A held block's move was stopped.
    blocked: bool,
    /// The world's rules refused the action: the step changed nothing.
    illegal: bool,
}

/// The part of every buffer that belongs to one of `VecEnv::chunks`' ranges, written by the
/// thread that steps that range: cut once per range per call, and cut again per
/// environment on that thread.
struct Chunk<'a> {
    /// The index of the chunk's first environment.
    start: usize,
    obs: ChunkObs<'a>,
    rewards: &'a mut [f64],
    terminations: &'a mut [bool],
    truncations: &'a mut [bool],
    mask: &'a mut [i8],
    blocked: &'a mut [bool],
    illegal: &'a mut [bool],
    pairs: &'a mut [i64],
    goal: &'a mut [i64],
    goal_tower: &'a mut [i64],
    /// Sizes per environment: observation bytes, actions, blocks.
    obs_len: usize,
    actions: usize,
    blocks: usize,
    /// `(index, last observation, flags)` of each episode that ended in this step under
    /// same-step autoreset, in index order.
    ended: Vec<(usize, Observation, Flags)>,
}

enum ChunkObs<'a> {
    Bytes(&'a mut [u8]),
    State {
        blocks: &'a mut [i64],
        held: &'a mut [i64],
        goal: &'a mut [i64],
        goal_tower: &'a mut [i64],
    },
}

impl Chunk<'_> {
    /// Writes `result` of the chunk's environment `i`.
    fn write(&mut self, kind: ObsKind, i: usize, result: &VecStepRef<'_>) {
        let (o, a, b) = (self.obs_len, self.actions, self.blocks);
        let obs = match &mut self.obs {
            ChunkObs::Bytes(bytes) => ObsSlot::Bytes(&mut bytes[i * o..(i + 1) * o]),
            ChunkObs::State {
                blocks,
                held,
                goal,
                goal_tower,
            } => ObsSlot::State {
                blocks: &mut blocks[2 * b * i..2 * b * (i + 1)],
                held: &mut held[i],
                goal: &mut goal[b * i..b * (i + 1)],
                goal_tower: &mut goal_tower[b * i..b * (i + 1)],
            },
        };
        let mut slot = Slot {
            obs,
            reward: &mut self.rewards[i],
            terminated: &mut self.terminations[i],
            truncated: &mut self.truncations[i],
            mask: &mut self.mask[a * i..a * (i + 1)],
            blocked: &mut self.blocked[i],
            illegal: &mut self.illegal[i],
            pairs: &mut self.pairs[i],
            goal: &mut self.goal[b * i..b * (i + 1)],
            goal_tower: &mut self.goal_tower[b * i..b * (i + 1)],
        };
        if let Some((last, flags)) = slot.write(kind, result) {
            self.ended.push((self.start + i, last, flags));
        }
    }
}

/// A batch of blockstack environments of one world; `blockstack.vector.StackVectorEnv`
/// wraps it.
#[pyclass(module = "blockstack._native")]
pub struct NativeVecEnv {
    vec: VecEnv,
    kind: ObsKind,
    blocks: usize,
    obs: ObsBuffers,
    rewards: Py<PyArray1<f64>>,
    terminations: Py<PyArray1<bool>>,
    truncations: Py<PyArray1<bool>>,
    action_mask: Py<PyArray2<i8>>,
    blocked: Py<PyArray1<bool>>,
    illegal: Py<PyArray1<bool>>,
    pairs_in_place: Py<PyArray1<i64>>,
    goal: Py<PyArray2<i64>>,
    goal_tower: Py<PyArray2<i64>>,
}

/// Borrows of every buffer, alive while a batch call writes into them.
struct Borrows<'py> {
    obs: ObsBorrow<'py>,
    rewards: PyReadwriteArray1<'py, f64>,
    terminations: PyReadwriteArray1<'py, bool>,
    truncations: PyReadwriteArray1<'py, bool>,
    action_mask: PyReadwriteArray2<'py, i8>,
    blocked: PyReadwriteArray1<'py, bool>,
    illegal: PyReadwriteArray1<'py, bool>,
    pairs_in_place: PyReadwriteArray1<'py, i64>,
    goal: PyReadwriteArray2<'py, i64>,
    goal_tower: PyReadwriteArray2<'py, i64>,
}

enum ObsBorrow<'py> {
    Bytes(PyReadwriteArrayDyn<'py, u8>),
    State {
        blocks: PyReadwriteArrayDyn<'py, i64>,
        held: PyReadwriteArray1<'py, i64>,
        goal: PyReadwriteArray2<'py, i64>,
        goal_tower: PyReadwriteArray2<'py, i64>,
    },
}

fn slice<'a, T: numpy::Element, D: numpy::ndarray::Dimension>(
    a: &'a mut numpy::PyReadwriteArray<'_, T, D>,
) -> &'a mut [T] {
    a.as_slice_mut().expect("the buffers are allocated contiguous")
}

/// The first `n` items of `rest`, which keeps the others.
fn take<'a, T>(rest: &mut &'a mut [T], n: usize) -> &'a mut [T] {
    let (head, tail) = std::mem::take(rest).split_at_mut(n);
    *rest = tail;
    head
}

impl<'py> Borrows<'py> {
    /// One chunk per range of environments (`VecEnv::chunks`, consecutive from 0) over these
    /// buffers.
    fn chunks<'a>(&'a mut self, ranges: &[Range<usize>], envs: usize, blocks: usize) -> Vec<Chunk<'a>> {
        let actions = Action::count(blocks);
        enum Rest<'a> {
            Bytes(&'a mut [u8], usize),
            State([&'a mut [i64]; 4]),
        }
        let mut obs = match &mut self.obs {
            ObsBorrow::Bytes(a) => {
                let s = slice(a);
                let len = s.len() / envs.max(1);
                Rest::Bytes(s, len)
            }
            ObsBorrow::State {
                blocks,
                held,
                goal,
                goal_tower,
            } => Rest::State([slice(blocks), slice(held), slice(goal), slice(goal_tower)]),
        };
        let mut rewards = slice(&mut self.rewards);
        let mut terminations = slice(&mut self.terminations);
        let mut truncations = slice(&mut self.truncations);
        let mut mask = slice(&mut self.action_mask);
        let mut blocked = slice(&mut self.blocked);
        let mut illegal = slice(&mut self.illegal);
        let mut pairs = slice(&mut self.pairs_in_place);
        let mut goal = slice(&mut self.goal);
        let mut goal_tower = slice(&mut self.goal_tower);
        ranges
            .iter()
            .map(|r| {
                let n = r.len();
                let (obs, obs_len) = match &mut obs {
                    Rest::Bytes(bytes, len) => (ChunkObs::Bytes(take(bytes, n * *len)), *len),
                    Rest::State([b, h, g, t]) => (
                        ChunkObs::State {
                            blocks: take(b, n * 2 * blocks),
                            held: take(h, n),
                            goal: take(g, n * blocks),
                            goal_tower: take(t, n * blocks),
                        },
                        0,
                    ),
                };
                Chunk {
                    start: r.start,
                    obs,
                    rewards: take(&mut rewards, n),
                    terminations: take(&mut terminations, n),
                    truncations: take(&mut truncations, n),
                    mask: take(&mut mask, n * actions),
                    blocked: take(&mut blocked, n),
                    illegal: take(&mut illegal, n),
                    pairs: take(&mut pairs, n),
                    goal: take(&mut goal, n * blocks),
                    goal_tower: take(&mut goal_tower, n * blocks),
                    obs_len,
                    actions,
                    blocks,
                    ended: Vec::new(),
                }
            })
            .collect()
    }
}

impl NativeVecEnv {
    fn borrow<'py>(&self, py: Python<'py>) -> Borrows<'py> {
        Borrows {
            obs: match &self.obs {
                ObsBuffers::Bytes(a) => ObsBorrow::Bytes(a.bind(py).readwrite()),
                ObsBuffers::State {
                    blocks,
                    held,
                    goal,
                    goal_tower,
                } => ObsBorrow::State {
                    blocks: blocks.bind(py).readwrite(),
                    held: held.bind(py).readwrite(),
                    goal: goal.bind(py).readwrite(),
                    goal_tower: goal_tower.bind(py).readwrite(),
                },
            },
            rewards: self.rewards.bind(py).readwrite(),
            terminations: self.terminations.bind(py).readwrite(),
            truncations: self.truncations.bind(py).readwrite(),
            action_mask: self.action_mask.bind(py).readwrite(),
            blocked: self.blocked.bind(py).readwrite(),
            illegal: self.illegal.bind(py).readwrite(),
            pairs_in_place: self.pairs_in_place.bind(py).readwrite(),
            goal: self.goal.bind(py).readwrite(),
            goal_tower: self.goal_tower.bind(py).readwrite(),
        }
    }

    /// The actions from a 1-D integer array with one action per environment, as `int64`
    /// values, copied while the GIL is held (another Python thread may write the array once
    /// it is released). Their range is checked where they are converted, on the threads
    /// that step them ([`to_action`]).
    fn actions(&self, actions: &Bound<'_, PyAny>) -> PyResult<Vec<i64>> {
        let n = self.vec.len();
        let array = actions.cast::<PyUntypedArray>().map_err(|_| {
            value_error(format!(
                "actions must be a numpy array of {n} integers, one per environment, not a {}",
                actions.get_type().name().map_or_else(|_| "?".into(), |t| t.to_string())
            ))
        })?;
        let kind = array.dtype().kind();
        if array.ndim() != 1 || array.shape()[0] != n || !(kind == b'i' || kind == b'u') {
            return Err(value_error(format!(
                "actions must be an integer array of shape ({n},), one per environment; got dtype {} and shape {:?}",
                array.dtype(),
                array.shape()
            )));
        }
        // An int64 array, the usual case, is read as it is; any other integer type goes
        // through numpy's conversion first (a Python call, which costs as much as stepping
        // dozens of environments).
        let values = match actions.cast::<PyArray1<i64>>() {
            Ok(int64) => int64.readonly(),
            Err(_) => {
                let no_copy = [("copy", false)].into_py_dict(actions.py())?;
                let as_i64 = array.call_method("astype", ("int64",), Some(&no_copy))?;
                as_i64.cast_into::<PyArray1<i64>>()?.readonly()
            }
        };
        Ok(match values.as_slice() {
            Ok(contiguous) => contiguous.to_vec(),
            Err(_) => values.as_array().to_vec(),
        })
    }
}

/// Why a batch call failed, raised as a `ValueError` with its message: a refused action
/// value, or the world's error.
struct Refusal(String);

impl From<sim::SimError> for Refusal {
    fn from(e: sim::SimError) -> Refusal {
        Refusal(e.to_string())
    }
}

/// The action of index `index` in a world of `blocks` blocks.
fn to_action(index: i64, blocks: usize) -> Result<Action, Refusal> {
    match usize::try_from(index) {
        Ok(i) => Ok(Action::from_index(i, blocks)?),
        Err(_) => Err(Refusal(format!(
            "action {index} is out of range: with {blocks} blocks the actions are 0..{}",
            Action::count(blocks)
        ))),
    }
}

#[pymethods]
impl NativeVecEnv {
    /// `num_envs` environments of one world, stepped on `threads` threads (1: on the
    /// caller's thread; 0: one per core), with autoreset `next-step` or `same-step`. An
    /// action the world's rules refuse is a step that changes nothing (`info["illegal"]`),
    /// or with `strict` a `ValueError` that steps nothing, as one environment's is.
    #[new]
    #[pyo3(signature = (num_envs, world, obs="planes", threads=1, autoreset="next-step", strict=false))]
    fn new(
        py: Python<'_>,
        num_envs: usize,
        world: World,
        obs: &str,
        threads: usize,
        autoreset: &str,
        strict: bool,
    ) -> PyResult<Self> {
        let kind = config::obs_kind(obs)?;
        let mode = match autoreset {
            "next-step" => Autoreset::NextStep,
            "same-step" => Autoreset::SameStep,
            _ => {
                return Err(value_error(format!(
                    "cannot read autoreset mode from {autoreset:?}: choose next-step or same-step"
                )));
            }
        };
        if num_envs == 0 {
            return Err(value_error("a vector environment needs at least one environment"));
        }
        let config = world.config()?;
        let blocks = config.blocks;
        kind.check(config.grid, config.blocks).or_value_error()?;
        let refusal = if strict {
            sim::Refusal::Error
        } else {
            sim::Refusal::Step
        };
        let vec = guard(|| VecEnv::new(config.clone(), num_envs, threads).or_value_error())?
            .with_autoreset(mode)
            .with_refusal(refusal);
        let n = blocks;
        let obs = match kind.shape(config.grid, n) {
            Some(shape) => {
                let shape = [&[num_envs][..], &shape[..]].concat();
                ObsBuffers::Bytes(PyArrayDyn::<u8>::zeros(py, shape, false).unbind())
            }
            None => ObsBuffers::State {
                blocks: PyArrayDyn::<i64>::zeros(py, vec![num_envs, n, 2], false).unbind(),
                held: PyArray1::<i64>::zeros(py, num_envs, false).unbind(),
                goal: PyArray2::<i64>::zeros(py, [num_envs, n], false).unbind(),
                goal_tower: PyArray2::<i64>::zeros(py, [num_envs, n], false).unbind(),
            },
        };
        Ok(NativeVecEnv {
            vec,
            kind,
            blocks,
            obs,
            rewards: PyArray1::zeros(py, num_envs, false).unbind(),
            terminations: PyArray1::zeros(py, num_envs, false).unbind(),
            truncations: PyArray1::zeros(py, num_envs, false).unbind(),
            action_mask: PyArray2::zeros(py, [num_envs, Action::count(blocks)], false).unbind(),
            blocked: PyArray1::zeros(py, num_envs, false).unbind(),
            illegal: PyArray1::zeros(py, num_envs, false).unbind(),
            pairs_in_place: PyArray1::zeros(py, num_envs, false).unbind(),
            goal: PyArray2::zeros(py, [num_envs, blocks], false).unbind(),
            goal_tower: PyArray2::zeros(py, [num_envs, blocks], false).unbind(),
        })
    }

    /// The buffers every call writes into, by name: `obs` (an array, or a dict of arrays
    /// for `state`), `rewards`, `terminations`, `truncations`, `action_mask`, `blocked`,
    /// `illegal`, `pairs_in_place`, `goal`, `goal_tower`.
    fn buffers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        match &self.obs {
            ObsBuffers::Bytes(a) => d.set_item("obs", a.bind(py))?,
            ObsBuffers::State {
                blocks,
                held,
                goal,
                goal_tower,
            } => {
                let o = PyDict::new(py);
                o.set_item("blocks", blocks.bind(py))?;
                o.set_item("held", held.bind(py))?;
                o.set_item("goal", goal.bind(py))?;
                o.set_item("goal_tower", goal_tower.bind(py))?;
                d.set_item("obs", o)?;
            }
        }
        d.set_item("rewards", self.rewards.bind(py))?;
        d.set_item("terminations", self.terminations.bind(py))?;
        d.set_item("truncations", self.truncations.bind(py))?;
        d.set_item("action_mask", self.action_mask.bind(py))?;
        d.set_item("blocked", self.blocked.bind(py))?;
        d.set_item("illegal", self.illegal.bind(py))?;
        d.set_item("pairs_in_place", self.pairs_in_place.bind(py))?;
        d.set_item("goal", self.goal.bind(py))?;
        d.set_item("goal_tower", self.goal_tower.bind(py))?;
        Ok(d)
    }

    /// Resets environment `i` with `seeds[i]` (`None`: continue its generator), writing
    /// first observations and infos into the buffers.
    fn reset(&mut self, py: Python<'_>, seeds: Vec<Option<u64>>) -> PyResult<()> {
        if seeds.len() != self.vec.len() {
            return Err(value_error(format!(
                "{} seeds given for {} environments: give one seed per environment, an int, or None",
                seeds.len(),
                self.vec.len()
            )));
        }
        let mut borrows = self.borrow(py);
        let ranges = self.vec.chunks();
        let mut chunks = borrows.chunks(&ranges, self.vec.len(), self.blocks);
        let (vec, kind) = (&mut self.vec, self.kind);
        py.detach(|| {
            guard(|| {
                vec.reset_chunks(&seeds, &mut chunks, |chunk, i, result| chunk.write(kind, i, result));
                Ok(())
            })
        })
    }

    /// Steps every environment with its action (a 1-D integer array), the GIL released,
    /// writing the results into the buffers. Returns, under same-step autoreset, a list of
    /// `(index, last observation, last info)` for the episodes that ended (empty
    /// otherwise).
    fn step<'py>(&mut self, py: Python<'py>, actions: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyList>> {
        let actions = self.actions(actions)?;
        let mut borrows = self.borrow(py);
        let ranges = self.vec.chunks();
        let mut chunks = borrows.chunks(&ranges, self.vec.len(), self.blocks);
        let (vec, kind) = (&mut self.vec, self.kind);
        let blocks = self.blocks;
        py.detach(|| {
            guard(|| {
                vec.step_chunks_of(
                    &actions,
                    |&i| to_action(i, blocks),
                    &mut chunks,
                    |chunk, i, result| chunk.write(kind, i, result),
                )
                .map_err(|Refusal(message)| value_error(message))
            })
        })?;
        let ended = PyList::empty(py);
        for (i, obs, flags) in chunks.iter().flat_map(|c| &c.ended) {
            let info = observe::info(py, obs, flags.blocked)?;
            info.set_item("illegal", flags.illegal)?;
            ended.append((i, observe::to_python(py, self.kind, obs)?, info))?;
        }
        Ok(ended)
    }

    /// Number of environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.vec.len()
    }

    /// The rendered frame of environment `index`, `uint8`, height x width x 3.
    fn render_rgb<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyAny>> {
        let env = self.vec.envs().get(index).ok_or_else(|| {
            value_error(format!(
                "environment {index} does not exist: there are {}",
                self.vec.len()
            ))
        })?;
        observe::to_python(py, ObsKind::Frame, &env.observation())
    }
}
