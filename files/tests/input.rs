//! Bounded reading: regular files by their size, anything else by what it yields.

use std::io::{Read, Write};
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
fn a_pipe_is_read_until_the_bound_and_no_further() {
    let dir = scratch("fifo");
    let fifo = dir.join("pipe");
    assert!(Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let writer = {
        let fifo = fifo.clone();
        // Writes more than the bound; stops when the reader goes.
        std::thread::spawn(move || {
            let mut f = std::fs::OpenOptions::new().write(true).open(&fifo).unwrap();
            for _ in 0..64 {
                if f.write_all(&[1u8; 1 << 16]).is_err() {
                    break;
                }
            }
        })
    };
    let mut reader = open_bounded(&fifo, 1 << 20, "a recording").unwrap();
    let mut bytes = Vec::new();
    let err = reader.read_to_end(&mut bytes).unwrap_err();
    assert_eq!(err.kind(), std::io::ErrorKind::FileTooLarge);
    assert!(err.to_string().contains("1 MiB, the most a recording can be"), "{err}");
    assert!(bytes.len() as u64 <= (1 << 20) + (1 << 16));
    drop(reader);
    writer.join().unwrap();
}
