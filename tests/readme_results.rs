//! The README's results are the committed reports', not typed in by hand: the block between
//! `<!-- results:begin -->` and `<!-- results:end -->` is what
//! `experiments::reproduce::summary` computes from `docs/results/results.json` (the report
//! `blockstack reproduce --long --seed 1 --out docs/results` writes, with the same block as
//! `summary.md`), and the block between `<!-- benchmark:begin -->` and `<!-- benchmark:end -->`
//! what it computes from `docs/benchmark/results.json` (`blockstack benchmark --long --seed 1
//! --out docs/benchmark`).

use std::path::Path;

/// A file of the repository, as text.
fn read(path: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The text between the `name` markers of `readme`.
fn block<'a>(readme: &'a str, name: &str) -> &'a str {
    let (begin, end) = (format!("<!-- {name}:begin -->"), format!("<!-- {name}:end -->"));
    let start = readme
        .find(&begin)
        .unwrap_or_else(|| panic!("the README has a {begin} marker"))
        + begin.len();
    let len = readme[start..]
        .find(&end)
        .unwrap_or_else(|| panic!("the README has a {end} marker after {begin}"));
    &readme[start..start + len]
}

#[test]
fn the_readmes_results_are_the_committed_reports() {
    let results = read("docs/results/results.json");
    let summary = experiments::reproduce::summary(&results).expect("a reproduction's results.json");
    assert_eq!(
        block(&read("README.md"), "results").trim(),
        summary.trim(),
        "run `blockstack reproduce --long --seed 1 --out docs/results` and paste docs/results/summary.md between the markers"
    );
    assert_eq!(read("docs/results/summary.md"), summary, "docs/results/summary.md");
    let json: serde_json::Value = serde_json::from_str(&results).expect("JSON");
    assert_eq!(json["options"]["quick"], false, "the committed report is a full run");
}

#[test]
fn the_readmes_benchmark_results_are_the_committed_benchmarks() {
    let results = read("docs/benchmark/results.json");
    let summary = experiments::reproduce::summary(&results).expect("a benchmark's results.json");
    assert_eq!(
        block(&read("README.md"), "benchmark").trim(),
        summary.trim(),
        "run `blockstack benchmark --long --seed 1 --out docs/benchmark` and paste docs/benchmark/summary.md between \
         the benchmark markers"
    );
    assert_eq!(read("docs/benchmark/summary.md"), summary, "docs/benchmark/summary.md");
    let json: serde_json::Value = serde_json::from_str(&results).expect("JSON");
    assert_eq!(json["options"]["report"], "blocks-world");
    assert_eq!(json["options"]["quick"], false, "the committed benchmark is a full run");
}
