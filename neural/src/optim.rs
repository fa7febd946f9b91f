//! Optimisers over the network's flat parameter buffer: RMSprop (the paper's) and Adam.
//!
//! PyTorch's update rules with its default constants, no weight decay of their own
//! (DQfD's L2 term is added to the gradient here, on the learner's word), and an optional
//! clip of the gradients' global norm. The parameters and the gradients are each one flat
//! slice ([`crate::net::QNet::params`]), so a step is two passes over memory, in place: one
//! that adds the L2 term and measures the norm, one that updates the moments and the
//! weights. Nothing is allocated after the optimiser is made. Subnormal values flush to
//! zero ([`crate::kernels::without_subnormals`]): the moments of weights no input reaches
//! decay into them.

use serde::{Deserialize, Serialize};

use crate::error::NeuralError;

/// Which optimiser.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OptimizerKind {
    /// RMSprop (PyTorch's: smoothing 0.99, epsilon 1e-8, no momentum): the paper's.
    Rmsprop,
    /// Adam (beta 0.9 / 0.999, epsilon 1e-8, bias-corrected).
    Adam,
}

sim::names!(OptimizerKind { Rmsprop = "rmsprop", Adam = "adam" } unknown(text) -> NeuralError {
    NeuralError::Config(format!("unknown optimiser {text:?}: choose rmsprop or adam"))
});

const RMS_ALPHA: f32 = 0.99;
const ADAM_BETAS: (f32, f32) = (0.9, 0.999);
const EPS: f32 = 1e-8;

/// An optimiser's state for a flat buffer of parameters.
pub struct Optimizer {
    kind: OptimizerKind,
    lr: f32,
    /// RMSprop's square average, or Adam's first moment.
    first: Vec<f32>,
    /// Adam's second moment (empty for RMSprop).
    second: Vec<f32>,
    steps: u64,
}

impl Optimizer {
    /// An optimiser for `count` parameters with learning rate `lr`.
    pub fn new(kind: OptimizerKind, lr: f64, count: usize) -> Optimizer {
        Optimizer {
            kind,
            lr: lr as f32,
            first: vec![0.0; count],
            second: if kind == OptimizerKind::Adam {
                vec![0.0; count]
            } else {
                Vec::new()
            },
            steps: 0,
        }
    }

    /// Changes the learning rate of the next steps.
    pub fn set_lr(&mut self, lr: f64) {
        self.lr = lr as f32;
    }

    /// The learning rate of the next step.
    pub(crate) fn lr(&self) -> f32 {
        self.lr
    }

    /// Steps taken (Adam's bias correction counts them).
    pub(crate) fn steps(&self) -> u64 {
        self.steps
    }

    /// The moments: RMSprop's square average or Adam's first moment, and Adam's second
    /// (empty for RMSprop).
    pub(crate) fn moments(&self) -> (&[f32], &[f32]) {
        (&self.first, &self.second)
    }

    /// An optimiser of `kind` for `count` parameters in the state these values describe
    /// (a checkpoint's); an error unless the moments fit `kind` and `count`.
    pub(crate) fn restore(
        kind: OptimizerKind,
        count: usize,
        lr: f32,
        steps: u64,
        first: Vec<f32>,
        second: Vec<f32>,
    ) -> Result<Optimizer, String> {
        let second_len = if kind == OptimizerKind::Adam { count } else { 0 };
        if first.len() != count || second.len() != second_len {
            return Err(format!(
                "its {kind} moments hold {} and {} values, and the network has {count} parameters",
                first.len(),
                second.len()
            ));
        }
        Ok(Optimizer {
            kind,
            lr,
            first,
            second,
            steps,
        })
    }

    /// One update of `params` from `grads` (the same length, the optimiser's): adds
    /// `2 * l2 * w` to each gradient (an L2 term `l2 * sum w^2` in the loss), scales all
    /// gradients down to a global norm of at most `clip` when given, and steps. Returns the
    /// gradients' global norm before the clip.
    pub fn step(&mut self, params: &mut [f32], grads: &mut [f32], l2: f64, clip: Option<f64>) -> f64 {
        assert!(
            params.len() == self.first.len() && grads.len() == params.len(),
            "the optimiser's parameters"
        );
        self.steps += 1;
        let t = self.steps.min(i32::MAX as u64) as i32;
        let settings = (self.kind, self.lr, t, l2, clip);
        let (first, second) = (&mut self.first, &mut self.second);
        crate::kernels::without_subnormals(|| update(settings, params, grads, first, second))
    }
}

