//! The relational network: passes along the towers and across the goal, then a score for
//! every legal move (the module docs of [`crate::relational`] say why this shape).
//!
//! # The computation
//!
//! Every block `b` carries a vector of [`Shape::width`] values. It starts from the block's
//! own relations (`on-table`, `clear`, the goal's `on-table`), and then, [`Shape::rounds`]
//! times with the same weights:
//!
//! 1. **Up the towers**, bottom to top: `u_b = up(h_b, u_below, on-as-goal_b)`, where
//!    `u_below` is the block's support's (a learnt vector for the table) and
//!    `on-as-goal_b` says whether the goal's `on` holds on the pair the state's `on` links
//!    (`b` and its support).
//! 2. **Down the towers**, top to bottom: `v_b = down(u_b, v_above, on-as-goal_above)`
//!    (a learnt vector above a clear block).
//! 3. **Across the goal**: `h_b = goal(v_b, v_goal-below, v_goal-above, on-as-goal_b,
//!    on-as-goal_goal-above)`, with learnt vectors where the goal puts the block on the
//!    table, leaves it free, or puts nothing on it.
//!
//! Each of `up`, `down` and `goal` is a cell: a linear layer to [`Shape::hidden`] units,
//! ReLU, a linear layer back to the width, tanh. A pass up or down a tower runs as many
//! steps as the tower is tall, so one round carries what a block learns to every block of
//! its tower, however tall; the rounds carry it from tower to tower through the goal.
//!
//! Then every legal move `x -> y` is scored by a perceptron over the pair:
//! `w . relu(A h_x + B h_y + c goal_on(x, y) + d)` (a learnt vector in place of `B h_y` for
//! the table), computed as `A h` and `B h` once per block and a sum per move.
//!
//! # How it is computed
//!
//! The blocks of a batch of problems are processed together, one height (or depth) at a
//! time for the passes along the towers and all at once across the goal: each step is one
//! matrix product per layer over the rows it holds ([`crate::kernels`]). A training pass
//! keeps every cell's inputs, hidden units and outputs on a [`Tape`], and the backward pass
//! runs the steps in reverse. Single-threaded, in a fixed order: the same seed gives the
//! same network, bit for bit, on one thread or two.

use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::seeding::SimRng;

use crate::error::{NeuralError, Result};
use crate::kernels::{matmul, matmul_nt, matmul_tn, tanh_in_place};
use crate::params::{NamedTensor, ParamStore, Slot};

use super::graph::{Graph, NONE, TABLE};

/// The sizes of a relational network.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shape {
    /// Values each block carries.
    pub width: usize,
    /// Hidden units of each cell.
    pub hidden: usize,
    /// Hidden units of the move scorer.
    pub score_hidden: usize,
    /// Rounds of passes (up, down, across the goal).
    pub rounds: usize,
}

impl Shape {
    /// An error naming a size that cannot work.
    pub fn validate(&self) -> Result<()> {
        for (name, v, max) in [
            ("width", self.width, 1024),
            ("hidden", self.hidden, 4096),
            ("score hidden", self.score_hidden, 4096),
            ("rounds", self.rounds, 64),
        ] {
            if v == 0 || v > max {
                return Err(NeuralError::Config(format!(
                    "the relational network's {name} is {v}: choose 1 to {max}"
                )));
            }
        }
        Ok(())
    }
}

/// Node input features: on-table, clear, the goal's on-table.
pub(super) const FEATURES: usize = 3;

/// Per-block scores: moving the block onto a block the goal does not relate it to, being
/// such a destination, moving the block to the table.
pub(super) const HEADS: usize = 3;

/// A cell: linear to `hidden`, ReLU, linear to `out`, tanh.
#[derive(Clone, Copy, Debug)]
struct Cell {
    inputs: usize,
    hidden: usize,
    out: usize,
    w1: Slot,
    b1: Slot,
    w2: Slot,
    b2: Slot,
}

/// Every tensor's slot.
#[derive(Clone, Copy, Debug)]
struct Slots {
    embed_w: Slot,
    embed_b: Slot,
    up: Cell,
    down: Cell,
    goal: Cell,
    table_up: Slot,
    clear_down: Slot,
    goal_table: Slot,
    goal_free: Slot,
    goal_top: Slot,
    head_w: Slot,
    head_b: Slot,
    head_out: Slot,
    pair_x: Slot,
    pair_y: Slot,
    pair_goal_on: Slot,
    pair_goal_under: Slot,
    pair_bias: Slot,
    pair_out: Slot,
}

/// A relational network (module docs): its shape and its parameters, one flat buffer laid
/// out tensor after tensor in [`RelationalNet::tensors`]' order.
#[derive(Clone, Debug)]
pub struct RelationalNet {
    shape: Shape,
    slots: Slots,
    store: ParamStore,
}

/// One cell's pass over its rows: inputs, hidden units (after ReLU), outputs (after tanh).
#[derive(Default, Debug)]
pub(super) struct CellTape {
    /// The inputs, a row per node.
    pub(super) x: Vec<f32>,
    h: Vec<f32>,
    /// The outputs, a row per node.
    pub(super) o: Vec<f32>,
}

/// A round's cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum CellKind {
    /// Up the towers.
    Up,
    /// Down the towers.
    Down,
    /// Across the goal.
    Goal,
}

/// Where [`RelationalNet::head_rows`] writes.
pub(super) struct HeadRows<'a> {
    pub(super) k: &'a mut [f32],
    pub(super) heads: &'a mut [f32],
    pub(super) px: &'a mut [f32],
    pub(super) qy: &'a mut [f32],
}

/// One round's three cells (by node) and the two scans: their values and, for every
/// value, the node whose local term it is.
#[derive(Default, Debug)]
struct RoundTape {
    up: CellTape,
    down: CellTape,
    goal: CellTape,
    u: Vec<f32>,
    u_src: Vec<u32>,
    v: Vec<f32>,
    v_src: Vec<u32>,
}

