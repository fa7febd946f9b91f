//! Network files: named `f32` tensors in a safetensors file, with the format's name, its
//! version and a CRC-32 of the tensors in the file's metadata, written atomically.
//!
//! This module is the one seam between the neural learner and the project's model
//! container: it writes through `sim::files`' atomic writer and checks integrity itself until
//! `files::container` (the project's safetensors container for every model file) lands, and
//! then becomes a thin call into it. Nothing else in the crate touches the file format.
//!
//! The checksum is the CRC-32 of every tensor, in name order: its name's bytes, then its
//! values (4 bytes each, little-endian). A reader refuses a file that is not safetensors, is
//! cut short, lacks the metadata, is of another format or version, or whose tensors do not
//! match the checksum, each with a message that says which.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use safetensors::tensor::{Dtype, SafeTensors, TensorView};

use crate::error::{NeuralError, Result};

/// What a network file holds besides its tensors.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Header {
    /// The format's name, e.g. `blockstack-dqn`.
    pub format: String,
    /// The format's version.
    pub version: u32,
    /// Every other metadata entry, by key.
    pub metadata: BTreeMap<String, String>,
}

/// A tensor: name, shape and values.
pub type NamedTensor = (String, Vec<usize>, Vec<f32>);

fn checksum<'a>(tensors: impl Iterator<Item = (&'a str, &'a [f32])>) -> u32 {
    let mut h = crc32fast::Hasher::new();
    for (name, values) in tensors {
        h.update(name.as_bytes());
        for v in values {
            h.update(&v.to_le_bytes());
        }
    }
    h.finalize()
}

/// Writes `tensors` to `path` with `header`, atomically.
pub fn write(path: &Path, header: &Header, tensors: &[NamedTensor]) -> Result<()> {
    let mut sorted: Vec<&NamedTensor> = tensors.iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    let bytes: Vec<Vec<u8>> = sorted
        .iter()
        .map(|(_, _, v)| v.iter().flat_map(|x| x.to_le_bytes()).collect())
        .collect();
    let views = sorted
        .iter()
        .zip(&bytes)
        .map(|((name, shape, _), data)| Ok((name.as_str(), TensorView::new(Dtype::F32, shape.clone(), data)?)))
        .collect::<std::result::Result<Vec<_>, safetensors::SafeTensorError>>()
        .map_err(|e| write_error(path, &e))?;
    let mut metadata: HashMap<String, String> = header.metadata.clone().into_iter().collect();
    metadata.insert("format".into(), header.format.clone());
    metadata.insert("version".into(), header.version.to_string());
    metadata.insert(
        "checksum".into(),
        checksum(sorted.iter().map(|(n, _, v)| (n.as_str(), v.as_slice()))).to_string(),
    );
    let out = safetensors::serialize(views, Some(metadata)).map_err(|e| write_error(path, &e))?;
    sim::files::write_atomic(path, &out)?;
    Ok(())
}

fn write_error(path: &Path, e: &dyn std::fmt::Display) -> NeuralError {
    NeuralError::Sim(sim::files::write_error(path, e))
}

/// The header of the file at `path`, if it is a network file of any format and version
/// (`None` for anything else: a JSON model, a text file, a missing file).
pub fn peek(path: &Path) -> Option<Header> {
    let bytes = std::fs::read(path).ok()?;
    let (_, metadata) = SafeTensors::read_metadata(&bytes).ok()?;
    header(metadata.metadata().as_ref()?).ok()
}

fn header(m: &HashMap<String, String>) -> std::result::Result<Header, String> {
    let format = m.get("format").ok_or("it has no format name in its metadata")?.clone();
    let version = m
        .get("version")
        .and_then(|v| v.parse().ok())
        .ok_or("it has no format version in its metadata")?;
    let metadata = m
        .iter()
        .filter(|(k, _)| !matches!(k.as_str(), "format" | "version"))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    Ok(Header {
        format,
        version,
        metadata,
    })
}

