//! The Q-networks: the paper's convolutional network on pixels, our small network on
//! centred planes, and our convolutional network on the compact screen (or the paper's).
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
//! # Ours on pixels (`conv`, the `pixels` preset)
//!
//! The compact screen ([`sim::screen`], `4H x 4W x 3`); one convolution of
//! [`NetConfig::channels`] filters (default [`CONV_CHANNELS`]) whose kernel and stride are
//! one cell (4 x 4), without a bias, ReLU; then the small network's perceptron (two hidden
//! layers of [`NetConfig::hidden`]). The convolution turns each cell's pixels into a
//! feature vector, the same filters for every cell; without a bias a black cell gives
//! exactly 0, so the perceptron's first layer sees a few non-zero cells and is computed
//! sparsely as on planes.
//!
//! The same network reads the paper's screen (`--screen paper`, 100 x 100 x 3, the goal a
//! picture in the corner) with a kernel of one of its cells ([`conv_cell`]): the learner
//! and the perceptron unchanged, only the goal's presentation differs.
//!
//! # How it is computed
//!
//! By hand, at the cost of the arithmetic (issue 19): activations are `batch x (rows *
//! columns * channels)`, channel fastest; a convolution gathers its patches with contiguous
//! row copies into a reused buffer (im2col, [`crate::kernels`]) and makes one matrix
//! product; every product runs on the `gemm` crate. Bias, batch normalisation and ReLU are
//! one pass each way. The backward pass computes only the gradients that are used (none
//! for the input image). The perceptrons' first layer reads planes of 0/1 values with
//! about one in sixteen set (and `conv`'s, the features of the few lit cells): it sums the
//! weight rows of the set inputs instead of multiplying by a mostly-zero matrix. The parameters are one flat buffer, so the
//! optimiser ([`crate::optim`]) updates them in one fused pass, and a [`Workspace`] holds
//! every intermediate buffer from one step to the next.
//!
//! Batch normalisation's running mean and variance are kept beside the weights
//! ([`QNet::buffers`]), so a target network copy and a saved file carry them, and the
//! optimiser never sees them. In training ([`QNet::forward_train`]) it normalises by the
//! batch's statistics and updates the running ones (momentum 0.1, PyTorch's); otherwise
//! (acting, and the target network) it uses the running ones.
//!
//! Large layers split a batch into two fixed halves that run on two threads when the
//! rayon pool has them. The split depends on the layer's size only, and every sum runs in
//! a fixed order, so the same seed gives the same network, bit for bit, on one thread or
//! two (on the same machine: `gemm` picks its kernels for the CPU). The sparse layer's
//! weight gradient is cut by rows where its work halves, which moves with the batch's
//! inputs, but each row's sums are its own and run in sample order, so the cut changes no
//! bit.
//!
//! Weights start as PyTorch's defaults do, uniform in `±1/sqrt(fan_in)`, drawn from the
//! seeded generator: same seed, same network.

use std::cell::RefCell;

use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::observation::PIXELS_SIDE;
use sim::seeding::SimRng;
use sim::{Action, SCREEN_CELL, ScreenGoal};

use crate::error::{NeuralError, Result};
use crate::input::{InputSpec, ObsKind};
use crate::kernels::{self, ConvGeometry, matmul, matmul_nt, matmul_tn};
pub use crate::params::NamedTensor;
use crate::params::{ParamStore, Slot};

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
    /// Ours on pixels: a convolution of one screen cell, then the small perceptron (the
    /// compact screen only, [`sim::screen`]).
    Conv,
}

sim::names!(NetKind { Paper = "paper", Small = "small", Mlp = "mlp", Conv = "conv" } unknown(text) -> NeuralError {
    NeuralError::Config(format!("unknown network {text:?}: choose paper, small, mlp or conv"))
});

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
    /// How the compact screen shows the goal (the `conv` network only); absent from a
    /// network file at its default, as in every file before it.
    #[serde(default, skip_serializing_if = "is_default")]
    pub screen: ScreenGoal,
    /// Channels of the `conv` network's convolution; absent from a network file (and 0)
    /// for the other networks.
    #[serde(default, skip_serializing_if = "is_default")]
    pub channels: usize,
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

impl NetConfig {
    /// The paper's network: 256 hidden units, batch normalisation.
    pub fn paper() -> NetConfig {
        NetConfig {
            kind: NetKind::Paper,
            hidden: 256,
            batch_norm: true,
            screen: ScreenGoal::default(),
            channels: 0,
        }
    }

    /// Ours: two hidden layers of 256 on centred planes.
    pub fn small() -> NetConfig {
        NetConfig {
            kind: NetKind::Small,
            hidden: 256,
            batch_norm: false,
            screen: ScreenGoal::default(),
            channels: 0,
        }
    }

    /// Ours on pixels: a convolution of [`CONV_CHANNELS`] channels over each cell of the
    /// compact screen (blocks coloured by goal place), then two hidden layers of 256.
    pub fn conv() -> NetConfig {
        NetConfig {
            kind: NetKind::Conv,
            channels: CONV_CHANNELS,
            ..NetConfig::small()
        }
    }

    /// The observation this network reads.
    pub fn obs(&self) -> ObsKind {
        match self.kind {
            NetKind::Paper => ObsKind::PaperScreen,
            NetKind::Small | NetKind::Mlp => ObsKind::RolePlanes,
            NetKind::Conv if self.screen == ScreenGoal::Paper => ObsKind::PaperScreen,
            NetKind::Conv => ObsKind::Screen,
        }
    }

