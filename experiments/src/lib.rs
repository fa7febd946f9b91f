//! Experiments.

pub mod stats;