/// Reads the file at `path`, which must be of `format` version `version`: its header and its
/// tensors in name order, checked against the checksum.
pub fn read(path: &Path, format: &str, version: u32) -> Result<(Header, Vec<NamedTensor>)> {
    let fail = |reason: String| NeuralError::Model {
        path: path.display().to_string(),
        reason,
    };
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let tensors = SafeTensors::deserialize(&bytes).map_err(|e| {
        fail(format!(
            "it is not a network file, or it is truncated or corrupt (safetensors: {e})"
        ))
    })?;
    let (_, metadata) = SafeTensors::read_metadata(&bytes).map_err(|e| fail(e.to_string()))?;
    let meta = metadata
        .metadata()
        .as_ref()
        .ok_or_else(|| fail("it has no metadata: it is not a blockstack network file".into()))?;
    let header = header(meta).map_err(|r| fail(r.to_string()))?;
    if header.format != format {
        return Err(fail(format!("it is a {} file, not {format}", header.format)));
    }
    if header.version != version {
        return Err(fail(format!(
            "it is {format} version {}, and this blockstack reads version {version}",
            header.version
        )));
    }
    let mut out = Vec::new();
    let mut names: Vec<String> = tensors.names().into_iter().map(String::from).collect();
    names.sort();
    for name in names {
        let view = tensors.tensor(&name).map_err(|e| fail(e.to_string()))?;
        if view.dtype() != Dtype::F32 {
            return Err(fail(format!("tensor {name} is {:?}, not f32", view.dtype())));
        }
        let values: Vec<f32> = view
            .data()
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        out.push((name, view.shape().to_vec(), values));
    }
    let expected: Option<u32> = header.metadata.get("checksum").and_then(|c| c.parse().ok());
    if expected != Some(checksum(out.iter().map(|(n, _, v)| (n.as_str(), v.as_slice())))) {
        return Err(fail(
            "the tensors do not match the file's checksum: the file is corrupt".into(),
        ));
    }
    Ok((header, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Header {
        Header {
            format: "test-format".into(),
            version: 2,
            metadata: [("config".to_string(), "{}".to_string())].into_iter().collect(),
        }
    }

    #[test]
    fn round_trip_and_every_kind_of_damage_is_named() {
        let dir = std::env::temp_dir().join(format!("neural-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("n.safetensors");
        let tensors = vec![
            ("b".to_string(), vec![2], vec![1.5, -2.0]),
            ("a".to_string(), vec![1, 3], vec![0.1, 0.2, 0.3]),
        ];
        write(&path, &header(), &tensors).unwrap();
        let (h, read_back) = read(&path, "test-format", 2).unwrap();
        assert_eq!((h.format.as_str(), h.version), ("test-format", 2));
        assert_eq!(h.metadata["config"], "{}");
        assert_eq!(read_back, vec![tensors[1].clone(), tensors[0].clone()]);
        assert_eq!(peek(&path).unwrap().format, "test-format");

        let err = |bytes: &[u8]| {
            std::fs::write(&path, bytes).unwrap();
            read(&path, "test-format", 2).unwrap_err().to_string()
        };
        let good = {
            write(&path, &header(), &tensors).unwrap();
            std::fs::read(&path).unwrap()
        };
        assert!(err(&good[..good.len() - 3]).contains("truncated or corrupt"));
        let mut flipped = good.clone();
        *flipped.last_mut().unwrap() ^= 0x40;
        assert!(err(&flipped).contains("checksum"));
        assert!(err(b"{\"format\":\"blockstack-q-agent\"}").contains("not a network file"));
        std::fs::write(&path, &good).unwrap();
        assert!(read(&path, "other", 2).unwrap_err().to_string().contains("not other"));
        assert!(
            read(&path, "test-format", 1)
                .unwrap_err()
                .to_string()
                .contains("version 2")
        );
        assert!(peek(&dir.join("missing")).is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