    /// An error naming what cannot work.
    pub fn validate(&self, obs: ObsKind) -> Result<()> {
        if obs != self.obs() {
            let hint = if self.kind == NetKind::Conv && obs == ObsKind::PaperScreen {
                " (`--screen paper` puts it on the paper's screen)"
            } else {
                ""
            };
            return Err(NeuralError::Config(format!(
                "the {} network reads {}, not {obs}{hint}",
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
        let conv = self.kind == NetKind::Conv;
        if conv && !(1..=1 << 10).contains(&self.channels) {
            return Err(NeuralError::Config(format!(
                "{} convolution channels: choose 1 to 1024",
                self.channels
            )));
        }
        if !conv && (self.channels != 0 || self.screen != ScreenGoal::default()) {
            return Err(NeuralError::Config(format!(
                "only the conv network reads the compact screen, not the {} one",
                self.kind
            )));
        }
        Ok(())
    }

    /// The input layout of this network in a world of `blocks` blocks on `grid`; an error
    /// if the `conv` network's kernel cannot be one of its cells ([`conv_cell`]).
    pub fn input(&self, grid: sim::Grid, blocks: usize) -> Result<InputSpec> {
        let spec = InputSpec {
            screen: self.screen,
            ..InputSpec::new(self.obs(), self.kind == NetKind::Small, grid, blocks)?
        };
        if self.kind == NetKind::Conv {
            conv_cell(&spec)?;
        }
        Ok(spec)
    }
}

/// Channels of the `conv` network's convolution.
pub const CONV_CHANNELS: usize = 16;

/// The `conv` network's kernel and stride on `input`: one cell of the screen.
///
/// On the compact screen a cell is [`SCREEN_CELL`] pixels. On the paper's screen, a square
/// grid of `n` cells scaled to [`PIXELS_SIDE`] pixels, a cell is `100 / n` pixels, not
/// a whole number (14.3 on 7 x 7): the stride is its whole part and the kernel reaches to
/// the screen's edge from the last stride (14 and 16 on 7 x 7), so that there are `n x n`
/// positions and each holds its whole cell and at most two pixels of its neighbours (which
/// the bilinear scaling blurs into anyway). A grid that is not square has cells of two
/// shapes there, which one square kernel cannot follow: an error.
pub fn conv_cell(input: &InputSpec) -> Result<(usize, usize)> {
    if input.kind != ObsKind::PaperScreen {
        return Ok((SCREEN_CELL, SCREEN_CELL));
    }
    let n = input.grid.width();
    if input.grid.height() != n || n > PIXELS_SIDE {
        return Err(NeuralError::Config(format!(
            "the conv network reads the paper's screen of a square grid of at most {} cells a side, not of {}: \
             its kernel is one cell",
            PIXELS_SIDE, input.grid
        )));
    }
    let stride = PIXELS_SIDE / n;
    Ok((PIXELS_SIDE - stride * (n - 1), stride))
}

/// Batch normalisation's momentum and epsilon (PyTorch's defaults).
const BN_MOMENTUM: f32 = 0.1;
const BN_EPS: f64 = 1e-5;

/// Below this many multiply-adds per half a layer runs on one thread: a fork and join
/// costs more than it saves.
const MIN_HALF_WORK: usize = 2_000_000;

/// Batch normalisation's tensors: scale and shift among the parameters, the running
/// statistics among the buffers.
#[derive(Clone, Debug)]
struct Norm {
    gamma: Slot,
    beta: Slot,
    running_mean: Slot,
    running_var: Slot,
}

#[derive(Clone, Debug)]
enum Layer {
    /// Convolution (+ batch normalisation) + ReLU. Without a bias (the `conv` network's),
    /// an all-black patch gives exactly 0, so the layer after it sees mostly zeros.
    Conv {
        geo: ConvGeometry,
        out: usize,
        weight: Slot,
        bias: Option<Slot>,
        norm: Option<Norm>,
    },
    /// Linear layer, ReLU unless it is the last. `sparse`: the first layer of a perceptron
    /// (on planes, or on the `conv` network's convolution), whose inputs are mostly 0,
    /// computed as a sum of the weight rows of its non-zero inputs.
    Linear {
        inputs: usize,
        out: usize,
        weight: Slot,
        bias: Slot,
        relu: bool,
        sparse: bool,
    },
}

impl Layer {
    /// Values per sample out of the layer.
    fn width(&self) -> usize {
        match self {
            Layer::Conv { geo, out, .. } => geo.positions() * out,
            Layer::Linear { out, .. } => *out,
        }
    }

    /// Multiply-adds per sample of the layer's forward pass.
    fn work(&self) -> usize {
        match self {
            Layer::Conv { geo, out, .. } => geo.positions() * geo.patch() * out,
            Layer::Linear { inputs, out, .. } => inputs * out,
        }
    }
}

/// A Q-network: one Q-value per action for a batch of inputs.
///
/// Its parameters are one flat buffer ([`QNet::params`]), laid out tensor after tensor in
/// [`QNet::tensors`]' order, so the optimiser runs over one slice.
#[derive(Clone, Debug)]
pub struct QNet {
    config: NetConfig,
    input: InputSpec,
    actions: usize,
    layers: Vec<Layer>,
    store: ParamStore,
}

/// The buffers of one layer's pass, kept for the backward pass.
#[derive(Default)]
struct LayerBuffers {
    /// A convolution's patches, a chunk of samples for each half of the batch.
    cols: Vec<f32>,
    /// A convolution's output before the ReLU: normalised (`x_hat`) with batch
    /// normalisation in training, else the plain product plus bias.
    pre: Vec<f32>,
    /// The layer's output (after the ReLU where there is one).
    out: Vec<f32>,
    /// Batch statistics of the last training pass: mean, 1 / standard deviation, and the
    /// biased variance.
    mean: Vec<f64>,
    inv_std: Vec<f64>,
    var: Vec<f64>,
    /// Per-channel coefficients of batch normalisation's element-wise pass.
    coef: Vec<f32>,
    /// A sparse layer's non-zero inputs: sample `b`'s are `nz[nz_start[b]..nz_start[b + 1]]`.
    nz: Vec<(u32, f32)>,
    nz_start: Vec<usize>,
    /// The second half's, while the two halves are found apart.
    nz_half: Vec<(u32, f32)>,
    nz_start_half: Vec<usize>,
}

/// Reusable buffers for passes through one network shape: made once, grown to the largest
/// batch seen, then reused (no allocation in the steady state). A training pass keeps what
/// its backward pass needs here.
#[derive(Default)]
pub struct Workspace {
    batch: usize,
    layers: Vec<LayerBuffers>,
    /// What the backward pass writes besides the layers' buffers.
    back: BackBuffers,
}

/// The buffers of a backward pass that belong to no one layer.
#[derive(Default)]
struct BackBuffers {
    /// The gradient with respect to the current layer's output, and its input's.
    delta: Vec<f32>,
    delta_in: Vec<f32>,
    /// A convolution's patches and their gradients, a chunk of samples for each half.
    cols: Vec<f32>,
    dcols: Vec<f32>,
    /// The second half's weight gradient, added to the first's.
    dw_half: Vec<f32>,
    /// Per-channel sums and coefficients of the batch-normalisation backward pass.
    sums: Vec<f64>,
    coef: Vec<f32>,
    /// A sparse layer's non-zero inputs regrouped by input: input `i`'s samples and
    /// values are `by_input[input_start[i]..input_start[i + 1]]`, in sample order.
    by_input: Vec<(u32, f32)>,
    input_start: Vec<usize>,
}

impl Workspace {
    /// An empty workspace.
    pub fn new() -> Workspace {
        Workspace::default()
    }

    /// The output of the last pass: `batch x actions` Q-values.
    pub fn output(&self) -> &[f32] {
        self.layers.last().map_or(&[][..], |l| l.out.as_slice())
    }
}

/// Resizes `v` to `n` values (allocating only when it grows past its capacity).
fn fit<T: Clone + Default>(v: &mut Vec<T>, n: usize) {
    v.resize(n, T::default());
}

/// Values of patches gathered at a time (1 MB): the chunk stays in the core's caches
/// between its gathering and its matrix product.
const CHUNK_VALUES: usize = 1 << 18;

/// Samples per chunk of a convolution's patches.
fn chunk_samples(geo: &ConvGeometry) -> usize {
    (CHUNK_VALUES / (geo.positions() * geo.patch())).max(1)
}

/// Splits `v` at `at` when there are two parts; with one the second part is empty.
fn halves(v: &mut [f32], at: usize, parts: usize) -> (&mut [f32], &mut [f32]) {
    if parts == 2 { v.split_at_mut(at) } else { (v, &mut []) }
}

/// Sets every row of `rows` (of `bias.len()` values) to `bias`.
#[inline(always)]
fn fill_rows_any(rows: &mut [f32], bias: &[f32]) {
    for row in rows.chunks_exact_mut(bias.len()) {
        row.copy_from_slice(bias);
    }
}

/// Adds every row of `rows` into `sum` (of one row's length), overwriting it.
#[inline(always)]
fn sum_rows_any(rows: &[f32], sum: &mut [f32]) {
    sum.fill(0.0);
    for row in rows.chunks_exact(sum.len()) {
        for (s, &v) in sum.iter_mut().zip(row) {
            *s += v;
        }
    }
}

/// Sets `delta` to 0 where the layer's output (after ReLU) is 0.
#[inline(always)]
fn relu_backward_any(delta: &mut [f32], out: &[f32]) {
    for (d, &o) in delta.iter_mut().zip(out) {
        if o <= 0.0 {
            *d = 0.0;
        }
    }
}

/// Uniform values in `±bound`.
fn uniform(rng: &mut SimRng, n: usize, bound: f32) -> Vec<f32> {
    (0..n).map(|_| rng.random_range(-bound..=bound)).collect()
}

thread_local! {
    /// The buffers of acting passes (one input at a time), per thread.
    static ACTING: RefCell<Workspace> = RefCell::new(Workspace::new());
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
            store: ParamStore::default(),
        };
        let mut width = input.len();
        // (kernel, stride, channels out) of each convolution.
        let convolutions = match config.kind {
            NetKind::Paper => vec![(8, 4, 16), (4, 2, 32)],
            NetKind::Conv => {
                let (k, s) = conv_cell(&input)?;
                vec![(k, s, config.channels)]
            }
            NetKind::Small | NetKind::Mlp => Vec::new(),
        };
        if !convolutions.is_empty() {
            let (mut rows, mut cols, mut ch) = input.shape();
            for (i, (k, s, out)) in convolutions.into_iter().enumerate() {
                let geo = ConvGeometry::new(rows, cols, ch, k, s).ok_or_else(|| {
                    NeuralError::Config(format!(
                        "a {rows} x {cols} input is smaller than the {} network's {k} x {k} filters",
                        config.kind
                    ))
                })?;
                let patch = geo.patch();
                let bound = 1.0 / (patch as f32).sqrt();
                let name = format!("conv{}", i + 1);
                let weight = net.store.add(
                    &format!("{name}.weight"),
                    uniform(rng, patch * out, bound),
                    &[patch, out],
                    false,
                );
                let bias = (config.kind == NetKind::Paper).then(|| {
                    net.store
                        .add(&format!("{name}.bias"), uniform(rng, out, bound), &[out], false)
                });
                let norm = config.batch_norm.then(|| Norm {
                    gamma: net
                        .store
                        .add(&format!("{name}.bn.weight"), vec![1.0; out], &[out], false),
                    beta: net.store.add(&format!("{name}.bn.bias"), vec![0.0; out], &[out], false),
                    running_mean: net
                        .store
                        .add(&format!("{name}.bn.running_mean"), vec![0.0; out], &[out], true),
                    running_var: net
                        .store
                        .add(&format!("{name}.bn.running_var"), vec![1.0; out], &[out], true),
                });
                net.layers.push(Layer::Conv {
                    geo,
                    out,
                    weight,
                    bias,
                    norm,
                });
                (rows, cols, ch) = (geo.out_rows, geo.out_cols, out);
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
            let weight = net.store.add(
                &format!("{name}.weight"),
                uniform(rng, fan_in * out, bound),
                &[fan_in, out],
                false,
            );
            let bias = net
                .store
                .add(&format!("{name}.bias"), uniform(rng, out, bound), &[out], false);
            net.layers.push(Layer::Linear {
                inputs: fan_in,
                out,
                weight,
                bias,
                relu: i + 2 < widths.len(),
                sparse: i == 0 && config.kind != NetKind::Paper,
            });
        }
        Ok(net)
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

    /// Every trainable value, tensor after tensor (the order of [`QNet::tensors`]).
    pub fn params(&self) -> &[f32] {
        &self.store.params
    }

    /// The trainable values, to update.
    pub fn params_mut(&mut self) -> &mut [f32] {
        &mut self.store.params
    }

    /// Batch normalisation's running statistics (empty without).
    pub fn buffers(&self) -> &[f32] {
        &self.store.buffers
    }

    /// Number of trainable values.
    pub fn parameter_count(&self) -> usize {
        self.store.params.len()
    }

    /// Every named tensor: parameters, then batch normalisation's running statistics.
    pub fn tensors(&self) -> impl Iterator<Item = NamedTensor<'_>> {
        self.store.tensors()
    }

    /// Where the parameter `name` lives in [`QNet::params`] (`None` for a buffer or an
    /// unknown name).
    pub fn param_range(&self, name: &str) -> Option<std::ops::Range<usize>> {
        self.store.param_range(name)
    }

    /// Sets the tensor named `name` to `values` (a network file's); an error naming it if
    /// the network has no such tensor or its shape differs.
    pub fn set_tensor(&mut self, name: &str, shape: &[usize], values: &[f32]) -> Result<()> {
        self.store.set_tensor(name, shape, values)
    }

    /// An independent copy.
    pub fn try_clone(&self) -> Result<QNet> {
        Ok(self.clone())
    }

    /// Sets every parameter and buffer to `other`'s (a network of the same shape).
    pub fn copy_from(&mut self, other: &QNet) {
        self.store.copy_from(&other.store);
    }

    /// Q-values of the encoded `inputs` (`batch * input length` floats), batch
    /// normalisation on its running statistics, as one row per input.
    pub fn q_values(&self, inputs: Vec<f32>) -> Result<Vec<Vec<f32>>> {
        let width = self.input.len();
        if !inputs.len().is_multiple_of(width) {
            return Err(NeuralError::Mismatch(format!(
                "{} input values are not a whole number of {width}-value inputs",
                inputs.len()
            )));
        }
        Ok(ACTING.with_borrow_mut(|ws| {
            self.forward(&inputs, ws)
                .chunks_exact(self.actions)
                .map(<[f32]>::to_vec)
                .collect()
        }))
    }

    /// The allowed action (see [`crate::mask`]) with the highest Q-value in `obs` (of this
    /// network's world).
    pub fn greedy_action(&self, obs: &sim::Observation, mask_noops: bool) -> Result<Action> {
        let x = self.input.batch(&[obs]);
        let allowed = self.input.allowed_columns(obs, mask_noops);
        let column = ACTING.with_borrow_mut(|ws| crate::mask::masked_argmax(self.forward(&x, ws), allowed));
        Ok(self
            .input
            .action(&obs.goal, column.expect("some action is always allowed")))
    }

    /// Q-values (`batch x actions`) of `x` (`batch x input length`), batch normalisation on
    /// its running statistics (acting, and the target network).
    pub fn forward<'w>(&self, x: &[f32], ws: &'w mut Workspace) -> &'w [f32] {
        kernels::without_subnormals(|| self.pass(x, ws, false));
        ws.output()
    }

    /// Q-values of `x` in training: batch normalisation on the batch's statistics, whose
    /// running averages it updates (momentum 0.1, the unbiased variance, as PyTorch keeps
    /// them). `ws` keeps what [`QNet::backward`] needs.
    pub fn forward_train<'w>(&mut self, x: &[f32], ws: &'w mut Workspace) -> &'w [f32] {
        kernels::without_subnormals(|| self.pass(x, ws, true));
        for (layer, buffers) in self.layers.iter().zip(&ws.layers) {
            if let Layer::Conv { norm: Some(n), .. } = layer {
                let rows = buffers.pre.len() / buffers.mean.len();
                let unbiased = if rows > 1 { rows as f64 / (rows - 1) as f64 } else { 1.0 };
                let stats = buffers.mean.iter().zip(&buffers.var);
                for (i, (&m, &v)) in stats.enumerate() {
                    let rm = &mut self.store.buffers[n.running_mean.offset + i];
                    *rm = *rm * (1.0 - BN_MOMENTUM) + m as f32 * BN_MOMENTUM;
                    let rv = &mut self.store.buffers[n.running_var.offset + i];
                    *rv = *rv * (1.0 - BN_MOMENTUM) + (v * unbiased) as f32 * BN_MOMENTUM;
                }
            }
        }
        ws.output()
    }

    /// One forward pass over every layer.
    fn pass(&self, x: &[f32], ws: &mut Workspace, train: bool) {
        let batch = x.len() / self.input.len();
        assert_eq!(batch * self.input.len(), x.len(), "a whole number of inputs");
        ws.batch = batch;
        if ws.layers.len() != self.layers.len() {
            ws.layers = (0..self.layers.len()).map(|_| LayerBuffers::default()).collect();
        }
        for (i, layer) in self.layers.iter().enumerate() {
            let (before, rest) = ws.layers.split_at_mut(i);
            let input: &[f32] = before.last().map_or(x, |l| &l.out);
            let buf = &mut rest[0];
            fit(&mut buf.out, batch * layer.width());
            let parts = kernels::parts(batch, MIN_HALF_WORK.div_ceil(layer.work()));
            let half = kernels::part_start(batch, parts, 1);
            match layer {
                Layer::Conv {
                    geo,
                    out,
                    weight,
                    bias,
                    norm,
                } => {
                    let (positions, patch, in_len) = (geo.positions(), geo.patch(), geo.input_len());
                    let chunk = chunk_samples(geo);
                    fit(&mut buf.cols, 2 * chunk * positions * patch);
                    fit(&mut buf.pre, batch * positions * out);
                    let w = &self.store.params[weight.range()];
                    let b = bias.map(|b| &self.store.params[b.range()]);
                    let (x0, x1) = input.split_at(half * in_len);
                    let (c0, c1) = buf.cols.split_at_mut(chunk * positions * patch);
                    let (z0, z1) = halves(&mut buf.pre, half * positions * out, parts);
                    // A few samples at a time, so the patches stay in cache.
                    let conv = |x: &[f32], cols: &mut [f32], z: &mut [f32]| {
                        match b {
                            Some(b) => fill_rows(z, b),
                            None => z.fill(0.0),
                        }
                        for (xc, zc) in x.chunks(chunk * in_len).zip(z.chunks_mut(chunk * positions * out)) {
                            let rows = xc.len() / in_len * positions;
                            let cols = &mut cols[..rows * patch];
                            geo.im2col(xc, cols);
                            matmul(zc, cols, w, (rows, patch, *out), true);
                        }
                    };
                    kernels::both(parts, || conv(x0, c0, z0), || conv(x1, c1, z1));
                    match norm {
                        Some(n) if train => norm_train(&self.store.params, n, buf),
                        Some(n) => norm_eval(&self.store.params, &self.store.buffers, n, buf),
                        None => {
                            for (o, &z) in buf.out.iter_mut().zip(&buf.pre) {
                                *o = z.max(0.0);
                            }
                        }
                    }
                }
                Layer::Linear {
                    inputs,
                    out,
                    weight,
                    bias,
                    relu,
                    sparse,
                } => {
                    let w = &self.store.params[weight.range()];
                    let b = &self.store.params[bias.range()];
                    if *sparse {
                        sparse_layer_forward(input, *inputs, w, b, buf, parts);
                    } else {
                        let (x0, x1) = input.split_at(half * inputs);
                        let (y0, y1) = halves(&mut buf.out, half * out, parts);
                        let linear = |x: &[f32], y: &mut [f32]| {
                            fill_rows(y, b);
                            matmul(y, x, w, (y.len() / out, *inputs, *out), true);
                        };
                        kernels::both(parts, || linear(x0, y0), || linear(x1, y1));
                    }
                    if *relu {
                        relu_in_place(&mut buf.out);
                    }
                }
            }
        }
    }

    /// The gradient of a loss with respect to every parameter, written over `grad` (laid out
    /// as [`QNet::params`]), from `dq`, its gradient with respect to the Q-values of the
    /// last [`QNet::forward_train`] through `ws`, whose input was `x`. No gradient is
    /// computed for the input.
    pub fn backward(&self, x: &[f32], ws: &mut Workspace, dq: &[f32], grad: &mut [f32]) {
        kernels::without_subnormals(|| self.backward_pass(x, ws, dq, grad));
    }

    /// [`QNet::backward`]'s passes, layer by layer.
    fn backward_pass(&self, x: &[f32], ws: &mut Workspace, dq: &[f32], grad: &mut [f32]) {
        let batch = ws.batch;
        assert_eq!(dq.len(), batch * self.actions, "one gradient per Q-value");
        assert_eq!(grad.len(), self.store.params.len(), "one gradient per parameter");
        let Workspace { layers, back, .. } = ws;
        fit(&mut back.delta, dq.len());
        back.delta.copy_from_slice(dq);
        for (i, layer) in self.layers.iter().enumerate().rev() {
            let (before, rest) = layers.split_at(i);
            let input: &[f32] = before.last().map_or(x, |l| l.out.as_slice());
            let pass = LayerPass {
                i,
                batch,
                input,
                buf: &rest[0],
            };
            let swap = match layer {
                Layer::Conv { .. } => {
                    self.conv_backward(layer, &pass, back, grad);
                    true
                }
                Layer::Linear { .. } => self.linear_backward(layer, &pass, back, grad),
            };
            if swap {
                std::mem::swap(&mut back.delta, &mut back.delta_in);
            }
        }
    }

    /// A convolution's backward pass: its parameters' gradients into `grad` and, below the
    /// first layer, its input's gradient into `back.delta_in`.
    fn conv_backward(&self, layer: &Layer, pass: &LayerPass<'_>, back: &mut BackBuffers, grad: &mut [f32]) {
        let Layer::Conv {
            geo,
            out,
            weight,
            bias,
            norm,
        } = layer
        else {
            unreachable!("a convolution")
        };
        let LayerPass { i, batch, input, buf } = *pass;
        let BackBuffers {
            delta,
            delta_in,
            cols,
            dcols,
            dw_half,
            sums,
            coef,
            ..
        } = back;
        let parts = kernels::parts(batch, MIN_HALF_WORK.div_ceil(layer.work()));
        let half = kernels::part_start(batch, parts, 1);
        let (positions, patch) = (geo.positions(), geo.patch());
        match norm {
            Some(n) => {
                norm_backward(&self.store.params, n, buf, delta, sums, coef, grad);
                // Batch normalisation subtracts the batch mean: the bias
                // changes no output in training, and its gradient is 0
                // (computed, it is rounding noise that Adam would turn
                // into a random walk).
                if let Some(bias) = bias {
                    grad[bias.range()].fill(0.0);
                }
            }
            None => {
                relu_backward(delta, &buf.out);
                if let Some(bias) = bias {
                    sum_rows(delta, &mut grad[bias.range()]);
                }
            }
        }
        let w = &self.store.params[weight.range()];
        let in_len = geo.input_len();
        let chunk = chunk_samples(geo);
        let chunk_len = chunk * positions * patch;
        fit(dw_half, weight.len);
        fit(cols, 2 * chunk_len);
        let wants_input = i > 0;
        if wants_input {
            fit(dcols, 2 * chunk_len);
            fit(delta_in, batch * in_len);
        }
        let (g0, g1) = (&mut grad[weight.range()], &mut dw_half[..]);
        let (x0, x1) = input.split_at(half * in_len);
        let (d0, d1) = delta.split_at(half * positions * out);
        let (cols0, cols1) = cols.split_at_mut(chunk_len);
        let (dc0, dc1, dx0, dx1) = if wants_input {
            let (dc0, dc1) = dcols.split_at_mut(chunk_len);
            let (dx0, dx1) = halves(delta_in, half * in_len, parts);
            (dc0, dc1, dx0, dx1)
        } else {
            (&mut [][..], &mut [][..], &mut [][..], &mut [][..])
        };
        // The patches again, a few samples at a time (cheaper than keeping
        // them all from the forward pass: they would not stay in cache).
        let conv = |x: &[f32], cols: &mut [f32], d: &[f32], g: &mut [f32], dc: &mut [f32], dx: &mut [f32]| {
            let chunks = x.chunks(chunk * in_len).zip(d.chunks(chunk * positions * out));
            for (k, (xc, dch)) in chunks.enumerate() {
                let samples = xc.len() / in_len;
                let rows = samples * positions;
                let cols = &mut cols[..rows * patch];
                geo.im2col(xc, cols);
                matmul_tn(g, cols, dch, (patch, rows, *out), k > 0);
                if wants_input {
                    let dc = &mut dc[..rows * patch];
                    matmul_nt(dc, dch, w, (rows, *out, patch), false);
                    let start = k * chunk * in_len;
                    geo.col2im(dc, &mut dx[start..start + samples * in_len]);
                }
            }
        };
        kernels::both(
            parts,
            || conv(x0, cols0, d0, g0, dc0, dx0),
            || conv(x1, cols1, d1, g1, dc1, dx1),
        );
        if parts == 2 {
            for (g, &h) in grad[weight.range()].iter_mut().zip(dw_half.iter()) {
                *g += h;
            }
        }
    }

    /// A linear layer's backward pass: its parameters' gradients into `grad` and, below the
    /// first layer, its input's gradient; whether that gradient is in `back.delta_in` (to be
    /// swapped into `back.delta`) rather than already in `back.delta`.
    fn linear_backward(&self, layer: &Layer, pass: &LayerPass<'_>, back: &mut BackBuffers, grad: &mut [f32]) -> bool {
        let Layer::Linear {
            inputs,
            out,
            weight,
            bias,
            relu,
            sparse,
        } = layer
        else {
            unreachable!("a linear layer")
        };
        let LayerPass { i, batch, input, buf } = *pass;
        let BackBuffers {
            delta,
            delta_in,
            dw_half,
            by_input,
            input_start,
            ..
        } = back;
        let parts = kernels::parts(batch, MIN_HALF_WORK.div_ceil(layer.work()));
        let half = kernels::part_start(batch, parts, 1);
        if *relu {
            relu_backward(delta, &buf.out);
        }
        sum_rows(delta, &mut grad[bias.range()]);
        if *sparse {
            let g = &mut grad[weight.range()];
            sparse_weight_gradient(buf, delta, *inputs, g, by_input, input_start);
            if i == 0 {
                return false;
            }
            // After a convolution: the gradient of the non-zero inputs only (a
            // zero input is a ReLU's zero, whose own gradient is 0 anyway).
            fit(delta_in, batch * inputs);
            let w = &self.store.params[weight.range()];
            sparse_input_gradient(buf, delta, w, *inputs, delta_in);
            std::mem::swap(delta, delta_in);
            return false;
        }
        let x = input;
        let w = &self.store.params[weight.range()];
        fit(dw_half, weight.len);
        fit(delta_in, batch * inputs);
        let (x0, x1) = x.split_at(half * inputs);
        let (d0, d1) = delta.split_at(half * out);
        let (g0, g1) = (&mut grad[weight.range()], &mut dw_half[..]);
        let (dx0, dx1) = halves(delta_in, half * inputs, parts);
        let linear = |x: &[f32], d: &[f32], g: &mut [f32], dx: &mut [f32]| {
            let r = d.len() / out;
            matmul_tn(g, x, d, (*inputs, r, *out), false);
            matmul_nt(dx, d, w, (r, *out, *inputs), false);
        };
        kernels::both(parts, || linear(x0, d0, g0, dx0), || linear(x1, d1, g1, dx1));
        if parts == 2 {
            for (g, &h) in grad[weight.range()].iter_mut().zip(dw_half.iter()) {
                *g += h;
            }
        }
        true
    }
}