/// Everything a pass computed that its backward pass needs, kept from one pass to the next
/// so that its buffers are reused.
#[derive(Default, Debug)]
pub struct Tape {
    /// Each node's place in the up and down orders.
    pos_up: Vec<u32>,
    pos_down: Vec<u32>,
    /// Node features and the embedding (after tanh), by node.
    features: Vec<f32>,
    h0: Vec<f32>,
    rounds: Vec<RoundTape>,
    /// The per-block head's hidden units (after ReLU) and its three scores, per node.
    k: Vec<f32>,
    heads: Vec<f32>,
    /// The pair perceptron's first layer's two halves, per node.
    px: Vec<f32>,
    qy: Vec<f32>,
    /// The pair perceptron's hidden units (after ReLU) per listed move (zero for a move
    /// between blocks the goal does not relate).
    act: Vec<f32>,
    /// Every move's score.
    scores: Vec<f32>,
    /// Gradients: of the current node vectors (by node), of the up and down passes' outputs
    /// (in their orders), of a cell's inputs and hidden units, of `A h` and `B h`.
    dh: Vec<f32>,
    du: Vec<f32>,
    dv: Vec<f32>,
    dx: Vec<f32>,
    dhid: Vec<f32>,
    dg: Vec<f32>,
    din: Vec<f32>,
    dk: Vec<f32>,
    dheads: Vec<f32>,
    dpx: Vec<f32>,
    dqy: Vec<f32>,
}

impl Tape {
    /// An empty tape.
    pub fn new() -> Tape {
        Tape::default()
    }

    /// The scores of the last pass, one per move of the graph.
    pub fn scores(&self) -> &[f32] {
        &self.scores
    }

    /// The last pass's embedding, a row per node.
    pub(super) fn embedding(&self) -> &[f32] {
        &self.h0
    }

    /// Round `r`'s values in the last pass, a row per node: the up cell's outputs, the up
    /// pass, the down cell's outputs, the down pass, and the round's output.
    pub(super) fn round_values(&self, r: usize) -> [&[f32]; 5] {
        let round = &self.rounds[r];
        [&round.up.o, &round.u, &round.down.o, &round.v, &round.goal.o]
    }

    /// The last pass's per-block values a move's score is read from.
    pub(super) fn values(&self) -> Values<'_> {
        Values {
            heads: &self.heads,
            px: &self.px,
            qy: &self.qy,
        }
    }
}

/// Resizes `v` to `n` zeros-or-old values (allocating only when it grows).
/// A candidate move's score, its order key (its place in `Towers::moves` order, which breaks
/// ties) and the move, as `(block, destination)`.
type ScoredMove = (f32, (u32, u32), (u32, u32));

fn fit(v: &mut Vec<f32>, n: usize) {
    v.resize(n, 0.0);
}

/// Uniform values in `±bound`.
fn uniform(rng: &mut SimRng, n: usize, bound: f32) -> Vec<f32> {
    (0..n).map(|_| rng.random_range(-bound..=bound)).collect()
}

/// The tensors and parameters of a network being made.
#[derive(Default)]
struct Builder {
    store: ParamStore,
}

impl Builder {
    /// A tensor of shape `dims`, uniform in `±1/sqrt(fan_in)`.
    fn add(&mut self, name: &str, dims: &[usize], fan_in: usize, rng: &mut SimRng) -> Slot {
        let len = dims.iter().product();
        let values = uniform(rng, len, 1.0 / (fan_in as f32).sqrt());
        self.store.add(name, values, dims, false)
    }

    /// A cell of `inputs` inputs.
    fn cell(&mut self, name: &str, inputs: usize, shape: Shape, rng: &mut SimRng) -> Cell {
        let (hidden, d) = (shape.hidden, shape.width);
        Cell {
            inputs,
            hidden,
            out: d,
            w1: self.add(&format!("{name}.linear1.weight"), &[inputs, hidden], inputs, rng),
            b1: self.add(&format!("{name}.linear1.bias"), &[hidden], inputs, rng),
            w2: self.add(&format!("{name}.linear2.weight"), &[hidden, d], hidden, rng),
            b2: self.add(&format!("{name}.linear2.bias"), &[d], hidden, rng),
        }
    }
}

impl RelationalNet {
    /// A freshly initialised network of `shape`, its weights drawn from `rng` (uniform in
    /// `±1/sqrt(fan_in)`, as PyTorch's linear layers start).
    pub fn new(shape: Shape, rng: &mut SimRng) -> Result<RelationalNet> {
        shape.validate()?;
        let (d, s) = (shape.width, shape.score_hidden);
        let mut b = Builder::default();
        let embed_w = b.add("embed.weight", &[FEATURES, d], FEATURES, rng);
        let embed_b = b.add("embed.bias", &[d], FEATURES, rng);
        let up = b.cell("up", 2 * d + 1, shape, rng);
        let down = b.cell("down", 3 * d + 1, shape, rng);
        let goal = b.cell("goal", 7 * d + 2, shape, rng);
        let slots = Slots {
            embed_w,
            embed_b,
            up,
            down,
            goal,
            table_up: b.add("table_up", &[d], d, rng),
            clear_down: b.add("clear_down", &[d], d, rng),
            goal_table: b.add("goal_table", &[2 * d], d, rng),
            goal_free: b.add("goal_free", &[2 * d], d, rng),
            goal_top: b.add("goal_top", &[2 * d], d, rng),
            head_w: b.add("head.linear1.weight", &[d, s], d, rng),
            head_b: b.add("head.linear1.bias", &[s], d, rng),
            head_out: b.add("head.linear2.weight", &[s, HEADS], s, rng),
            pair_x: b.add("pair.block.weight", &[d, s], 2 * d + 2, rng),
            pair_y: b.add("pair.destination.weight", &[d, s], 2 * d + 2, rng),
            pair_goal_on: b.add("pair.goal_on.weight", &[s], 2 * d + 2, rng),
            pair_goal_under: b.add("pair.goal_under.weight", &[s], 2 * d + 2, rng),
            pair_bias: b.add("pair.bias", &[s], 2 * d + 2, rng),
            pair_out: b.add("pair.linear2.weight", &[s], s, rng),
        };
        Ok(RelationalNet {
            shape,
            slots,
            store: b.store,
        })
    }

    /// Its shape.
    pub fn shape(&self) -> Shape {
        self.shape
    }

