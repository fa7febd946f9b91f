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

use candle_core::{Device, Tensor};
use serde::Serialize;

use crate::config::{DqnConfig, LossKind, TdLoss};
use crate::error::Result;
use crate::mask::{masked_argmax, masked_max};
use crate::net::{Mode, QNet};
use crate::optim::Optimizer;
use crate::replay::Transition;

/// Stands in for minus infinity where a masked action must lose every maximum.
const MASKED: f32 = -1e9;

/// The parts of one step's loss.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
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

/// The online and target networks and the optimiser.
pub struct Learner {
    online: QNet,
    target: QNet,
    optimizer: Optimizer,
    gradient_steps: u64,
}

impl Learner {
    /// A learner starting from `online` (the target a copy of it).
    pub fn new(online: QNet, config: &DqnConfig) -> Result<Learner> {
        let target = online.try_clone()?;
        let optimizer = Optimizer::new(config.optimizer, config.lr, online.params());
        Ok(Learner {
            online,
            target,
            optimizer,
            gradient_steps: 0,
        })
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
        self.target.copy_from(&self.online)
    }

    /// One gradient step on `batch` (not empty) with `config`'s losses.
    pub fn step(&mut self, batch: &[&Transition], config: &DqnConfig) -> Result<Losses> {
        let dqfd = config.loss == LossKind::Dqfd;
        let spec = *self.online.input();
        let b = batch.len();
        let actions = self.online.actions();

        // Targets, without gradients: next observations, then the n-step ones.
        let mut next: Vec<_> = batch.iter().map(|t| &t.next).collect();
        if dqfd {
            next.extend(batch.iter().map(|t| &t.n_step.last));
        }
        let next_x = Tensor::from_vec(spec.batch(&next), (next.len(), spec.len()), &Device::Cpu)?;
        let target_q = self.target.forward(&next_x, Mode::Eval)?.detach().to_vec2::<f32>()?;
        let chooser_q = if config.double {
            self.online.forward(&next_x, Mode::Eval)?.detach().to_vec2::<f32>()?
        } else {
            Vec::new()
        };
        let value = |row: usize, obs: &sim::Observation| -> f32 {
            let allowed = spec.allowed_columns(obs, config.mask_noops);
            if config.double {
                masked_argmax(&chooser_q[row], allowed).map_or(0.0, |a| target_q[row][a])
            } else {
                masked_max(&target_q[row], allowed).unwrap_or(0.0)
            }
        };
        let gamma = config.gamma as f32;
        let mut y1 = Vec::with_capacity(b);
        let mut yn = Vec::with_capacity(b);
        for (i, t) in batch.iter().enumerate() {
            let bootstrap = if t.terminal { 0.0 } else { gamma * value(i, &t.next) };
            y1.push(t.reward + bootstrap);
            if dqfd {
                let n = &t.n_step;
                let bootstrap = if n.terminal {
                    0.0
                } else {
                    gamma.powi(n.steps as i32) * value(b + i, &n.last)
                };
                yn.push(n.rewards + bootstrap);
            }
        }

        // The online network's values, with gradients.
        let obs: Vec<_> = batch.iter().map(|t| &t.obs).collect();
        let x = Tensor::from_vec(spec.batch(&obs), (b, spec.len()), &Device::Cpu)?;
        let q = self.online.forward(&x, Mode::Train)?;
        let taken: Vec<u32> = batch
            .iter()
            .map(|t| spec.column(&t.obs.goal, t.action) as u32)
            .collect();
        let taken = Tensor::from_vec(taken, (b, 1), &Device::Cpu)?;
        let q_taken = q.gather(&taken, 1)?.squeeze(1)?;

        let td_of = |y: Vec<f32>| -> Result<Tensor> {
            let d = (&q_taken - Tensor::from_vec(y, b, &Device::Cpu)?)?;
            Ok(match config.td_loss {
                TdLoss::Mse => d.sqr()?.mean_all()?,
                TdLoss::Huber => {
                    let a = d.abs()?;
                    let c = a.clamp(0f32, 1f32)?;
                    ((c.sqr()? * 0.5)? + (a - c)?)?.mean_all()?
                }
            })
        };
        let td = td_of(y1)?;
        let mut total = td.clone();
        let mut losses = Losses::default();
        if dqfd {
            let n_step = td_of(yn)?;
            total = (total + (&n_step * config.lambda_n_step)?)?;
            losses.n_step = n_step.to_scalar::<f32>()?;
            let experts = batch.iter().filter(|t| t.expert).count();
            if experts > 0 {
                let margin = config.margin as f32;
                let mut l = vec![0f32; b * actions];
                let mut weight = vec![0f32; b];
                for (i, t) in batch.iter().enumerate().filter(|(_, t)| t.expert) {
                    let allowed = spec.allowed_columns(&t.obs, config.mask_noops);
                    let expert = spec.column(&t.obs.goal, t.action);
                    for a in 0..actions {
                        l[i * actions + a] = if a == expert {
                            0.0
                        } else if allowed.contains(a) {
                            margin
                        } else {
                            MASKED
                        };
                    }
                    weight[i] = 1.0 / experts as f32;
                }
                let l = Tensor::from_vec(l, (b, actions), &Device::Cpu)?;
                let weight = Tensor::from_vec(weight, b, &Device::Cpu)?;
                let j = ((q.broadcast_add(&l)?.max(1)? - &q_taken)? * weight)?.sum_all()?;
                total = (total + (&j * config.lambda_margin)?)?;
                losses.margin = j.to_scalar::<f32>()?;
            }
        }
        losses.td = td.to_scalar::<f32>()?;
        losses.total = total.to_scalar::<f32>()?;
        let grads = total.backward()?;
        let l2 = if dqfd { config.l2 } else { 0.0 };
        self.optimizer
            .step(self.online.params(), &grads, l2, config.clip_norm)?;
        self.gradient_steps += 1;
        Ok(losses)
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
            ..DqnConfig::preset("dqn-planes", 2).unwrap()
        };
        let net_config = NetConfig {
            kind: NetKind::Mlp,
            hidden: 1,
            batch_norm: false,
        };
        let input = net_config.input(Grid::default(), 2).unwrap();
        let net = QNet::new(net_config, input, &mut sim::seeding::rng(0)).unwrap();
        // Zero every weight; the last bias alone sets Q(s, .) = b for every s.
        let q = [1.0f32, 2.0, 0.5, -1.0, 0.0, 0.3, 0.1];
        for (name, v) in net.params() {
            let values = if name == "linear3.bias" {
                q.to_vec()
            } else {
                vec![0.0; v.elem_count()]
            };
            net.set_tensor(name, v.dims(), values).unwrap();
        }
        let obs = Observation {
            grid: Grid::default(),
            state: State::new(&[Cell::new(2, 2), Cell::new(4, 4)], Some(BlockId(0))).unwrap(),
            protocol: sim::ActionProtocol::Free,
            goal: Goal::identity(2).unwrap(),
        };
        // The expert took Left (index 2): J = max(1 + .8, 2 + .8, 0.5, -1 + .8, .8, 1.1, .9) - 0.5
        // = 2.3; its gradient on the last bias is +1 at Down (the max) and -1 at Left.
        let t = Transition {
            obs,
            action: Action::Left,
            reward: 0.0,
            next: obs,
            terminal: true,
            n_step: NStepReturn {
                rewards: 0.0,
                last: obs,
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
        // Recompute the loss graph by hand to read the gradient before the step.
        let spec = *learner.online.input();
        let x = Tensor::from_vec(spec.batch(&[&obs]), (1, spec.len()), &Device::Cpu).unwrap();
        let qt = learner.online.forward(&x, Mode::Train).unwrap();
        let l = Tensor::from_vec(vec![0.8f32, 0.8, 0.0, 0.8, 0.8, 0.8, 0.8], (1, 7), &Device::Cpu).unwrap();
        let taken = Tensor::from_vec(vec![2u32], (1, 1), &Device::Cpu).unwrap();
        let j = (qt.broadcast_add(&l).unwrap().max(1).unwrap() - qt.gather(&taken, 1).unwrap().squeeze(1).unwrap())
            .unwrap()
            .sum_all()
            .unwrap();
        assert!((j.to_scalar::<f32>().unwrap() - 2.3).abs() < 1e-6);
        let grads = j.backward().unwrap();
        let bias = &learner
            .online
            .params()
            .iter()
            .find(|(n, _)| n == "linear3.bias")
            .unwrap()
            .1;
        let g = grads.get(bias.as_tensor()).unwrap().to_vec1::<f32>().unwrap();
        assert_eq!(g, vec![0.0, 1.0, -1.0, 0.0, 0.0, 0.0, 0.0]);
        // The learner's own step reports the same margin loss (and the TD loss of a terminal
        // step with reward 0: (Q(s, Left) - 0)^2 = 0.25).
        let losses = learner.step(&batch, &dqfd_margin_only).unwrap();
        assert!((losses.margin - 2.3).abs() < 1e-6, "{losses:?}");
        assert!((losses.td - 0.25).abs() < 1e-6, "{losses:?}");
    }
}
