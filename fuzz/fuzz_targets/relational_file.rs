//! Fuzz target: `blockstack::fuzz_checks::relational_file` on every input (`cargo fuzz run relational_file`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::relational_file(data));
