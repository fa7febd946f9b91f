//! One gradient step of DQN or DQfD on a batch of transitions.
//!
//! For a batch of transitions `(s, a, r, s')` the loss is
//!
//! - **1-step TD**: `L(Q(s,a) - y)`, `y = r + gamma * max_a' Q_target(s', a')` (0 after the
//!   goal), `L` Huber or squared error. With double DQN the online network chooses `a'` and
//!   the target network values it.
//! - **n-step TD** (DQfD): the same with `y_n = r_t + ... + gamma^(k-1) r_(t+k-1) + gamma^k
//!   max_a' Q_target(s_(t+k), a')`, weighted `lambda_n_step`.
//! - **Large margin** (DQfD, demonstrated transitions only): `J_E = max_a [Q(s,a) + l(a_E,a)]
//!   - Q(s,a_E)`, `l` = the margin for `a != a_E` and 0 for `a_E`: zero exactly when the
//!   demonstrated action beats every other by the margin. Averaged over the demonstrated
//!   transitions of the batch, weighted `lambda_margin`.
//! - **L2** (DQfD): `l2 * sum w^2` over every weight, added to the gradient by the optimiser.
//!
//! Every maximum over actions (the targets' and the margin's) runs over the allowed actions
//! only ([`crate::mask`]).
//!
//! The losses' gradients with respect to the Q-values are written by hand here (each term
//! is a sum over the batch of a function of one or two Q-values); [`QNet::backward`] takes
//! them through the network. A maximum's gradient goes to its first maximal action. Every
//! buffer of a step (inputs, Q-values, gradients, the networks' workspaces) is kept from
//! one step to the next.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::config::{DqnConfig, LossKind, TdLoss};
use crate::error::Result;
use crate::input::{InputSpec, ObsKind};
use crate::kernels;
use crate::mask::{ActionSet, masked_argmax, masked_max};
use crate::net::{QNet, Workspace};
use crate::optim::Optimizer;
use crate::replay::Transition;

/// Stands in for minus infinity where a masked action must lose every maximum.
const MASKED: f32 = -1e9;

/// The parts of one step's loss.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Losses {
    /// The whole loss minimised (without L2).
    pub total: f32,
    /// The 1-step TD loss.
    pub td: f32,
    /// The n-step TD loss (0 without DQfD).
    pub n_step: f32,
    /// The large-margin loss (0 without DQfD or without demonstrated transitions).
    pub margin: f32,
}

/// The online and target networks, the optimiser, and the buffers of a step.
pub struct Learner {
    online: QNet,
    target: QNet,
    optimizer: Optimizer,
    gradient_steps: u64,
    /// The online network's training pass, and the target and choosing passes.
    train_ws: Workspace,
    eval_ws: [Workspace; 2],
    encoder: Encoder,
    x: Vec<f32>,
    next_x: Vec<f32>,
    target_q: Vec<f32>,
    chooser_q: Vec<f32>,
    y1: Vec<f32>,
    yn: Vec<f32>,
    dq: Vec<f32>,
    grad: Vec<f32>,
}

/// At most this many bytes of rendered screens are kept (about 8,700 screens); past it the
/// cache starts again empty.
const SCREEN_CACHE_BYTES: usize = 256 << 20;

/// Turns observations into the network's floats, for the learner's batches.
///
/// Rendering the paper's screen costs about 0.1 ms, and a DQfD step of the paper network
/// needs 192 of them (20-25 ms, as much as its arithmetic). A replay buffer samples the
/// same observations again and again (the demonstrations above all), so the rendered bytes
/// of each are kept, up to [`SCREEN_CACHE_BYTES`]. Planes cost little to encode and are
/// not kept. The inputs are the same either way.
#[derive(Default)]
struct Encoder {
    /// Each half's encoded bytes, before they become floats.
    bytes: [Vec<u8>; 2],
    screens: HashMap<sim::Observation, Box<[u8]>>,
    cached: usize,
    /// The samples of a batch whose screen is not yet cached, one per observation.
    missing: Vec<usize>,
    /// Their screens, rendered.
    rendered: [Vec<Box<[u8]>>; 2],
}

/// Samples each half of an encoding must hold, or it stays whole ([`kernels::parts`]):
/// a few samples' encoding costs less than handing them to another thread.
const MIN_HALF_ENCODE: usize = 16;

