//! The Q-networks: the paper's convolutional network on pixels, and our small network on
//! centred planes.
//!
//! # The paper's network (`paper`, section III-C)
//!
//! 100 x 100 x 3 pixels; convolution 16 filters 8 x 8 stride 4 (24 x 24 out), batch
//! normalisation, ReLU; convolution 32 filters 4 x 4 stride 2 (11 x 11 out), batch
//! normalisation, ReLU; a linear layer to [`NetConfig::hidden`] units (the paper does not give
//! its width; the authors' last code has 256), ReLU; a linear layer to one Q-value per
//! action. About a million parameters, almost all in the first linear layer.
//!
//! # Ours (`small`)
//!
//! The planes centred on the goal's bottom block ([`crate::input`]), then a multi-layer
//! perceptron with two hidden layers of [`NetConfig::hidden`] units (default 256) and ReLU.
//! Why: the task is nearly translation-invariant, and centring gives the network that
//! invariance for free (a convolution would too, at several times the cost per step here),
//! while an MLP on centred planes still sees the whole board at once, which a Q-value
//! needs. `mlp` is the same perceptron on the absolute planes: the spike's network, kept
//! to measure what centring buys.
//!
//! # How it is computed
//!
//! Activations are `batch x (rows * columns * channels)`, channel fastest. A convolution is
//! an `index_select` of every patch (a precomputed index, "im2col") and one matrix product:
//! identical to a direct convolution, and about twice as fast as candle's `conv2d`, whose
//! backward pass also computes a gradient for the input image that nobody needs. Batch
//! normalisation is written here too: its running mean and variance are kept beside the
//! weights ([`QNet::buffers`]), so a target network copy and a saved file carry them, and
//! the optimiser never sees them. In training mode it normalises by the batch's statistics
//! and updates the running ones (momentum 0.1, PyTorch's); in evaluation mode (acting, and
//! the target network) it uses the running ones.
//!
//! Weights start as PyTorch's defaults do, uniform in `±1/sqrt(fan_in)`, drawn from the
//! seeded generator: same seed, same network.

use std::fmt;

use candle_core::{DType, Device, Tensor, Var};
use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::Action;
use sim::seeding::SimRng;

use crate::error::{NeuralError, Result};
use crate::input::{InputSpec, ObsKind};

/// Which network.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NetKind {
    /// The paper's convolutional network (pixels only).
    Paper,
    /// Ours: a perceptron on planes centred on the goal's bottom block (planes only).
    Small,
    /// The same perceptron on the absolute planes (planes only).
    Mlp,
}

impl NetKind {
    /// The name it is chosen by.
    pub fn name(self) -> &'static str {
        match self {
            NetKind::Paper => "paper",
            NetKind::Small => "small",
            NetKind::Mlp => "mlp",
        }
    }
}

impl fmt::Display for NetKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for NetKind {
    type Err = NeuralError;

    fn from_str(text: &str) -> Result<NetKind> {
        match text {
            "paper" => Ok(NetKind::Paper),
            "small" => Ok(NetKind::Small),
            "mlp" => Ok(NetKind::Mlp),
            _ => Err(NeuralError::Config(format!(
                "unknown network {text:?}: choose paper, small or mlp"
            ))),
        }
    }
}

/// A network's shape.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NetConfig {
    /// Which network.
    pub kind: NetKind,
    /// Units of each hidden linear layer.
    pub hidden: usize,
    /// Batch normalisation after each convolution (the paper's network only).
    pub batch_norm: bool,
}

impl NetConfig {
    /// The paper's network: 256 hidden units, batch normalisation.
    pub fn paper() -> NetConfig {
        NetConfig {
            kind: NetKind::Paper,
            hidden: 256,
            batch_norm: true,
        }
    }

    /// Ours: two hidden layers of 256 on centred planes.
    pub fn small() -> NetConfig {
        NetConfig {
            kind: NetKind::Small,
            hidden: 256,
            batch_norm: false,
        }
    }

    /// The observation this network reads.
    pub fn obs(&self) -> ObsKind {
        match self.kind {
            NetKind::Paper => ObsKind::PaperScreen,
            NetKind::Small | NetKind::Mlp => ObsKind::RolePlanes,
        }
    }

