//! Observations as numpy arrays: fresh objects for one environment, and writes into a
//! batch's preallocated buffers for many.

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{Action, ActionMask, Goal, Observation};

use crate::boundary::{OrValueError, value_error};
use crate::config::ObsKind;

/// The held block as an integer: its id, or -1 when nothing is held.
pub fn held_index(obs: &Observation) -> i64 {
    obs.held_block().map_or(-1, |b| i64::from(b.0))
}

/// Writes the legal actions of `obs` (under its environment's action protocol) into
/// `out`, 1 legal and 0 not, one per action index.
pub fn write_action_mask(obs: &Observation, out: &mut [i8]) {
    write_mask(&obs.legal_actions(), out);
}

/// Writes `mask` into `out`, 1 legal and 0 not, one per action index.
pub fn write_mask(mask: &ActionMask, out: &mut [i8]) {
    for (i, byte) in out.iter_mut().enumerate() {
        *byte = i8::from(mask.contains_index(i));
    }
}

/// The observation of kind `kind` as a fresh Python object: a `uint8` array for the array
/// kinds (`sim::ObsKind::shape`), a dict of arrays for `state`.
pub fn to_python<'py>(py: Python<'py>, kind: ObsKind, obs: &Observation) -> PyResult<Bound<'py, PyAny>> {
    let Some(shape) = kind.shape(obs.grid, obs.state.block_count()) else {
        let n = obs.state.block_count();
        let blocks = PyArray2::<i64>::zeros(py, [n, 2], false);
        let goal = PyArray1::<i64>::zeros(py, n, false);
        let goal_tower = PyArray1::<i64>::zeros(py, n, false);
        {
            let (mut b, mut g, mut t) = (blocks.readwrite(), goal.readwrite(), goal_tower.readwrite());
            write_state(
                obs,
                b.as_slice_mut().expect("contiguous"),
                GoalOut {
                    goal: g.as_slice_mut().expect("contiguous"),
                    tower: t.as_slice_mut().expect("contiguous"),
                },
            );
        }
        let dict = PyDict::new(py);
        dict.set_item("blocks", blocks)?;
        dict.set_item("held", held_index(obs))?;
        dict.set_item("goal", goal)?;
        dict.set_item("goal_tower", goal_tower)?;
        return Ok(dict.into_any());
    };
    let array = PyArray3::<u8>::zeros(py, shape, false);
    kind.write(
        obs,
        array.readwrite().as_slice_mut().expect("a fresh array is contiguous"),
    )
    .or_value_error()?;
    Ok(array.into_any())
}

/// Where a goal is written: `goal` (`N`) and `tower` (`N`).
pub struct GoalOut<'a> {
    /// The named blocks, tower by tower, each bottom to top; -1 past them.
    pub goal: &'a mut [i64],
    /// The tower (0 the first the goal lists) of each entry of `goal`; -1 past them.
    pub tower: &'a mut [i64],
}

/// Writes every block's `[x, y]` into `blocks` (`N x 2`) and the goal into `goal`.
pub fn write_state(obs: &Observation, blocks: &mut [i64], goal: GoalOut<'_>) {
    for (i, c) in obs.blocks().iter().enumerate() {
        blocks[2 * i] = i64::from(c.x);
        blocks[2 * i + 1] = i64::from(c.y);
    }
    write_goal(obs, goal);
}

/// Writes the goal's blocks and their towers (a goal of one tower: every tower 0). A goal
/// of towers may leave blocks free: their entries are -1, as a block id never is.
pub fn write_goal(obs: &Observation, out: GoalOut<'_>) {
    out.goal.fill(-1);
    out.tower.fill(-1);
    let named = obs
        .goal
        .towers()
        .enumerate()
        .flat_map(|(t, tower)| tower.iter().map(move |b| (i64::from(b.0), t as i64)));
    for ((g, t), (block, tower)) in out.goal.iter_mut().zip(out.tower.iter_mut()).zip(named) {
        (*g, *t) = (block, tower);
    }
}

/// The goal that `goal` and `tower` describe, as [`write_goal`] writes them, in a world of
/// `blocks` blocks; a `ValueError` naming what is wrong.
pub fn read_goal(goal: &[i64], tower: &[i64], blocks: usize) -> PyResult<Goal> {
    if goal.len() != tower.len() {
        return Err(value_error(format!(
            "goal has {} entries and goal_tower {}: give one tower per goal entry",
            goal.len(),
            tower.len()
        )));
    }
    let mut towers: Vec<Vec<usize>> = Vec::new();
    let mut current = None;
    for (&block, &t) in goal.iter().zip(tower) {
        if block < 0 {
            continue;
        }
        if current != Some(t) {
            towers.push(Vec::new());
            current = Some(t);
        }
        towers.last_mut().expect("pushed above").push(block as usize);
    }
    Goal::of_towers(&towers, blocks).or_value_error()
}

/// The `info` of a reset or a step, as a dict: `action_mask` (int8, 1 for each legal
/// action), `blocked`, `pairs_in_place`, `goal` and `goal_tower` (int64, as [`write_goal`]
/// writes them).
pub fn info<'py>(py: Python<'py>, obs: &Observation, blocked: bool) -> PyResult<Bound<'py, PyDict>> {
    let n = obs.state.block_count();
    let mask = PyArray1::<i8>::zeros(py, Action::count(n), false);
    write_action_mask(obs, mask.readwrite().as_slice_mut().expect("contiguous"));
    let goal = PyArray1::<i64>::zeros(py, n, false);
    let goal_tower = PyArray1::<i64>::zeros(py, n, false);
    write_goal(
        obs,
        GoalOut {
            goal: goal.readwrite().as_slice_mut().expect("contiguous"),
            tower: goal_tower.readwrite().as_slice_mut().expect("contiguous"),
        },
    );
    let dict = PyDict::new(py);
    dict.set_item("action_mask", mask)?;
    dict.set_item("blocked", blocked)?;
    dict.set_item("pairs_in_place", obs.goal.pairs_in_place(&obs.state))?;
    dict.set_item("goal", goal)?;
    dict.set_item("goal_tower", goal_tower)?;
    Ok(dict)
}
