//! Optimisers over the network's flat parameter buffer: RMSprop (the paper's) and Adam.
//!
//! PyTorch's update rules with its default constants, no weight decay of their own
//! (DQfD's L2 term is added to the gradient here, on the learner's word), and an optional
//! clip of the gradients' global norm. The parameters and the gradients are each one flat
//! slice ([`crate::net::QNet::params`]), so a step is at most two passes over memory, in
//! place: with a clip, one that adds the L2 term and measures the norm; then one that
//! updates the moments and the weights, cut in two fixed halves that two threads share.
//! Nothing is allocated after the optimiser is made. Subnormal values flush to zero
//! ([`crate::kernels::without_subnormals`]): the moments of weights no input reaches decay
//! into them.

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
    /// gradients' global norm before the clip when there is a clip; without one the norm is
    /// not measured, and `grads` is left as it was.
    ///
    /// Without a clip a step is one pass over memory: each value's update reads only its
    /// own weight, gradient and moments. The pass is cut into two fixed halves
    /// ([`crate::kernels::both`]), on two threads when the pool has them, which give the
    /// bits one pass does: the network's largest pass over memory (Adam reads and writes
    /// four values a parameter) is shared. A clip needs the norm first, a pass of its own.
    pub fn step(&mut self, params: &mut [f32], grads: &mut [f32], l2: f64, clip: Option<f64>) -> Option<f64> {
        assert!(
            params.len() == self.first.len() && grads.len() == params.len(),
            "the optimiser's parameters"
        );
        self.steps += 1;
        let t = self.steps.min(i32::MAX as u64) as i32;
        let k = if l2 > 0.0 { (2.0 * l2) as f32 } else { 0.0 };
        // With a clip, the L2 term is added to `grads` by the pass that measures the norm.
        let (norm, settings) = match clip {
            Some(clip) => {
                let (norm, scale) = crate::kernels::without_subnormals(|| measure(params, grads, k, clip));
                (Some(norm), (self.kind, self.lr, t, 0.0, scale))
            }
            None => (None, (self.kind, self.lr, t, k, 1.0)),
        };
        let grads = &*grads;
        let parts = crate::kernels::parts(params.len(), MIN_HALF);
        let half = crate::kernels::part_start(params.len(), parts, 1);
        let (params_a, params_b) = params.split_at_mut(half);
        let (grads_a, grads_b) = grads.split_at(half);
        let (first_a, first_b) = self.first.split_at_mut(half);
        // Adam's second moment, or RMSprop's empty one.
        let second_half = half.min(self.second.len());
        let (second_a, second_b) = self.second.split_at_mut(second_half);
        crate::kernels::both(
            parts,
            || update(settings, params_a, grads_a, first_a, second_a),
            || update(settings, params_b, grads_b, first_b, second_b),
        );
        norm
    }
}

/// Parameters each half of the update pass must hold, or it stays whole
/// ([`crate::kernels::parts`]): two threads' hand-off costs more than half a shorter pass.
const MIN_HALF: usize = 1 << 15;

/// What one update needs beside the buffers: the kind, the learning rate, the step number
/// (from 1), the L2 term's factor still to add to each gradient (0 once added) and the
/// factor the clip scales the gradients by.
type Settings = (OptimizerKind, f32, i32, f32, f32);

crate::kernels::avx2_dispatch! {
    fn measure => measure_any(params: &[f32], grads: &mut [f32], k: f32, clip: f64) -> (f64, f32)
}

crate::kernels::avx2_dispatch! {
    fn update => update_any(
        settings: Settings,
        params: &mut [f32],
        grads: &[f32],
        first: &mut [f32],
        second: &mut [f32],
    )
}

/// [`Optimizer::step`]'s pass before a clip: adds `k * w` to the gradients (unless `k` is
/// 0) and returns their global norm and the factor the clip scales them by.
#[inline(always)]
fn measure_any(params: &[f32], grads: &mut [f32], k: f32, clip: f64) -> (f64, f32) {
    // Eight partial sums in a fixed order (value `i` into sum `i % 8`): vectorised, and the
    // same bits every time. Each sum's additions form a chain, so each round works on a
    // local copy of the eight, which the compiler keeps in registers: updated in the array
    // itself, every addition also waited for the store of the one before.
    let mut lanes = [0.0f64; 8];
    let add = |g: &mut f32, w: f32, lane: &mut f64| {
        if k != 0.0 {
            *g += k * w;
        }
        *lane += f64::from(*g) * f64::from(*g);
    };
    let mut g_eights = grads.chunks_exact_mut(8);
    let mut w_eights = params.chunks_exact(8);
    for (g, w) in g_eights.by_ref().zip(w_eights.by_ref()) {
        let g: &mut [f32; 8] = g.try_into().expect("eight values");
        let w: &[f32; 8] = w.try_into().expect("eight values");
        let mut eight = lanes;
        for j in 0..8 {
            add(&mut g[j], w[j], &mut eight[j]);
        }
        lanes = eight;
    }
    let rest = g_eights.into_remainder().iter_mut().zip(w_eights.remainder());
    for ((g, &w), lane) in rest.zip(lanes.iter_mut()) {
        add(g, w, lane);
    }
    let norm = lanes.iter().sum::<f64>().sqrt();
    let scale = if norm > clip && norm > 0.0 {
        (clip / norm) as f32
    } else {
        1.0
    };
    (norm, scale)
}

