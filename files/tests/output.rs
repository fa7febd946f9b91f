//! The output helper against every kind of destination, made by the tests in their own
//! scratch folders (never the real `/dev/null`).

use std::fs;
use std::io::{Read, Write};
use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::Command;

use files::{Destination, OutputPath, Special, live_temp_files, prepare_folder, refuse_same_file};

use testkit::scratch;

/// Every file in `dir` whose name says it is a temporary file.
fn temps(dir: &Path) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

#[test]
fn a_regular_file_is_replaced_atomically_and_keeps_its_permissions() {
    let dir = scratch("regular");
    let path = dir.join("out.txt");
    fs::write(&path, "old").unwrap();
    fs::set_permissions(&path, fs::Permissions::from_mode(0o640)).unwrap();
    let out = OutputPath::check(&path).unwrap();
    assert_eq!(out.destination(), &Destination::File { target: path.clone() });
    let mut w = out.create().unwrap();
    w.write_all(b"new").unwrap();
    // Until the commit, the target is the old file and a hidden temporary is listed.
    assert_eq!(fs::read_to_string(&path).unwrap(), "old");
    let live: Vec<PathBuf> = live_temp_files().into_iter().filter(|p| p.starts_with(&dir)).collect();
    assert_eq!(live.len(), 1);
    assert!(live[0].file_name().unwrap().to_string_lossy().starts_with(".out.txt."));
    w.commit().unwrap();
    assert_eq!(fs::read_to_string(&path).unwrap(), "new");
    assert_eq!(fs::metadata(&path).unwrap().permissions().mode() & 0o777, 0o640);
    assert!(temps(&dir).is_empty());
    assert!(!live_temp_files().iter().any(|p| p.starts_with(&dir)));
}

#[test]
fn an_abandoned_write_leaves_the_target_and_no_temporary_file() {
    let dir = scratch("abandoned");
    let path = dir.join("model.bin");
    fs::write(&path, "kept").unwrap();
    {
        let mut w = OutputPath::check(&path).unwrap().create().unwrap();
        w.write_all(&[7; 100_000]).unwrap();
        assert_eq!(temps(&dir).len(), 1);
        // Dropped: an error on the way.
    }
    assert_eq!(fs::read_to_string(&path).unwrap(), "kept");
    assert!(temps(&dir).is_empty());
    // A new path is not created either.
    drop(OutputPath::check(dir.join("new.bin")).unwrap().create().unwrap());
    assert!(!dir.join("new.bin").exists());
    assert!(temps(&dir).is_empty());
}

#[test]
fn bad_destinations_are_refused_before_anything_is_written() {
    let dir = scratch("bad");
    let check = |p: &Path| OutputPath::check(p).unwrap_err().to_string();
    let missing = dir.join("no/such/folder/m.bin");
    let e = check(&missing);
    assert!(
        e.contains(&missing.display().to_string()) && e.contains("does not exist") && e.contains("mkdir -p"),
        "{e}"
    );
    let e = check(&dir);
    assert!(e.contains("is a directory"), "{e}");
    let e = check(Path::new(&format!("{}/", dir.join("sub").display())));
    assert!(e.contains("names a folder"), "{e}");
    fs::write(dir.join("file"), "").unwrap();
    let e = check(&dir.join("file").join("m.bin"));
    assert!(e.contains("is not a folder"), "{e}");
    let e = check(Path::new(""));
    assert!(e.contains("empty"), "{e}");
    // A link loop.
    std::os::unix::fs::symlink(dir.join("b"), dir.join("a")).unwrap();
    std::os::unix::fs::symlink(dir.join("a"), dir.join("b")).unwrap();
    let e = check(&dir.join("a"));
    assert!(e.contains("symbolic links"), "{e}");
    assert!(temps(&dir).is_empty());
}

#[test]
fn standard_output_is_a_dash() {
    let out = OutputPath::check("-").unwrap();
    assert!(out.is_stdout());
    assert!(refuse_same_file("-", "-").is_ok());
}