/// Where a layer's backward pass stands: its index, the batch, its input and its buffers of
/// the forward pass.
#[derive(Clone, Copy)]
struct LayerPass<'a> {
    i: usize,
    batch: usize,
    input: &'a [f32],
    buf: &'a LayerBuffers,
}

/// Batch normalisation on the batch's statistics, then ReLU: `pre` becomes `x_hat`.
#[inline(always)]
fn norm_train_any(params: &[f32], n: &Norm, buf: &mut LayerBuffers) {
    let channels = n.gamma.len;
    fit(&mut buf.mean, channels);
    fit(&mut buf.inv_std, channels);
    fit(&mut buf.var, channels);
    let (sum, sq) = (&mut buf.mean, &mut buf.var);
    sum.fill(0.0);
    sq.fill(0.0);
    for row in buf.pre.chunks_exact(channels) {
        for ((s, q), &z) in sum.iter_mut().zip(sq.iter_mut()).zip(row) {
            let z = f64::from(z);
            *s += z;
            *q += z * z;
        }
    }
    let rows = (buf.pre.len() / channels) as f64;
    for c in 0..channels {
        let mean = buf.mean[c] / rows;
        let var = (buf.var[c] / rows - mean * mean).max(0.0);
        buf.mean[c] = mean;
        buf.var[c] = var;
        buf.inv_std[c] = 1.0 / (var + BN_EPS).sqrt();
    }
    // x_hat = z * scale + shift, y = gamma * x_hat + beta, per channel in f32.
    let gamma = &params[n.gamma.range()];
    let beta = &params[n.beta.range()];
    fit(&mut buf.coef, 2 * channels);
    let (scale, shift) = buf.coef.split_at_mut(channels);
    for c in 0..channels {
        scale[c] = buf.inv_std[c] as f32;
        shift[c] = (-buf.mean[c] * buf.inv_std[c]) as f32;
    }
    for (pre, out) in buf
        .pre
        .chunks_exact_mut(channels)
        .zip(buf.out.chunks_exact_mut(channels))
    {
        let per_channel = scale.iter().zip(shift.iter()).zip(gamma.iter().zip(beta));
        for ((z, o), ((&sc, &sh), (&g, &b))) in pre.iter_mut().zip(out.iter_mut()).zip(per_channel) {
            let x_hat = *z * sc + sh;
            *z = x_hat;
            *o = (g * x_hat + b).max(0.0);
        }
    }
}

