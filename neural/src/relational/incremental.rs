//! The network's pass kept up to date move by move, for play: a policy that passes over
//! every block for every move plays a game of N blocks in O(N^2); this one recomputes, after
//! a move, only the values whose inputs changed.
//!
//! # What a move changes
//!
//! A move changes the relations of three blocks: the moved block (what it stands on), the
//! block it left and the block it landed on (whether they are clear). In each round
//! ([`super::net`] gives the computation) the evaluator recomputes:
//!
//! - the up cell of every block whose vector changed, of the block on it, and of the moved
//!   block; then the up pass from each changed term upwards, as long as its running value
//!   changes;
//! - the down cell of every block whose vector or up value changed, of the block under one
//!   whose vector changed, and of the two blocks whose top changed; then the down pass from
//!   each changed term downwards, as long as it changes;
//! - the goal cell of every block whose vector, up or down value changed, of their goal
//!   partners (the goal's block under and over them), of the moved block and of its goal
//!   partner under it;
//!
//! and the next round starts from the blocks whose output changed. A value counts as changed
//! when its bits do: a running minimum or maximum often stops changing a few blocks from the
//! move, so most of a tower keeps its values. Then the per-block heads of the blocks whose
//! final vector changed, and the sets the best move is read from.
//!
//! # Bit for bit the full pass's values
//!
//! Every value is computed by the same functions of [`super::net`] on the same inputs, so
//! it is the full pass's value as long as the matrix products give a row the same bits in a
//! product of a few rows as in one of all N. `gemm` (0.19) does not: a product of at most
//! 256 outputs takes its small-product kernels, which sum in an order that depends on where
//! a row falls in their tiles; one row alone takes its matrix-vector kernel; and past 64
//! rows or columns, a product of more than 512 inner terms is cut where its cache sizes
//! say. So the evaluator pads a product of a few rows to the size class of the full pass's
//! product over N rows, or, where that is a small product (N of at most 256 over the
//! columns: a few dozen blocks), recomputes every row. The tests compare every
//! value with a full pass after every move of random walks, and every move of whole games
//! with the full pass's, on random shapes.
//!
//! # The best move without a scan
//!
//! [`super::net::RelationalNet::best_move`] looks at every clear block. The live pass keeps the
//! clear blocks sorted by each of their three per-block scores, and the moves between blocks
//! the goal relates sorted by score, each updated for the blocks a move touched. The best
//! move onto an unrelated block is, for all but the few blocks related to the best
//! destination, the block with the best score for moving onto it, so it is read from the
//! first entries of two sets.
//!
//! # What it costs
//!
//! With one round, a move changes the values of the two towers it touched and of their goal
//! partners: a game is about linear in the blocks. With two, what the first round changed,
//! scattered over the goal partners' towers, spreads in the second through those towers and
//! their partners, to a large part of the blocks while towers are tall, so a game stays
//! superlinear (docs/dqn.md, "Playing 10,000 blocks", and docs/results/general).

use std::cmp::Reverse;
use std::collections::BTreeSet;

use oracle::towers::{Move, Place, Table, TowerGoal, Towers};

use crate::error::Result;

use super::graph::{Graph, NONE, TABLE};
use super::net::{CellKind, CellTape, FEATURES, HEADS, HeadRows, RelationalNet, Tape, Values, extends, node_features};

/// A pass over one problem kept up to date as its moves are made (module docs): the state,
/// the goal's relations, every round's values for every block, the heads, and the sets the
/// best move is read from.
pub struct LivePass<'n> {
    net: &'n RelationalNet,
    state: Towers,
    /// The relations; `below` and `above` follow the moves (its up and down orders are not
    /// kept: they are only the full pass's).
    graph: Graph,
    /// Named blocks that do not stand where the goal puts them.
    unmet: usize,
    /// The embedding, a row of `width` per block.
    h0: Vec<f32>,
    rounds: Vec<RoundValues>,
    heads: Vec<f32>,
    px: Vec<f32>,
    qy: Vec<f32>,
    picks: Picks,
    work: Work,
}

