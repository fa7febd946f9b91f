//! Deadlocks: misplaced blocks of which at least one must move twice.
//!
//! Suppose every misplaced block moved exactly once, straight to where it ends. Then:
//!
//! 1. a block standing on another moves first (only a clear block moves);
//! 2. a block's goal support, if misplaced, is placed before it (a block placed for good
//!    never moves again, so what it stands on is final by then);
//! 3. whatever stands on a well-placed goal support `y` leaves before the named block
//!    that must stand on `y` arrives.
//!
//! These "moves before" edges between misplaced blocks must then be acyclic. Conversely,
//! if they are acyclic, moving the blocks in a topological order (free blocks to the
//! table, named ones onto their goal support) is a plan with one move per misplaced block.
//! So in any plan the blocks that move twice or more meet every cycle of this graph: the
//! number of vertex-disjoint cycles is a lower bound on the extra moves (Gupta & Nau's
//! deadlocks; finding the fewest blocks that break every cycle is what makes optimal
//! Blocks World planning NP-hard).

use super::bitset::BitSet;
use super::goal::TowerGoal;
use super::state::NONE;

/// The "a moves before b" edges out of the misplaced block `a` in the state `below` (see
/// the module docs; [`NONE`] pads); `wp` says which blocks are well placed.
fn edges_of(a: usize, below: &[usize], goal: &TowerGoal, wp: &[bool]) -> [usize; 3] {
    let s = below[a];
    let mut out = [NONE; 3];
    if s != NONE && !wp[s] {
        // 1: a stands on s.
        out[0] = s;
    }
    // 2: the block that must stand on a is final after a (both are misplaced).
    out[1] = goal.above_of(a);
    if s != NONE && wp[s] {
        // 3: a stands on the well-placed s, where another block must go.
        out[2] = goal.above_of(s);
    }
    out
}

/// The lower bound on the block moves from a state of at most 32 blocks: one per
/// misplaced block, plus one per cycle of a greedy packing of vertex-disjoint cycles of
/// the "moves before" graph (shortest cycles first).
pub(crate) fn lower_bound(below: &[usize], above: &[usize], goal: &TowerGoal) -> u32 {
    debug_assert!(below.len() <= 32);
    let wp = goal.well_placed(below, above);
    let mut succ = [0u32; 32];
    let mut misplaced = 0u32;
    for (b, &w) in wp.iter().enumerate() {
        if !w {
            misplaced |= 1 << b;
        }
    }
    for a in bits(misplaced) {
        for b in edges_of(a, below, goal, &wp).into_iter().filter(|&b| b != NONE) {
            succ[a] |= 1 << b;
        }
    }
    misplaced.count_ones() + disjoint_cycles(&succ, misplaced)
}

/// How many vertex-disjoint cycles a greedy packing finds among the nodes of `alive`:
/// repeatedly the shortest cycle left, its nodes then removed.
fn disjoint_cycles(succ: &[u32; 32], mut alive: u32) -> u32 {
    let mut count = 0;
    // A node on a cycle has an edge in and an edge out among the living nodes; pruning the
    // others first keeps the searches small.
    loop {
        loop {
            let mut has_in = 0u32;
            let mut keep = 0u32;
            for v in bits(alive) {
                let out = succ[v] & alive;
                has_in |= out;
                if out != 0 {
                    keep |= 1 << v;
                }
            }
            let pruned = keep & has_in;
            if pruned == alive {
                break;
            }
            alive = pruned;
        }
        if alive == 0 {
            return count;
        }
        let mut best: Option<u32> = None;
        for v in bits(alive) {
            if let Some(cycle) = shortest_cycle_through(succ, alive, v)
                && best.is_none_or(|b| cycle.count_ones() < b.count_ones())
            {
                best = Some(cycle);
                if cycle.count_ones() == 2 {
                    break;
                }
            }
        }
        match best {
            Some(cycle) => {
                count += 1;
                alive &= !cycle;
            }
            None => return count,
        }
    }
}

