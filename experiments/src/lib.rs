//! Experiments.

pub mod plots;
pub mod stats;
