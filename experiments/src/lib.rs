//! Experiments: the paper reproduced ([`reproduce`]), with its statistics ([`stats`]) and
//! pictures ([`plots`]).

pub mod plots;
pub mod reproduce;
pub mod stats;