    /// An error naming what cannot work.
    pub fn validate(&self, obs: ObsKind) -> Result<()> {
        if obs != self.obs() {
            return Err(NeuralError::Config(format!(
                "the {} network reads {}, not {obs}",
                self.kind,
                self.obs()
            )));
        }
        if self.hidden == 0 || self.hidden > 1 << 16 {
            return Err(NeuralError::Config(format!(
                "{} hidden units: choose 1 to 65536",
                self.hidden
            )));
        }
        if self.batch_norm && self.kind != NetKind::Paper {
            return Err(NeuralError::Config(
                "batch normalisation follows convolutions: only the paper network has it".into(),
            ));
        }
        Ok(())
    }

    /// The input layout of this network in a world of `blocks` blocks on `grid`.
    pub fn input(&self, grid: sim::Grid, blocks: usize) -> Result<InputSpec> {
        InputSpec::new(self.obs(), self.kind == NetKind::Small, grid, blocks)
    }
}

/// Whether a forward pass trains (batch statistics) or evaluates (running statistics).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Training: batch normalisation uses and updates batch statistics.
    Train,
    /// Evaluation: batch normalisation uses its running statistics.
    Eval,
}

/// Batch normalisation's momentum and epsilon (PyTorch's defaults).
const BN_MOMENTUM: f64 = 0.1;
const BN_EPS: f64 = 1e-5;

/// A convolution's geometry and its im2col index.
struct Conv {
    index: Tensor,
    /// Output positions (rows * columns).
    positions: usize,
    /// Values per patch (k * k * channels in).
    patch: usize,
    channels_out: usize,
}

struct BatchNorm {
    gamma: Var,
    beta: Var,
    running_mean: Var,
    running_var: Var,
}

enum Layer {
    Conv {
        conv: Conv,
        weight: Var,
        bias: Var,
        norm: Option<BatchNorm>,
    },
    Linear {
        weight: Var,
        bias: Var,
        relu: bool,
    },
}

/// A Q-network: one Q-value per action for a batch of inputs.
pub struct QNet {
    config: NetConfig,
    input: InputSpec,
    actions: usize,
    layers: Vec<Layer>,
    /// Trainable variables by name, in a fixed order.
    params: Vec<(String, Var)>,
    /// Batch normalisation's running statistics by name, in a fixed order.
    buffers: Vec<(String, Var)>,
}

/// Uniform values in `±bound`.
fn uniform(rng: &mut SimRng, n: usize, bound: f32) -> Vec<f32> {
    (0..n).map(|_| rng.random_range(-bound..=bound)).collect()
}

fn var(values: Vec<f32>, shape: &[usize]) -> Result<Var> {
    Ok(Var::from_tensor(&Tensor::from_vec(values, shape, &Device::Cpu)?)?)
}

/// The im2col index of a `k x k` stride-`s` convolution over `rows x cols x ch` inputs.
fn conv_index(rows: usize, cols: usize, ch: usize, k: usize, s: usize) -> Result<(Conv, usize, usize)> {
    let (out_r, out_c) = ((rows - k) / s + 1, (cols - k) / s + 1);
    let mut index = Vec::with_capacity(out_r * out_c * k * k * ch);
    for or in 0..out_r {
        for oc in 0..out_c {
            for kr in 0..k {
                for kc in 0..k {
                    for c in 0..ch {
                        index.push((((or * s + kr) * cols + oc * s + kc) * ch + c) as u32);
                    }
                }
            }
        }
    }
    let len = index.len();
    Ok((
        Conv {
            index: Tensor::from_vec(index, len, &Device::Cpu)?,
            positions: out_r * out_c,
            patch: k * k * ch,
            channels_out: 0,
        },
        out_r,
        out_c,
    ))
}

