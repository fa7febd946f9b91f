//! One parameter store for every network: its named tensors laid out in flat buffers.
//!
//! Why one: both networks ([`crate::net::QNet`] and [`crate::relational::RelationalNet`])
//! keep their values in one flat buffer, so that the optimiser ([`crate::optim`]) updates
//! them in one fused pass, and both name their tensors for the network file
//! ([`crate::netfile`]) and the checkpoint. The table of names, shapes and places lives here
//! once, with the file's view of it ([`NamedTensor`]) and the one way a file's tensor is set.
//!
//! Trainable values are the parameters; values a network keeps beside them but never
//! trains (batch normalisation's running statistics) are the buffers, which the optimiser
//! never sees and a file stores after the parameters.

use crate::error::{NeuralError, Result};

/// Where a tensor lives in a flat buffer.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slot {
    /// Its first value's index.
    pub(crate) offset: usize,
    /// Its number of values.
    pub(crate) len: usize,
}

impl Slot {
    /// Its values' indices.
    pub(crate) fn range(self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.len
    }
}

/// One of a network's named tensors, as a network file stores it.
#[derive(Clone, Copy, Debug)]
pub struct NamedTensor<'a> {
    /// Its name (`conv1.weight`, `linear2.bias`, `conv1.bn.running_mean`, ...).
    pub name: &'a str,
    /// Its shape.
    pub shape: &'a [usize],
    /// Its values, row-major.
    pub values: &'a [f32],
}

/// A named tensor's entry in the table: its shape and where it lives.
#[derive(Clone, Debug)]
struct TensorInfo {
    name: String,
    shape: Vec<usize>,
    slot: Slot,
    /// Among the buffers (never trained), not the parameters.
    buffer: bool,
}

/// A network's tensors: the table of names, shapes and slots, the parameters and the
/// buffers, each tensor after the one added before it.
#[derive(Clone, Debug, Default)]
pub(crate) struct ParamStore {
    tensors: Vec<TensorInfo>,
    /// Every trainable value, tensor after tensor.
    pub(crate) params: Vec<f32>,
    /// Every value kept but never trained, tensor after tensor.
    pub(crate) buffers: Vec<f32>,
}

impl ParamStore {
    /// Appends a tensor named `name` of `shape` holding `values` to the parameters, or to
    /// the buffers when `buffer`; its slot.
    pub(crate) fn add(&mut self, name: &str, values: Vec<f32>, shape: &[usize], buffer: bool) -> Slot {
        debug_assert_eq!(
            values.len(),
            shape.iter().product::<usize>(),
            "{name}'s values fill its shape"
        );
        let store = if buffer { &mut self.buffers } else { &mut self.params };
        let slot = Slot {
            offset: store.len(),
            len: values.len(),
        };
        store.extend(values);
        self.tensors.push(TensorInfo {
            name: name.to_string(),
            shape: shape.to_vec(),
            slot,
            buffer,
        });
        slot
    }

    /// Every named tensor: the parameters, then the buffers, each in the order added.
    pub(crate) fn tensors(&self) -> impl Iterator<Item = NamedTensor<'_>> {
        let params = self.tensors.iter().filter(|t| !t.buffer);
        params
            .chain(self.tensors.iter().filter(|t| t.buffer))
            .map(|t| NamedTensor {
                name: &t.name,
                shape: &t.shape,
                values: if t.buffer {
                    &self.buffers[t.slot.range()]
                } else {
                    &self.params[t.slot.range()]
                },
            })
    }

    /// Where the parameter `name` lives in the parameters (`None` for a buffer or an
    /// unknown name).
    pub(crate) fn param_range(&self, name: &str) -> Option<std::ops::Range<usize>> {
        self.tensors
            .iter()
            .find(|t| t.name == name && !t.buffer)
            .map(|t| t.slot.range())
    }

    /// Sets the tensor named `name` to `values` (a file's); an error naming it if there is
    /// no such tensor or its shape differs.
    pub(crate) fn set_tensor(&mut self, name: &str, shape: &[usize], values: &[f32]) -> Result<()> {
        let t = self
            .tensors
            .iter()
            .find(|t| t.name == name)
            .ok_or_else(|| NeuralError::Mismatch(format!("the network has no tensor {name}")))?;
        if t.shape != shape || values.len() != t.slot.len {
            return Err(NeuralError::Mismatch(format!(
                "tensor {name} is {:?} in the network and {shape:?} in the file",
                t.shape
            )));
        }
        let store = if t.buffer { &mut self.buffers } else { &mut self.params };
        store[t.slot.range()].copy_from_slice(values);
        Ok(())
    }

    /// Sets every parameter and buffer to `other`'s (a store of the same layout).
    pub(crate) fn copy_from(&mut self, other: &ParamStore) {
        self.params.copy_from_slice(&other.params);
        self.buffers.copy_from_slice(&other.buffers);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_lists_parameters_then_buffers_and_sets_them_by_name() {
        let mut store = ParamStore::default();
        let w = store.add("w", vec![1.0, 2.0], &[2], false);
        let mean = store.add("mean", vec![0.5], &[1], true);
        let b = store.add("b", vec![3.0], &[1], false);
        assert_eq!((w.range(), mean.range(), b.range()), (0..2, 0..1, 2..3));
        let names: Vec<&str> = store.tensors().map(|t| t.name).collect();
        assert_eq!(names, ["w", "b", "mean"]);
        assert_eq!(store.param_range("b"), Some(2..3));
        assert_eq!(store.param_range("mean"), None);
        store.set_tensor("mean", &[1], &[7.0]).unwrap();
        assert_eq!(store.buffers, [7.0]);
        let wrong = store.set_tensor("w", &[1, 2], &[0.0, 0.0]).unwrap_err().to_string();
        assert!(wrong.contains("tensor w is [2]"), "{wrong}");
        assert!(
            store
                .set_tensor("x", &[1], &[0.0])
                .unwrap_err()
                .to_string()
                .contains("no tensor x")
        );
    }
}