/// Screens each half of a batch's rendering must hold, or it stays whole: one screen
/// costs about 0.1 ms, far more than a hand-off.
const MIN_HALF_RENDER: usize = 2;

impl Encoder {
    /// The inputs of observations `0..count` as floats into `out`.
    ///
    /// Every part runs in two fixed halves, on two threads when the pool has them (each
    /// sample's floats are its own, so the bits are one pass's): planes and the compact
    /// screen are encoded whole; the paper's screens not yet cached are rendered, then
    /// kept, and every sample's floats read from the cache.
    fn encode<'a>(
        &mut self,
        spec: &InputSpec,
        count: usize,
        observation: impl Fn(usize) -> &'a sim::Observation + Sync,
        out: &mut Vec<f32>,
    ) {
        let width = spec.len();
        out.resize(count * width, 0.0);
        let scale = spec.scale();
        if spec.kind != ObsKind::PaperScreen {
            let part = |samples: std::ops::Range<usize>, bytes: &mut Vec<u8>, out: &mut [f32]| {
                bytes.clear();
                for i in samples {
                    spec.encode(observation(i), bytes);
                }
                to_floats(bytes, out, scale);
            };
            halves(count, MIN_HALF_ENCODE, width, out, &mut self.bytes, part);
            return;
        }
        // Room for the whole batch first, so that no screen it needs is dropped midway.
        if self.cached + count * width > SCREEN_CACHE_BYTES {
            self.screens.clear();
            self.cached = 0;
        }
        self.missing.clear();
        let mut seen = std::collections::HashSet::new();
        for i in 0..count {
            let obs = observation(i);
            if !self.screens.contains_key(obs) && seen.insert(obs) {
                self.missing.push(i);
            }
        }
        let missing = &self.missing;
        let render = |samples: &[usize], screens: &mut Vec<Box<[u8]>>| {
            screens.clear();
            screens.extend(samples.iter().map(|&i| {
                let mut bytes = Vec::with_capacity(width);
                spec.encode(observation(i), &mut bytes);
                bytes.into_boxed_slice()
            }));
        };
        let parts = kernels::parts(missing.len(), MIN_HALF_RENDER);
        let (first, second) = missing.split_at(kernels::part_start(missing.len(), parts, 1));
        let [rendered_a, rendered_b] = &mut self.rendered;
        kernels::both(parts, || render(first, rendered_a), || render(second, rendered_b));
        for (&i, screen) in missing.iter().zip(rendered_a.drain(..).chain(rendered_b.drain(..))) {
            self.screens.insert(observation(i).clone(), screen);
            self.cached += width;
        }
        let screens = &self.screens;
        let part = |samples: std::ops::Range<usize>, _: &mut Vec<u8>, out: &mut [f32]| {
            for (i, x) in samples.zip(out.chunks_exact_mut(width)) {
                to_floats(&screens[observation(i)], x, scale);
            }
        };
        halves(count, MIN_HALF_ENCODE, width, out, &mut self.bytes, part);
    }
}

/// Runs `part` on samples `0..count` in two fixed halves ([`kernels::parts`] with
/// `min_half`), each with its own byte buffer and its rows of `out` (`width` floats a
/// sample).
fn halves(
    count: usize,
    min_half: usize,
    width: usize,
    out: &mut [f32],
    bytes: &mut [Vec<u8>; 2],
    part: impl Fn(std::ops::Range<usize>, &mut Vec<u8>, &mut [f32]) + Sync,
) {
    let parts = kernels::parts(count, min_half);
    let half = kernels::part_start(count, parts, 1);
    let (out_a, out_b) = out.split_at_mut(half * width);
    let [bytes_a, bytes_b] = bytes;
    kernels::both(
        parts,
        || part(0..half, bytes_a, out_a),
        || part(half..count, bytes_b, out_b),
    );
}

kernels::avx2_dispatch! {
    fn to_floats => to_floats_any(bytes: &[u8], out: &mut [f32], scale: f32)
}

/// `out[i] = bytes[i] * scale`.
#[inline(always)]
fn to_floats_any(bytes: &[u8], out: &mut [f32], scale: f32) {
    for (x, &b) in out.iter_mut().zip(bytes) {
        *x = f32::from(b) * scale;
    }
}

