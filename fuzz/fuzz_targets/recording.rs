//! Fuzz target: `blockstack::fuzz_checks::recording` on every input (`cargo fuzz run recording`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::recording(data));
