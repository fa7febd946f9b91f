//! Keeps the docs true to the repository, because a page that nothing checks goes stale:
//!
//! - every `path/to/file.rs::Symbol` anchor of `docs/architecture.md` names a file that
//!   exists and declares that symbol (`Type::method`: a `fn method` inside an `impl` of
//!   `Type` or the `trait Type`; a bare name: any item of that name);
//! - no Markdown file of the repository points outside it (to the team's folder beside one
//!   checkout, which a clone does not have), links to a file that does not exist, or
//!   links to a heading that the linked page does not have.

use std::path::{Component, Path, PathBuf};
use std::process::Command;

/// The repository's root (the root crate's folder).
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// An anchor of the architecture page: a file and a symbol path in it.
#[derive(Debug, PartialEq)]
struct Anchor {
    file: String,
    symbol: String,
}

/// The anchors of `text`: code spans of the form `path/to/file.rs::Symbol[::member]`.
fn anchors(text: &str) -> Vec<Anchor> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .filter_map(|span| {
            let (file, symbol) = span.split_once(".rs::")?;
            let ok = |s: &str, extra: &[char]| {
                !s.is_empty()
                    && s.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || extra.contains(&c))
            };
            (ok(file, &['/', '-', '.']) && ok(symbol, &[':'])).then(|| Anchor {
                file: format!("{file}.rs"),
                symbol: symbol.to_string(),
            })
        })
        .collect()
}

/// Whether `word` occurs in `line` as a whole identifier.
fn has_word(line: &str, word: &str) -> bool {
    line.match_indices(word).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + word.len()..].chars().next();
        let ident = |c: Option<char>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
        !ident(before) && !ident(after)
    })
}

/// Whether `line` declares an item called `name` (`fn`, `struct`, `enum`, `trait`, `type`,
/// `mod`, `const`, `static`, `macro_rules!`), with any visibility and qualifiers.
fn declares(line: &str, name: &str) -> bool {
    const ITEMS: [&str; 9] = [
        "fn",
        "struct",
        "enum",
        "trait",
        "type",
        "mod",
        "const",
        "static",
        "macro_rules!",
    ];
    let words: Vec<&str> = line.split_whitespace().collect();
    let qualifier = |i: usize| {
        let w = words[i];
        w == "pub"
            || w.starts_with("pub(")
            || ["async", "unsafe", "extern", "default"].contains(&w)
            || w.starts_with('"')
            || (w == "const"
                && words
                    .get(i + 1)
                    .is_some_and(|next| ["fn", "unsafe", "async", "extern"].contains(next)))
    };
    let mut i = 0;
    while i < words.len() && qualifier(i) {
        i += 1;
    }
    let (Some(keyword), Some(item)) = (words.get(i), words.get(i + 1)) else {
        return false;
    };
    ITEMS.contains(keyword)
        && item
            .strip_prefix(name)
            .is_some_and(|after| !after.starts_with(|c: char| c.is_ascii_alphanumeric() || c == '_'))
}

/// The self type of an `impl` header line (`impl<T> Trait for Type<T> {` gives `Type`), or
/// `None` for another line.
fn impl_type(line: &str) -> Option<&str> {
    let rest = line.strip_prefix("impl")?;
    if !rest.starts_with([' ', '<']) {
        return None;
    }
    let header = rest.trim_end().trim_end_matches('{').trim_end();
    let header = header.split(" where ").next()?.trim_start();
    let ty = match header.rsplit_once(" for ") {
        Some((_, ty)) => ty,
        // `impl<T: Bound<U>> Type<T>`: skip the generics of the impl itself.
        None if header.starts_with('<') => {
            let mut depth = 0;
            let mut end = header.len();
            for (i, c) in header.char_indices() {
                match c {
                    '<' => depth += 1,
                    '>' => {
                        depth -= 1;
                        if depth == 0 {
                            end = i + 1;
                            break;
                        }
                    }
                    _ => {}
                }
            }
            &header[end..]
        }
        None => header,
    };
    let ty = ty.trim().trim_start_matches('&');
    Some(ty.split('<').next().unwrap_or(ty).trim())
}