/// Batch normalisation on the running statistics, then ReLU.
#[inline(always)]
fn norm_eval_any(params: &[f32], buffers: &[f32], n: &Norm, buf: &mut LayerBuffers) {
    let channels = n.gamma.len;
    let gamma = &params[n.gamma.range()];
    let beta = &params[n.beta.range()];
    let mean = &buffers[n.running_mean.range()];
    let var = &buffers[n.running_var.range()];
    // y = z * scale + shift per channel.
    fit(&mut buf.coef, 2 * channels);
    let (scale, shift) = buf.coef.split_at_mut(channels);
    for c in 0..channels {
        scale[c] = gamma[c] / (f64::from(var[c]) + BN_EPS).sqrt() as f32;
        shift[c] = beta[c] - mean[c] * scale[c];
    }
    for (pre, out) in buf.pre.chunks_exact(channels).zip(buf.out.chunks_exact_mut(channels)) {
        for ((&z, o), (&sc, &sh)) in pre.iter().zip(out.iter_mut()).zip(scale.iter().zip(shift.iter())) {
            *o = (z * sc + sh).max(0.0);
        }
    }
}

/// Batch normalisation's and ReLU's backward pass, in place over `delta` (gradient of
/// the output, then of the convolution's output), with the scale's and shift's gradients.
#[inline(always)]
fn norm_backward_any(
    params: &[f32],
    n: &Norm,
    buf: &LayerBuffers,
    delta: &mut [f32],
    sums: &mut Vec<f64>,
    coef: &mut Vec<f32>,
    grad: &mut [f32],
) {
    let channels = n.gamma.len;
    fit(sums, 2 * channels);
    sums.fill(0.0);
    let (d_beta, d_gamma) = sums.split_at_mut(channels);
    let rows = buf.out.chunks_exact(channels).zip(buf.pre.chunks_exact(channels));
    for (d, (out, x_hat)) in delta.chunks_exact_mut(channels).zip(rows) {
        let sums = d_beta.iter_mut().zip(d_gamma.iter_mut());
        for (((d, &o), &x), (sb, sg)) in d.iter_mut().zip(out).zip(x_hat).zip(sums) {
            if o <= 0.0 {
                *d = 0.0;
            }
            *sb += f64::from(*d);
            *sg += f64::from(*d) * f64::from(x);
        }
    }
    for c in 0..channels {
        grad[n.beta.offset + c] = d_beta[c] as f32;
        grad[n.gamma.offset + c] = d_gamma[c] as f32;
    }
    // dz = gamma / std * (dy - mean(dy) - x_hat * mean(dy * x_hat)) = k * dy + a + b * x_hat.
    let count = (buf.pre.len() / channels) as f64;
    let gamma = &params[n.gamma.range()];
    fit(coef, 3 * channels);
    let (k, rest) = coef.split_at_mut(channels);
    let (a, b) = rest.split_at_mut(channels);
    for c in 0..channels {
        let kc = f64::from(gamma[c]) * buf.inv_std[c];
        k[c] = kc as f32;
        a[c] = (-kc * d_beta[c] / count) as f32;
        b[c] = (-kc * d_gamma[c] / count) as f32;
    }
    for (d, x_hat) in delta.chunks_exact_mut(channels).zip(buf.pre.chunks_exact(channels)) {
        let per_channel = k.iter().zip(a.iter()).zip(b.iter());
        for ((d, &x), ((&k, &a), &b)) in d.iter_mut().zip(x_hat).zip(per_channel) {
            *d = k * *d + a + b * x;
        }
    }
}

