//! The README's results are the committed report's, not typed in by hand: the block between
//! `<!-- results:begin -->` and `<!-- results:end -->` is what
//! `experiments::reproduce::summary` computes from `docs/results/results.json` (the report
//! `blockstack reproduce --long --seed 1 --out docs/results` writes, with the same block as `summary.md`).

use std::path::Path;

/// A file of the repository, as text.
fn read(path: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The text between the results markers of `readme`.
fn results_block(readme: &str) -> &str {
    let (begin, end) = ("<!-- results:begin -->", "<!-- results:end -->");
    let start = readme.find(begin).expect("the README has a results:begin marker") + begin.len();
    let len = readme[start..]
        .find(end)
        .expect("the README has a results:end marker after results:begin");
    &readme[start..start + len]
}

#[test]
fn the_readmes_results_are_the_committed_reports() {
    let results = read("docs/results/results.json");
    let summary = experiments::reproduce::summary(&results).expect("a reproduction's results.json");
    assert_eq!(
        results_block(&read("README.md")).trim(),
        summary.trim(),
        "run `blockstack reproduce --long --seed 1 --out docs/results` and paste docs/results/summary.md between the markers"
    );
    assert_eq!(read("docs/results/summary.md"), summary, "docs/results/summary.md");
    let json: serde_json::Value = serde_json::from_str(&results).expect("JSON");
    assert_eq!(json["options"]["quick"], false, "the committed report is a full run");
}
