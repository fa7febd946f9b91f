//! The integration tests of this crate, in one test binary (ripgrep's `autotests = false`
//! pattern): one link step instead of one per file, and the helpers compiled once.

mod common;
mod exact;
mod pddl;
mod protocol;
mod side_steps;
mod soundness;
mod towers;