kernels::avx2_dispatch! {
    fn fill_rows => fill_rows_any(rows: &mut [f32], bias: &[f32])
}

kernels::avx2_dispatch! {
    fn sum_rows => sum_rows_any(rows: &[f32], sum: &mut [f32])
}

kernels::avx2_dispatch! {
    fn relu_backward => relu_backward_any(delta: &mut [f32], out: &[f32])
}

kernels::avx2_dispatch! {
    fn sparse_forward => sparse_forward_any(
        x: &[f32],
        inputs: usize,
        w: &[f32],
        b: &[f32],
        y: &mut [f32],
        nz_all: &mut Vec<(u32, f32)>,
        nz_start: &mut Vec<usize>,
    )
}

kernels::avx2_dispatch! {
    fn sparse_backward => sparse_backward_any(by_input: &[(u32, f32)], starts: &[usize], delta: &[f32], grad: &mut [f32])
}

kernels::avx2_dispatch! {
    fn sparse_input_gradient => sparse_input_gradient_any(
        buf: &LayerBuffers,
        delta: &[f32],
        w: &[f32],
        inputs: usize,
        delta_in: &mut [f32],
    )
}

kernels::avx2_dispatch! {
    fn norm_train => norm_train_any(params: &[f32], n: &Norm, buf: &mut LayerBuffers)
}

