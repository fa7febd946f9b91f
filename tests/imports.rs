//! No circle of `use` lines between the files of a crate: a file that imports from a second
//! file which imports back makes two concepts one, and a review found three such circles
//! (experiments' arms and spread, E3/E4 and the shared stage, the relational model and its
//! trainer). One exception: a crate's `error` module names the values its messages report
//! (an action, a protocol) while every module returns its error type, so its own imports
//! are not followed.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A file's module path inside its crate: `["reproduce", "arms"]` for
/// `src/reproduce/arms.rs`, `[]` for `lib.rs`, `["demos"]` for `demos/mod.rs`.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let relative = file
        .strip_prefix(src)
        .expect("the file is under src")
        .with_extension("");
    let mut parts: Vec<String> = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The paths a `use` line names, braces expanded one level: `super::{a::B, c}` gives
/// `super::a::B` and `super::c`.
fn named_paths(used: &str) -> Vec<String> {
    let used: String = used.split_whitespace().collect();
    match used.split_once("::{") {
        Some((head, rest)) => rest
            .trim_end_matches('}')
            .split(',')
            .filter(|item| !item.is_empty())
            .map(|item| format!("{head}::{item}"))
            .collect(),
        None => vec![used],
    }
}

/// The file module a path names from `module`, if any: the longest prefix that is a file.
fn target(module: &[String], path: &str, files: &BTreeSet<Vec<String>>) -> Option<Vec<String>> {
    let mut parts: Vec<&str> = path.split("::").collect();
    let mut base: Vec<String> = match *parts.first()? {
        "crate" => Vec::new(),
        "self" => module.to_vec(),
        "super" => module.to_vec(),
        _ => return None,
    };
    while parts.first() == Some(&"super") {
        base.pop();
        parts.remove(0);
    }
    if matches!(parts.first(), Some(&"crate" | &"self")) {
        parts.remove(0);
    }
    base.extend(parts.iter().map(|p| p.to_string()));
    (1..=base.len())
        .rev()
        .map(|n| base[..n].to_vec())
        .find(|m| files.contains(m))
}

/// The circles among the files of the crate whose sources are `src`, each as the files on it.
fn circles(src: &Path) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    rust_files(src, &mut paths);
    let modules: BTreeMap<Vec<String>, PathBuf> = paths.into_iter().map(|p| (module_of(src, &p), p)).collect();
    let files: BTreeSet<Vec<String>> = modules.keys().cloned().collect();
    let mut imports: BTreeMap<&Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (module, path) in &modules {
        if module.last().is_some_and(|m| m == "error") {
            continue;
        }
        let text = std::fs::read_to_string(path).expect("a source file is readable");
        let mut statement = String::new();
        for line in text.lines().map(str::trim) {
            let line = line
                .strip_prefix("pub(crate) ")
                .or(line.strip_prefix("pub "))
                .unwrap_or(line);
            if statement.is_empty() && !line.starts_with("use ") {
                continue;
            }
            statement.push_str(line);
            if let Some(used) = statement.strip_prefix("use ").and_then(|s| s.strip_suffix(';')) {
                for p in named_paths(used) {
                    // An import from an enclosing module is the file's own parent, not a circle.
                    if let Some(t) = target(module, &p, &files).filter(|t| t != module && !module.starts_with(t)) {
                        imports.entry(module).or_default().insert(t);
                    }
                }
                statement.clear();
            }
        }
    }
    // A file is on a circle when it reaches itself; one circle is reported once, as the set of
    // files that reach each other.
    let reach = |from: &Vec<String>| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.clone()];
        while let Some(m) = todo.pop() {
            for next in imports.get(&m).into_iter().flatten() {
                if seen.insert(next.clone()) {
                    todo.push(next.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&Vec<String>, BTreeSet<Vec<String>>> = files.iter().map(|f| (f, reach(f))).collect();
    let mut found: BTreeSet<Vec<String>> = BTreeSet::new();
    for (file, seen) in &reached {
        if seen.contains(*file) {
            let circle = seen
                .iter()
                .filter(|other| reached[other].contains(*file))
                .map(|m| m.join("::"))
                .collect();
            found.insert(circle);
        }
    }
    found.into_iter().collect()
}

#[test]
fn no_file_imports_from_a_file_that_imports_back() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut crates = vec![root.join("src")];
    for entry in std::fs::read_dir(&root).expect("the workspace is readable") {
        let src = entry.expect("a directory entry").path().join("src");
        if src.is_dir() && src.parent().is_some_and(|c| c.join("Cargo.toml").is_file()) {
            crates.push(src);
        }
    }
    let found: Vec<String> = crates
        .iter()
        .flat_map(|src| {
            circles(src)
                .into_iter()
                .map(move |c| format!("{}: {}", src.display(), c.join(", ")))
        })
        .collect();
    assert!(
        found.is_empty(),
        "files that import from each other:\n{}",
        found.join("\n")
    );
}

#[test]
fn a_circle_is_found() {
    let dir = testkit::scratch("imports");
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\nmod c;\n").unwrap();
    std::fs::write(src.join("a/mod.rs"), "use crate::b::{\n    X,\n};\npub struct Y;\n").unwrap();
    std::fs::write(src.join("b.rs"), "pub use super::a::Y;\npub struct X;\n").unwrap();
    std::fs::write(src.join("c.rs"), "use super::a::Y;\n").unwrap();
    assert_eq!(circles(&src), vec![vec!["a".to_string(), "b".to_string()]]);
}