/// A TD loss of the difference `d` and its derivative.
fn td_term(d: f32, kind: TdLoss) -> (f32, f32) {
    match kind {
        TdLoss::Mse => (d * d, 2.0 * d),
        TdLoss::Huber => {
            let a = d.abs();
            let c = a.min(1.0);
            (0.5 * c * c + (a - c), if a <= 1.0 { d } else { d.signum() })
        }
    }
}

/// The large margin of one demonstrated transition: `max_a [Q(s,a) + l(a_E,a)] - Q(s,a_E)`
/// over the allowed actions (`l` = `margin` but 0 at `expert`), and the action of the
/// maximum (its gradient is +1 there and -1 at `expert`).
pub fn margin_term(q: &[f32], expert: usize, allowed: ActionSet, margin: f32) -> (f32, usize) {
    let mut best = (f32::NEG_INFINITY, 0);
    for (a, &v) in q.iter().enumerate() {
        let l = if a == expert {
            0.0
        } else if allowed.contains(a) {
            margin
        } else {
            MASKED
        };
        if v + l > best.0 {
            best = (v + l, a);
        }
    }
    (best.0 - q[expert], best.1)
}

impl Learner {
    /// A learner starting from `online` (the target a copy of it).
    pub fn new(online: QNet, config: &DqnConfig) -> Result<Learner> {
        let target = online.try_clone()?;
        let optimizer = Optimizer::new(config.optimizer, config.lr, online.parameter_count());
        Ok(Learner::from_parts(online, target, optimizer, 0))
    }

    /// A learner in the state these parts describe (a checkpoint's): networks of the same
    /// shape, and an optimiser of their parameters.
    pub(crate) fn from_parts(online: QNet, target: QNet, optimizer: Optimizer, gradient_steps: u64) -> Learner {
        Learner {
            grad: vec![0.0; online.parameter_count()],
            online,
            target,
            optimizer,
            gradient_steps,
            train_ws: Workspace::new(),
            eval_ws: [Workspace::new(), Workspace::new()],
            encoder: Encoder::default(),
            x: Vec::new(),
            next_x: Vec::new(),
            target_q: Vec::new(),
            chooser_q: Vec::new(),
            y1: Vec::new(),
            yn: Vec::new(),
            dq: Vec::new(),
        }
    }

    /// The target network.
    pub(crate) fn target(&self) -> &QNet {
        &self.target
    }

    /// The optimiser.
    pub(crate) fn optimizer(&self) -> &Optimizer {
        &self.optimizer
    }

    /// The online network.
    pub fn online(&self) -> &QNet {
        &self.online
    }

    /// Gradient steps taken.
    pub fn gradient_steps(&self) -> u64 {
        self.gradient_steps
    }

    /// Changes the learning rate of the next steps.
    pub fn set_lr(&mut self, lr: f64) {
        self.optimizer.set_lr(lr);
    }

    /// Copies the online network into the target network.
    pub fn refresh_target(&mut self) -> Result<()> {
        self.target.copy_from(&self.online);
        Ok(())
    }

    /// One gradient step on `batch` (not empty) with `config`'s losses.
    pub fn step(&mut self, batch: &[&Transition], config: &DqnConfig) -> Result<Losses> {
        let losses = self.gradients(batch, config);
        let l2 = if config.loss == LossKind::Dqfd { config.l2 } else { 0.0 };
        self.optimizer
            .step(self.online.params_mut(), &mut self.grad, l2, config.clip_norm);
        self.gradient_steps += 1;
        Ok(losses)
    }

