//! The integration tests of this crate, in one test binary (ripgrep's `autotests = false`
//! pattern): one link step instead of one per file, and the helpers compiled once.

mod any_model;
mod checkpoint;
mod engine;
mod learning;
mod main_files;
mod picture;
mod relational;
