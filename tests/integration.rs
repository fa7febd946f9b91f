//! The integration tests of this crate, in one test binary (ripgrep's `autotests = false`
//! pattern): one link step instead of one per file, and the helpers compiled once.

mod cli_agent;
mod cli_bounds;
mod cli_checkpoint;
mod cli_correct;
mod cli_dqn;
mod cli_files;
mod cli_general;
mod cli_original;
mod cli_pddl;
mod cli_preset;
mod cli_readers;
mod cli_reproduce;
mod cli_serve;
mod cli_side;
mod cli_solve;
mod cli_world;
mod common;
mod docs_anchors;
mod docs_maps;
mod fuzz_corpus;
mod imports;
mod readme_results;
mod tui_tmux;