    /// The losses of `batch`, and their gradient with respect to the online network's
    /// parameters in `self.grad`; the training pass moves batch normalisation's running
    /// statistics.
    fn gradients(&mut self, batch: &[&Transition], config: &DqnConfig) -> Losses {
        let dqfd = config.loss == LossKind::Dqfd;
        let spec = *self.online.input();
        let b = batch.len();
        let actions = self.online.actions();
        self.targets(batch, config);

        // The online network's values, and the losses' gradient with respect to them.
        self.encoder.encode(&spec, b, |i| &batch[i].obs, &mut self.x);
        let q = self.online.forward_train(&self.x, &mut self.train_ws);
        self.dq.clear();
        self.dq.resize(b * actions, 0.0);
        let mut losses = Losses::default();
        let inv_b = 1.0 / b as f32;
        let experts = batch.iter().filter(|t| t.expert).count();
        let lambda_n = config.lambda_n_step as f32;
        let lambda_margin = config.lambda_margin as f32;
        for (i, t) in batch.iter().enumerate() {
            let row = i * actions;
            let taken = spec.column(&t.obs.goal, t.action);
            let q_taken = q[row + taken];
            let (l, g) = td_term(q_taken - self.y1[i], config.td_loss);
            losses.td += l * inv_b;
            self.dq[row + taken] += g * inv_b;
            if dqfd {
                let (l, g) = td_term(q_taken - self.yn[i], config.td_loss);
                losses.n_step += l * inv_b;
                self.dq[row + taken] += lambda_n * g * inv_b;
                if t.expert {
                    let weight = 1.0 / experts as f32;
                    let allowed = spec.allowed_columns(&t.obs, config.mask_noops);
                    let (j, best) = margin_term(&q[row..row + actions], taken, allowed, config.margin as f32);
                    losses.margin += j * weight;
                    self.dq[row + best] += lambda_margin * weight;
                    self.dq[row + taken] -= lambda_margin * weight;
                }
            }
        }
        losses.total = losses.td;
        if dqfd {
            losses.total += losses.n_step * lambda_n;
            if experts > 0 {
                losses.total += losses.margin * lambda_margin;
            }
        }
        self.online
            .backward(&self.x, &mut self.train_ws, &self.dq, &mut self.grad);
        losses
    }

