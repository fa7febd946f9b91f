//! What the command-line tests share: running the binary, reading what it printed, and
//! scratch folders.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

#[allow(unused_imports)]
pub use testkit::scratch;

/// The `blockstack` binary built for these tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_blockstack");

/// Runs `blockstack` with `args` and waits for it.
pub fn blockstack(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("the binary runs")
}

/// A `blockstack` command line, built flag by flag: `cli("run").flag("blocks", 2).arg("--json")`.
/// Clone one to vary a shared base.
#[derive(Clone, Debug)]
pub struct Cli {
    args: Vec<String>,
}

/// The command line `blockstack COMMAND`.
pub fn cli(command: &str) -> Cli {
    Cli {
        args: vec![command.to_string()],
    }
}

impl Cli {
    /// Adds one argument as it is.
    pub fn arg(mut self, arg: impl ToString) -> Cli {
        self.args.push(arg.to_string());
        self
    }

    /// Adds each of `args` as it is.
    pub fn args(mut self, args: &[&str]) -> Cli {
        self.args.extend(args.iter().map(|a| a.to_string()));
        self
    }

    /// Adds `--NAME VALUE`.
    pub fn flag(self, name: &str, value: impl ToString) -> Cli {
        self.arg(format!("--{name}")).arg(value)
    }

    /// The arguments, the command first.
    pub fn argv(&self) -> Vec<&str> {
        self.args.iter().map(String::as_str).collect()
    }

    /// Runs it and waits.
    pub fn run(&self) -> Output {
        blockstack(&self.argv())
    }

    /// Runs it, checks that it succeeded, and returns what it printed.
    pub fn ok(&self) -> String {
        let o = self.run();
        assert!(o.status.success(), "{:?}: {}", self.args, stderr(&o));
        stdout(&o)
    }

    /// Runs it, checks that it succeeded, and reads what it printed as JSON.
    pub fn json(&self) -> serde_json::Value {
        let out = self.ok();
        serde_json::from_str(&out).unwrap_or_else(|e| panic!("{:?}: {e}: {out}", self.args))
    }
}

/// What a run printed on standard output.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// What a run printed on standard error.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The README's role recipe (alpha 1, gamma 1, epsilon 0, the step-cost reward) on goal
/// 0,1,2, on the grid backend (quick); add `--games N`.
pub const ROLE_ON_GRID: [&str; 14] = [
    "--repr",
    "role",
    "--reward",
    "step-cost",
    "--goals",
    "0,1,2",
    "--alpha",
    "1",
    "--gamma",
    "1",
    "--epsilon",
    "0",
    "--backend",
    "grid",
];

/// Runs `blockstack train ARGS`, checks that it succeeded, and returns what it printed.
pub fn train(args: &[&str]) -> Output {
    let o = blockstack(&[&["train"][..], args].concat());
    assert!(o.status.success(), "train {args:?}: {}", stderr(&o));
    o
}

/// Runs `blockstack train ARGS --out DIR/NAME`, checks that it succeeded, and returns the
/// model's path.
pub fn train_model(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let out = dir.join(name);
    train(&[args, &["--out", path(&out)]].concat());
    out
}

/// The JSON metadata of a file blockstack wrote in its safetensors container, read as any
/// program could (8 bytes of header length, the JSON header, blockstack's `metadata` entry
/// in it), checked to be of `format`.
pub fn file_metadata(file: &Path, format: &str) -> serde_json::Value {
    let bytes = std::fs::read(file).expect("the file exists");
    let n = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).expect("a JSON header");
    assert_eq!(header["__metadata__"]["format"], format);
    serde_json::from_str(header["__metadata__"]["metadata"].as_str().expect("metadata text")).expect("JSON metadata")
}

/// The JSON metadata of a Q-learner's model file.
pub fn model_metadata(model: &Path) -> serde_json::Value {
    file_metadata(model, "blockstack-q-agent")
}

/// A path as a command-line argument.
pub fn path(p: &Path) -> &str {
    p.to_str().expect("test paths are UTF-8")
}