/// One round's values, a row of `width` per block.
struct RoundValues {
    /// The up cell's outputs (the up pass's local terms).
    up: Vec<f32>,
    /// The up pass.
    u: Vec<f32>,
    /// The down cell's outputs.
    down: Vec<f32>,
    /// The down pass.
    v: Vec<f32>,
    /// The goal cell's outputs: the round's node vectors.
    out: Vec<f32>,
}

/// Scratch of an update.
struct Work {
    /// Every block, in order.
    all: Vec<u32>,
    /// Blocks whose round input changed, and whose output changed.
    changed: NodeSet,
    next: NodeSet,
    /// Blocks to recompute, and local terms that changed.
    dirty: NodeSet,
    terms: NodeSet,
    /// Blocks whose up and down values changed.
    u: NodeSet,
    v: NodeSet,
    cell: CellTape,
    features: Vec<f32>,
    rows: Vec<f32>,
    heads: [Vec<f32>; 4],
}

/// A set of blocks, listed in the order they came, with a flag per block.
struct NodeSet {
    mark: Vec<bool>,
    list: Vec<u32>,
}

impl NodeSet {
    fn new(n: usize) -> NodeSet {
        NodeSet {
            mark: vec![false; n],
            list: Vec::new(),
        }
    }

    /// Adds `b`, if it is a block (not [`NONE`] or [`TABLE`]) and not in the set.
    fn insert(&mut self, b: u32) {
        if let Some(m) = self.mark.get_mut(b as usize)
            && !*m
        {
            *m = true;
            self.list.push(b);
        }
    }

    fn clear(&mut self) {
        for &b in &self.list {
            self.mark[b as usize] = false;
        }
        self.list.clear();
    }
}

/// gemm's products of at most this many outputs take its small-product kernels.
const SMALL_PRODUCT: usize = 256;
/// Past this many rows or columns, a product's inner terms are cut by cache sizes ...
const SMALL_SIDE: usize = 64;
/// ... when there are more than this many of them.
const SMALL_INNER: usize = 512;

/// The rows to compute and the rows of the products that compute them, so that gemm
/// computes each row as the full pass's products over `all` blocks do (module docs), for
/// every product in `products` (inner size, columns): `dirty` padded to the size class of
/// those products, or every block, in order, where one of them takes the small-product
/// kernels (whose sums run in an order that depends on where a row falls in its tile).
fn batch<'a>(dirty: &'a [u32], all: &'a [u32], products: &[(usize, usize)]) -> (&'a [u32], usize) {
    let full = all.len();
    if products.iter().any(|&(_, cols)| full * cols <= SMALL_PRODUCT) {
        return (all, full);
    }
    let mut rows = dirty.len();
    for &(inner, cols) in products {
        rows = rows.max(SMALL_PRODUCT / cols + 1).max(2);
        if full > SMALL_SIDE && cols <= SMALL_SIDE && inner > SMALL_INNER {
            rows = rows.max(SMALL_SIDE + 1);
        }
    }
    (dirty, rows)
}

/// Whether two rows hold the same bits.
fn same_bits(a: &[f32], b: &[f32]) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

