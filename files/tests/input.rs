//! Bounded reading: regular files by their size; a pipe or a device refused before it is opened.

use std::io::Read;
use std::path::Path;
use std::process::Command;

use files::{FilesError, ReadProblem, open_bounded};

use testkit::scratch;

#[test]
fn a_regular_file_larger_than_the_bound_is_refused_from_its_size() {
    let dir = scratch("regular");
    let path = dir.join("big");
    std::fs::write(&path, [0u8; 100]).unwrap();
    let err = open_bounded(&path, 99, "a test file").unwrap_err();
    assert_eq!(
        err,
        FilesError::Read {
            path: path.display().to_string(),
            problem: ReadProblem::TooLarge {
                bound: 99,
                what: "a test file"
            }
        }
    );
    assert!(
        err.to_string()
            .ends_with("it is larger than 99 bytes, the most a test file can be")
    );
    let mut text = Vec::new();
    open_bounded(&path, 100, "a test file")
        .unwrap()
        .read_to_end(&mut text)
        .unwrap();
    assert_eq!(text.len(), 100);
    let dir_err = open_bounded(&dir, 100, "a test file").unwrap_err().to_string();
    assert!(dir_err.contains("directory"), "{dir_err}");
    assert!(
        open_bounded(&dir.join("missing"), 1, "x")
            .unwrap_err()
            .to_string()
            .contains("missing")
    );
}

#[test]
fn a_pipe_or_a_device_is_refused_before_it_is_opened() {
    let dir = scratch("fifo");
    let fifo = dir.join("pipe");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    // No writer: opening the FIFO would block until one came; it is refused at once.
    for path in [fifo.as_path(), Path::new("/dev/zero"), Path::new("/dev/null")] {
        let err = open_bounded(path, 1 << 20, "a recording").unwrap_err().to_string();
        assert!(err.contains("a pipe or a device, not a regular file"), "{err}");
        assert!(err.contains("a recording is read from a file"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
}

#[test]
fn a_digest_is_the_files_sha256_and_changes_with_its_contents() {
    let dir = scratch("digest");
    let path = dir.join("demos.jsonl");
    std::fs::write(&path, b"abc").unwrap();
    // The SHA-256 of "abc" (FIPS 180-2's example).
    assert_eq!(
        files::digest_file(&path, 1 << 20, "a recording").unwrap(),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    std::fs::write(&path, b"abd").unwrap();
    assert_ne!(
        files::digest_file(&path, 1 << 20, "a recording").unwrap(),
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    let err = files::digest_file(&path, 2, "a recording").unwrap_err().to_string();
    assert!(err.contains("the most a recording can be"), "{err}");
}