/// What one update needs beside the buffers: the kind, the learning rate, the step number
/// (from 1), the L2 weight and the clip.
type Settings = (OptimizerKind, f32, i32, f64, Option<f64>);

crate::kernels::avx2_dispatch! {
    fn update => update_any(
        settings: Settings,
        params: &mut [f32],
        grads: &mut [f32],
        first: &mut [f32],
        second: &mut [f32],
    ) -> f64
}

/// [`Optimizer::step`]'s two passes.
#[inline(always)]
fn update_any(
    (kind, lr, t, l2, clip): Settings,
    params: &mut [f32],
    grads: &mut [f32],
    first: &mut [f32],
    second: &mut [f32],
) -> f64 {
    let k = (2.0 * l2) as f32;
    // Eight partial sums in a fixed order: vectorised, and the same bits every time.
    let mut lanes = [0.0f64; 8];
    for (g, w) in grads.chunks_mut(8).zip(params.chunks(8)) {
        for ((g, &w), lane) in g.iter_mut().zip(w).zip(lanes.iter_mut()) {
            if l2 > 0.0 {
                *g += k * w;
            }
            *lane += f64::from(*g) * f64::from(*g);
        }
    }
    let norm = lanes.iter().sum::<f64>().sqrt();
    let scale = match clip {
        Some(c) if norm > c && norm > 0.0 => (c / norm) as f32,
        _ => 1.0,
    };
    match kind {
        OptimizerKind::Rmsprop => {
            for ((w, &g), sq) in params.iter_mut().zip(grads.iter()).zip(first.iter_mut()) {
                let g = g * scale;
                *sq = RMS_ALPHA * *sq + (1.0 - RMS_ALPHA) * g * g;
                *w -= lr * g / (sq.sqrt() + EPS);
            }
        }
        OptimizerKind::Adam => {
            // w -= lr * (m / c1) / (sqrt(s / c2) + eps), with the bias corrections folded
            // into the constants: one division a value.
            let (b1, b2) = ADAM_BETAS;
            let (c1, c2) = (1.0 - b1.powi(t), 1.0 - b2.powi(t));
            let (step, inv_c2) = (lr / c1, 1.0 / c2);
            let moments = first.iter_mut().zip(second.iter_mut());
            for ((w, &g), (m, s)) in params.iter_mut().zip(grads.iter()).zip(moments) {
                let g = g * scale;
                *m = b1 * *m + (1.0 - b1) * g;
                *s = b2 * *s + (1.0 - b2) * g * g;
                *w -= step * *m / ((*s * inv_c2).sqrt() + EPS);
            }
        }
    }
    norm
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Minimises (w - 3)^2 from w = 0.
    fn minimise(kind: OptimizerKind, lr: f64, steps: usize) -> f32 {
        let mut w = [0f32];
        let mut opt = Optimizer::new(kind, lr, 1);
        for _ in 0..steps {
            let mut grad = [2.0 * (w[0] - 3.0)];
            opt.step(&mut w, &mut grad, 0.0, None);
        }
        w[0]
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
        let mut w = [0f32, 0.0];
        let mut opt = Optimizer::new(OptimizerKind::Rmsprop, 0.01, 2);
        // The gradient of (w - (30, 40))^2 at 0.
        let mut grad = [-60f32, -80.0];
        let norm = opt.step(&mut w, &mut grad, 0.0, Some(1.0));
        assert!((norm - 100.0).abs() < 1e-3, "gradient (-60, -80) has norm 100: {norm}");
    }

    #[test]
    fn the_l2_term_adds_to_the_gradient() {
        // w = 2, zero loss gradient, l2 0.25: the gradient is 2 * 0.25 * 2 = 1.
        let mut w = [2f32];
        let mut opt = Optimizer::new(OptimizerKind::Adam, 0.1, 1);
        let norm = opt.step(&mut w, &mut [0.0], 0.25, None);
        assert!((norm - 1.0).abs() < 1e-9 && (w[0] - 1.9).abs() < 1e-5, "{norm} {w:?}");
    }
}