/// Whether `source` declares `symbol`: `Name`, or `Type::member` (a `fn member` in the body
/// of an `impl` of `Type` or of `trait Type`, bodies delimited by rustfmt's closing `}` in
/// the first column).
fn declares_symbol(source: &str, symbol: &str) -> bool {
    let parts: Vec<&str> = symbol.split("::").collect();
    match parts.as_slice() {
        [name] => source.lines().any(|line| declares(line, name)),
        [ty, member] => {
            let mut inside = false;
            for line in source.lines() {
                if inside {
                    if line.starts_with('}') {
                        inside = false;
                    } else if declares(line, member) {
                        return true;
                    }
                } else if line.starts_with("impl") {
                    inside = impl_type(line) == Some(ty);
                } else if declares(line, ty) && has_word(line, "trait") {
                    inside = true;
                }
            }
            false
        }
        _ => false,
    }
}

#[test]
fn every_anchor_of_the_architecture_page_names_a_file_that_declares_its_symbol() {
    let page = read(&root().join("docs/architecture.md"));
    let anchors = anchors(&page);
    assert!(
        anchors.len() >= 15,
        "docs/architecture.md has {} anchors: the page lost its paths",
        anchors.len()
    );
    let mut broken = Vec::new();
    for anchor in &anchors {
        let path = root().join(&anchor.file);
        if !path.is_file() {
            broken.push(format!("{}::{}: no file {}", anchor.file, anchor.symbol, anchor.file));
        } else if !declares_symbol(&read(&path), &anchor.symbol) {
            broken.push(format!(
                "{}::{}: {} does not declare it",
                anchor.file, anchor.symbol, anchor.file
            ));
        }
    }
    assert!(
        broken.is_empty(),
        "docs/architecture.md has stale anchors:\n{}",
        broken.join("\n")
    );
}

#[test]
fn the_anchor_checks_tell_declarations_from_mentions() {
    let source = "pub struct Env {\n}\n\nimpl Env {\n    pub fn step(&mut self) {}\n    fn check_running(&self) {}\n}\n\n\
                  impl<'a> World for GridWorld<'a> {\n    fn try_move(&mut self) {}\n}\n\n\
                  impl<T: Into<u8>> Grid<T> {\n    pub const fn cells(&self) {}\n}\n\n\
                  pub trait World {\n    fn act(&mut self) {}\n}\n\npub(crate) fn train() {}\n\
                  fn other() { step(); }\n";
    for symbol in [
        "Env",
        "Env::step",
        "Env::check_running",
        "GridWorld::try_move",
        "World::act",
        "Grid::cells",
        "train",
    ] {
        assert!(declares_symbol(source, symbol), "{symbol} is declared");
    }
    for symbol in [
        "Env::act",
        "GridWorld::step",
        "World::try_move",
        "check",
        "Other",
        "Env::step::x",
        "trai",
    ] {
        assert!(!declares_symbol(source, symbol), "{symbol} is not declared");
    }
    assert_eq!(
        anchors("see `sim/src/env.rs::Env::step`, `Env::step` and `a.rs` or `x.rs::` "),
        vec![Anchor {
            file: "sim/src/env.rs".into(),
            symbol: "Env::step".into()
        }]
    );
}

/// The Markdown files git tracks (every Markdown file outside `target/` and hidden folders
/// when git is not there).
fn markdown_files() -> Vec<PathBuf> {
    let listed = Command::new("git")
        .args([
            "ls-files",
            "-z",
            "--cached",
            "--others",
            "--exclude-standard",
            "--",
            "*.md",
        ])
        .current_dir(root())
        .output()
        .ok()
        .filter(|out| out.status.success());
    match listed {
        Some(out) => String::from_utf8_lossy(&out.stdout)
            .split('\0')
            .filter(|p| !p.is_empty())
            .map(|p| root().join(p))
            .filter(|p| p.is_file())
            .collect(),
        None => {
            let mut found = Vec::new();
            let mut folders = vec![root()];
            while let Some(folder) = folders.pop() {
                for entry in std::fs::read_dir(&folder).unwrap().flatten() {
                    let path = entry.path();
                    let name = entry.file_name().to_string_lossy().into_owned();
                    if path.is_dir() {
                        if !name.starts_with('.') && name != "target" && name != "report" {
                            folders.push(path);
                        }
                    } else if name.ends_with(".md") {
                        found.push(path);
                    }
                }
            }
            found
        }
    }
}

