//! The safetensors container: round trips of every element type, and every refusal.

use files::container::to_bytes;
use files::{Container, Dtype, Expect, OutputPath, ReadProblem, Tensor};
use proptest::prelude::*;
use serde_json::json;

const EXPECT: Expect<'static> = Expect {
    format: "test-format",
    version: 3,
    max_bytes: 1 << 20,
    what: "a test file",
};

use testkit::scratch;

fn sample() -> Vec<u8> {
    let tensors = [
        (
            "values",
            Tensor::from_values(&[2, 3], &[1.5f32, -2.0, 0.0, -0.0, 1e-40, 3e38]).unwrap(),
        ),
        ("keys", Tensor::from_values(&[2], &[7u32, 9]).unwrap()),
    ];
    to_bytes("test-format", 3, &json!({"grid": [7, 7], "name": "sample"}), &tensors).unwrap()
}

fn parse(bytes: &[u8]) -> Result<Container, files::FilesError> {
    Container::read_from(bytes, "x.safetensors", &EXPECT)
}

fn problem(bytes: &[u8]) -> ReadProblem {
    match parse(bytes).unwrap_err() {
        files::FilesError::Read { path, problem } => {
            assert_eq!(path, "x.safetensors");
            problem
        }
        other => panic!("{other}"),
    }
}

#[test]
fn every_element_type_round_trips_bit_for_bit() {
    let dir = scratch("round-trip");
    let path = dir.join("all.safetensors");
    let f16s: Vec<half::f16> = [0.5f32, -1.0, 65504.0]
        .iter()
        .map(|&v| half::f16::from_f32(v))
        .collect();
    let bf16s: Vec<half::bf16> = [0.5f32, -1.0].iter().map(|&v| half::bf16::from_f32(v)).collect();
    let tensors = [
        ("u8", Tensor::from_values(&[3], &[0u8, 1, 255]).unwrap()),
        ("i8", Tensor::from_values(&[3], &[-128i8, 0, 127]).unwrap()),
        ("u16", Tensor::from_values(&[1, 2], &[0u16, u16::MAX]).unwrap()),
        ("i16", Tensor::from_values(&[2], &[i16::MIN, i16::MAX]).unwrap()),
        ("u32", Tensor::from_values(&[2], &[0u32, u32::MAX]).unwrap()),
        ("i32", Tensor::from_values(&[2], &[i32::MIN, -1]).unwrap()),
        ("u64", Tensor::from_values(&[2], &[0u64, u64::MAX]).unwrap()),
        ("i64", Tensor::from_values(&[2], &[i64::MIN, 5]).unwrap()),
        (
            "f32",
            Tensor::from_values(&[2, 2], &[f32::MIN_POSITIVE, -0.0, f32::NAN, f32::MAX]).unwrap(),
        ),
        ("f64", Tensor::from_values(&[1], &[std::f64::consts::PI]).unwrap()),
        ("f16", Tensor::from_values(&[3], &f16s).unwrap()),
        ("bf16", Tensor::from_values(&[2], &bf16s).unwrap()),
        ("empty", Tensor::from_values::<u32>(&[0], &[]).unwrap()),
    ];
    let meta = json!({"nested": {"a": [1, 2.5, null]}, "text": "é"});
    files::container::write(&OutputPath::check(&path).unwrap(), "test-format", 3, &meta, &tensors).unwrap();
    let c = Container::read(&path, &EXPECT).unwrap();
    assert_eq!((c.format(), c.version()), ("test-format", 3));
    assert_eq!(c.metadata::<serde_json::Value>().unwrap(), meta);
    let mut names = c.names();
    names.sort();
    let mut expected: Vec<String> = tensors.iter().map(|(n, _)| n.to_string()).collect();
    expected.sort();
    assert_eq!(names, expected);
    for (name, t) in &tensors {
        let read = c.tensor(name).unwrap();
        assert_eq!(read.dtype(), t.dtype(), "{name}");
        assert_eq!(read.shape(), t.shape(), "{name}");
        assert_eq!(read.bytes(), t.bytes(), "{name}");
    }
    let f32s: Vec<u32> = c
        .tensor("f32")
        .unwrap()
        .values::<f32>()
        .unwrap()
        .iter()
        .map(|v| v.to_bits())
        .collect();
    assert_eq!(f32s, [f32::MIN_POSITIVE, -0.0, f32::NAN, f32::MAX].map(f32::to_bits));
    assert_eq!(c.tensor("u64").unwrap().values::<u64>().unwrap(), [0, u64::MAX]);
    assert!(
        c.tensor("u64").unwrap().values::<i64>().is_none(),
        "the dtype must match"
    );
    assert!(c.tensor("missing").is_none());
    // The safetensors library itself reads it.
    let bytes = std::fs::read(&path).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    assert_eq!(st.tensor("i8").unwrap().dtype(), Dtype::I8);
}

