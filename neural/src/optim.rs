//! Optimisers written over the network's variables: RMSprop (the paper's) and Adam.
//!
//! candle ships AdamW and SGD only, and its AdamW cost about 28 ms a step on the paper
//! network here (its default weight decay is also 0.01, which nobody asked for). These are
//! plain loops over each variable's values: PyTorch's update rules with its default
//! constants, no weight decay of their own (DQfD's L2 term is added to the gradient by the
//! learner), and an optional clip of the gradients' global norm.

use std::fmt;

use candle_core::backprop::GradStore;
use candle_core::{Device, Tensor, Var};
use serde::{Deserialize, Serialize};

use crate::error::{NeuralError, Result};

/// Which optimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OptimizerKind {
    /// RMSprop (PyTorch's: smoothing 0.99, epsilon 1e-8, no momentum): the paper's.
    Rmsprop,
    /// Adam (beta 0.9 / 0.999, epsilon 1e-8, bias-corrected).
    Adam,
}

impl OptimizerKind {
    /// The name it is chosen by.
    pub fn name(self) -> &'static str {
        match self {
            OptimizerKind::Rmsprop => "rmsprop",
            OptimizerKind::Adam => "adam",
        }
    }
}

impl fmt::Display for OptimizerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for OptimizerKind {
    type Err = NeuralError;

    fn from_str(text: &str) -> Result<OptimizerKind> {
        match text {
            "rmsprop" => Ok(OptimizerKind::Rmsprop),
            "adam" => Ok(OptimizerKind::Adam),
            _ => Err(NeuralError::Config(format!(
                "unknown optimiser {text:?}: choose rmsprop or adam"
            ))),
        }
    }
}

const RMS_ALPHA: f32 = 0.99;
const ADAM_BETAS: (f32, f32) = (0.9, 0.999);
const EPS: f32 = 1e-8;

/// An optimiser's state for a list of variables.
pub struct Optimizer {
    kind: OptimizerKind,
    lr: f32,
    /// Per variable: RMSprop's square average, or Adam's first and second moments.
    state: Vec<(Vec<f32>, Vec<f32>)>,
    steps: u64,
}

impl Optimizer {
    /// An optimiser for `params` with learning rate `lr`.
    pub fn new(kind: OptimizerKind, lr: f64, params: &[(String, Var)]) -> Optimizer {
        let state = params
            .iter()
            .map(|(_, v)| {
                let n = v.elem_count();
                (
                    vec![0.0; n],
                    if kind == OptimizerKind::Adam {
                        vec![0.0; n]
                    } else {
                        Vec::new()
                    },
                )
            })
            .collect();
        Optimizer {
            kind,
            lr: lr as f32,
            state,
            steps: 0,
        }
    }

    /// Changes the learning rate of the next steps.
    pub fn set_lr(&mut self, lr: f64) {
        self.lr = lr as f32;
    }

