//! Fuzz target: `blockstack::fuzz_checks::model_file` on every input (`cargo fuzz run model_file`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::model_file(data));
