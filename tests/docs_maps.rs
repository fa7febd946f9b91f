//! Keeps the front door's maps true to the repository, because each of them once drifted:
//!
//! - the Rust version the README, docs/development.md, python/README.md and Cargo.toml's
//!   `rust-version` state is the highest `rust_version` of the locked packages (a newcomer
//!   on an older toolchain failed to build while the docs said it would);
//! - the README's crate table and docs/architecture.md's crate list name exactly the
//!   workspace's crates (`serve` was missing from both);
//! - docs/cli.md's command table names exactly the binary's subcommands;
//! - the README's crate table says which crates each crate uses, as its Cargo.toml does
//!   (a map drawn by hand once showed arrows no manifest had).

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::Command;

use clap::CommandFactory;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(relative: &str) -> String {
    let path = root().join(relative);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// A version `1.89` or `1.89.0` as comparable numbers (a missing patch is 0).
fn version(text: &str) -> Vec<u64> {
    let mut parts: Vec<u64> = text
        .split('.')
        .map(|p| p.parse().unwrap_or_else(|_| panic!("{text:?} is not a version")))
        .collect();
    parts.resize(3, 0);
    parts
}

/// The host's target triple, so that packages only other platforms build are left out.
fn host() -> String {
    let out = Command::new("rustc").arg("-vV").output().expect("rustc runs");
    String::from_utf8(out.stdout)
        .expect("rustc -vV prints UTF-8")
        .lines()
        .find_map(|l| l.strip_prefix("host: ").map(str::to_string))
        .expect("rustc -vV names the host")
}

/// The highest `rust_version` among the locked packages built on this host, outside the
/// workspace, as written in its manifest.
fn highest_locked_rust_version() -> String {
    let out = Command::new(env!("CARGO"))
        .args(["metadata", "--format-version", "1", "--locked", "--filter-platform"])
        .arg(host())
        .current_dir(root())
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("cargo metadata prints JSON");
    let members: BTreeSet<&str> = meta["workspace_members"]
        .as_array()
        .expect("workspace_members")
        .iter()
        .filter_map(|m| m.as_str())
        .collect();
    meta["packages"]
        .as_array()
        .expect("packages")
        .iter()
        .filter(|p| !members.contains(p["id"].as_str().unwrap_or_default()))
        .filter_map(|p| p["rust_version"].as_str())
        .max_by_key(|v| version(v))
        .expect("some locked package states a rust_version")
        .to_string()
}

/// Every `(X.Y or newer)` of `text`, whitespace folded (a sentence may wrap inside one).
fn stated_versions(text: &str) -> Vec<String> {
    let folded = text.split_whitespace().collect::<Vec<_>>().join(" ");
    folded
        .match_indices(" or newer)")
        .filter_map(|(end, _)| {
            let start = folded[..end].rfind('(')? + 1;
            let v = &folded[start..end];
            v.chars().all(|c| c.is_ascii_digit() || c == '.').then(|| v.to_string())
        })
        .collect()
}

#[test]
fn the_stated_rust_version_is_the_lockfiles() {
    let needed = highest_locked_rust_version();
    let manifest = read("Cargo.toml");
    let declared = manifest
        .lines()
        .find_map(|l| l.trim().strip_prefix("rust-version = \""))
        .and_then(|l| l.strip_suffix('"'))
        .expect("Cargo.toml declares the workspace's rust-version");
    assert_eq!(
        version(declared),
        version(&needed),
        "Cargo.toml says rust-version {declared}; the locked packages need {needed}"
    );
    for page in ["README.md", "docs/development.md", "python/README.md"] {
        let stated = stated_versions(&read(page));
        assert!(!stated.is_empty(), "{page} does not say which Rust it needs");
        for v in stated {
            assert_eq!(
                version(&v),
                version(&needed),
                "{page} says Rust {v} or newer; the locked packages need {needed}"
            );
        }
    }
}

/// The workspace's crates by folder name (the root package is `blockstack`).
fn workspace_crates() -> BTreeSet<String> {
    let manifest = read("Cargo.toml");
    let members = manifest
        .split("members = [")
        .nth(1)
        .and_then(|rest| rest.split(']').next())
        .expect("Cargo.toml lists the workspace's members");
    members
        .split(',')
        .map(|m| m.trim().trim_matches('"').to_string())
        .filter(|m| !m.is_empty())
        .chain(["blockstack".to_string()])
        .collect()
}

/// The code spans that open each line of `text` starting with `prefix`: `a` in
/// "| `a` | ...", `stats` and `plots` in "- `stats`, `plots`: ...".
fn first_spans(text: &str, prefix: &str) -> BTreeSet<String> {
    text.lines()
        .filter_map(|l| l.strip_prefix(prefix))
        .filter(|rest| rest.starts_with('`'))
        .flat_map(|rest| {
            let head = rest.split(['|', ':']).next().unwrap_or_default();
            head.split('`')
                .skip(1)
                .step_by(2)
                .map(str::to_string)
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn the_architecture_lists_every_crate() {
    let architecture = read("docs/architecture.md");
    let list = &architecture[..architecture.find("## ").unwrap_or(architecture.len())];
    assert_eq!(
        first_spans(list, "- "),
        workspace_crates(),
        "docs/architecture.md's crate list"
    );
}

/// The crates of the workspace a crate's manifest lists under `[dependencies]` (not the
/// tests' or the build's): `name.workspace = true`, `name = { workspace = true, ... }` or
/// `name = { path = ... }`.
fn uses(manifest: &str, crates: &BTreeSet<String>) -> BTreeSet<String> {
    let section = manifest.split("\n[dependencies]\n").nth(1).unwrap_or_default();
    let section = &section[..section.find("\n[").unwrap_or(section.len())];
    section
        .lines()
        .filter_map(|l| l.split(['.', '=', ' ']).next())
        .filter(|name| crates.contains(*name))
        .map(str::to_string)
        .collect()
}

#[test]
fn the_crate_table_says_what_each_crate_uses() {
    let crates = workspace_crates();
    let readme = read("README.md");
    let table = readme
        .split("| crate | uses | what it holds |")
        .nth(1)
        .expect("the README's crate table has a column of the crates each uses");
    let table = &table[..table.find("\n\n").unwrap_or(table.len())];
    let mut checked = BTreeSet::new();
    for row in table.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let name = cells[1].trim_matches('`');
        let stated: BTreeSet<String> = cells[2].split('`').skip(1).step_by(2).map(str::to_string).collect();
        let manifest = if name == "blockstack" {
            "Cargo.toml".to_string()
        } else {
            format!("{name}/Cargo.toml")
        };
        assert_eq!(
            stated,
            uses(&read(&manifest), &crates),
            "the README's crate table: what `{name}` uses"
        );
        checked.insert(name.to_string());
    }
    assert_eq!(
        checked,
        workspace_crates(),
        "the README's crate table has a row per crate"
    );
}

#[test]
fn the_command_table_names_every_subcommand() {
    let commands: BTreeSet<String> = blockstack::cli::Cli::command()
        .get_subcommands()
        .filter(|c| !c.is_hide_set())
        .map(|c| c.get_name().to_string())
        .collect();
    let page = read("docs/cli.md");
    let table = page
        .split("| command | what it does |")
        .nth(1)
        .expect("docs/cli.md has a command table");
    let table = &table[..table.find("\n\n").unwrap_or(table.len())];
    assert_eq!(first_spans(table, "| "), commands, "docs/cli.md's command table");
}