/// The nodes of a shortest cycle through `v` among `alive`, by breadth-first layers.
fn shortest_cycle_through(succ: &[u32; 32], alive: u32, v: usize) -> Option<u32> {
    let mut layers = [0u32; 33];
    layers[0] = 1 << v;
    let mut seen = 1u32 << v;
    let mut depth = 0;
    loop {
        let next = bits(layers[depth]).fold(0, |acc, u| acc | succ[u]) & alive;
        depth += 1;
        if next & (1 << v) != 0 {
            break;
        }
        let fresh = next & !seen;
        if fresh == 0 {
            return None;
        }
        seen |= fresh;
        layers[depth] = fresh;
    }
    // Walk back from v through the layers, one predecessor per layer.
    let mut cycle = 1u32 << v;
    let mut cur = v;
    for d in (1..depth).rev() {
        let u = bits(layers[d]).find(|&u| succ[u] & (1 << cur) != 0)?;
        cycle |= 1 << u;
        cur = u;
    }
    Some(cycle)
}

/// The indices of the set bits of `mask`, lowest first.
fn bits(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let b = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            b
        })
    })
}

/// The deadlock graph of a problem of any size, over the blocks that may need a second
/// move (docs of [`super::optimal`]): an edge `x -> y` when, with `x` and `y` each moved
/// once, `x` must move before `y` is placed, through the chains of the start's towers
/// (down) and the goal's (up). A set of blocks moved twice (to the table, then to where
/// they end) gives a plan exactly when the graph without them has no cycle; a loop marks a
/// block that moves twice in every plan.
pub(crate) struct DeadlockGraph {
    /// How many blocks are misplaced (each moves at least once).
    pub(crate) misplaced: usize,
    /// The block of each vertex.
    pub(crate) blocks: Vec<usize>,
    /// Each vertex's successors (a loop included).
    pub(crate) succ: Vec<BitSet>,
    /// Which blocks are well placed.
    pub(crate) well_placed: Vec<bool>,
}

impl DeadlockGraph {
    /// How many vertices have a loop: blocks that move twice in every plan.
    pub(crate) fn loops(&self) -> usize {
        self.succ.iter().enumerate().filter(|(v, row)| row.contains(*v)).count()
    }

    /// The graph of the problem from `start` (with `below`/`above` its supports) to `goal`.
    pub(crate) fn of(below: &[usize], above: &[usize], goal: &TowerGoal) -> DeadlockGraph {
        let n = below.len();
        let wp = goal.well_placed(below, above);
        let misplaced = wp.iter().filter(|&&w| !w).count();
        // A block can need a second move only if a path can enter its goal side from below
        // (its goal support is misplaced, or well placed with a block on it now) and leave
        // its start side downwards (it stands on a misplaced block, or on a well-placed one
        // that another block must stand on): every other block's cycles pass around it.
        let is_vertex = |x: usize| {
            if wp[x] || !goal.is_named(x) {
                return false;
            }
            let g = goal.below_of(x);
            let s = below[x];
            g != NONE && (!wp[g] || above[g] != NONE) && s != NONE && (!wp[s] || goal.above_of(s) != NONE)
        };
        let mut vertex = vec![NONE; n];
        let mut blocks = Vec::new();
        for x in (0..n).filter(|&x| is_vertex(x)) {
            vertex[x] = blocks.len();
            blocks.push(x);
        }
        let k = blocks.len();
        // The vertices at or above `w` in its goal tower.
        let up = |w: usize, into: &mut BitSet| {
            let mut u = w;
            while u != NONE {
                if vertex[u] != NONE {
                    into.insert(vertex[u]);
                }
                u = goal.above_of(u);
            }
        };
        let mut succ = vec![BitSet::new(k); k];
        // Each start tower's misplaced blocks, bottom up: a block reaches what every block
        // below it reaches (it leaves first), and what stands above each in the goal.
        for bottom in (0..n).filter(|&b| below[b] == NONE) {
            let mut b = bottom;
            while b != NONE && wp[b] {
                b = above[b];
            }
            if b == NONE {
                continue;
            }
            let mut reach = BitSet::new(k);
            let s = below[b];
            if s != NONE && goal.above_of(s) != NONE {
                up(goal.above_of(s), &mut reach);
            }
            while b != NONE {
                let looped = vertex[b] != NONE && reach.contains(vertex[b]);
                up(b, &mut reach);
                if vertex[b] != NONE {
                    let mut row = reach.clone();
                    if !looped {
                        row.remove(vertex[b]);
                    }
                    succ[vertex[b]] = row;
                }
                b = above[b];
            }
        }
        DeadlockGraph {
            misplaced,
            blocks,
            succ,
            well_placed: wp,
        }
    }
}
