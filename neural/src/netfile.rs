//! The container the network files share (`files::container`: safetensors with blockstack's
//! metadata and a CRC-32): a network's tensors written with its metadata, and read back with
//! the checks every network file gets. What each file holds (its format, version, metadata
//! and network) is its owner's: [`crate::model`] and [`crate::relational::model`].

use std::io::Read;
use std::path::Path;

use files::container::{Container, Expect, Tensor};
use files::{FilesError, OutputPath};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::error::{NeuralError, Result};
use crate::params::NamedTensor;

/// Writes a network file of `expect`'s format and version to `path`: `metadata` and one
/// `F32` tensor per item of `tensors`, through the project's output helper (atomically for a
/// regular file).
pub(crate) fn save<'t, M: Serialize>(
    path: &Path,
    expect: &Expect<'_>,
    metadata: &M,
    tensors: impl Iterator<Item = NamedTensor<'t>>,
) -> Result<()> {
    let out = OutputPath::check(path)?;
    let tensors: Vec<(&str, Tensor<'_>)> = tensors
        .map(|t| {
            let tensor = Tensor::from_values(t.shape, t.values).expect("a tensor's shape fits its values");
            (t.name, tensor)
        })
        .collect();
    files::container::write(&out, expect.format, expect.version, metadata, &tensors)?;
    Ok(())
}

/// A network file read and checked as a container, not yet as a network: its errors name
/// the file.
pub(crate) struct NetFile {
    name: String,
    container: Container,
}

impl NetFile {
    /// Reads the file at `path`: an error if it is missing, too large, truncated, corrupt, or
    /// of another format or version than `expect`'s.
    pub(crate) fn open(path: &Path, expect: &Expect<'_>) -> Result<NetFile> {
        let name = path.display().to_string();
        let input = files::open_bounded(path, expect.max_bytes, expect.what).map_err(|e| read_failure(&name, e))?;
        NetFile::read_from(input, &name, expect)
    }

    /// [`NetFile::open`] from the bytes of a file, named `name` in errors.
    pub(crate) fn read_from(input: impl Read, name: &str, expect: &Expect<'_>) -> Result<NetFile> {
        let container = Container::read_from(input, name, expect).map_err(|e| read_failure(name, e))?;
        Ok(NetFile {
            name: name.to_string(),
            container,
        })
    }

    /// An error about this file.
    pub(crate) fn fail(&self, reason: String) -> NeuralError {
        NeuralError::Model {
            path: self.name.clone(),
            reason,
        }
    }

    /// The file's metadata; an error if it does not read as `M`.
    pub(crate) fn metadata<M: DeserializeOwned>(&self) -> Result<M> {
        self.container
            .metadata()
            .map_err(|e| self.fail(format!("the file is corrupt: its metadata does not read ({e})")))
    }

    /// `checked` (the stored training config's validation) as an error about this file.
    pub(crate) fn config_checked<E: std::fmt::Display>(&self, checked: std::result::Result<(), E>) -> Result<()> {
        checked.map_err(|e| self.fail(format!("its training config is not valid: {e}")))
    }

    /// Sets every tensor of the file with `set` (a network's `set_tensor`), once the file is
    /// known to hold `expected` tensors, the count of `network` (named so in the error).
    pub(crate) fn fill(
        &self,
        network: &str,
        expected: usize,
        mut set: impl FnMut(&str, &[usize], &[f32]) -> Result<()>,
    ) -> Result<()> {
        let names = self.container.names();
        if names.len() != expected {
            return Err(self.fail(format!(
                "it holds {} tensors, and {network} has {expected}",
                names.len()
            )));
        }
        for name in names {
            let tensor = self.container.tensor(&name).expect("a name of the container");
            let values = tensor
                .values::<f32>()
                .ok_or_else(|| self.fail(format!("tensor {name} is {:?}, not F32", tensor.dtype())))?;
            set(&name, tensor.shape(), &values).map_err(|e| self.fail(e.to_string()))?;
        }
        Ok(())
    }
}

/// A file error while reading network `name`, as one line naming it.
fn read_failure(name: &str, e: FilesError) -> NeuralError {
    NeuralError::Model {
        path: name.to_string(),
        reason: match e {
            FilesError::Read { problem, .. } => problem.to_string(),
            other => other.to_string(),
        },
    }
}
