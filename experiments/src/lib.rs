//! Experiments: the paper reproduced ([`reproduce`]), and the pictures of its episodes
//! ([`episode`]). The statistics and the charts it uses are crates of their own (`stats`,
//! `plots`), knowing nothing of blocks; this crate is the reproduction only.

pub mod episode;
pub mod reproduce;