impl QNet {
    /// A freshly initialised network for inputs laid out as `input`, with one output per
    /// action, its weights drawn from `rng`.
    pub fn new(config: NetConfig, input: InputSpec, rng: &mut SimRng) -> Result<QNet> {
        config.validate(input.kind)?;
        let actions = Action::count(input.blocks);
        let mut net = QNet {
            config,
            input,
            actions,
            layers: Vec::new(),
            params: Vec::new(),
            buffers: Vec::new(),
        };
        let mut width = input.len();
        if config.kind == NetKind::Paper {
            let (mut rows, mut cols, mut ch) = input.shape();
            for (i, (k, s, out)) in [(8, 4, 16), (4, 2, 32)].into_iter().enumerate() {
                if rows < k || cols < k {
                    return Err(NeuralError::Config(format!(
                        "a {rows} x {cols} input is smaller than the paper network's {k} x {k} filters"
                    )));
                }
                let (mut conv, r, c) = conv_index(rows, cols, ch, k, s)?;
                conv.channels_out = out;
                let bound = 1.0 / (conv.patch as f32).sqrt();
                let name = format!("conv{}", i + 1);
                let weight = net.param(
                    &format!("{name}.weight"),
                    uniform(rng, conv.patch * out, bound),
                    &[conv.patch, out],
                )?;
                let bias = net.param(&format!("{name}.bias"), uniform(rng, out, bound), &[out])?;
                let norm = if config.batch_norm {
                    Some(BatchNorm {
                        gamma: net.param(&format!("{name}.bn.weight"), vec![1.0; out], &[out])?,
                        beta: net.param(&format!("{name}.bn.bias"), vec![0.0; out], &[out])?,
                        running_mean: net.buffer(&format!("{name}.bn.running_mean"), vec![0.0; out], &[out])?,
                        running_var: net.buffer(&format!("{name}.bn.running_var"), vec![1.0; out], &[out])?,
                    })
                } else {
                    None
                };
                net.layers.push(Layer::Conv {
                    conv,
                    weight,
                    bias,
                    norm,
                });
                (rows, cols, ch) = (r, c, out);
            }
            width = rows * cols * ch;
        }
        let hidden_layers = if config.kind == NetKind::Paper { 1 } else { 2 };
        let mut widths = vec![width];
        widths.extend(std::iter::repeat_n(config.hidden, hidden_layers));
        widths.push(actions);
        for (i, w) in widths.windows(2).enumerate() {
            let (fan_in, out) = (w[0], w[1]);
            let bound = 1.0 / (fan_in as f32).sqrt();
            let name = format!("linear{}", i + 1);
            let weight = net.param(
                &format!("{name}.weight"),
                uniform(rng, fan_in * out, bound),
                &[fan_in, out],
            )?;
            let bias = net.param(&format!("{name}.bias"), uniform(rng, out, bound), &[out])?;
            net.layers.push(Layer::Linear {
                weight,
                bias,
                relu: i + 2 < widths.len(),
            });
        }
        Ok(net)
    }

    fn param(&mut self, name: &str, values: Vec<f32>, shape: &[usize]) -> Result<Var> {
        let v = var(values, shape)?;
        self.params.push((name.into(), v.clone()));
        Ok(v)
    }

    fn buffer(&mut self, name: &str, values: Vec<f32>, shape: &[usize]) -> Result<Var> {
        let v = var(values, shape)?;
        self.buffers.push((name.into(), v.clone()));
        Ok(v)
    }

    /// The network's shape.
    pub fn config(&self) -> &NetConfig {
        &self.config
    }

    /// The input layout.
    pub fn input(&self) -> &InputSpec {
        &self.input
    }

    /// Outputs: one Q-value per action.
    pub fn actions(&self) -> usize {
        self.actions
    }

    /// The trainable variables, by name, in a fixed order.
    pub fn params(&self) -> &[(String, Var)] {
        &self.params
    }

    /// Batch normalisation's running statistics, by name, in a fixed order (empty without).
    pub fn buffers(&self) -> &[(String, Var)] {
        &self.buffers
    }

    /// Number of trainable values.
    pub fn parameter_count(&self) -> usize {
        self.params.iter().map(|(_, v)| v.elem_count()).sum()
    }

    /// Every named tensor: parameters, then buffers.
    pub fn tensors(&self) -> impl Iterator<Item = &(String, Var)> {
        self.params.iter().chain(&self.buffers)
    }

    /// Q-values `[batch, actions]` of `x`, `[batch, input length]`.
    pub fn forward(&self, x: &Tensor, mode: Mode) -> Result<Tensor> {
        let batch = x.dim(0)?;
        let mut h = x.clone();
        for layer in &self.layers {
            h = match layer {
                Layer::Conv {
                    conv,
                    weight,
                    bias,
                    norm,
                } => {
                    let cols = h.index_select(&conv.index, 1)?;
                    let rows = batch * conv.positions;
                    let mut y = cols
                        .reshape((rows, conv.patch))?
                        .matmul(weight.as_tensor())?
                        .broadcast_add(bias.as_tensor())?;
                    if let Some(bn) = norm {
                        y = batch_norm(&y, bn, mode)?;
                    }
                    y.relu()?.reshape((batch, conv.positions * conv.channels_out))?
                }
                Layer::Linear { weight, bias, relu } => {
                    let y = h.matmul(weight.as_tensor())?.broadcast_add(bias.as_tensor())?;
                    if *relu { y.relu()? } else { y }
                }
            };
        }
        Ok(h)
    }

