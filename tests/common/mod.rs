//! What the command-line tests share: running the binary, reading what it printed, and
//! scratch folders.

// Each test binary uses its own subset of these helpers.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

mod scratch;
#[allow(unused_imports)]
pub use scratch::scratch;

/// The `blockstack` binary built for these tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_blockstack");

/// Runs `blockstack` with `args` and waits for it.
pub fn blockstack(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("the binary runs")
}

/// What a run printed on standard output.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// What a run printed on standard error.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The JSON metadata of a model file, read as any program could: the safetensors layout
/// (8 bytes of header length, the JSON header) and blockstack's `metadata` entry in it.
pub fn model_metadata(model: &Path) -> serde_json::Value {
    let bytes = std::fs::read(model).expect("the model exists");
    let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).expect("a JSON header");
    assert_eq!(header["__metadata__"]["format"], "blockstack-q-agent");
    serde_json::from_str(header["__metadata__"]["metadata"].as_str().expect("metadata text")).expect("JSON metadata")
}

/// A path as a command-line argument.
pub fn path(p: &Path) -> &str {
    p.to_str().expect("test paths are UTF-8")
}
