//! Observations as numpy arrays: fresh objects for one environment, and writes into a
//! batch's preallocated buffers for many.

use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{Action, Observation};

use crate::boundary::OrValueError;
use crate::config::ObsKind;

/// The held block as an integer: its id, or -1 when nothing is held.
pub fn held_index(obs: &Observation) -> i64 {
    obs.held_block().map_or(-1, |b| i64::from(b.0))
}

/// Writes the legal actions of `obs` (under its environment's action protocol) into
/// `out`, 1 legal and 0 not, one per action index.
pub fn write_action_mask(obs: &Observation, out: &mut [i8]) {
    let mask = obs.legal_actions();
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
        {
            let mut b = blocks.readwrite();
            let mut g = goal.readwrite();
            write_state(
                obs,
                b.as_slice_mut().expect("contiguous"),
                g.as_slice_mut().expect("contiguous"),
            );
        }
        let dict = PyDict::new(py);
        dict.set_item("blocks", blocks)?;
        dict.set_item("held", held_index(obs))?;
        dict.set_item("goal", goal)?;
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

/// Writes every block's `[x, y]` into `blocks` (`N x 2`) and the goal, bottom to top, into
/// `goal` (`N`).
pub fn write_state(obs: &Observation, blocks: &mut [i64], goal: &mut [i64]) {
    for (i, c) in obs.blocks().iter().enumerate() {
        blocks[2 * i] = i64::from(c.x);
        blocks[2 * i + 1] = i64::from(c.y);
    }
    write_goal(obs, goal);
}

/// Writes the goal, bottom to top, into `goal`.
pub fn write_goal(obs: &Observation, goal: &mut [i64]) {
    for (g, b) in goal.iter_mut().zip(obs.goal.order()) {
        *g = i64::from(b.0);
    }
}

/// The `info` of a reset or a step, as a dict: `action_mask` (int8, 1 for each legal
/// action), `blocked`, `pairs_in_place` and `goal` (int64, bottom to top).
pub fn info<'py>(py: Python<'py>, obs: &Observation, blocked: bool) -> PyResult<Bound<'py, PyDict>> {
    let n = obs.state.block_count();
    let mask = PyArray1::<i8>::zeros(py, Action::count(n), false);
    write_action_mask(obs, mask.readwrite().as_slice_mut().expect("contiguous"));
    let goal = PyArray1::<i64>::zeros(py, n, false);
    write_goal(obs, goal.readwrite().as_slice_mut().expect("contiguous"));
    let dict = PyDict::new(py);
    dict.set_item("action_mask", mask)?;
    dict.set_item("blocked", blocked)?;
    dict.set_item("pairs_in_place", obs.goal.pairs_in_place(&obs.state))?;
    dict.set_item("goal", goal)?;
    Ok(dict)
}
