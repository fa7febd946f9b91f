//! Fuzz target: `blockstack::fuzz_checks::cli_parsers` on every input (`cargo fuzz run cli_parsers`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::cli_parsers(data));