impl<'n> LivePass<'n> {
    /// The pass of `net` over `state` towards `goal`; an error if the goal names a block the
    /// state lacks.
    pub fn new(net: &'n RelationalNet, state: &Towers, goal: &TowerGoal) -> Result<LivePass<'n>> {
        goal.check_blocks(state.blocks())?;
        let mut graph = Graph::of([(state, goal)]);
        let mut tape = Tape::new();
        net.forward(&graph, &mut tape);
        let n = graph.nodes();
        let d = net.shape().width;
        let s = net.shape().score_hidden;
        let rounds = (0..net.shape().rounds)
            .map(|r| {
                let [up, u, down, v, out] = tape.round_values(r).map(|x| x[..n * d].to_vec());
                RoundValues { up, u, down, v, out }
            })
            .collect();
        let values = tape.values();
        (graph.up_order, graph.up_levels, graph.down_order, graph.down_levels) = Default::default();
        let unmet = (0..n)
            .filter(|&b| graph.goal_below[b] != NONE && !graph.stands_as_goal(b))
            .count();
        let mut live = LivePass {
            net,
            state: state.clone(),
            unmet,
            h0: tape.embedding()[..n * d].to_vec(),
            rounds,
            heads: values.heads[..n * HEADS].to_vec(),
            px: values.px[..n * s].to_vec(),
            qy: values.qy[..n * s].to_vec(),
            picks: Picks::new(n),
            work: Work {
                all: (0..n as u32).collect(),
                changed: NodeSet::new(n),
                next: NodeSet::new(n),
                dirty: NodeSet::new(n),
                terms: NodeSet::new(n),
                u: NodeSet::new(n),
                v: NodeSet::new(n),
                cell: CellTape::default(),
                features: Vec::new(),
                rows: Vec::new(),
                heads: Default::default(),
            },
            graph,
        };
        for b in 0..n {
            live.picks.enter(&live.graph, &live.heads, b);
        }
        for b in 0..n {
            let values = Values {
                heads: &live.heads,
                px: &live.px,
                qy: &live.qy,
            };
            live.picks.enter_related(net, &live.graph, values, b);
        }
        Ok(live)
    }

    /// The state.
    pub fn state(&self) -> &Towers {
        &self.state
    }

    /// Whether the goal holds.
    pub fn goal_holds(&self) -> bool {
        self.unmet == 0
    }

    /// The legal move with the highest score, as [`RelationalNet::best_move`] chooses it
    /// (the same move, ties included); moves to the table only if `table_free`; `None` if
    /// no move is legal.
    pub fn best_move(&self, table_free: bool) -> Option<Move> {
        let values = Values {
            heads: &self.heads,
            px: &self.px,
            qy: &self.qy,
        };
        let (x, to) = self.picks.best(self.net, &self.graph, values, table_free)?;
        Some(Move {
            block: x as usize,
            to: if to == TABLE {
                Place::Table
            } else {
                Place::On(to as usize)
            },
        })
    }

    /// Makes `mv` on `table` and brings every value up to date; an error, and nothing
    /// changed, if the move is not legal.
    pub fn apply(&mut self, mv: Move, table: Table) -> Result<()> {
        self.state.apply(mv, table)?;
        crate::kernels::without_subnormals(|| self.update(mv));
        Ok(())
    }

    /// Brings the relations and every value up to date after `mv` (module docs).
    fn update(&mut self, mv: Move) {
        let moved = self.relink(mv);
        self.embed(moved);
        for r in 0..self.rounds.len() {
            self.update_round(r, moved);
        }
        self.update_heads();
        self.update_picks(moved);
    }

    /// Moves `mv`'s block in the relations and in the count of unmet goal facts; the blocks
    /// whose relations changed: (the moved block, the one it left, the one it landed on),
    /// [`NONE`] for the table.
    fn relink(&mut self, mv: Move) -> [u32; 3] {
        let g = &mut self.graph;
        let x = mv.block;
        let from = g.below[x];
        let to = match mv.to {
            Place::Table => NONE,
            Place::On(y) => y as u32,
        };
        let named = g.goal_below[x] != NONE;
        let stood = g.stands_as_goal(x);
        if from != NONE {
            g.above[from as usize] = NONE;
        }
        g.below[x] = to;
        if to != NONE {
            g.above[to as usize] = x as u32;
        }
        match (named, stood, g.stands_as_goal(x)) {
            (true, true, false) => self.unmet += 1,
            (true, false, true) => self.unmet -= 1,
            _ => {}
        }
        [x as u32, from, to]
    }

    /// The embedding of the blocks whose relations changed; they start the first round's
    /// changed set.
    fn embed(&mut self, moved: [u32; 3]) {
        let (g, net, w) = (&self.graph, self.net, &mut self.work);
        let d = net.shape().width;
        w.changed.clear();
        w.dirty.clear();
        moved.iter().for_each(|&b| w.dirty.insert(b));
        let (nodes, rows) = batch(&w.dirty.list, &w.all, &[(FEATURES, d)]);
        w.features.clear();
        w.features.resize(rows * FEATURES, 0.0);
        for (i, &b) in nodes.iter().enumerate() {
            node_features(g, b as usize, &mut w.features[i * FEATURES..(i + 1) * FEATURES]);
        }
        w.rows.resize(rows * d, 0.0);
        net.embed_rows(&w.features, rows, &mut w.rows);
        write_rows(nodes, &w.rows, &mut self.h0, d, &mut w.changed);
    }

    /// Round `r`'s values recomputed where their inputs changed: the blocks the previous
    /// round changed (in `work.changed`) and the `moved` ones; leaves in `work.changed` the
    /// blocks whose output this round changed.
    fn update_round(&mut self, r: usize, [x, from, to]: [u32; 3]) {
        let (g, net, w) = (&self.graph, self.net, &mut self.work);
        let d = net.shape().width;
        let half = d / 2;
        let (done, rest) = self.rounds.split_at_mut(r);
        let h: &[f32] = if r == 0 { &self.h0 } else { &done[r - 1].out };
        let round = &mut rest[0];
        // Up: the cells, then the pass from each changed term upwards.
        w.dirty.clear();
        for &b in &w.changed.list {
            w.dirty.insert(b);
            w.dirty.insert(g.above[b as usize]);
        }
        w.dirty.insert(x);
        w.terms.clear();
        recompute(
            net,
            CellKind::Up,
            &w.all,
            &w.dirty.list,
            &mut w.cell,
            &mut round.up,
            &mut w.terms,
            |b, row| net.up_input(g, h, b, row),
        );
        w.terms.insert(x);
        w.u.clear();
        let mut scratch = std::mem::take(&mut w.rows);
        for &b in &w.terms.list {
            walk(
                b,
                (&g.below, &g.above),
                &round.up,
                &mut round.u,
                (d, half),
                &mut scratch,
                &mut w.u,
            );
        }
        // Down: the cells, then the pass from each changed term downwards.
        w.dirty.clear();
        for &b in &w.changed.list {
            w.dirty.insert(b);
            w.dirty.insert(g.below[b as usize]);
        }
        w.u.list.iter().for_each(|&b| w.dirty.insert(b));
        w.dirty.insert(from);
        w.dirty.insert(to);
        w.terms.clear();
        let u = &round.u;
        recompute(
            net,
            CellKind::Down,
            &w.all,
            &w.dirty.list,
            &mut w.cell,
            &mut round.down,
            &mut w.terms,
            |b, row| net.down_input(g, h, u, b, row),
        );
        w.terms.insert(from);
        w.terms.insert(to);
        w.v.clear();
        for &b in &w.terms.list {
            walk(
                b,
                (&g.above, &g.below),
                &round.down,
                &mut round.v,
                (d, half),
                &mut scratch,
                &mut w.v,
            );
        }
        w.rows = scratch;
        // Across the goal.
        w.dirty.clear();
        w.changed.list.iter().for_each(|&b| w.dirty.insert(b));
        for &b in w.u.list.iter().chain(&w.v.list) {
            w.dirty.insert(b);
            w.dirty.insert(g.goal_below[b as usize]);
            w.dirty.insert(g.goal_above[b as usize]);
        }
        w.dirty.insert(x);
        w.dirty.insert(g.goal_below[x as usize]);
        w.next.clear();
        let (u, v) = (&round.u, &round.v);
        recompute(
            net,
            CellKind::Goal,
            &w.all,
            &w.dirty.list,
            &mut w.cell,
            &mut round.out,
            &mut w.next,
            |b, row| net.goal_input(g, h, u, v, b, row),
        );
        std::mem::swap(&mut w.changed, &mut w.next);
    }

    /// The heads of the blocks whose final vector changed (`work.changed`).
    fn update_heads(&mut self) {
        let (net, w) = (self.net, &mut self.work);
        let shape = net.shape();
        let (d, s) = (shape.width, shape.score_hidden);
        let h: &[f32] = self.rounds.last().map_or(&self.h0, |r| &r.out);
        let (list, rows) = batch(&w.changed.list, &w.all, &net.head_products());
        w.rows.clear();
        w.rows.resize(rows * d, 0.0);
        for (i, &b) in list.iter().enumerate() {
            let b = b as usize;
            w.rows[i * d..(i + 1) * d].copy_from_slice(&h[b * d..(b + 1) * d]);
        }
        let [k, heads, px, qy] = &mut w.heads;
        for (buf, width) in [(&mut *k, s), (&mut *heads, HEADS), (&mut *px, s), (&mut *qy, s)] {
            buf.resize(rows * width, 0.0);
        }
        net.head_rows(&w.rows, rows, HeadRows { k, heads, px, qy });
        for (i, &b) in list.iter().enumerate() {
            let b = b as usize;
            self.heads[b * HEADS..(b + 1) * HEADS].copy_from_slice(&heads[i * HEADS..(i + 1) * HEADS]);
            self.px[b * s..(b + 1) * s].copy_from_slice(&px[i * s..(i + 1) * s]);
            self.qy[b * s..(b + 1) * s].copy_from_slice(&qy[i * s..(i + 1) * s]);
        }
    }

    /// The sets the best move is read from, for every block touched: the `moved` ones and
    /// those whose heads changed, and their goal partners' related moves.
    fn update_picks(&mut self, moved: [u32; 3]) {
        let (g, net, w) = (&self.graph, self.net, &mut self.work);
        moved.iter().for_each(|&b| w.changed.insert(b));
        w.dirty.clear();
        for &b in &w.changed.list {
            self.picks.enter(g, &self.heads, b as usize);
            w.dirty.insert(b);
            w.dirty.insert(g.goal_below[b as usize]);
            w.dirty.insert(g.goal_above[b as usize]);
        }
        let values = Values {
            heads: &self.heads,
            px: &self.px,
            qy: &self.qy,
        };
        for &b in &w.dirty.list {
            self.picks.enter_related(net, g, values, b as usize);
        }
    }
}

/// Recomputes the cell `kind`'s rows of the blocks `dirty` (`input` writes a block's input
/// row) in products of the full pass's size class over `all` blocks ([`batch`]); writes
/// each into `values` and adds the blocks whose row changed to `changed`.
#[allow(clippy::too_many_arguments)]
fn recompute(
    net: &RelationalNet,
    kind: CellKind,
    all: &[u32],
    dirty: &[u32],
    tape: &mut CellTape,
    values: &mut [f32],
    changed: &mut NodeSet,
    input: impl Fn(usize, &mut [f32]),
) {
    if dirty.is_empty() {
        return;
    }
    let inputs = net.cell_inputs(kind);
    let (nodes, rows) = batch(dirty, all, &net.cell_products(kind));
    tape.reserve_for(net, kind, rows);
    for (i, &b) in nodes.iter().enumerate() {
        input(b as usize, &mut tape.x[i * inputs..(i + 1) * inputs]);
    }
    tape.x[nodes.len() * inputs..rows * inputs].fill(0.0);
    net.cell_rows(kind, tape, rows);
    write_rows(nodes, &tape.o, values, net.shape().width, changed);
}

/// Writes row `i` of `rows` over block `nodes[i]`'s row of `values` (`d` a row), adding
/// the blocks whose row changed to `changed`.
fn write_rows(nodes: &[u32], rows: &[f32], values: &mut [f32], d: usize, changed: &mut NodeSet) {
    for (i, &b) in nodes.iter().enumerate() {
        let (new, old) = (
            &rows[i * d..(i + 1) * d],
            &mut values[b as usize * d..(b as usize + 1) * d],
        );
        if !same_bits(new, old) {
            old.copy_from_slice(new);
            changed.insert(b);
        }
    }
}

/// Brings a running minimum / maximum along a tower (the up pass, `(prev, next)` = (below,
/// above), or the down pass, (above, below)) up to date from block `b` on, as long as it
/// changes; adds the blocks whose value changed to `changed`.
fn walk(
    b: u32,
    (prev, next): (&[u32], &[u32]),
    terms: &[f32],
    values: &mut [f32],
    (d, half): (usize, usize),
    row: &mut Vec<f32>,
    changed: &mut NodeSet,
) {
    row.resize(d, 0.0);
    let mut b = b as usize;
    loop {
        let here = &terms[b * d..(b + 1) * d];
        match prev[b] {
            NONE => row.copy_from_slice(here),
            p => {
                let before = &values[p as usize * d..(p as usize + 1) * d];
                for c in 0..d {
                    row[c] = if extends(c, half, here[c], before[c]) {
                        here[c]
                    } else {
                        before[c]
                    };
                }
            }
        }
        let old = &mut values[b * d..(b + 1) * d];
        if same_bits(row, old) {
            return;
        }
        old.copy_from_slice(row);
        changed.insert(b as u32);
        match next[b] {
            NONE => return,
            above => b = above as usize,
        }
    }
}

/// A score as a key that sorts as scores compare: -0 as 0 (they compare equal), and
/// descending under [`Reverse`].
fn key(score: f32) -> Reverse<u32> {
    let bits = (score + 0.0).to_bits();
    Reverse(if bits >> 31 == 1 { !bits } else { bits | 1 << 31 })
}

/// A candidate move's score, its order key (its place in `Towers::moves` order, which
/// breaks ties) and the move, as in [`RelationalNet::best_move`].
type Candidate = (f32, (u32, u32), (u32, u32));

/// The sets the best move is read from (module docs): the clear blocks by each per-block
/// score, and the moves between related clear blocks by score, each set's entries ordered
/// by score, then by block.
struct Picks {
    /// Clear blocks by their score for moving onto an unrelated block (`a`).
    by_a: BTreeSet<(Reverse<u32>, u32)>,
    /// Clear blocks by their score as such a destination (`b`).
    by_b: BTreeSet<(Reverse<u32>, u32)>,
    /// Clear blocks not on the table by their score for moving there.
    to_table: BTreeSet<(Reverse<u32>, u32)>,
    /// Moves between clear blocks the goal relates: (score, block, destination + 1).
    related: BTreeSet<(Reverse<u32>, u32, u32)>,
    /// Each block's entries: its keys in the first three sets and its related moves.
    entries: Vec<Entries>,
}

/// Where one block stands in [`Picks`].
#[derive(Clone, Copy, Default)]
struct Entries {
    a: Option<Reverse<u32>>,
    b: Option<Reverse<u32>>,
    table: Option<Reverse<u32>>,
    related: [Option<(Reverse<u32>, u32)>; 2],
}

impl Picks {
    fn new(n: usize) -> Picks {
        Picks {
            by_a: BTreeSet::new(),
            by_b: BTreeSet::new(),
            to_table: BTreeSet::new(),
            related: BTreeSet::new(),
            entries: vec![Entries::default(); n],
        }
    }