    /// One update of `params` from `grads`: adds `2 * l2 * w` to each gradient (an L2 term
    /// `l2 * sum w^2` in the loss), scales all gradients down to a global norm of at most
    /// `clip` when given, and steps. Returns the gradients' global norm before the clip.
    /// Variables without a gradient are left alone.
    pub fn step(&mut self, params: &[(String, Var)], grads: &GradStore, l2: f64, clip: Option<f64>) -> Result<f64> {
        let mut values = Vec::with_capacity(params.len());
        let mut gradients = Vec::with_capacity(params.len());
        for (_, v) in params {
            let w = v.as_tensor().flatten_all()?.to_vec1::<f32>()?;
            let g = match grads.get(v.as_tensor()) {
                Some(g) => {
                    let mut g = g.flatten_all()?.to_vec1::<f32>()?;
                    if l2 > 0.0 {
                        let k = (2.0 * l2) as f32;
                        g.iter_mut().zip(&w).for_each(|(g, w)| *g += k * w);
                    }
                    Some(g)
                }
                None => None,
            };
            values.push(w);
            gradients.push(g);
        }
        let norm = gradients
            .iter()
            .flatten()
            .flat_map(|g| g.iter())
            .map(|&g| f64::from(g) * f64::from(g))
            .sum::<f64>()
            .sqrt();
        let scale = match clip {
            Some(c) if norm > c && norm > 0.0 => (c / norm) as f32,
            _ => 1.0,
        };
        self.steps += 1;
        let t = self.steps as i32;
        for (i, (_, v)) in params.iter().enumerate() {
            let Some(g) = &gradients[i] else { continue };
            let w = &mut values[i];
            let (s1, s2) = &mut self.state[i];
            match self.kind {
                OptimizerKind::Rmsprop => {
                    for ((w, &g), sq) in w.iter_mut().zip(g).zip(s1.iter_mut()) {
                        let g = g * scale;
                        *sq = RMS_ALPHA * *sq + (1.0 - RMS_ALPHA) * g * g;
                        *w -= self.lr * g / (sq.sqrt() + EPS);
                    }
                }
                OptimizerKind::Adam => {
                    let (b1, b2) = ADAM_BETAS;
                    let (c1, c2) = (1.0 - b1.powi(t), 1.0 - b2.powi(t));
                    for (((w, &g), m), s) in w.iter_mut().zip(g).zip(s1.iter_mut()).zip(s2.iter_mut()) {
                        let g = g * scale;
                        *m = b1 * *m + (1.0 - b1) * g;
                        *s = b2 * *s + (1.0 - b2) * g * g;
                        *w -= self.lr * (*m / c1) / ((*s / c2).sqrt() + EPS);
                    }
                }
            }
            let shape = v.dims().to_vec();
            v.set(&Tensor::from_vec(std::mem::take(w), shape, &Device::Cpu)?)?;
        }
        Ok(norm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Minimises (w - 3)^2 from w = 0.
    fn minimise(kind: OptimizerKind, lr: f64, steps: usize) -> f32 {
        let w = Var::from_tensor(&Tensor::new(&[0f32], &Device::Cpu).unwrap()).unwrap();
        let params = vec![("w".to_string(), w.clone())];
        let mut opt = Optimizer::new(kind, lr, &params);
        for _ in 0..steps {
            let loss = (w.as_tensor() - 3.0).unwrap().sqr().unwrap().sum_all().unwrap();
            let grads = loss.backward().unwrap();
            opt.step(&params, &grads, 0.0, None).unwrap();
        }
        w.as_tensor().to_vec1::<f32>().unwrap()[0]
    }

    #[test]
    fn both_optimisers_descend() {
        assert!((minimise(OptimizerKind::Adam, 0.1, 300) - 3.0).abs() < 0.05);
        assert!((minimise(OptimizerKind::Rmsprop, 0.01, 600) - 3.0).abs() < 0.05);
    }

    #[test]
    fn the_first_rmsprop_and_adam_steps_match_pytorch() {
        // PyTorch, w = 0, loss (w - 3)^2, one step: RMSprop lr 0.01 gives w = 0.1 (the
        // normalised step is lr / sqrt(1 - alpha) = 0.1); Adam lr 0.1 gives w = 0.1.
        assert!((minimise(OptimizerKind::Rmsprop, 0.01, 1) - 0.1).abs() < 1e-5);
        assert!((minimise(OptimizerKind::Adam, 0.1, 1) - 0.1).abs() < 1e-5);
    }

    #[test]
    fn the_clip_bounds_the_global_norm() {
        let w = Var::from_tensor(&Tensor::new(&[0f32, 0.0], &Device::Cpu).unwrap()).unwrap();
        let params = vec![("w".to_string(), w.clone())];
        let mut opt = Optimizer::new(OptimizerKind::Rmsprop, 0.01, &params);
        let target = Tensor::new(&[30f32, 40.0], &Device::Cpu).unwrap();
        let loss = (w.as_tensor() - &target).unwrap().sqr().unwrap().sum_all().unwrap();
        let grads = loss.backward().unwrap();
        let norm = opt.step(&params, &grads, 0.0, Some(1.0)).unwrap();
        assert!((norm - 100.0).abs() < 1e-3, "gradient (-60, -80) has norm 100: {norm}");
    }
}