    /// Q-values of the encoded `inputs` (`batch * input length` floats), evaluation mode,
    /// as one row per input.
    pub fn q_values(&self, inputs: Vec<f32>) -> Result<Vec<Vec<f32>>> {
        let batch = inputs.len() / self.input.len();
        let x = Tensor::from_vec(inputs, (batch, self.input.len()), &Device::Cpu)?;
        Ok(self.forward(&x, Mode::Eval)?.detach().to_vec2::<f32>()?)
    }

    /// The allowed action (see [`crate::mask`]) with the highest Q-value in `obs` (of this
    /// network's world).
    pub fn greedy_action(&self, obs: &sim::Observation, mask_noops: bool) -> Result<Action> {
        let q = self.q_values(self.input.batch(&[obs]))?;
        let allowed = self.input.allowed_columns(obs, mask_noops);
        let column = crate::mask::masked_argmax(&q[0], allowed).expect("some action is always allowed");
        Ok(self.input.action(&obs.goal, column))
    }

    /// An independent copy (new variables with the same values).
    pub fn try_clone(&self) -> Result<QNet> {
        let mut rng = sim::seeding::rng(0);
        let copy = QNet::new(self.config, self.input, &mut rng)?;
        copy.copy_from(self)?;
        Ok(copy)
    }

    /// Sets every parameter and buffer to `other`'s (a network of the same shape).
    pub fn copy_from(&self, other: &QNet) -> Result<()> {
        for ((_, dst), (_, src)) in self.tensors().zip(other.tensors()) {
            dst.set(&src.as_tensor().copy()?)?;
        }
        Ok(())
    }

    /// Sets the tensor named `name` to `values` (a network file's); an error naming it if
    /// the network has no such tensor or its shape differs.
    pub fn set_tensor(&self, name: &str, shape: &[usize], values: Vec<f32>) -> Result<()> {
        let (_, v) = self
            .tensors()
            .find(|(n, _)| n == name)
            .ok_or_else(|| NeuralError::Mismatch(format!("the network has no tensor {name}")))?;
        if v.dims() != shape {
            return Err(NeuralError::Mismatch(format!(
                "tensor {name} is {:?} in the network and {shape:?} in the file",
                v.dims()
            )));
        }
        v.set(&Tensor::from_vec(values, shape, &Device::Cpu)?)?;
        Ok(())
    }
}

/// Batch normalisation over the rows of `y` (`[rows, channels]`).
fn batch_norm(y: &Tensor, bn: &BatchNorm, mode: Mode) -> Result<Tensor> {
    let (mean, var) = match mode {
        Mode::Train => {
            let mean = y.mean_keepdim(0)?;
            let var = y.broadcast_sub(&mean)?.sqr()?.mean_keepdim(0)?;
            // Running statistics: the unbiased variance, as PyTorch keeps it.
            let rows = y.dim(0)? as f64;
            let unbiased = if rows > 1.0 { rows / (rows - 1.0) } else { 1.0 };
            let m = mean.detach().squeeze(0)?;
            let v = (var.detach().squeeze(0)? * unbiased)?;
            bn.running_mean
                .set(&((bn.running_mean.as_tensor() * (1.0 - BN_MOMENTUM))? + (m * BN_MOMENTUM)?)?)?;
            bn.running_var
                .set(&((bn.running_var.as_tensor() * (1.0 - BN_MOMENTUM))? + (v * BN_MOMENTUM)?)?)?;
            (mean, var)
        }
        Mode::Eval => (
            bn.running_mean.as_tensor().unsqueeze(0)?,
            bn.running_var.as_tensor().unsqueeze(0)?,
        ),
    };
    let x_hat = y.broadcast_sub(&mean)?.broadcast_div(&(var + BN_EPS)?.sqrt()?)?;
    Ok(x_hat
        .broadcast_mul(bn.gamma.as_tensor())?
        .broadcast_add(bn.beta.as_tensor())?)
}

/// A batch of float inputs as a tensor.
pub fn inputs_tensor(values: Vec<f32>, width: usize) -> Result<Tensor> {
    let batch = values.len() / width;
    Ok(Tensor::from_vec(values, (batch, width), &Device::Cpu)?)
}