    /// The TD targets of `batch`, without gradients: the one-step ones in `self.y1` and,
    /// under the DQfD loss, the n-step ones in `self.yn`, from the target network's values
    /// (with double DQN, at the online network's choices).
    fn targets(&mut self, batch: &[&Transition], config: &DqnConfig) {
        let dqfd = config.loss == LossKind::Dqfd;
        let spec = *self.online.input();
        let b = batch.len();
        let actions = self.online.actions();
        // Next observations, then the n-step ones.
        let next = |i: usize| {
            if i < b {
                &batch[i].next
            } else {
                &batch[i - b].n_step.last
            }
        };
        let count = if dqfd { 2 * b } else { b };
        self.encoder.encode(&spec, count, next, &mut self.next_x);
        // The target network's values, and with double DQN the online network's choices,
        // side by side on two threads when the pool has them (neither changes a network).
        let next_x = &self.next_x;
        let values = |net: &QNet, ws: &mut Workspace, out: &mut Vec<f32>| {
            out.clear();
            out.extend_from_slice(net.forward(next_x, ws));
        };
        let (target, online) = (&self.target, &self.online);
        let [target_ws, chooser_ws] = &mut self.eval_ws;
        let (target_q, chooser_q) = (&mut self.target_q, &mut self.chooser_q);
        chooser_q.clear();
        if config.double {
            kernels::join(
                || values(target, target_ws, target_q),
                || values(online, chooser_ws, chooser_q),
            );
        } else {
            values(target, target_ws, target_q);
        }
        let (target_q, chooser_q) = (&self.target_q, &self.chooser_q);
        let value = |row: usize, obs: &sim::Observation| -> f32 {
            let allowed = spec.allowed_columns(obs, config.mask_noops);
            let target = &target_q[row * actions..(row + 1) * actions];
            if config.double {
                let chooser = &chooser_q[row * actions..(row + 1) * actions];
                masked_argmax(chooser, allowed).map_or(0.0, |a| target[a])
            } else {
                masked_max(target, allowed).unwrap_or(0.0)
            }
        };
        let gamma = config.gamma as f32;
        self.y1.clear();
        self.yn.clear();
        for (i, t) in batch.iter().enumerate() {
            let bootstrap = if t.terminal { 0.0 } else { gamma * value(i, &t.next) };
            self.y1.push(t.reward + bootstrap);
            if dqfd {
                let n = &t.n_step;
                let bootstrap = if n.terminal {
                    0.0
                } else {
                    gamma.powi(n.steps as i32) * value(b + i, &n.last)
                };
                self.yn.push(n.rewards + bootstrap);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetConfig, NetKind};
    use crate::replay::NStepReturn;
    use sim::{Action, BlockId, Cell, Goal, Grid, Observation, State};

    /// The margin loss and its gradient, for a hand-computed case: Q(s) = (1, 2, 0.5, ...)
    /// made by a network whose last layer is set by hand.
    #[test]
    fn the_margin_loss_and_its_gradient_match_a_hand_computation() {
        let config = DqnConfig {
            loss: LossKind::Dqfd,
            lambda_n_step: 0.0,
            margin: 0.8,
            gamma: 0.0,
            l2: 0.0,
            mask_noops: false,
            optimizer: crate::optim::OptimizerKind::Adam,
            lr: 1e-3,
            ..DqnConfig::preset(crate::preset::Preset::DqnPlanes, 2).unwrap()
        };
        let net_config = NetConfig {
            kind: NetKind::Mlp,
            hidden: 1,
            ..NetConfig::small()
        };
        let input = net_config.input(Grid::default(), 2).unwrap();
        let mut net = QNet::new(net_config, input, &mut sim::seeding::rng(0)).unwrap();
        // Zero every weight; the last bias alone sets Q(s, .) = b for every s.
        let q = [1.0f32, 2.0, 0.5, -1.0, 0.0, 0.3, 0.1];
        let shapes: Vec<(String, Vec<usize>, usize)> = net
            .tensors()
            .map(|t| (t.name.to_string(), t.shape.to_vec(), t.values.len()))
            .collect();
        for (name, shape, len) in shapes {
            let values = if name == "linear3.bias" {
                q.to_vec()
            } else {
                vec![0.0; len]
            };
            net.set_tensor(&name, &shape, &values).unwrap();
        }
        let obs = Observation {
            grid: Grid::default(),
            state: State::new(&[Cell::new(2, 2), Cell::new(4, 4)], Some(BlockId(0))).unwrap(),
            protocol: sim::ActionProtocol::Free,
            goal: Goal::identity(2).unwrap(),
            view: sim::View::Top,
        };
        // The expert took Left (index 2): J = max(1 + .8, 2 + .8, 0.5, -1 + .8, .8, 1.1, .9) - 0.5
        // = 2.3; its gradient on the last bias is +1 at Down (the max) and -1 at Left.
        let t = Transition {
            obs: obs.clone(),
            action: Action::Left,
            reward: 0.0,
            next: obs.clone(),
            terminal: true,
            n_step: NStepReturn {
                rewards: 0.0,
                last: obs.clone(),
                steps: 1,
                terminal: true,
            },
            expert: true,
        };
        let batch = vec![&t];
        let dqfd_margin_only = DqnConfig {
            td_loss: TdLoss::Mse,
            ..config
        };
        let mut learner = Learner::new(net, &dqfd_margin_only).unwrap();
        // The margin term alone, taken through the network by hand.
        let spec = *learner.online.input();
        let x = spec.batch(&[&obs]);
        let mut ws = Workspace::new();
        let qt = learner.online.forward_train(&x, &mut ws).to_vec();
        let taken = spec.column(&obs.goal, Action::Left);
        assert_eq!(taken, 2);
        let (j, best) = margin_term(&qt, taken, ActionSet::from_indices(0..7), 0.8);
        assert!((j - 2.3).abs() < 1e-6);
        let mut dq = vec![0.0; 7];
        dq[best] += 1.0;
        dq[taken] -= 1.0;
        let mut grad = vec![0.0; learner.online.parameter_count()];
        learner.online.backward(&x, &mut ws, &dq, &mut grad);
        let bias = learner.online.param_range("linear3.bias").unwrap();
        assert_eq!(grad[bias].to_vec(), vec![0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0]);
        // The learner's own step reports the same margin loss (and the TD loss of a terminal
        // step with reward 0: (Q(s, Left) - 0)^2 = 0.25).
        let losses = learner.step(&batch, &dqfd_margin_only).unwrap();
        assert!((losses.margin - 2.3).abs() < 1e-6, "{losses:?}");
        assert!((losses.td - 0.25).abs() < 1e-6, "{losses:?}");
    }

    #[test]
    fn the_td_terms_and_their_derivatives() {
        assert_eq!(td_term(0.5, TdLoss::Mse), (0.25, 1.0));
        assert_eq!(td_term(0.5, TdLoss::Huber), (0.125, 0.5));
        assert_eq!(td_term(-3.0, TdLoss::Huber), (2.5, -1.0));
    }
}
