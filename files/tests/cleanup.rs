//! `remove_temp_files`, in a test binary of its own: it closes the registry for the
//! whole process.

use std::io::Write;

use files::{OutputPath, live_temp_files, remove_temp_files};

#[test]
fn removing_the_temporary_files_removes_every_live_one_and_closes_the_registry() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    let mut a = OutputPath::check(dir.join("a.bin")).unwrap().create().unwrap();
    let mut b = OutputPath::check(dir.join("b.bin")).unwrap().create().unwrap();
    a.write_all(b"a").unwrap();
    b.write_all(b"b").unwrap();
    let live = live_temp_files();
    assert_eq!(live.len(), 2);
    assert!(live.iter().all(|p| p.exists()));
    assert_eq!(remove_temp_files(), 2);
    assert!(live.iter().all(|p| !p.exists()));
    assert!(live_temp_files().is_empty());
    // Closed: a commit, and any new atomic write, fails and leaves nothing behind.
    assert!(a.commit().is_err());
    assert!(OutputPath::check(dir.join("c.bin")).is_err());
    drop(b);
    assert_eq!(std::fs::read_dir(dir).unwrap().count(), 0);
}