kernels::avx2_dispatch! {
    fn norm_eval => norm_eval_any(params: &[f32], buffers: &[f32], n: &Norm, buf: &mut LayerBuffers)
}

kernels::avx2_dispatch! {
    fn norm_backward => norm_backward_any(
        params: &[f32],
        n: &Norm,
        buf: &LayerBuffers,
        delta: &mut [f32],
        sums: &mut Vec<f64>,
        coef: &mut Vec<f32>,
        grad: &mut [f32],
    )
}

kernels::avx2_dispatch! {
    fn relu_in_place => relu_any(v: &mut [f32])
}

/// ReLU in place.
#[inline(always)]
fn relu_any(v: &mut [f32]) {
    for v in v {
        *v = v.max(0.0);
    }
}

/// The first layer of a perceptron: for each sample, the bias plus `x_i` times weight row
/// `i` for every non-zero input `i` (planes are 0/1 with about one value in sixteen set),
/// into `y`; the non-zero inputs are kept in `nz_all`, sample `s`'s at
/// `nz_all[nz_start[s]..nz_start[s + 1]]`.
#[inline(always)]
fn sparse_forward_any(
    x: &[f32],
    inputs: usize,
    w: &[f32],
    b: &[f32],
    y: &mut [f32],
    nz_all: &mut Vec<(u32, f32)>,
    nz_start: &mut Vec<usize>,
) {
    /// Outputs summed at a time: eight 256-bit registers that stay put while the weight
    /// rows stream past (the same sums in the same order as one output at a time).
    const BLOCK: usize = 64;
    let out = b.len();
    nz_all.clear();
    nz_start.clear();
    for (sample, y) in x.chunks_exact(inputs).zip(y.chunks_exact_mut(out)) {
        let start = nz_all.len();
        nz_start.push(start);
        push_nonzero(sample, nz_all);
        let nz = &nz_all[start..];
        let blocks = out / BLOCK * BLOCK;
        for k in (0..blocks).step_by(BLOCK) {
            let mut acc: [f32; BLOCK] = b[k..k + BLOCK].try_into().expect("a block");
            for &(i, v) in nz {
                let row: &[f32; BLOCK] = w[i as usize * out + k..][..BLOCK].try_into().expect("a block");
                for (a, &w) in acc.iter_mut().zip(row) {
                    *a += v * w;
                }
            }
            y[k..k + BLOCK].copy_from_slice(&acc);
        }
        y[blocks..].copy_from_slice(&b[blocks..]);
        for &(i, v) in nz {
            let row = &w[i as usize * out + blocks..(i as usize + 1) * out];
            for (y, &w) in y[blocks..].iter_mut().zip(row) {
                *y += v * w;
            }
        }
    }
    nz_start.push(nz_all.len());
}