/// The element type of every tensor here.
pub const DTYPE: DType = DType::F32;

#[cfg(test)]
mod tests {
    use super::*;
    use sim::Grid;

    fn paper(batch_norm: bool) -> QNet {
        let config = NetConfig {
            batch_norm,
            ..NetConfig::paper()
        };
        let input = config.input(Grid::default(), 3).unwrap();
        QNet::new(config, input, &mut sim::seeding::rng(1)).unwrap()
    }

    #[test]
    fn the_paper_network_has_the_papers_layers() {
        let net = paper(true);
        let shapes: Vec<(String, Vec<usize>)> = net
            .params()
            .iter()
            .map(|(n, v)| (n.clone(), v.dims().to_vec()))
            .collect();
        assert_eq!(shapes[0], ("conv1.weight".into(), vec![8 * 8 * 3, 16]));
        assert_eq!(shapes[4], ("conv2.weight".into(), vec![4 * 4 * 16, 32]));
        assert_eq!(shapes[8], ("linear1.weight".into(), vec![11 * 11 * 32, 256]));
        assert_eq!(shapes[10], ("linear2.weight".into(), vec![256, 8]));
        assert_eq!(net.buffers().len(), 4);
        assert!(
            (1_000_000..1_010_000).contains(&net.parameter_count()),
            "{}",
            net.parameter_count()
        );
        assert!(paper(false).buffers().is_empty());
    }

    #[test]
    fn the_im2col_convolution_equals_a_direct_one() {
        // One 5 x 5 x 2 input, a 3 x 3 stride-2 convolution to 1 channel, computed both ways.
        let (rows, cols, ch, k, s) = (5, 5, 2, 3, 2);
        let x: Vec<f32> = (0..rows * cols * ch).map(|i| (i as f32 * 0.37).sin()).collect();
        let w: Vec<f32> = (0..k * k * ch).map(|i| (i as f32 * 0.11).cos()).collect();
        let (conv, out_r, out_c) = conv_index(rows, cols, ch, k, s).unwrap();
        let xt = Tensor::from_vec(x.clone(), (1, rows * cols * ch), &Device::Cpu).unwrap();
        let wt = Tensor::from_vec(w.clone(), (k * k * ch, 1), &Device::Cpu).unwrap();
        let got = xt
            .index_select(&conv.index, 1)
            .unwrap()
            .reshape((conv.positions, conv.patch))
            .unwrap()
            .matmul(&wt)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1::<f32>()
            .unwrap();
        for or in 0..out_r {
            for oc in 0..out_c {
                let mut sum = 0.0;
                for kr in 0..k {
                    for kc in 0..k {
                        for c in 0..ch {
                            sum += x[((or * s + kr) * cols + oc * s + kc) * ch + c] * w[(kr * k + kc) * ch + c];
                        }
                    }
                }
                assert!((got[or * out_c + oc] - sum).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn batch_norm_trains_on_batch_statistics_and_plays_on_running_ones() {
        let net = paper(true);
        let x = Tensor::rand(0f32, 1.0, (4, net.input().len()), &Device::Cpu).unwrap();
        let before = net.buffers()[0].1.as_tensor().to_vec1::<f32>().unwrap();
        let eval_a = net.forward(&x, Mode::Eval).unwrap().to_vec2::<f32>().unwrap();
        net.forward(&x, Mode::Train).unwrap();
        let after = net.buffers()[0].1.as_tensor().to_vec1::<f32>().unwrap();
        assert_ne!(before, after, "a training pass moves the running mean");
        let eval_b = net.forward(&x, Mode::Eval).unwrap().to_vec2::<f32>().unwrap();
        assert_ne!(eval_a, eval_b);
        // A copy carries the running statistics.
        let copy = net.try_clone().unwrap();
        assert_eq!(copy.forward(&x, Mode::Eval).unwrap().to_vec2::<f32>().unwrap(), eval_b);
    }

    #[test]
    fn networks_only_read_their_observation() {
        assert!(NetConfig::paper().validate(ObsKind::RolePlanes).is_err());
        assert!(NetConfig::small().validate(ObsKind::PaperScreen).is_err());
        let bad = NetConfig {
            batch_norm: true,
            ..NetConfig::small()
        };
        assert!(bad.validate(ObsKind::RolePlanes).is_err());
    }
}
