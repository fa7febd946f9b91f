//! Fuzz target: `blockstack::fuzz_checks::trajectory` on every input (`cargo fuzz run trajectory`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::trajectory(data));