#[test]
fn a_fifo_is_written_directly_and_stays_a_fifo() {
    let dir = scratch("fifo");
    let fifo = dir.join("pipe");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    let out = OutputPath::check(&fifo).unwrap();
    assert!(matches!(
        out.destination(),
        Destination::Special {
            kind: Special::Fifo,
            ..
        }
    ));
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = String::new();
            fs::File::open(&fifo).unwrap().read_to_string(&mut text).unwrap();
            text
        })
    };
    out.write(b"through the pipe\n").unwrap();
    assert_eq!(reader.join().unwrap(), "through the pipe\n");
    assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    assert!(temps(&dir).is_empty());
}

#[test]
fn a_character_device_is_written_directly_and_stays_a_device() {
    let dir = scratch("device");
    let null = dir.join("null");
    // A null device of our own (major 1, minor 3), never the real /dev/null.
    let made = Command::new("mknod").arg(&null).args(["c", "1", "3"]).output();
    match made {
        Ok(o) if o.status.success() => {}
        other => {
            println!("skipped: cannot make a character device here ({other:?})");
            return;
        }
    }
    let out = OutputPath::check(&null).unwrap();
    assert!(matches!(
        out.destination(),
        Destination::Special {
            kind: Special::CharDevice,
            ..
        }
    ));
    out.write(&[1; 4096]).unwrap();
    let mut appended = out.append().unwrap();
    appended.write_all(b"line\n").unwrap();
    appended.commit().unwrap();
    assert!(fs::symlink_metadata(&null).unwrap().file_type().is_char_device());
    assert!(temps(&dir).is_empty());
}