/// Appends the index and value of every non-zero value of `sample` to `nz`, in order.
/// Eight values are compared at once and only the set bits of their mask visited: the
/// planes are mostly zeros, and one branch per value cost more than the rows it finds.
#[inline(always)]
fn push_nonzero(sample: &[f32], nz: &mut Vec<(u32, f32)>) {
    let mut eights = sample.chunks_exact(8);
    for (c, eight) in eights.by_ref().enumerate() {
        let eight: &[f32; 8] = eight.try_into().expect("eight values");
        let mut mask = 0u32;
        for (j, &v) in eight.iter().enumerate() {
            mask |= u32::from(v != 0.0) << j;
        }
        while mask != 0 {
            let j = mask.trailing_zeros() as usize;
            nz.push(((c * 8 + j) as u32, eight[j]));
            mask &= mask - 1;
        }
    }
    let base = sample.len() - eights.remainder().len();
    let rest = eights.remainder().iter().enumerate().filter(|(_, v)| **v != 0.0);
    nz.extend(rest.map(|(j, &v)| ((base + j) as u32, v)));
}

/// [`sparse_forward`] of a batch in `parts` fixed halves (one or two, as
/// [`kernels::parts`] gives), on two threads when there are two, with one list of the
/// batch's non-zero inputs after: each sample's outputs are its own, so the bits are one
/// pass's.
fn sparse_layer_forward(x: &[f32], inputs: usize, w: &[f32], b: &[f32], buf: &mut LayerBuffers, parts: usize) {
    let batch = x.len() / inputs;
    let half = kernels::part_start(batch, parts, 1);
    let LayerBuffers {
        out: y,
        nz,
        nz_start,
        nz_half,
        nz_start_half,
        ..
    } = buf;
    let (x0, x1) = x.split_at(half * inputs);
    let (y0, y1) = halves(y, half * b.len(), parts);
    kernels::both(
        parts,
        || sparse_forward(x0, inputs, w, b, y0, nz, nz_start),
        || sparse_forward(x1, inputs, w, b, y1, nz_half, nz_start_half),
    );
    if parts == 2 {
        // One list for the backward pass, the second half's after the first's.
        let base = nz.len();
        nz_start.pop();
        nz_start.extend(nz_start_half.iter().map(|s| s + base));
        nz.extend_from_slice(nz_half);
    }
}

/// The sparse layer's weight gradient into `grad` (`inputs` rows), from `delta`, the
/// gradient with respect to its outputs, and the non-zero inputs of its last pass in
/// `buf`; `by_input` and `input_start` are its workspace. The rows are cut in two parts
/// of about as many sums each, on two threads when the pool has them: each row's sums are
/// its own, so where the cut falls changes no bit.
fn sparse_weight_gradient(
    buf: &LayerBuffers,
    delta: &[f32],
    inputs: usize,
    grad: &mut [f32],
    by_input: &mut Vec<(u32, f32)>,
    input_start: &mut Vec<usize>,
) {
    let out = grad.len() / inputs;
    let rows = by_inputs(buf, inputs, by_input, input_start);
    let cut = input_start.partition_point(|&s| s < rows.len() / 2).min(inputs);
    let (starts_a, starts_b) = (&input_start[..=cut], &input_start[cut..]);
    let (g_a, g_b) = grad.split_at_mut(cut * out);
    let parts = kernels::parts(rows.len(), MIN_HALF_SPARSE_ROWS);
    kernels::both(
        parts,
        || sparse_backward(rows, starts_a, delta, g_a),
        || sparse_backward(rows, starts_b, delta, g_b),
    );
}

/// Sparse-layer weight-gradient sums a part must hold, or the rows stay whole: a sum is a
/// row of a few hundred values.
const MIN_HALF_SPARSE_ROWS: usize = 256;

/// The sparse layer's non-zero inputs of the last pass regrouped by input, each input's in
/// sample order (a stable counting sort) into `by_input`, with `input_start` (`inputs + 1`
/// values) where each input's begin; returns them.
fn by_inputs<'a>(
    buf: &LayerBuffers,
    inputs: usize,
    by_input: &'a mut Vec<(u32, f32)>,
    input_start: &mut Vec<usize>,
) -> &'a [(u32, f32)] {
    input_start.clear();
    input_start.resize(inputs + 2, 0);
    for &(i, _) in &buf.nz {
        input_start[i as usize + 2] += 1;
    }
    for i in 2..input_start.len() {
        input_start[i] += input_start[i - 1];
    }
    // Now input `i`'s first free place is `input_start[i + 1]`; filling moves it to its end,
    // which is input `i + 1`'s beginning.
    fit(by_input, buf.nz.len());
    for (sample, ends) in buf.nz_start.windows(2).enumerate() {
        for &(i, v) in &buf.nz[ends[0]..ends[1]] {
            let place = &mut input_start[i as usize + 1];
            by_input[*place] = (sample as u32, v);
            *place += 1;
        }
    }
    input_start.pop();
    by_input
}