    /// Puts block `b` in the per-block sets as its relations and `heads` now say.
    fn enter(&mut self, g: &Graph, heads: &[f32], b: usize) {
        let e = &mut self.entries[b];
        let id = b as u32;
        for (set, slot) in [
            (&mut self.by_a, &mut e.a),
            (&mut self.by_b, &mut e.b),
            (&mut self.to_table, &mut e.table),
        ] {
            if let Some(k) = slot.take() {
                set.remove(&(k, id));
            }
        }
        if g.above[b] != NONE {
            return;
        }
        let head = |i: usize| key(heads[b * HEADS + i]);
        e.a = Some(head(0));
        e.b = Some(head(1));
        self.by_a.insert((head(0), id));
        self.by_b.insert((head(1), id));
        if g.below[b] != NONE {
            e.table = Some(head(2));
            self.to_table.insert((head(2), id));
        }
    }

    /// Puts block `x`'s moves onto the blocks the goal relates it to in the related set, as
    /// the relations and `values` now say.
    fn enter_related(&mut self, net: &RelationalNet, g: &Graph, values: Values<'_>, x: usize) {
        let e = &mut self.entries[x];
        let id = x as u32;
        for slot in &mut e.related {
            if let Some((k, to)) = slot.take() {
                self.related.remove(&(k, id, to));
            }
        }
        if g.above[x] != NONE {
            return;
        }
        for (slot, y) in e.related.iter_mut().zip([g.goal_below[x], g.goal_above[x]]) {
            if y != NONE && y != TABLE && y != id && g.above[y as usize] == NONE {
                let k = key(net.score(g, values, id, y, None));
                *slot = Some((k, y + 1));
                self.related.insert((k, id, y + 1));
            }
        }
    }

