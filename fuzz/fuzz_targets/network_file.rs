//! Fuzz target: `blockstack::fuzz_checks::network_file` on every input (`cargo fuzz run network_file`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::network_file(data));