    /// The parameters, one flat buffer.
    pub fn params(&self) -> &[f32] {
        &self.store.params
    }

    /// The parameters, for the optimiser.
    pub fn params_mut(&mut self) -> &mut [f32] {
        &mut self.store.params
    }

    /// Every tensor's name, shape and values, in the buffer's order.
    pub fn tensors(&self) -> impl Iterator<Item = NamedTensor<'_>> {
        self.store.tensors()
    }

    /// Sets the tensor `name` from a file's values; an error if the network has no such
    /// tensor or it has another shape.
    pub fn set_tensor(&mut self, name: &str, shape: &[usize], values: &[f32]) -> Result<()> {
        self.store.set_tensor(name, shape, values)
    }

    /// The number of tensors.
    pub fn tensor_count(&self) -> usize {
        self.store.tensors().count()
    }

    /// A pass over `graph`: every move's score, on the tape ([`Tape::scores`]), with what
    /// a backward pass needs.
    pub fn forward(&self, graph: &Graph, tape: &mut Tape) {
        crate::kernels::without_subnormals(|| self.forward_any(graph, tape));
    }

    fn forward_any(&self, g: &Graph, t: &mut Tape) {
        let n = g.nodes();
        let d = self.shape.width;
        t.pos_up.resize(n, 0);
        t.pos_down.resize(n, 0);
        for (i, &b) in g.up_order.iter().enumerate() {
            t.pos_up[b as usize] = i as u32;
        }
        for (i, &b) in g.down_order.iter().enumerate() {
            t.pos_down[b as usize] = i as u32;
        }
        // Embedding.
        fit(&mut t.features, n * FEATURES);
        for b in 0..n {
            node_features(g, b, &mut t.features[b * FEATURES..(b + 1) * FEATURES]);
        }
        fit(&mut t.h0, n * d);
        self.embed_rows(&t.features, n, &mut t.h0);
        t.rounds.resize_with(self.shape.rounds, RoundTape::default);
        for r in 0..self.shape.rounds {
            let (done, rest) = t.rounds.split_at_mut(r);
            let h: &[f32] = if r == 0 { &t.h0 } else { &done[r - 1].goal.o };
            self.round_forward(g, h, &mut rest[0]);
        }
        self.scores_forward(g, t);
    }

    /// One round (module docs) from the node vectors `h`: up the towers, down, across the
    /// goal; its values on `round`.
    fn round_forward(&self, g: &Graph, h: &[f32], round: &mut RoundTape) {
        let n = g.nodes();
        let d = self.shape.width;
        let half = d / 2;
        let p = &self.store.params;
        let sl = &self.slots;
        // Up the towers: a local term per block, then its running min / max from the
        // table up.
        let up = &sl.up;
        round.up.reserve(n, up);
        for b in 0..n {
            self.up_input(g, h, b, &mut round.up.x[b * up.inputs..(b + 1) * up.inputs]);
        }
        cell_forward(p, up, &mut round.up, 0, n);
        scan(
            &g.up_order,
            &g.below,
            &round.up.o,
            d,
            half,
            &mut round.u,
            &mut round.u_src,
        );
        // Down the towers: a local term per block, then its running min / max from the
        // top down.
        let down = &sl.down;
        round.down.reserve(n, down);
        for b in 0..n {
            let x = &mut round.down.x[b * down.inputs..(b + 1) * down.inputs];
            self.down_input(g, h, &round.u, b, x);
        }
        cell_forward(p, down, &mut round.down, 0, n);
        scan(
            &g.down_order,
            &g.above,
            &round.down.o,
            d,
            half,
            &mut round.v,
            &mut round.v_src,
        );
        // Across the goal.
        let goal = &sl.goal;
        round.goal.reserve(n, goal);
        self.goal_inputs(g, h, round);
        cell_forward(p, goal, &mut round.goal, 0, n);
    }

    /// The per-block scores, the pair perceptron's halves and every listed move's score,
    /// from the last round's node vectors.
    fn scores_forward(&self, g: &Graph, t: &mut Tape) {
        let n = g.nodes();
        // The per-block scores and the pair perceptron's halves.
        let h: &[f32] = match t.rounds.last() {
            Some(r) => &r.goal.o,
            None => &t.h0,
        };
        let s = self.shape.score_hidden;
        fit(&mut t.k, n * s);
        fit(&mut t.heads, n * HEADS);
        fit(&mut t.px, n * s);
        fit(&mut t.qy, n * s);
        let out = HeadRows {
            k: &mut t.k,
            heads: &mut t.heads,
            px: &mut t.px,
            qy: &mut t.qy,
        };
        self.head_rows(h, n, out);
        // The listed moves' scores.
        let m = g.moves.len();
        fit(&mut t.act, m * s);
        fit(&mut t.scores, m);
        let Tape {
            heads,
            px,
            qy,
            act,
            scores,
            ..
        } = t;
        for (k, &(x, y)) in g.moves.iter().enumerate() {
            let values = Values { heads, px, qy };
            scores[k] = self.score(g, values, x, y, Some(&mut act[k * s..(k + 1) * s]));
        }
    }

    /// The inputs of the cell across the goal, by node ([`RelationalNet::goal_input`]).
    fn goal_inputs(&self, g: &Graph, h: &[f32], round: &mut RoundTape) {
        let inputs = self.slots.goal.inputs;
        for b in 0..g.nodes() {
            let x = &mut round.goal.x[b * inputs..(b + 1) * inputs];
            self.goal_input(g, h, &round.u, &round.v, b, x);
        }
    }

    /// Node `b`'s input to the cell up the towers, into `x`: its vector, its support's (a
    /// learnt vector for the table), and whether it stands as the goal wants.
    pub(super) fn up_input(&self, g: &Graph, h: &[f32], b: usize, x: &mut [f32]) {
        let d = self.shape.width;
        let p = &self.store.params;
        x[..d].copy_from_slice(&h[b * d..(b + 1) * d]);
        let below = g.below[b];
        x[d..2 * d].copy_from_slice(if below == NONE {
            &p[self.slots.table_up.range()]
        } else {
            let below = below as usize;
            &h[below * d..(below + 1) * d]
        });
        x[2 * d] = flag(g.stands_as_goal(b));
    }

    /// Node `b`'s input to the cell down the towers, into `x`: its vector, its up value,
    /// and the vector of the block on it (a learnt vector above a clear block) with whether
    /// that block stands as the goal wants.
    pub(super) fn down_input(&self, g: &Graph, h: &[f32], u: &[f32], b: usize, x: &mut [f32]) {
        let d = self.shape.width;
        let p = &self.store.params;
        let row = |b: usize| b * d..(b + 1) * d;
        x[..d].copy_from_slice(&h[row(b)]);
        x[d..2 * d].copy_from_slice(&u[row(b)]);
        let above = g.above[b];
        if above == NONE {
            x[2 * d..3 * d].copy_from_slice(&p[self.slots.clear_down.range()]);
            x[3 * d] = 0.0;
        } else {
            x[2 * d..3 * d].copy_from_slice(&h[row(above as usize)]);
            x[3 * d] = flag(g.stands_as_goal(above as usize));
        }
    }

    /// Node `b`'s input to the cell across the goal, into `x`: its vector, its up and down
    /// values, and those of the blocks the goal puts under and over it (learnt vectors where
    /// there are none), and whether the goal's `on` holds under it and over it.
    pub(super) fn goal_input(&self, g: &Graph, h: &[f32], u: &[f32], v: &[f32], b: usize, x: &mut [f32]) {
        let d = self.shape.width;
        let p = &self.store.params;
        let sl = &self.slots;
        let row = |b: usize| b * d..(b + 1) * d;
        x[..d].copy_from_slice(&h[row(b)]);
        x[d..2 * d].copy_from_slice(&u[row(b)]);
        x[2 * d..3 * d].copy_from_slice(&v[row(b)]);
        let gb = g.goal_below[b];
        match gb {
            TABLE => x[3 * d..5 * d].copy_from_slice(&p[sl.goal_table.range()]),
            NONE => x[3 * d..5 * d].copy_from_slice(&p[sl.goal_free.range()]),
            _ => {
                x[3 * d..4 * d].copy_from_slice(&u[row(gb as usize)]);
                x[4 * d..5 * d].copy_from_slice(&v[row(gb as usize)]);
            }
        }
        let ga = g.goal_above[b];
        if ga == NONE {
            x[5 * d..7 * d].copy_from_slice(&p[sl.goal_top.range()]);
        } else {
            x[5 * d..6 * d].copy_from_slice(&u[row(ga as usize)]);
            x[6 * d..7 * d].copy_from_slice(&v[row(ga as usize)]);
        }
        x[7 * d] = flag(g.stands_as_goal(b));
        x[7 * d + 1] = if ga == NONE {
            0.0
        } else {
            flag(g.stands_as_goal(ga as usize))
        };
    }

    /// The embedding of `rows` nodes' features (`FEATURES` a row, [`node_features`]) into
    /// `h0` (`width` a row).
    pub(super) fn embed_rows(&self, features: &[f32], rows: usize, h0: &mut [f32]) {
        let d = self.shape.width;
        let p = &self.store.params;
        let h0 = &mut h0[..rows * d];
        fill_rows(h0, &p[self.slots.embed_b.range()]);
        matmul(h0, features, &p[self.slots.embed_w.range()], (rows, FEATURES, d), true);
        tanh_in_place(h0);
    }

    /// The cell `kind`'s pass over the first `rows` rows of `tape` (inputs already there,
    /// [`CellTape::reserve`]d for them).
    pub(super) fn cell_rows(&self, kind: CellKind, tape: &mut CellTape, rows: usize) {
        cell_forward(&self.store.params, self.cell(kind), tape, 0, rows);
    }

    /// The cell of `kind`.
    fn cell(&self, kind: CellKind) -> &Cell {
        match kind {
            CellKind::Up => &self.slots.up,
            CellKind::Down => &self.slots.down,
            CellKind::Goal => &self.slots.goal,
        }
    }

    /// The inputs of the cell of `kind`.
    pub(super) fn cell_inputs(&self, kind: CellKind) -> usize {
        self.cell(kind).inputs
    }

    /// The matrix products the cell of `kind` is made of, each as (inner size, columns).
    pub(super) fn cell_products(&self, kind: CellKind) -> [(usize, usize); 2] {
        let c = self.cell(kind);
        [(c.inputs, c.hidden), (c.hidden, c.out)]
    }

    /// The per-block heads of `rows` node vectors `h`: the head's hidden units (into `k`,
    /// `score_hidden` a row), its three scores (`heads`) and the pair perceptron's two halves
    /// (`px`, `qy`, `score_hidden` a row).
    pub(super) fn head_rows(&self, h: &[f32], rows: usize, out: HeadRows<'_>) {
        let (d, s) = (self.shape.width, self.shape.score_hidden);
        let p = &self.store.params;
        let sl = &self.slots;
        let k = &mut out.k[..rows * s];
        fill_rows(k, &p[sl.head_b.range()]);
        matmul(k, h, &p[sl.head_w.range()], (rows, d, s), true);
        k.iter_mut().for_each(|v| *v = v.max(0.0));
        matmul(out.heads, k, &p[sl.head_out.range()], (rows, s, HEADS), false);
        matmul(out.px, h, &p[sl.pair_x.range()], (rows, d, s), false);
        matmul(out.qy, h, &p[sl.pair_y.range()], (rows, d, s), false);
    }

    /// The matrix products of [`RelationalNet::head_rows`], each as (inner size, columns).
    pub(super) fn head_products(&self) -> [(usize, usize); 4] {
        let (d, s) = (self.shape.width, self.shape.score_hidden);
        [(d, s), (s, HEADS), (d, s), (d, s)]
    }

    /// The score of moving `x` to `y` (a node or [`TABLE`]) from a pass's per-block values:
    /// `a_x + b_y + r(x, y)`, `r` the pair perceptron where the goal relates the two blocks
    /// (0 elsewhere), or `t_x` to the table. `act` receives the pair perceptron's hidden
    /// units (zero where it is not run).
    pub(super) fn score(&self, g: &Graph, t: Values<'_>, x: u32, y: u32, act: Option<&mut [f32]>) -> f32 {
        let (x, s) = (x as usize, self.shape.score_hidden);
        if y == TABLE {
            if let Some(act) = act {
                act.fill(0.0);
            }
            return t.heads[x * HEADS + 2];
        }
        let y = y as usize;
        let base = t.heads[x * HEADS] + t.heads[y * HEADS + 1];
        let (on, under) = (g.goal_below[x] == y as u32, g.goal_below[y] == x as u32);
        if !(on || under) {
            if let Some(act) = act {
                act.fill(0.0);
            }
            return base;
        }
        let p = &self.store.params;
        let sl = &self.slots;
        let (px, qy) = (&t.px[x * s..(x + 1) * s], &t.qy[y * s..(y + 1) * s]);
        let (won, wunder, bias, out) = (
            &p[sl.pair_goal_on.range()],
            &p[sl.pair_goal_under.range()],
            &p[sl.pair_bias.range()],
            &p[sl.pair_out.range()],
        );
        let mut r = 0.0;
        let mut store = act;
        for j in 0..s {
            let mut pre = px[j] + qy[j] + bias[j];
            if on {
                pre += won[j];
            }
            if under {
                pre += wunder[j];
            }
            let a = pre.max(0.0);
            if let Some(act) = store.as_deref_mut() {
                act[j] = a;
            }
            r += a * out[j];
        }
        base + r
    }

    /// The legal move of `graph`'s problem `problem` with the highest score after a pass
    /// ([`RelationalNet::forward`]): (block node, destination node or [`TABLE`]), the
    /// first in [`oracle::towers::Towers::moves`] order on a tie; `None` if no move is
    /// legal. Moves to the table are left out unless `table_free`. It does not list the
    /// moves: a move between blocks the goal does not relate scores `a_x + b_y`, so the
    /// best such move of each block takes the best `b` among the few clear blocks that
    /// are not it or related to it.
    pub fn best_move(&self, g: &Graph, t: &Tape, problem: usize, table_free: bool) -> Option<(u32, u32)> {
        let span = g.spans[problem];
        let values = Values {
            heads: &t.heads,
            px: &t.px,
            qy: &t.qy,
        };
        let clear: Vec<u32> = (span.first_node..span.first_node + span.nodes)
            .filter(|&b| g.above[b] == NONE)
            .map(|b| b as u32)
            .collect();
        let b_of = |y: u32| t.heads[y as usize * HEADS + 1];
        // The four best destinations by b (ties to the lower node): enough to skip the
        // block itself and the two the goal relates it to.
        let mut top: Vec<u32> = Vec::with_capacity(5);
        for &y in &clear {
            let at = top.iter().position(|&z| b_of(y) > b_of(z)).unwrap_or(top.len());
            if at < 4 {
                top.insert(at, y);
                top.truncate(4);
            }
        }
        // (score, order key, move): the order key is the move's place in Towers::moves order.
        let mut best: Option<ScoredMove> = None;
        let mut offer = |score: f32, key: (u32, u32), mv: (u32, u32)| {
            if best.is_none_or(|(s, k, _)| score > s || (score == s && key < k)) {
                best = Some((score, key, mv));
            }
        };
        for &x in &clear {
            let xs = x as usize;
            if table_free && g.below[xs] != NONE {
                offer(self.score(g, values, x, TABLE, None), (x, 0), (x, TABLE));
            }
            let related = |y: u32| g.goal_below[xs] == y || g.goal_above[xs] == y;
            for y in [g.goal_below[xs], g.goal_above[xs]] {
                if y != NONE && y != TABLE && y != x && g.above[y as usize] == NONE {
                    offer(self.score(g, values, x, y, None), (x, y + 1), (x, y));
                }
            }
            if let Some(&y) = top.iter().find(|&&y| y != x && !related(y)) {
                let score = t.heads[xs * HEADS] + b_of(y);
                offer(score, (x, y + 1), (x, y));
            }
        }
        best.map(|(_, _, mv)| mv)
    }

    /// The backward pass of the last [`RelationalNet::forward`] on `graph` with `tape`:
    /// given each move's score gradient `dscores`, adds every parameter's gradient into
    /// `grads` (as long as the parameters).
    pub fn backward(&self, graph: &Graph, tape: &mut Tape, dscores: &[f32], grads: &mut [f32]) {
        crate::kernels::without_subnormals(|| self.backward_any(graph, tape, dscores, grads));
    }

    fn backward_any(&self, g: &Graph, t: &mut Tape, dscores: &[f32], grads: &mut [f32]) {
        assert_eq!(grads.len(), self.store.params.len(), "a gradient per parameter");
        assert_eq!(dscores.len(), g.moves.len(), "a score gradient per move");
        let n = g.nodes();
        let (d, s) = (self.shape.width, self.shape.score_hidden);
        let p = &self.store.params;
        let sl = &self.slots;
        self.moves_backward(g, t, dscores, grads);
        let h: &[f32] = match t.rounds.last() {
            Some(r) => &r.goal.o,
            None => &t.h0,
        };
        matmul_tn(&mut grads[sl.head_out.range()], &t.k, &t.dheads, (s, n, HEADS), true);
        fit(&mut t.dk, n * s);
        matmul_nt(&mut t.dk, &t.dheads, &p[sl.head_out.range()], (n, HEADS, s), false);
        for (g, &a) in t.dk.iter_mut().zip(&t.k) {
            if a <= 0.0 {
                *g = 0.0;
            }
        }
        matmul_tn(&mut grads[sl.head_w.range()], h, &t.dk, (d, n, s), true);
        add_row_sums(&mut grads[sl.head_b.range()], &t.dk);
        matmul_tn(&mut grads[sl.pair_x.range()], h, &t.dpx, (d, n, s), true);
        matmul_tn(&mut grads[sl.pair_y.range()], h, &t.dqy, (d, n, s), true);
        fit(&mut t.dh, n * d);
        matmul_nt(&mut t.dh, &t.dk, &p[sl.head_w.range()], (n, s, d), false);
        matmul_nt(&mut t.dh, &t.dpx, &p[sl.pair_x.range()], (n, s, d), true);
        matmul_nt(&mut t.dh, &t.dqy, &p[sl.pair_y.range()], (n, s, d), true);
        // The rounds, last first: `dh` holds the gradient of the round's output.
        for r in (0..self.shape.rounds).rev() {
            self.round_backward(g, r, t, grads);
        }
        // The embedding.
        for (dh, &h0) in t.dh.iter_mut().zip(&t.h0) {
            *dh *= 1.0 - h0 * h0;
        }
        matmul_tn(
            &mut grads[sl.embed_w.range()],
            &t.features,
            &t.dh,
            (FEATURES, n, d),
            true,
        );
        add_row_sums(&mut grads[sl.embed_b.range()], &t.dh);
    }

    /// The listed moves' part of the backward pass: from each move's score gradient
    /// `dscores`, the gradients of the per-block scores and of the pair perceptron's halves
    /// (on `t`), and of the pair perceptron's own parameters (into `grads`).
    fn moves_backward(&self, g: &Graph, t: &mut Tape, dscores: &[f32], grads: &mut [f32]) {
        let n = g.nodes();
        let s = self.shape.score_hidden;
        let p = &self.store.params;
        let sl = &self.slots;
        // The scorer: per-block scores and the pair perceptron.
        fit(&mut t.dheads, n * HEADS);
        t.dheads.fill(0.0);
        fit(&mut t.dpx, n * s);
        fit(&mut t.dqy, n * s);
        t.dpx.fill(0.0);
        t.dqy.fill(0.0);
        let out = &p[sl.pair_out.range()];
        for (k, &(x, y)) in g.moves.iter().enumerate() {
            let ds = dscores[k];
            let x = x as usize;
            if y == TABLE {
                t.dheads[x * HEADS + 2] += ds;
                continue;
            }
            let y = y as usize;
            t.dheads[x * HEADS] += ds;
            t.dheads[y * HEADS + 1] += ds;
            let (on, under) = (g.goal_below[x] == y as u32, g.goal_below[y] == x as u32);
            if !(on || under) {
                continue;
            }
            let act = &t.act[k * s..(k + 1) * s];
            for j in 0..s {
                grads[sl.pair_out.offset + j] += ds * act[j];
                if act[j] <= 0.0 {
                    continue;
                }
                let dpre = ds * out[j];
                t.dpx[x * s + j] += dpre;
                t.dqy[y * s + j] += dpre;
                if on {
                    grads[sl.pair_goal_on.offset + j] += dpre;
                }
                if under {
                    grads[sl.pair_goal_under.offset + j] += dpre;
                }
                grads[sl.pair_bias.offset + j] += dpre;
            }
        }
    }

    /// Round `r`'s backward pass: from the gradient of its output in `t.dh` to that of its
    /// input, left in `t.dh`, adding its parameters' gradients into `grads`.
    fn round_backward(&self, g: &Graph, r: usize, t: &mut Tape, grads: &mut [f32]) {
        let n = g.nodes();
        let d = self.shape.width;
        let p = &self.store.params;
        let sl = &self.slots;
        let round = &t.rounds[r];
        // Across the goal.
        let goal = &sl.goal;
        fit(&mut t.dx, n * goal.inputs);
        cell_backward(p, goal, &round.goal, 0, n, &mut t.dh, &mut t.dx, &mut t.dhid, grads);
        fit(&mut t.du, n * d);
        fit(&mut t.dv, n * d);
        t.du.fill(0.0);
        t.dv.fill(0.0);
        // The gradient of the round's input h, gathered from the three cells.
        fit(&mut t.din, n * d);
        t.din.fill(0.0);
        for b in 0..n {
            let dx = &t.dx[b * goal.inputs..(b + 1) * goal.inputs];
            add_into(&mut t.din, b, &dx[..d]);
            add_into(&mut t.du, b, &dx[d..2 * d]);
            add_into(&mut t.dv, b, &dx[2 * d..3 * d]);
            let gb = g.goal_below[b];
            match gb {
                TABLE => add_slice(&mut grads[sl.goal_table.range()], &dx[3 * d..5 * d]),
                NONE => add_slice(&mut grads[sl.goal_free.range()], &dx[3 * d..5 * d]),
                _ => {
                    add_into(&mut t.du, gb as usize, &dx[3 * d..4 * d]);
                    add_into(&mut t.dv, gb as usize, &dx[4 * d..5 * d]);
                }
            }
            let ga = g.goal_above[b];
            if ga == NONE {
                add_slice(&mut grads[sl.goal_top.range()], &dx[5 * d..7 * d]);
            } else {
                add_into(&mut t.du, ga as usize, &dx[5 * d..6 * d]);
                add_into(&mut t.dv, ga as usize, &dx[6 * d..7 * d]);
            }
        }
        // Down: through the scan to the local terms, then the cell.
        let down = &sl.down;
        fit(&mut t.dg, n * d);
        scan_backward(&round.v_src, &t.dv, d, &mut t.dg);
        fit(&mut t.dx, n * down.inputs);
        cell_backward(p, down, &round.down, 0, n, &mut t.dg, &mut t.dx, &mut t.dhid, grads);
        for b in 0..n {
            let dx = &t.dx[b * down.inputs..(b + 1) * down.inputs];
            add_into(&mut t.din, b, &dx[..d]);
            add_into(&mut t.du, b, &dx[d..2 * d]);
            let above = g.above[b];
            if above == NONE {
                add_slice(&mut grads[sl.clear_down.range()], &dx[2 * d..3 * d]);
            } else {
                add_into(&mut t.din, above as usize, &dx[2 * d..3 * d]);
            }
        }
        // Up: through the scan, then the cell.
        let up = &sl.up;
        scan_backward(&round.u_src, &t.du, d, &mut t.dg);
        fit(&mut t.dx, n * up.inputs);
        cell_backward(p, up, &round.up, 0, n, &mut t.dg, &mut t.dx, &mut t.dhid, grads);
        for b in 0..n {
            let dx = &t.dx[b * up.inputs..(b + 1) * up.inputs];
            add_into(&mut t.din, b, &dx[..d]);
            let below = g.below[b];
            if below == NONE {
                add_slice(&mut grads[sl.table_up.range()], &dx[d..2 * d]);
            } else {
                add_into(&mut t.din, below as usize, &dx[d..2 * d]);
            }
        }
        std::mem::swap(&mut t.dh, &mut t.din);
    }
}