    /// The best legal move, as [`RelationalNet::best_move`] finds it.
    fn best(&self, net: &RelationalNet, g: &Graph, values: Values<'_>, table_free: bool) -> Option<(u32, u32)> {
        let mut best: Option<Candidate> = None;
        let mut offer = |score: f32, order: (u32, u32), mv: (u32, u32)| {
            if best.is_none_or(|(s, k, _)| score > s || (score == s && order < k)) {
                best = Some((score, order, mv));
            }
        };
        if table_free && let Some(&(_, x)) = self.to_table.first() {
            offer(values.heads[x as usize * HEADS + 2], (x, 0), (x, TABLE));
        }
        if let Some(&(_, x, y)) = self.related.first() {
            offer(net.score(g, values, x, y - 1, None), (x, y), (x, y - 1));
        }
        // The four best destinations by b, as best_move keeps them.
        let top: Vec<u32> = self.by_b.iter().take(4).map(|&(_, y)| y).collect();
        let Some(&first) = top.first() else {
            return best.map(|(_, _, mv)| mv);
        };
        let a = |x: u32| values.heads[x as usize * HEADS];
        let b = |y: u32| values.heads[y as usize * HEADS + 1];
        let related = |x: u32, y: u32| g.goal_below[x as usize] == y || g.goal_above[x as usize] == y;
        // The blocks the best destination does not serve: itself and its goal partners.
        let own = [first, g.goal_below[first as usize], g.goal_above[first as usize]];
        for &x in &own {
            if (x as usize) < g.nodes()
                && g.above[x as usize] == NONE
                && let Some(&y) = top.iter().find(|&&y| y != x && !related(x, y))
            {
                offer(a(x) + b(y), (x, y + 1), (x, y));
            }
        }
        // Every other clear block moves best onto the best destination: the best score is
        // the best a's (a sum keeps the order of a), the lowest block among equal sums.
        let mut others = self.by_a.iter().map(|&(_, x)| x).filter(|x| !own.contains(x));
        if let Some(x) = others.next() {
            let score = a(x) + b(first);
            let lowest = others.take_while(|&x| a(x) + b(first) == score).fold(x, u32::min);
            offer(score, (lowest, first + 1), (lowest, first));
        }
        best.map(|(_, _, mv)| mv)
    }
}

/// The move a full pass over `state` chooses, every value computed afresh: what the live
/// pass's tests (and `MovePolicy`'s) compare with.
#[cfg(test)]
pub(super) fn full_pass_move(net: &RelationalNet, state: &Towers, goal: &TowerGoal, table: Table) -> Option<Move> {
    if goal.holds(state) {
        return None;
    }
    let graph = Graph::of([(state, goal)]);
    let mut tape = Tape::new();
    net.forward(&graph, &mut tape);
    let (x, to) = net.best_move(&graph, &tape, 0, table.has_free_column(state.tower_count()))?;
    Some(Move {
        block: x as usize,
        to: if to == TABLE {
            Place::Table
        } else {
            Place::On(to as usize)
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::relational::Shape;
    use oracle::towers::{random_goal, random_state};
    use proptest::prelude::*;

    /// Whether every value the live pass holds has the bits of a full pass over its state.
    fn same_as_full_pass(live: &LivePass<'_>, goal: &TowerGoal) -> std::result::Result<(), String> {
        let graph = Graph::of([(live.state(), goal)]);
        let mut tape = Tape::new();
        live.net.forward(&graph, &mut tape);
        let n = graph.nodes();
        let (d, s) = (live.net.shape().width, live.net.shape().score_hidden);
        let check = |what: &str, kept: &[f32], full: &[f32]| {
            if same_bits(kept, full) && kept.len() == full.len() {
                Ok(())
            } else {
                Err(format!("{what} differs"))
            }
        };
        check("the embedding", &live.h0, &tape.embedding()[..n * d])?;
        for (r, round) in live.rounds.iter().enumerate() {
            let full = tape.round_values(r);
            for (i, kept) in [&round.up, &round.u, &round.down, &round.v, &round.out]
                .into_iter()
                .enumerate()
            {
                check(&format!("round {r} value {i}"), kept, &full[i][..n * d])?;
            }
        }
        let values = tape.values();
        check("the heads", &live.heads, &values.heads[..n * HEADS])?;
        check("px", &live.px, &values.px[..n * s])?;
        check("qy", &live.qy, &values.qy[..n * s])
    }

    fn problem(n: usize, seed: u64, partial: bool) -> (Towers, TowerGoal) {
        let goal = if partial {
            random_goal(n, 1, n.min(3), seed).unwrap()
        } else {
            TowerGoal::new(&random_state(n, seed ^ 0x5eed).towers()).unwrap()
        };
        (random_state(n, seed), goal)
    }

    fn any_shape() -> impl Strategy<Value = Shape> {
        (1usize..=12, 1usize..=12, 1usize..=12, 1usize..=3).prop_map(|(width, hidden, score_hidden, rounds)| Shape {
            width,
            hidden,
            score_hidden,
            rounds,
        })
    }

    #[test]
    fn a_batch_keeps_the_full_products_size_class() {
        let all = |n: u32| (0..n).collect::<Vec<u32>>();
        let dirty = [7u32];
        // 20 blocks: products of 16 columns are past the small-product bound, of 3 are not.
        assert_eq!(batch(&dirty, &all(20), &[(49, 16)]), (&dirty[..], 17));
        assert_eq!(batch(&dirty, &all(20), &[(49, 16), (16, 3)]).1, 20);
        assert_eq!(batch(&dirty, &all(100), &[(16, 16), (16, 3)]), (&dirty[..], 86));
        assert_eq!(batch(&dirty, &all(100), &[(600, 16)]), (&dirty[..], 65));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// After every move of a random walk, every value the live pass keeps is the full
        /// pass's, bit for bit.
        #[test]
        fn every_value_is_the_full_passs(shape in any_shape(), weights in 0u64..1000, n in 1usize..120, seed in 0u64..1000, partial: bool) {
            let net = RelationalNet::new(shape, &mut sim::seeding::rng(weights)).unwrap();
            let (start, goal) = problem(n, seed, partial);
            let mut live = LivePass::new(&net, &start, &goal).unwrap();
            let mut rng = sim::seeding::rng(seed);
            for _ in 0..40 {
                let legal = live.state().moves(Table::Unbounded);
                if legal.is_empty() {
                    break;
                }
                let mv = legal[rand::RngExt::random_range(&mut rng, 0..legal.len())];
                live.apply(mv, Table::Unbounded).unwrap();
                prop_assert_eq!(live.goal_holds(), goal.holds(live.state()));
                if let Err(e) = same_as_full_pass(&live, &goal) {
                    prop_assert!(false, "after {}: {}", mv, e);
                }
            }
        }

        /// A whole game played on the live pass is the full pass's game, move for move, on
        /// an unbounded table and on a table of few columns.
        #[test]
        fn a_game_is_the_full_passs_move_for_move(shape in any_shape(), weights in 0u64..1000, n in 1usize..120, seed in 0u64..1000, partial: bool, spare in 0usize..3) {
            let net = RelationalNet::new(shape, &mut sim::seeding::rng(weights)).unwrap();
            let (start, goal) = problem(n, seed, partial);
            for table in [Table::Unbounded, Table::Columns(start.tower_count() + spare)] {
                let mut live = LivePass::new(&net, &start, &goal).unwrap();
                let mut state = start.clone();
                for _ in 0..super::super::move_limit(n) {
                    let full = full_pass_move(&net, &state, &goal, table);
                    let kept = if live.goal_holds() {
                        None
                    } else {
                        live.best_move(table.has_free_column(live.state().tower_count()))
                    };
                    prop_assert_eq!(kept, full);
                    let Some(mv) = full else { break };
                    state.apply(mv, table).unwrap();
                    live.apply(mv, table).unwrap();
                }
            }
        }
    }

    #[test]
    fn an_illegal_move_is_refused_and_changes_nothing() {
        let shape = Shape {
            width: 4,
            hidden: 4,
            score_hidden: 4,
            rounds: 2,
        };
        let net = RelationalNet::new(shape, &mut sim::seeding::rng(1)).unwrap();
        let (start, goal) = problem(8, 3, false);
        let mut live = LivePass::new(&net, &start, &goal).unwrap();
        let buried = (0..8).find(|&b| !start.is_clear(b)).unwrap();
        let mv = Move {
            block: buried,
            to: Place::Table,
        };
        assert!(live.apply(mv, Table::Unbounded).is_err());
        assert_eq!(live.state(), &start);
        same_as_full_pass(&live, &goal).unwrap();
    }
}
