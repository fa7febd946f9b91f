//! Fuzz target: `blockstack::fuzz_checks::dqn_checkpoint` on every input (`cargo fuzz run dqn_checkpoint`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::dqn_checkpoint(data));