/// The per-node values a move's score is read from.
#[derive(Clone, Copy)]
pub(super) struct Values<'a> {
    pub(super) heads: &'a [f32],
    pub(super) px: &'a [f32],
    pub(super) qy: &'a [f32],
}

impl CellTape {
    /// Makes room for `n` rows of the cell of `kind` of `net`.
    pub(super) fn reserve_for(&mut self, net: &RelationalNet, kind: CellKind, n: usize) {
        self.reserve(n, net.cell(kind));
    }

    /// Makes room for `n` rows of `cell`.
    fn reserve(&mut self, n: usize, cell: &Cell) {
        fit(&mut self.x, n * cell.inputs);
        fit(&mut self.h, n * cell.hidden);
        fit(&mut self.o, n * cell.out);
    }
}

/// 1.0 for true, 0.0 for false.
fn flag(b: bool) -> f32 {
    if b { 1.0 } else { 0.0 }
}

/// Sets every row of `rows` to `bias`.
fn fill_rows(rows: &mut [f32], bias: &[f32]) {
    for row in rows.chunks_exact_mut(bias.len()) {
        row.copy_from_slice(bias);
    }
}

/// Adds `values` into row `row` of `m` (rows of `values.len()`).
fn add_into(m: &mut [f32], row: usize, values: &[f32]) {
    let w = values.len();
    add_slice(&mut m[row * w..(row + 1) * w], values);
}

