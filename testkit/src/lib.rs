//! What the workspace's tests share, a dev-dependency only (no build ships it): scratch
//! folders removed when a test ends ([`scratch`]), and the fixtures, files an earlier release
//! wrote that every later one must still read ([`fixture`]; `fixtures/README.md` says how
//! each was made). It sits below every crate of the workspace and depends on none of them,
//! so any crate's tests may use it without an arrow running back up.

use std::path::PathBuf;

mod scratch;

pub use scratch::{Scratch, scratch};

/// The fixture file `name` (`fixtures/` of this crate), e.g. `trajectory.jsonl`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures").join(name)
}

/// The text of the fixture file `name`; a panic naming the file if it cannot be read (a test
/// helper: the fixture is part of the checkout).
pub fn fixture_text(name: &str) -> String {
    let path = fixture(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
