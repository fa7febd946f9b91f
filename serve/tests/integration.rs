//! The integration tests of this crate, in one test binary (the workspace's `autotests =
//! false` pattern): one link step instead of one per file, and the helpers compiled once.

mod bounds;
mod common;
mod load;
mod restart;
mod session;
mod study;