/// `a += b`.
fn add_slice(a: &mut [f32], b: &[f32]) {
    for (x, &y) in a.iter_mut().zip(b) {
        *x += y;
    }
}

/// Adds the sum of the rows of `rows` (each `sum.len()` long) into `sum`.
fn add_row_sums(sum: &mut [f32], rows: &[f32]) {
    for row in rows.chunks_exact(sum.len()) {
        add_slice(sum, row);
    }
}

/// A running minimum (channels `..half`) and maximum (channels `half..`) of the local
/// terms `terms` along a relation, in `order` (each node after the node `prev` names, or
/// first where it names [`NONE`]): `out[b] = min / max(out[prev[b]], terms[b])`, with
/// `src` the node whose term each value is (the earlier one on a tie).
fn scan(order: &[u32], prev: &[u32], terms: &[f32], d: usize, half: usize, out: &mut Vec<f32>, src: &mut Vec<u32>) {
    let n = prev.len();
    fit(out, n * d);
    src.resize(n * d, 0);
    for &b in order {
        let b = b as usize;
        let here = &terms[b * d..(b + 1) * d];
        let p = prev[b];
        if p == NONE {
            out[b * d..(b + 1) * d].copy_from_slice(here);
            src[b * d..(b + 1) * d].fill(b as u32);
            continue;
        }
        let p = p as usize;
        for c in 0..d {
            let (before, now) = (out[p * d + c], here[c]);
            let take = extends(c, half, now, before);
            if take {
                out[b * d + c] = now;
                src[b * d + c] = b as u32;
            } else {
                out[b * d + c] = before;
                src[b * d + c] = src[p * d + c];
            }
        }
    }
}