#[test]
fn the_same_contents_give_the_same_bytes() {
    let tensors = || {
        [
            ("b", Tensor::from_values(&[2], &[1.0f32, 2.0]).unwrap()),
            ("a", Tensor::from_values(&[3], &[1u8, 2, 3]).unwrap()),
        ]
    };
    let meta = json!({"z": 1, "a": [1, 2]});
    let first = to_bytes("f", 1, &meta, &tensors()).unwrap();
    for _ in 0..10 {
        assert_eq!(to_bytes("f", 1, &meta, &tensors()).unwrap(), first);
    }
    // The header is padded to a multiple of 8 bytes, so the tensors are aligned.
    assert_eq!(u64::from_le_bytes(first[..8].try_into().unwrap()) % 8, 0);
}

#[test]
fn bad_tensor_sets_are_not_written() {
    let t = || Tensor::from_values(&[1], &[1u8]).unwrap();
    assert!(Tensor::from_values(&[2, 2], &[1u8; 3]).is_none());
    assert!(
        to_bytes("f", 1, &json!(null), &[("a", t()), ("a", t())])
            .unwrap_err()
            .contains("two tensors")
    );
    let other = Tensor::from_values(&[1], &[1.0f32]).unwrap();
    assert!(to_bytes("f", 1, &json!(null), &[("a", t()), ("b", t()), ("a", other)]).is_err());
    assert!(to_bytes("f", 1, &json!(null), &[("__metadata__", t())]).is_err());
}

#[test]
fn files_that_are_not_containers_are_refused_with_the_reason() {
    let json_model = br#"{"format":"blockstack-q-agent","version":1,"grid":{"width":7,"height":7}}"#;
    assert!(matches!(problem(json_model), ReadProblem::NotSafetensors(_)));
    assert!(matches!(problem(&[0u8; 4096]), ReadProblem::NotSafetensors(_)));
    assert!(matches!(problem(b"hello, world\n"), ReadProblem::NotSafetensors(_)));
    assert!(matches!(problem(b"garbage"), ReadProblem::NotSafetensors(_)));
    assert!(matches!(problem(b""), ReadProblem::Truncated(_)));
    let mut not_json = 8u64.to_le_bytes().to_vec();
    not_json.extend(b"{garbage");
    assert!(matches!(problem(&not_json), ReadProblem::Corrupt(_)));
    // A safetensors file without blockstack's metadata, and one of another format.
    let plain = safetensors::serialize(
        [(
            "t",
            safetensors::tensor::TensorView::new(Dtype::U8, vec![1], &[1]).unwrap(),
        )],
        None,
    )
    .unwrap();
    assert_eq!(
        problem(&plain),
        ReadProblem::OtherFormat {
            expected: "test-format".into(),
            found: None
        }
    );
    let other = to_bytes("other-format", 3, &json!(null), &[]).unwrap();
    let p = problem(&other);
    assert!(
        p.to_string().contains("other-format") && p.to_string().contains("test-format"),
        "{p}"
    );
}

