//! `blockstack._native`: the Rust side of the Python package `blockstack`.
//!
//! A thin layer over the crates: every rule, reward, planner and trainer it reaches is the
//! one in `sim`, `oracle` or `agent`; this crate only turns Python arguments into their
//! configs and their results into numpy arrays.
//!
//! - [`env::NativeEnv`]: one environment, behind the Gymnasium class `blockstack.StackEnv`.
//! - [`vector::NativeVecEnv`]: a batch stepped in one call with the GIL released, writing
//!   into preallocated numpy arrays, behind `blockstack.vector.StackVectorEnv`.
//! - [`goal_env`]: the goal a state achieves and the goal rewards, behind
//!   `blockstack.StackGoalEnv` (Gymnasium-Robotics' `GoalEnv`, for hindsight relabelling).
//! - [`planning`]: the exact solver and the oracle (`blockstack.solve`), PDDL problems
//!   read and planned (`blockstack.read_pddl`, `solve_pddl`, `solve_all`).
//! - [`demos`]: expert demonstrations and recorded episodes as arrays.
//! - [`training`]: the tabular trainer, in-process (`blockstack.train`, the Ray sweep).
//! - [`dqn`]: the network trainer, in-process (`blockstack.train_dqn`).
//! - [`model`]: a model file of any kind (q, dqn, relational), loaded, played and evaluated (`blockstack.load`).
//! - [`output`]: files written through the `files` crate (the sweep's table).
//! - [`reproduce`]: the reproduction (`experiments`), its E8 arms run where a callable
//!   says (`python -m blockstack.reproduce --ray`).
//!
//! Errors: every error of the crates reaches Python as `ValueError` with the crate's own
//! message; a panic (a bug) is caught at the boundary and raised as `RuntimeError`, so
//! nothing unwinds into the interpreter.

use pyo3::prelude::*;

mod boundary;
mod config;
mod demos;
mod dqn;
mod env;
mod goal_env;
mod model;
mod observe;
mod output;
mod planning;
mod reproduce;
mod training;
mod vector;

/// The module `blockstack._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<env::NativeEnv>()?;
    m.add_class::<vector::NativeVecEnv>()?;
    // One home for the size below which a batch stays on the caller's thread.
    m.add("PARALLEL_FROM_ENVS", sim::vec_env::PARALLEL_FROM_ENVS)?;
    m.add_class::<model::NativeModel>()?;
    m.add_function(wrap_pyfunction!(planning::solve, m)?)?;
    m.add_function(wrap_pyfunction!(planning::read_pddl, m)?)?;
    m.add_function(wrap_pyfunction!(planning::solve_pddl, m)?)?;
    m.add_function(wrap_pyfunction!(planning::solve_all, m)?)?;
    m.add_function(wrap_pyfunction!(planning::pddl_task, m)?)?;
    m.add_function(wrap_pyfunction!(goal_env::achieved_goal, m)?)?;
    m.add_function(wrap_pyfunction!(goal_env::goal_rewards, m)?)?;
    m.add_function(wrap_pyfunction!(goal_env::check_stack_goal, m)?)?;
    m.add_function(wrap_pyfunction!(demos::demonstrations, m)?)?;
    m.add_function(wrap_pyfunction!(demos::read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(demos::recording_episodes, m)?)?;
    m.add_function(wrap_pyfunction!(training::train, m)?)?;
    m.add_function(wrap_pyfunction!(dqn::train_dqn, m)?)?;
    m.add_function(wrap_pyfunction!(reproduce::e8_arms, m)?)?;
    m.add_function(wrap_pyfunction!(reproduce::e8_start_order, m)?)?;
    m.add_function(wrap_pyfunction!(reproduce::run_e8_arm, m)?)?;
    m.add_function(wrap_pyfunction!(reproduce::reproduce, m)?)?;
    m.add_function(wrap_pyfunction!(config::episode_seed, m)?)?;
    m.add_function(wrap_pyfunction!(config::observation_shape, m)?)?;
    m.add_function(wrap_pyfunction!(config::grid_size, m)?)?;
    m.add("OBS_KINDS", sim::ObsKind::NAMES.to_vec())?;
    m.add_function(wrap_pyfunction!(output::check_output, m)?)?;
    m.add_function(wrap_pyfunction!(output::write_output, m)?)?;
    m.add_function(wrap_pyfunction!(output::check_folder, m)?)?;
    m.add_function(wrap_pyfunction!(output::read_config_file, m)?)?;
    m.add_function(wrap_pyfunction!(output::file_digest, m)?)?;
    m.add_function(wrap_pyfunction!(output::bar_chart, m)?)?;
    let experiments: Vec<&str> = experiments::reproduce::Report::Paper
        .experiments()
        .iter()
        .map(|e| e.id)
        .collect();
    m.add("EXPERIMENTS", experiments)?;
    m.add("REWARDS", sim::RewardModel::NAMES.to_vec())?;
    Ok(())
}
