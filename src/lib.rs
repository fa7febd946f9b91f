//! blockstack: a physics-backed 2D block-stacking world, its planners and learners, and
//! the reproduction of "Interactive Robot Learning".
//!
//! The work lives in the workspace's crates (`docs/architecture.md` maps them), all but
//! `neural` re-exported here; [`cli`] is the command line over them, and [`fuzz_checks`]
//! what the fuzz targets (`fuzz/`) check on each input.

pub mod cli;
pub mod fuzz_checks;
pub mod tui;

pub use agent;
pub use experiments;
pub use files;
pub use oracle;
pub use sim;