#[test]
fn versions_other_than_the_readers_are_refused() {
    let newer = to_bytes("test-format", 4, &json!(null), &[]).unwrap();
    let p = problem(&newer);
    assert!(matches!(
        p,
        ReadProblem::Newer {
            found: 4,
            supported: 3,
            ..
        }
    ));
    assert!(p.to_string().contains("newer"), "{p}");
    let older = to_bytes("test-format", 2, &json!(null), &[]).unwrap();
    assert!(matches!(
        problem(&older),
        ReadProblem::Older {
            found: 2,
            supported: 3,
            ..
        }
    ));
}

#[test]
fn a_changed_byte_is_caught_by_the_checksum() {
    let bytes = sample();
    parse(&bytes).unwrap();
    let n = 8 + u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    // Every byte of the data section.
    for at in n..bytes.len() {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        assert!(matches!(problem(&bad), ReadProblem::Corrupt(_)), "byte {at}");
    }
    // A digit of the caller's metadata.
    let at = bytes
        .windows(5)
        .position(|w| w == b"[7,7]")
        .expect("the grid in the metadata");
    let mut changed = bytes.clone();
    changed[at + 3] = b'8';
    assert!(matches!(problem(&changed), ReadProblem::Corrupt(_)));
    // Bytes after the last tensor.
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(problem(&longer).to_string().contains("after its last tensor"));
}

#[test]
fn a_file_larger_than_the_bound_is_refused_before_its_tensors_are_read() {
    let bytes = sample();
    let small = Expect {
        max_bytes: bytes.len() as u64 - 1,
        ..EXPECT
    };
    let err = Container::read_from(&bytes[..], "x", &small).unwrap_err().to_string();
    assert!(err.contains("the most a test file can be"), "{err}");
    // And from a path: by the file's size, before reading.
    let dir = scratch("bound");
    let path = dir.join("x.safetensors");
    std::fs::write(&path, &bytes).unwrap();
    let err = Container::read(&path, &small).unwrap_err().to_string();
    assert!(err.contains(&path.display().to_string()) && err.contains("the most a test file can be"));
    // An endless input (a device) is not read past the header.
    let endless = std::io::repeat(0);
    assert!(matches!(
        Container::read_from(endless, "zero", &EXPECT).unwrap_err(),
        files::FilesError::Read {
            problem: ReadProblem::NotSafetensors(_),
            ..
        }
    ));
}

#[test]
fn a_header_that_promises_more_than_the_file_holds_is_truncated() {
    // 500 MB declared, a few bytes present: refused as truncated, without reserving the
    // declared size first.
    let header = br#"{"t":{"dtype":"U8","shape":[500000000],"data_offsets":[0,500000000]}}"#;
    let mut bytes = (header.len() as u64).to_le_bytes().to_vec();
    bytes.extend_from_slice(header);
    bytes.extend_from_slice(&[0; 16]);
    let expect = Expect {
        max_bytes: 1 << 30,
        ..EXPECT
    };
    let err = Container::read_from(&bytes[..], "x", &expect).unwrap_err().to_string();
    assert!(err.contains("truncated") && err.contains("500000000"), "{err}");
}

proptest! {
    /// A file cut anywhere is refused, and as truncated.
    #[test]
    fn a_file_cut_short_anywhere_is_truncated(cut in 0usize..1000) {
        let bytes = sample();
        let cut = cut % bytes.len();
        let p = problem(&bytes[..cut]);
        prop_assert!(matches!(p, ReadProblem::Truncated(_)), "cut at {}: {}", cut, p);
    }
}

#[test]
fn the_format_of_a_file_is_read_from_its_header() {
    let dir = scratch("format-of");
    let file = dir.join("m.safetensors");
    std::fs::write(&file, sample()).unwrap();
    assert_eq!(
        files::container::format_of(&file, 1 << 20).as_deref(),
        Some("test-format")
    );
    for (name, bytes) in [
        ("json", &b"{\"format\":\"blockstack-q-agent\"}"[..]),
        ("empty", &b""[..]),
        ("cut", &sample()[..12]),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(files::container::format_of(&path, 1 << 20), None, "{name}");
    }
    assert_eq!(files::container::format_of(&dir.join("missing"), 1 << 20), None);
}
