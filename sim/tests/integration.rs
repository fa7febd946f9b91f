//! The integration tests of this crate, in one test binary (ripgrep's `autotests = false`
//! pattern): one link step instead of one per file, and the helpers compiled once.

mod env;
mod original;
mod physics_matches_grid;
mod refusal;
mod rules;
mod side_view;
mod towers;