/// Whether channel `c`'s running value along a tower moves from `before` to `now`: a
/// running minimum in channels `..half`, a maximum in the others (the earlier value on a
/// tie).
pub(super) fn extends(c: usize, half: usize, now: f32, before: f32) -> bool {
    if c < half { now < before } else { now > before }
}

/// A node's input features, into `f`: on-table, clear, the goal's on-table.
pub(super) fn node_features(g: &Graph, b: usize, f: &mut [f32]) {
    f[0] = flag(g.below[b] == NONE);
    f[1] = flag(g.above[b] == NONE);
    f[2] = flag(g.goal_below[b] == TABLE);
}

/// The gradient of [`scan`]'s local terms (into `dterms`, overwritten) from its values'
/// (`dout`), `d` values a node.
fn scan_backward(src: &[u32], dout: &[f32], d: usize, dterms: &mut [f32]) {
    dterms.fill(0.0);
    for (i, (&from, &g)) in src.iter().zip(dout).enumerate() {
        dterms[from as usize * d + i % d] += g;
    }
}

/// The cell's forward pass over rows `s..e` of its tape (inputs already there).
fn cell_forward(p: &[f32], c: &Cell, t: &mut CellTape, s: usize, e: usize) {
    let rows = e - s;
    if rows == 0 {
        return;
    }
    let x = &t.x[s * c.inputs..e * c.inputs];
    let h = &mut t.h[s * c.hidden..e * c.hidden];
    fill_rows(h, &p[c.b1.range()]);
    matmul(h, x, &p[c.w1.range()], (rows, c.inputs, c.hidden), true);
    h.iter_mut().for_each(|v| *v = v.max(0.0));
    let o = &mut t.o[s * c.out..e * c.out];
    fill_rows(o, &p[c.b2.range()]);
    matmul(o, h, &p[c.w2.range()], (rows, c.hidden, c.out), true);
    tanh_in_place(o);
}

