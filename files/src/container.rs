//! The model container: named tensors plus JSON metadata in a safetensors file.
//!
//! [safetensors](https://github.com/huggingface/safetensors) is the ML ecosystem's plain
//! tensor file: 8 bytes (a little-endian `u64`, the header's length), a JSON header, then
//! the tensors' raw little-endian bytes, C order, one after another. numpy reads it with
//! a dozen lines, Python's `safetensors` package and candle with one call. The header
//! maps each tensor's name to its `dtype`, `shape` and `data_offsets`, and its
//! `__metadata__` entry (a map of strings) holds, for a blockstack file:
//!
//! | key | value |
//! |---|---|
//! | `format` | the kind of file, e.g. `blockstack-q-agent` |
//! | `version` | the format's version, a decimal integer |
//! | `crc32` | 8 hex digits: the CRC-32 of the data section (every byte after the header) followed by the bytes of `metadata` |
//! | `metadata` | the writer's own JSON document (configs, shapes, whatever it needs) |
//!
//! In Python, the check is `zlib.crc32(meta["metadata"].encode(), zlib.crc32(data)) ==
//! int(meta["crc32"], 16)`.
//!
//! [`Container::read`] refuses, each with one line saying which: a file that is not
//! safetensors, one of another format, a newer or older version, a corrupt file (an
//! inconsistent header, bytes after the last tensor, a checksum that does not match) and
//! a truncated one. It reads through [`crate::open_bounded`]: the header is read and
//! checked first, and a file whose declared size passes the caller's bound is refused
//! before its tensors are read.

use std::borrow::Cow;
use std::io::{self, Read};
use std::path::Path;

pub use safetensors::Dtype;
use safetensors::SafeTensors;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::{FilesError, ReadProblem, Result};
use crate::input::open_bounded;
use crate::output::OutputPath;

/// The safetensors library's own limit on a header's size.
const MAX_HEADER_BYTES: u64 = 100_000_000;

/// What a reader expects of a container file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Expect<'a> {
    /// The `format` name.
    pub format: &'a str,
    /// The version this build reads.
    pub version: u32,
    /// The largest file of this format, in bytes.
    pub max_bytes: u64,
    /// The kind of file in errors ("a model file").
    pub what: &'static str,
}

/// A number type a tensor can hold, with its safetensors dtype.
pub trait Element: Copy {
    /// The dtype of a tensor of these.
    const DTYPE: Dtype;
    /// Bytes per element.
    const SIZE: usize;
    /// Appends the little-endian bytes of `self`.
    fn put(self, out: &mut Vec<u8>);
    /// Reads one from `SIZE` little-endian bytes.
    fn get(bytes: &[u8]) -> Self;
}

macro_rules! element {
    ($t:ty, $dtype:ident) => {
        impl Element for $t {
            const DTYPE: Dtype = Dtype::$dtype;
            const SIZE: usize = std::mem::size_of::<$t>();
            fn put(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
            fn get(bytes: &[u8]) -> Self {
                <$t>::from_le_bytes(bytes.try_into().expect("SIZE bytes"))
            }
        }
    };
}

element!(u8, U8);
element!(i8, I8);
element!(u16, U16);
element!(i16, I16);
element!(u32, U32);
element!(i32, I32);
element!(u64, U64);
element!(i64, I64);
element!(f32, F32);
element!(f64, F64);
element!(half::f16, F16);
element!(half::bf16, BF16);

/// One tensor: a dtype, a shape (C order) and its little-endian bytes, owned (to write)
/// or borrowed from a [`Container`] (read).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tensor<'a> {
    dtype: Dtype,
    shape: Vec<usize>,
    data: Cow<'a, [u8]>,
}

