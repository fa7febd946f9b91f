//! Fuzz target: `blockstack::fuzz_checks::train_checkpoint` on every input (`cargo fuzz run train_checkpoint`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::train_checkpoint(data));