/// The cell's backward pass over rows `s..e`: `dout` (rows in the tape's order) holds the
/// output gradients, `dx` receives the input gradients (same rows), and the weight
/// gradients are added into `grads`. `dhid` is scratch.
#[allow(clippy::too_many_arguments)]
fn cell_backward(
    p: &[f32],
    c: &Cell,
    t: &CellTape,
    s: usize,
    e: usize,
    dout: &mut [f32],
    dx: &mut [f32],
    dhid: &mut Vec<f32>,
    grads: &mut [f32],
) {
    let rows = e - s;
    if rows == 0 {
        return;
    }
    let o = &t.o[s * c.out..e * c.out];
    let dz = &mut dout[s * c.out..e * c.out];
    for (g, &y) in dz.iter_mut().zip(o) {
        *g *= 1.0 - y * y;
    }
    let h = &t.h[s * c.hidden..e * c.hidden];
    matmul_tn(&mut grads[c.w2.range()], h, dz, (c.hidden, rows, c.out), true);
    add_row_sums(&mut grads[c.b2.range()], dz);
    fit(dhid, rows * c.hidden);
    matmul_nt(dhid, dz, &p[c.w2.range()], (rows, c.out, c.hidden), false);
    for (g, &a) in dhid.iter_mut().zip(h) {
        if a <= 0.0 {
            *g = 0.0;
        }
    }
    let x = &t.x[s * c.inputs..e * c.inputs];
    matmul_tn(&mut grads[c.w1.range()], x, dhid, (c.inputs, rows, c.hidden), true);
    add_row_sums(&mut grads[c.b1.range()], dhid);
    matmul_nt(
        &mut dx[s * c.inputs..e * c.inputs],
        dhid,
        &p[c.w1.range()],
        (rows, c.hidden, c.inputs),
        false,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use oracle::towers::{TowerGoal, Towers, random_goal, random_state};

    fn shape() -> Shape {
        Shape {
            width: 5,
            hidden: 6,
            score_hidden: 4,
            rounds: 2,
        }
    }

    fn problems() -> Vec<(Towers, TowerGoal)> {
        (0..4)
            .map(|seed| {
                let n = 3 + seed as usize;
                let goal = if seed % 2 == 0 {
                    TowerGoal::new(&random_state(n, seed + 50).towers()).unwrap()
                } else {
                    random_goal(n, 2, n - 1, seed).unwrap()
                };
                (random_state(n, seed), goal)
            })
            .collect()
    }

    /// A loss that touches every score: sum of w_k * score_k.
    fn loss(net: &RelationalNet, g: &Graph, w: &[f32]) -> f64 {
        let mut tape = Tape::new();
        net.forward(g, &mut tape);
        tape.scores()
            .iter()
            .zip(w)
            .map(|(&s, &w)| f64::from(s) * f64::from(w))
            .sum()
    }

    #[test]
    fn the_backward_pass_is_the_gradient() {
        let mut net = RelationalNet::new(shape(), &mut sim::seeding::rng(3)).unwrap();
        let problems = problems();
        let g = Graph::with_moves(problems.iter().map(|(s, goal)| (s, goal)));
        let w: Vec<f32> = (0..g.moves.len()).map(|k| ((k as f32) * 0.77).sin()).collect();
        let mut tape = Tape::new();
        net.forward(&g, &mut tape);
        let mut grads = vec![0.0; net.params().len()];
        net.backward(&g, &mut tape, &w, &mut grads);
        // Central differences; a step may move a scan's minimum or maximum to another
        // block, or a ReLU across 0, where the loss has a kink: a few parameters may
        // disagree there, and no more than that.
        let eps = 1e-3f32;
        let mut off = Vec::new();
        for (i, &analytic) in grads.iter().enumerate() {
            let keep = net.params()[i];
            net.params_mut()[i] = keep + eps;
            let plus = loss(&net, &g, &w);
            net.params_mut()[i] = keep - eps;
            let minus = loss(&net, &g, &w);
            net.params_mut()[i] = keep;
            let numeric = (plus - minus) / (2.0 * f64::from(eps));
            let err = (numeric - f64::from(analytic)).abs() / (1e-2 + numeric.abs().max(f64::from(analytic).abs()));
            if err > 2e-2 {
                // The tensors lie one after another in the parameters.
                let mut start = 0;
                let t = net
                    .tensors()
                    .find(|t| {
                        let hit = i < start + t.values.len();
                        start += if hit { 0 } else { t.values.len() };
                        hit
                    })
                    .unwrap();
                off.push(format!(
                    "{}[{}]: numeric {numeric} analytic {analytic}",
                    t.name,
                    i - start
                ));
            }
        }
        assert!(
            off.len() * 100 <= net.params().len(),
            "{} of {}: {off:?}",
            off.len(),
            net.params().len()
        );
    }

    #[test]
    fn a_pass_is_the_same_for_a_problem_alone_or_in_a_batch() {
        let net = RelationalNet::new(shape(), &mut sim::seeding::rng(4)).unwrap();
        let problems = problems();
        let g = Graph::with_moves(problems.iter().map(|(s, goal)| (s, goal)));
        let mut tape = Tape::new();
        net.forward(&g, &mut tape);
        let all = tape.scores().to_vec();
        for (p, (s, goal)) in problems.iter().enumerate() {
            let alone = Graph::with_moves([(s, goal)]);
            net.forward(&alone, &mut tape);
            let span = g.spans[p];
            let batch = &all[span.first_move..span.first_move + span.moves];
            for (a, b) in tape.scores().iter().zip(batch) {
                assert!((a - b).abs() < 1e-5, "problem {p}: {a} {b}");
            }
        }
    }

    #[test]
    fn the_best_move_has_the_best_listed_score() {
        for seed in 0..30u64 {
            let net = RelationalNet::new(shape(), &mut sim::seeding::rng(seed)).unwrap();
            let n = 2 + seed as usize % 9;
            let state = random_state(n, seed + 7);
            let goal = if seed % 3 == 0 {
                random_goal(n, 1, n.min(2), seed).unwrap()
            } else {
                TowerGoal::new(&random_state(n, seed + 8).towers()).unwrap()
            };
            let listed = Graph::with_moves([(&state, &goal)]);
            let mut tape = Tape::new();
            net.forward(&listed, &mut tape);
            let scores = tape.scores().to_vec();
            for table_free in [true, false] {
                // The best listed score (the sums of a and b may round to ties).
                let allowed = |k: &usize| table_free || listed.moves[*k].1 != TABLE;
                let best = (0..scores.len())
                    .filter(allowed)
                    .map(|k| scores[k])
                    .fold(f32::NEG_INFINITY, f32::max);
                let alone = Graph::of([(&state, &goal)]);
                net.forward(&alone, &mut tape);
                let got = net.best_move(&alone, &tape, 0, table_free);
                let k = got.map(|mv| listed.moves.iter().position(|&m| m == mv).expect("a legal move"));
                match k {
                    Some(k) => assert!(
                        allowed(&k) && scores[k] >= best - 1e-6,
                        "seed {seed}: {} < {best}",
                        scores[k]
                    ),
                    None => assert_eq!(best, f32::NEG_INFINITY, "seed {seed}"),
                }
            }
        }
    }
}