/// The sparse layer's weight gradient for the weight rows `grad` holds (`starts.len() - 1`
/// of them): for each row `i`, `delta`'s row of every sample whose input `i` is non-zero,
/// times that input, added sample after sample. Each row stays in cache while its samples
/// stream past, and each value gets the same sums in the same order as when the samples
/// were the outer loop.
#[inline(always)]
fn sparse_backward_any(by_input: &[(u32, f32)], starts: &[usize], delta: &[f32], grad: &mut [f32]) {
    let rows = starts.len().saturating_sub(1);
    if rows == 0 {
        return;
    }
    let out = grad.len() / rows;
    for (g, ends) in grad.chunks_exact_mut(out).zip(starts.windows(2)) {
        g.fill(0.0);
        for &(sample, v) in &by_input[ends[0]..ends[1]] {
            let d = &delta[sample as usize * out..][..out];
            for (g, &d) in g.iter_mut().zip(d) {
                *g += v * d;
            }
        }
    }
}

/// The sparse layer's input gradient: for each non-zero input `i` of a sample, the dot
/// product of its `delta` row with weight row `i`; 0 for every other input.
#[inline(always)]
fn sparse_input_gradient_any(buf: &LayerBuffers, delta: &[f32], w: &[f32], inputs: usize, delta_in: &mut [f32]) {
    delta_in.fill(0.0);
    let out = delta.len() / buf.nz_start.len().saturating_sub(1).max(1);
    for (b, (d, dx)) in delta
        .chunks_exact(out)
        .zip(delta_in.chunks_exact_mut(inputs))
        .enumerate()
    {
        for &(i, _) in &buf.nz[buf.nz_start[b]..buf.nz_start[b + 1]] {
            let i = i as usize;
            let row = &w[i * out..(i + 1) * out];
            dx[i] = row.iter().zip(d).map(|(&w, &d)| w * d).sum();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sim::Grid;

    proptest! {
        #[test]
        fn the_nonzero_scan_finds_every_set_value_in_order(
            sample in prop::collection::vec(prop_oneof![3 => Just(0.0f32), 1 => -2.0f32..2.0, 1 => Just(-0.0f32)], 0..70),
        ) {
            let mut nz = vec![(9, 9.0)];
            push_nonzero(&sample, &mut nz);
            let expected: Vec<(u32, f32)> = std::iter::once((9, 9.0))
                .chain(sample.iter().enumerate().filter(|(_, v)| **v != 0.0).map(|(i, &v)| (i as u32, v)))
                .collect();
            prop_assert_eq!(nz, expected);
        }

        #[test]
        fn the_sparse_layer_in_halves_gives_one_pass_bits(
            (inputs, samples, x, delta) in (1usize..40, 0usize..24).prop_flat_map(|(inputs, samples)| (
                Just(inputs),
                Just(samples),
                prop::collection::vec(prop_oneof![4 => Just(0.0f32), 1 => -2.0f32..2.0], inputs * samples),
                prop::collection::vec(-1.0f32..1.0, samples * 3),
            )),
        ) {
            const OUT: usize = 3;
            let w: Vec<f32> = (0..inputs * OUT).map(|i| (i as f32 * 0.37).sin()).collect();
            let b = [0.1, -0.2, 0.3];
            // The reference: sample after sample, every output's sum in input order.
            let mut y_ref = vec![0.0f32; samples * OUT];
            let mut grad_ref = vec![0.0f32; inputs * OUT];
            for (s, x) in x.chunks_exact(inputs).enumerate() {
                for o in 0..OUT {
                    let mut sum = b[o];
                    for (i, &v) in x.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                        sum += v * w[i * OUT + o];
                        grad_ref[i * OUT + o] += v * delta[s * OUT + o];
                    }
                    y_ref[s * OUT + o] = sum;
                }
            }
            for parts in [1, 2] {
                let mut buf = LayerBuffers { out: vec![0.0; samples * OUT], ..LayerBuffers::default() };
                sparse_layer_forward(&x, inputs, &w, &b, &mut buf, parts);
                prop_assert_eq!(&buf.out, &y_ref);
                prop_assert_eq!(buf.nz_start.len(), samples + 1);
                let mut grad = vec![f32::NAN; inputs * OUT];
                let (mut by_input, mut input_start) = (Vec::new(), Vec::new());
                sparse_weight_gradient(&buf, &delta, inputs, &mut grad, &mut by_input, &mut input_start);
                prop_assert_eq!(&grad, &grad_ref);
            }
        }
    }

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
        let shapes: Vec<(String, Vec<usize>)> = net.tensors().map(|t| (t.name.to_string(), t.shape.to_vec())).collect();
        assert_eq!(shapes[0], ("conv1.weight".into(), vec![8 * 8 * 3, 16]));
        assert_eq!(shapes[4], ("conv2.weight".into(), vec![4 * 4 * 16, 32]));
        assert_eq!(shapes[8], ("linear1.weight".into(), vec![11 * 11 * 32, 256]));
        assert_eq!(shapes[10], ("linear2.weight".into(), vec![256, 8]));
        assert_eq!(shapes.iter().filter(|(n, _)| n.contains("running")).count(), 4);
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
        let geo = ConvGeometry::new(rows, cols, ch, k, s).unwrap();
        let (out_r, out_c) = (geo.out_rows, geo.out_cols);
        let mut patches = vec![0.0; geo.positions() * geo.patch()];
        geo.im2col(&x, &mut patches);
        let mut got = vec![0.0; geo.positions()];
        matmul(&mut got, &patches, &w, (geo.positions(), geo.patch(), 1), false);
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
        let mut net = paper(true);
        let mut rng = sim::seeding::rng(9);
        let x: Vec<f32> = (0..4 * net.input().len()).map(|_| rng.random_range(0.0..1.0)).collect();
        let mut ws = Workspace::new();
        let before = net.buffers().to_vec();
        let eval_a = net.forward(&x, &mut ws).to_vec();
        net.forward_train(&x, &mut ws);
        let after = net.buffers().to_vec();
        assert_ne!(before[..16], after[..16], "a training pass moves the running mean");
        let eval_b = net.forward(&x, &mut ws).to_vec();
        assert_ne!(eval_a, eval_b);
        // A copy carries the running statistics.
        let copy = net.try_clone().unwrap();
        assert_eq!(copy.forward(&x, &mut ws), eval_b);
        // One input at a time gives the same values as the batch.
        let single = net.q_values(x[..net.input().len()].to_vec()).unwrap();
        let close = single[0]
            .iter()
            .zip(&eval_b)
            .all(|(a, b)| (a - b).abs() <= 1e-5 * (1.0 + b.abs()));
        assert!(close, "{:?} {:?}", single[0], &eval_b[..net.actions()]);
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
