//! Fuzz target: `blockstack::fuzz_checks::pddl_problem` on every input (`cargo fuzz run pddl_problem`).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| blockstack::fuzz_checks::pddl_problem(data));