/// [`Optimizer::step`]'s update of one part of the buffers: the moments and the weights,
/// from each gradient plus its L2 term, scaled.
#[inline(always)]
fn update_any(
    (kind, lr, t, k, scale): Settings,
    params: &mut [f32],
    grads: &[f32],
    first: &mut [f32],
    second: &mut [f32],
) {
    // The gradient the measuring pass would have stored: `g + k * w`, then scaled.
    let gradient = |g: f32, w: f32| (if k != 0.0 { g + k * w } else { g }) * scale;
    match kind {
        OptimizerKind::Rmsprop => {
            for ((w, &g), sq) in params.iter_mut().zip(grads.iter()).zip(first.iter_mut()) {
                let g = gradient(g, *w);
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
                let g = gradient(g, *w);
                *m = b1 * *m + (1.0 - b1) * g;
                *s = b2 * *s + (1.0 - b2) * g * g;
                *w -= step * *m / ((*s * inv_c2).sqrt() + EPS);
            }
        }
    }
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
        let norm = opt
            .step(&mut w, &mut grad, 0.0, Some(1.0))
            .expect("a clip measures the norm");
        assert!((norm - 100.0).abs() < 1e-3, "gradient (-60, -80) has norm 100: {norm}");
    }

    #[test]
    fn the_l2_term_adds_to_the_gradient() {
        // w = 2, zero loss gradient, l2 0.25: the gradient is 2 * 0.25 * 2 = 1.
        let mut w = [2f32];
        let mut opt = Optimizer::new(OptimizerKind::Adam, 0.1, 1);
        let mut opt_clipped = Optimizer::new(OptimizerKind::Adam, 0.1, 1);
        let norm = opt_clipped
            .step(&mut [2.0], &mut [0.0], 0.25, Some(100.0))
            .expect("a clip measures the norm");
        assert!((norm - 1.0).abs() < 1e-9, "{norm}");
        assert_eq!(opt.step(&mut w, &mut [0.0], 0.25, None), None, "no clip, no norm");
        assert!((w[0] - 1.9).abs() < 1e-5, "{w:?}");
    }

    #[test]
    fn a_step_cut_in_halves_on_two_threads_gives_the_bits_of_one_pass() {
        // A buffer cut in two: three steps of each optimiser on a pool of two threads,
        // against the same steps as one whole pass over every buffer.
        let count = MIN_HALF * 4 + 40;
        let value = |i: usize, k: u64| ((i as u64 * 2_654_435_761 + k * 97) % 2_001) as f32 / 1_000.0 - 1.0;
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for kind in [OptimizerKind::Adam, OptimizerKind::Rmsprop] {
            let mut cut: Vec<f32> = (0..count).map(|i| value(i, 0)).collect();
            let mut whole = cut.clone();
            let mut opt = Optimizer::new(kind, 0.01, count);
            let (mut first, mut second) = (opt.first.clone(), opt.second.clone());
            for step in 1..=3 {
                let grads: Vec<f32> = (0..count).map(|i| value(i, step)).collect();
                // Without a clip (one fused pass, cut in two), then with one (the norm
                // pass first): each against the two passes over the whole buffers.
                let clip = (step == 3).then_some(50.0);
                pool.install(|| opt.step(&mut cut, &mut grads.clone(), 1e-4, clip));
                let mut g = grads.clone();
                let (_, scale) = measure_any(&whole, &mut g, 2e-4, clip.unwrap_or(f64::INFINITY));
                update_any(
                    (kind, 0.01, step as i32, 0.0, scale),
                    &mut whole,
                    &g,
                    &mut first,
                    &mut second,
                );
            }
            assert_eq!(crate::kernels::parts(count, MIN_HALF), 2, "the buffer is cut");
            let differ = cut
                .iter()
                .zip(&whole)
                .filter(|(a, b)| a.to_bits() != b.to_bits())
                .count();
            assert_eq!(differ, 0, "{kind}: {differ} of {count} weights differ");
            assert_eq!(
                (&opt.first, &opt.second),
                (&first, &second),
                "{kind}: the moments differ"
            );
        }
    }
}