impl<'a> Tensor<'a> {
    /// A tensor of `values` with `shape`; `None` if the shape does not hold exactly as
    /// many values.
    pub fn from_values<T: Element>(shape: &[usize], values: &[T]) -> Option<Tensor<'static>> {
        if element_count(shape)? != values.len() {
            return None;
        }
        let mut data = Vec::with_capacity(values.len() * T::SIZE);
        for &v in values {
            v.put(&mut data);
        }
        Some(Tensor {
            dtype: T::DTYPE,
            shape: shape.to_vec(),
            data: Cow::Owned(data),
        })
    }

    /// The element type.
    pub fn dtype(&self) -> Dtype {
        self.dtype
    }

    /// The shape, outermost dimension first.
    pub fn shape(&self) -> &[usize] {
        &self.shape
    }

    /// The raw little-endian bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.data
    }

    /// The values, if the tensor holds `T`s.
    pub fn values<T: Element>(&self) -> Option<Vec<T>> {
        (self.dtype == T::DTYPE).then(|| self.data.chunks_exact(T::SIZE).map(T::get).collect())
    }
}

fn element_count(shape: &[usize]) -> Option<usize> {
    shape.iter().try_fold(1usize, |n, &d| n.checked_mul(d))
}

/// The bytes of a container file holding `tensors` (name, tensor) and `metadata` (any
/// serialisable document) as `format` version `version` (module docs).
///
/// The layout is safetensors' own (tensors ordered by alignment, then name; the header
/// padded with spaces to a multiple of 8 bytes), and the header's keys are sorted, so the
/// same contents always give the same bytes.
pub fn to_bytes(
    format: &str,
    version: u32,
    metadata: &impl Serialize,
    tensors: &[(&str, Tensor<'_>)],
) -> std::result::Result<Vec<u8>, String> {
    let mut names: Vec<&str> = tensors.iter().map(|(name, _)| *name).collect();
    names.sort_unstable();
    if let Some(pair) = names.windows(2).find(|pair| pair[0] == pair[1]) {
        return Err(format!("two tensors are named {:?}", pair[0]));
    }
    let mut order: Vec<&(&str, Tensor<'_>)> = tensors.iter().collect();
    order.sort_by(|(a_name, a), (b_name, b)| b.dtype.cmp(&a.dtype).then(a_name.cmp(b_name)));
    let text = serde_json::to_string(metadata).map_err(|e| format!("cannot write its metadata: {e}"))?;
    let mut header = serde_json::Map::new();
    let mut data = Vec::with_capacity(tensors.iter().map(|(_, t)| t.data.len()).sum());
    for (name, t) in order {
        if *name == "__metadata__" {
            return Err("a tensor cannot be named __metadata__".into());
        }
        let start = data.len();
        data.extend_from_slice(&t.data);
        header.insert(
            (*name).to_string(),
            serde_json::json!({"dtype": t.dtype, "shape": t.shape, "data_offsets": [start, data.len()]}),
        );
    }
    header.insert(
        "__metadata__".into(),
        serde_json::json!({
            "format": format,
            "version": version.to_string(),
            "crc32": format!("{:08x}", checksum(&data, &text)),
            "metadata": text,
        }),
    );
    let mut head = serde_json::to_vec(&header).map_err(|e| format!("cannot write its header: {e}"))?;
    head.resize(head.len().next_multiple_of(8), b' ');
    let mut bytes = Vec::with_capacity(8 + head.len() + data.len());
    bytes.extend_from_slice(&(head.len() as u64).to_le_bytes());
    bytes.extend_from_slice(&head);
    bytes.extend_from_slice(&data);
    Ok(bytes)
}

/// Writes a container file (module docs) to `out`, through the output helper (atomically
/// for a regular file).
pub fn write(
    out: &OutputPath,
    format: &str,
    version: u32,
    metadata: &impl Serialize,
    tensors: &[(&str, Tensor<'_>)],
) -> Result<()> {
    let bytes = to_bytes(format, version, metadata, tensors).map_err(|reason| FilesError::Write {
        path: out.path().display().to_string(),
        reason,
        kind: io::ErrorKind::InvalidInput,
    })?;
    out.write(&bytes)
}

fn checksum(data: &[u8], metadata: &str) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(data);
    h.update(metadata.as_bytes());
    h.finalize()
}

/// A container file read and checked (module docs).
#[derive(Debug)]
pub struct Container {
    format: String,
    version: u32,
    metadata: String,
    /// The whole file.
    bytes: Vec<u8>,
    /// Where the data section starts in `bytes`.
    data_start: usize,
    layout: safetensors::tensor::Metadata,
}

impl Container {
    /// Reads and checks the container file at `path` (module docs).
    pub fn read(path: &Path, expect: &Expect<'_>) -> Result<Container> {
        let reader = open_bounded(path, expect.max_bytes, expect.what)?;
        Container::read_from(reader, &path.display().to_string(), expect)
    }

    /// Reads and checks a container file from `reader`, named `name` in errors. A
    /// [`crate::BoundedReader`]'s error is reported as the file being too large.
    pub fn read_from(mut reader: impl Read, name: &str, expect: &Expect<'_>) -> Result<Container> {
        let fail = |problem| FilesError::read(name, problem);
        let too_large = || {
            fail(ReadProblem::TooLarge {
                bound: expect.max_bytes,
                what: expect.what,
            })
        };
        let io_fail = |e: io::Error| {
            if e.kind() == io::ErrorKind::FileTooLarge {
                too_large()
            } else {
                fail(ReadProblem::Io(e.to_string()))
            }
        };
        let mut bytes = vec![0; 8];
        let got = read_up_to(&mut reader, &mut bytes).map_err(io_fail)?;
        if got == 0 {
            return Err(fail(ReadProblem::Truncated("it is empty".into())));
        }
        // A header length is below 2^27: its last four bytes are zero.
        if got > 4 && bytes[4..got].iter().any(|&b| b != 0) {
            return Err(fail(ReadProblem::NotSafetensors(
                "its first bytes are not the length of a header".into(),
            )));
        }
        if got < 8 {
            return Err(fail(ReadProblem::Truncated(format!(
                "it ends after {got} bytes, inside the 8-byte length of its header"
            ))));
        }
        let n = u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes"));
        if !(2..=MAX_HEADER_BYTES).contains(&n) {
            return Err(fail(ReadProblem::NotSafetensors(format!(
                "its first 8 bytes give a header of {n} bytes"
            ))));
        }
        if 8 + n > expect.max_bytes {
            return Err(too_large());
        }
        let n = n as usize;
        let got = read_more(&mut reader, &mut bytes, n as u64).map_err(io_fail)?;
        if got == 0 {
            return Err(fail(ReadProblem::Truncated(format!(
                "it ends after the length of its header ({n} bytes)"
            ))));
        }
        if bytes[8] != b'{' {
            return Err(fail(ReadProblem::NotSafetensors(
                "its header is not a JSON object".into(),
            )));
        }
        if got < n {
            return Err(fail(ReadProblem::Truncated(format!(
                "it ends {} bytes into a header of {n} bytes",
                got
            ))));
        }
        let header: serde_json::Map<String, serde_json::Value> = serde_json::from_slice(&bytes[8..])
            .map_err(|e| fail(ReadProblem::Corrupt(format!("its header is not valid JSON ({e})"))))?;
        // Where the data section ends, from the largest end offset declared.
        let data_len = header
            .iter()
            .filter(|(key, _)| *key != "__metadata__")
            .map(|(key, info)| {
                info.get("data_offsets")
                    .and_then(|o| o.get(1))
                    .and_then(serde_json::Value::as_u64)
                    .ok_or_else(|| fail(ReadProblem::Corrupt(format!("tensor {key:?} has no data offsets"))))
            })
            .try_fold(0u64, |end, e| e.map(|e| end.max(e)))?;
        if (8 + n as u64).saturating_add(data_len) > expect.max_bytes {
            return Err(too_large());
        }
        let data_start = 8 + n;
        let got = read_more(&mut reader, &mut bytes, data_len).map_err(io_fail)?;
        if got < data_len as usize {
            return Err(fail(ReadProblem::Truncated(format!(
                "its tensors take {data_len} bytes, and it ends after {got}"
            ))));
        }
        let mut extra = [0u8; 1];
        if read_up_to(&mut reader, &mut extra).map_err(io_fail)? > 0 {
            return Err(fail(ReadProblem::Corrupt(
                "there are bytes after its last tensor".into(),
            )));
        }
        let (_, layout) = SafeTensors::read_metadata(&bytes).map_err(|e| {
            fail(ReadProblem::Corrupt(format!(
                "its header does not describe its tensors ({e})"
            )))
        })?;
        let meta = layout.metadata().clone().unwrap_or_default();
        let other_format = |found: Option<&String>| {
            fail(ReadProblem::OtherFormat {
                expected: expect.format.into(),
                found: found.cloned(),
            })
        };
        match meta.get("format") {
            Some(f) if f == expect.format => {}
            found => return Err(other_format(found)),
        }
        let version: u32 = meta
            .get("version")
            .and_then(|v| v.parse().ok())
            .ok_or_else(|| fail(ReadProblem::Corrupt("its version is missing or not a number".into())))?;
        if version != expect.version {
            let (format, found, supported) = (expect.format.to_string(), version, expect.version);
            return Err(fail(if version > expect.version {
                ReadProblem::Newer {
                    format,
                    found,
                    supported,
                }
            } else {
                ReadProblem::Older {
                    format,
                    found,
                    supported,
                }
            }));
        }
        let crc = meta
            .get("crc32")
            .and_then(|c| u32::from_str_radix(c, 16).ok())
            .ok_or_else(|| {
                fail(ReadProblem::Corrupt(
                    "its checksum is missing or not hexadecimal".into(),
                ))
            })?;
        let metadata = meta
            .get("metadata")
            .cloned()
            .ok_or_else(|| fail(ReadProblem::Corrupt("its metadata is missing".into())))?;
        if checksum(&bytes[data_start..], &metadata) != crc {
            return Err(fail(ReadProblem::Corrupt(
                "its contents do not match their checksum".into(),
            )));
        }
        Ok(Container {
            format: expect.format.into(),
            version,
            metadata,
            bytes,
            data_start,
            layout,
        })
    }

    /// The format name.
    pub fn format(&self) -> &str {
        &self.format
    }

    /// The format version.
    pub fn version(&self) -> u32 {
        self.version
    }

    /// The writer's metadata, as JSON text.
    pub fn metadata_text(&self) -> &str {
        &self.metadata
    }

    /// The writer's metadata, read as a `T`.
    pub fn metadata<T: DeserializeOwned>(&self) -> serde_json::Result<T> {
        serde_json::from_str(&self.metadata)
    }

    /// The tensors' names, in file order.
    pub fn names(&self) -> Vec<String> {
        self.layout.offset_keys()
    }

    /// The tensor `name`, borrowing the file's bytes.
    pub fn tensor(&self, name: &str) -> Option<Tensor<'_>> {
        let info = self.layout.info(name)?;
        let (start, end) = info.data_offsets;
        Some(Tensor {
            dtype: info.dtype,
            shape: info.shape.clone(),
            data: Cow::Borrowed(&self.bytes[self.data_start + start..self.data_start + end]),
        })
    }
}

/// Appends up to `len` bytes of `reader` to `bytes`, stopping early where the input ends;
/// how many were read. Memory grows with what arrives, not with what a header declares.
fn read_more(reader: &mut impl Read, bytes: &mut Vec<u8>, len: u64) -> io::Result<usize> {
    let before = bytes.len();
    bytes.reserve(len.min(1 << 26) as usize);
    reader.take(len).read_to_end(bytes)?;
    Ok(bytes.len() - before)
}

/// Fills `buf` from `reader` until it is full or the input ends; how many bytes were read.
fn read_up_to(reader: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match reader.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(k) => got += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}
