//! Walking a folder tree: every file below a folder, each listed once, whatever links the
//! tree holds.
//!
//! Links to folders are followed (a tasks folder assembled from links is common), but a
//! folder is entered only once: the walk keeps a visited set of (device, inode), so a link
//! back to an ancestor (a loop) or a second link to a folder already walked adds nothing,
//! and a file reached twice through links is listed once. Entries are visited in sorted
//! order, so the list is the same on every run.

use std::collections::HashSet;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

use crate::error::{FilesError, ReadProblem, Result};

/// The files below `dir` (in it and in every folder below it, links followed, each folder
/// and file once: module docs) for which `keep` holds, in the walk's order: each folder's
/// entries sorted by name, a subfolder's files where the subfolder sorts.
pub fn files_below(dir: &Path, keep: impl Fn(&Path) -> bool) -> Result<Vec<PathBuf>> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    let meta = std::fs::metadata(dir).map_err(|e| read_error(dir, e))?;
    if !meta.is_dir() {
        return Err(FilesError::read(
            &dir.display().to_string(),
            ReadProblem::Io("it is not a folder".into()),
        ));
    }
    seen.insert((meta.dev(), meta.ino()));
    walk(dir, &keep, &mut seen, &mut out)?;
    Ok(out)
}

fn walk(
    dir: &Path,
    keep: &impl Fn(&Path) -> bool,
    seen: &mut HashSet<(u64, u64)>,
    out: &mut Vec<PathBuf>,
) -> Result<()> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| read_error(dir, e))?
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()
        .map_err(|e| read_error(dir, e))?;
    paths.sort();
    for path in paths {
        // A dangling link, or one that cannot be followed, names nothing to walk.
        let Ok(meta) = std::fs::metadata(&path) else { continue };
        if !seen.insert((meta.dev(), meta.ino())) {
            continue;
        }
        if meta.is_dir() {
            walk(&path, keep, seen, out)?;
        } else if keep(&path) {
            out.push(path);
        }
    }
    Ok(())
}

fn read_error(path: &Path, e: std::io::Error) -> FilesError {
    FilesError::read(&path.display().to_string(), ReadProblem::Io(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::symlink;

    fn names(dir: &Path, files: &[PathBuf]) -> Vec<String> {
        files
            .iter()
            .map(|p| p.strip_prefix(dir).unwrap().display().to_string())
            .collect()
    }

    #[test]
    fn links_are_followed_once_and_loops_end() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::create_dir_all(dir.join("other")).unwrap();
        std::fs::write(dir.join("sub/p01.pddl"), "x").unwrap();
        std::fs::write(dir.join("other/p02.pddl"), "x").unwrap();
        std::fs::write(dir.join("a.txt"), "x").unwrap();
        // Two loops back to an ancestor, a second link to a walked folder, a link to a
        // file already listed, a dangling link.
        symlink("..", dir.join("sub/up")).unwrap();
        symlink(dir, dir.join("other/self")).unwrap();
        symlink(dir.join("sub"), dir.join("zz-sub-again")).unwrap();
        symlink(dir.join("sub/p01.pddl"), dir.join("zz-p01.pddl")).unwrap();
        symlink(dir.join("missing"), dir.join("dangling")).unwrap();
        let all = files_below(dir, |p| p.extension().is_some_and(|e| e == "pddl")).unwrap();
        assert_eq!(names(dir, &all), ["other/p02.pddl", "sub/p01.pddl"]);
        let every = files_below(dir, |_| true).unwrap();
        assert_eq!(names(dir, &every), ["a.txt", "other/p02.pddl", "sub/p01.pddl"]);
    }

    #[test]
    fn a_file_or_a_missing_folder_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let file = tmp.path().join("f");
        std::fs::write(&file, "x").unwrap();
        let err = files_below(&file, |_| true).unwrap_err().to_string();
        assert!(err.contains("not a folder"), "{err}");
        assert!(files_below(&tmp.path().join("missing"), |_| true).is_err());
    }
}