#[test]
fn a_symlink_is_followed_and_stays_a_link() {
    let dir = scratch("symlink");
    fs::create_dir(dir.join("real")).unwrap();
    let target = dir.join("real/model.bin");
    fs::write(&target, "old").unwrap();
    let link = dir.join("link.bin");
    std::os::unix::fs::symlink("real/model.bin", &link).unwrap();
    // A link to the link, too.
    let link2 = dir.join("link2.bin");
    std::os::unix::fs::symlink(&link, &link2).unwrap();
    let out = OutputPath::check(&link2).unwrap();
    assert_eq!(
        out.destination(),
        &Destination::File {
            target: dir.join("real/model.bin")
        }
    );
    out.write(b"new").unwrap();
    assert_eq!(fs::read_to_string(&target).unwrap(), "new");
    assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert!(fs::symlink_metadata(&link2).unwrap().file_type().is_symlink());
    // The temporary file was made beside the target, not beside the link.
    assert!(temps(&dir).is_empty() && temps(&dir.join("real")).is_empty());
    // A dangling link creates its target.
    let dangling = dir.join("dangling.bin");
    std::os::unix::fs::symlink("real/created.bin", &dangling).unwrap();
    files::write(&dangling, b"made").unwrap();
    assert_eq!(fs::read_to_string(dir.join("real/created.bin")).unwrap(), "made");
    assert!(fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
    // A link to a directory is a directory.
    std::os::unix::fs::symlink("real", dir.join("to-dir")).unwrap();
    assert!(
        OutputPath::check(dir.join("to-dir"))
            .unwrap_err()
            .to_string()
            .contains("is a directory")
    );
}

#[test]
fn appending_keeps_what_is_there_and_writes_in_place() {
    let dir = scratch("append");
    let path = dir.join("demos.jsonl");
    let out = OutputPath::check(&path).unwrap();
    for line in ["one\n", "two\n"] {
        let mut w = out.append().unwrap();
        w.write_all(line.as_bytes()).unwrap();
        w.flush().unwrap();
        // In place: the line is in the file before any commit, and no temporary exists.
        assert!(fs::read_to_string(&path).unwrap().ends_with(line));
        assert!(temps(&dir).is_empty());
        w.commit().unwrap();
    }
    assert_eq!(fs::read_to_string(&path).unwrap(), "one\ntwo\n");
}

#[test]
fn an_output_that_is_an_input_is_refused() {
    let dir = scratch("same");
    let model = dir.join("model.bin");
    fs::write(&model, "m").unwrap();
    let err = refuse_same_file(&model, &model).unwrap_err().to_string();
    assert!(err.contains("model.bin") && err.contains("another file"), "{err}");
    // Other spellings, a symlink and a hard link of the same file.
    let dotted = dir.join(".").join("sub").join("..").join("model.bin");
    fs::create_dir(dir.join("sub")).unwrap();
    assert!(refuse_same_file(&dotted, &model).is_err());
    std::os::unix::fs::symlink(&model, dir.join("link")).unwrap();
    assert!(refuse_same_file(dir.join("link"), &model).is_err());
    fs::hard_link(&model, dir.join("hard")).unwrap();
    assert!(refuse_same_file(dir.join("hard"), &model).is_err());
    // A new output path against a missing input: compared as paths.
    assert!(refuse_same_file(dir.join("sub/../new.bin"), dir.join("new.bin")).is_err());
    assert!(refuse_same_file(dir.join("other.bin"), &model).is_ok());
    assert!(refuse_same_file(dir.join("other.bin"), dir.join("missing.bin")).is_ok());
}

#[test]
fn a_folder_output_is_made_if_missing() {
    let dir = scratch("folder");
    let report = dir.join("a/b/report");
    prepare_folder(&report).unwrap();
    assert!(report.is_dir());
    prepare_folder(&report).unwrap();
    fs::write(dir.join("file"), "").unwrap();
    assert!(
        prepare_folder(dir.join("file"))
            .unwrap_err()
            .to_string()
            .contains("not a folder")
    );
    assert!(temps(&report).is_empty());
}

#[test]
fn stale_temporary_files_of_the_same_destination_are_removed_by_the_next_write() {
    let dir = tempfile::tempdir().unwrap();
    let dir = dir.path();
    // No process has an id this large (Linux's pid_max is at most 2^22).
    let gone = 999_999_999u32;
    let own = std::process::id();
    let names = [
        format!(".out.st.{gone}-0.tmp"),
        format!(".out.st.{gone}-12.tmp"),
        format!(".out.st.{own}-77.tmp"),
        format!(".other.st.{gone}-0.tmp"),
        format!(".out.st.x.{gone}-0.tmp"),
        format!(".out.st.{gone}-0.tmp.bak"),
        ".out.st.1-.tmp".to_string(),
        "out.st.999999999-0.tmp".to_string(),
    ];
    for name in &names {
        std::fs::write(dir.join(name), b"stale").unwrap();
    }
    let out = OutputPath::check(dir.join("out.st")).unwrap();
    let left = |name: &String| dir.join(name).exists();
    // Only the dead process's files for exactly this destination went.
    assert!(!left(&names[0]) && !left(&names[1]));
    assert!(names[2..].iter().all(left), "others kept");
    std::fs::write(dir.join(&names[0]), b"stale again").unwrap();
    let mut o = out.create().unwrap();
    o.write_all(b"new").unwrap();
    o.commit().unwrap();
    assert!(!left(&names[0]));
    assert_eq!(std::fs::read(dir.join("out.st")).unwrap(), b"new");
}

#[test]
fn check_regular_takes_files_and_new_paths_and_refuses_the_rest() {
    let dir = scratch("regular_only");
    let file = dir.join("plan.txt");
    assert!(OutputPath::check_regular(&file).is_ok(), "a new path");
    fs::write(&file, "old").unwrap();
    let link = dir.join("link.txt");
    std::os::unix::fs::symlink(&file, &link).unwrap();
    OutputPath::check_regular(&link).unwrap().write(b"new").unwrap();
    assert_eq!(fs::read_to_string(&file).unwrap(), "new");
    assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    let fifo = dir.join("pipe");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("mkfifo runs")
            .success()
    );
    let err = OutputPath::check_regular(&fifo).unwrap_err().to_string();
    assert!(err.contains("it is a named pipe, not a regular file"), "{err}");
    let err = OutputPath::check_regular("-").unwrap_err().to_string();
    assert!(err.contains("it is standard output, not a regular file"), "{err}");
    let err = OutputPath::check_regular(&dir).unwrap_err().to_string();
    assert!(err.starts_with(&format!("cannot write {}", dir.display())), "{err}");
}