/// The link targets of Markdown `text` (`[text](target)`, `![alt](target)` and
/// `[label]: target`), outside code blocks and code spans.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Code spans hold examples, not links.
        let prose: String = line.split('`').step_by(2).collect::<Vec<_>>().join(" ");
        let trimmed = prose.trim_start();
        if let Some((label, target)) = trimmed.split_once("]: ")
            && label.starts_with('[')
            && !label.contains(']')
        {
            targets.push(target.split_whitespace().next().unwrap_or("").to_string());
        }
        let mut rest = prose.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let end = after.find(')').unwrap_or(after.len());
            targets.push(after[..end].split_whitespace().next().unwrap_or("").to_string());
            rest = &after[end..];
        }
    }
    targets
}

/// `path` with `.` and `..` resolved lexically; `None` if it climbs above its start.
fn normalise(path: &Path) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for part in path.components() {
        match part {
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    Some(out)
}

/// The anchor GitHub gives a heading: lower case, spaces as hyphens, punctuation dropped.
fn slug(heading: &str) -> String {
    heading
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c.to_ascii_lowercase()),
            _ => None,
        })
        .collect()
}

/// The anchors of the headings of Markdown `text` (outside code blocks).
fn heading_anchors(text: &str) -> Vec<String> {
    let mut fenced = false;
    let mut anchors = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            anchors.push(slug(line.trim_start_matches('#').trim()));
        }
    }
    anchors
}

/// The paths a Markdown file must not name: the team's folder beside one checkout and the
/// paper's copy in it. Spelt in two pieces so that this file does not name them either.
const OUTSIDE: [&str; 2] = [concat!("..", "/shared"), concat!("shared", "/paper")];

#[test]
fn no_markdown_file_points_outside_the_repository_or_to_a_missing_file() {
    let root = root();
    let files = markdown_files();
    assert!(
        files.iter().any(|f| f.ends_with("docs/architecture.md")),
        "the docs were not found under {}",
        root.display()
    );
    // The results report is generated (`blockstack reproduce --long --seed 1 --out docs/results`); until a
    // first one is committed, links into it cannot resolve.
    let results_committed = root.join("docs/results").is_dir();
    let mut problems = Vec::new();
    for file in &files {
        let text = read(file);
        let name = file.strip_prefix(&root).unwrap_or(file).display().to_string();
        for forbidden in OUTSIDE {
            if text.contains(forbidden) {
                problems.push(format!("{name}: mentions `{forbidden}`, which a clone does not have"));
            }
        }
        for target in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, fragment) = target.split_once('#').unwrap_or((&target, ""));
            if path.is_empty() {
                if !fragment.is_empty() && !heading_anchors(&text).iter().any(|a| a == fragment) {
                    problems.push(format!("{name}: links to #{fragment}, a heading it does not have"));
                }
                continue;
            }
            let folder = file.parent().unwrap().strip_prefix(&root).unwrap_or(Path::new(""));
            let Some(resolved) = normalise(&folder.join(path)) else {
                problems.push(format!("{name}: links to {target}, outside the repository"));
                continue;
            };
            if !results_committed && resolved.starts_with("docs/results") {
                continue;
            }
            let linked = root.join(&resolved);
            if !linked.exists() {
                problems.push(format!("{name}: links to {target}, which does not exist"));
            } else if !fragment.is_empty()
                && path.ends_with(".md")
                && !heading_anchors(&read(&linked)).iter().any(|a| a == fragment)
            {
                problems.push(format!("{name}: links to {target}, a heading {path} does not have"));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "broken links in the docs:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_link_reader_finds_links_and_skips_code() {
    let text = "See [the world](docs/world.md#actions) and ![a picture](e4.png).\n\
                `[not](a-link.md)` and\n```sh\n[nor](this.md)\n```\n[label]: ref.md \"title\"\n\
                [web](https://example.org) [two](a.md) [three](b.md)\n";
    assert_eq!(
        link_targets(text),
        [
            "docs/world.md#actions",
            "e4.png",
            "ref.md",
            "https://example.org",
            "a.md",
            "b.md"
        ]
    );
    assert_eq!(
        normalise(Path::new("docs/../README.md")),
        Some(PathBuf::from("README.md"))
    );
    assert_eq!(
        heading_anchors("# Title\n```\n# not a heading\n```\n## 10. The `original` world: as coded\n"),
        ["title", "10-the-original-world-as-coded"]
    );
    assert_eq!(normalise(Path::new("docs/../../elsewhere/rules.md")), None);
}
