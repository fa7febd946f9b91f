//! Replays the kept fuzz corpus (`fuzz/corpus/<target>/`) through the checks the fuzz
//! targets make (`blockstack::fuzz_checks`), on stable Rust: an input the fuzzer once ran
//! crash-free (or once crashed on, and was fixed) stays so.

use std::path::Path;

type Check = fn(&[u8]);

#[test]
fn every_kept_fuzz_input_passes_its_targets_check() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus");
    let targets: [(&str, Check); 9] = [
        ("model_file", blockstack::fuzz_checks::model_file),
        ("network_file", blockstack::fuzz_checks::network_file),
        ("recording", blockstack::fuzz_checks::recording),
        ("trajectory", blockstack::fuzz_checks::trajectory),
        ("cli_parsers", blockstack::fuzz_checks::cli_parsers),
        ("relational_file", blockstack::fuzz_checks::relational_file),
        ("pddl_problem", blockstack::fuzz_checks::pddl_problem),
        ("train_checkpoint", blockstack::fuzz_checks::train_checkpoint),
        ("dqn_checkpoint", blockstack::fuzz_checks::dqn_checkpoint),
    ];
    for (target, check) in targets {
        let dir = corpus.join(target);
        let mut inputs = 0;
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.unwrap().path();
            let data = std::fs::read(&path).unwrap();
            let outcome = std::panic::catch_unwind(|| check(&data));
            assert!(outcome.is_ok(), "{target}: {} fails its check", path.display());
            inputs += 1;
        }
        assert!(inputs > 0, "{target}: no kept inputs in {}", dir.display());
    }
}
