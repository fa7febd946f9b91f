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

use super::goal::TowerGoal;
use super::state::NONE;

/// Calls `edge(a, b)` for each "a moves before b" edge between misplaced blocks of the
/// state `below` (see the module docs); `wp` says which blocks are well placed.
/// Each block has at most three out-edges.
pub(crate) fn for_each_edge(below: &[usize], goal: &TowerGoal, wp: &[bool], mut edge: impl FnMut(usize, usize)) {
    for a in (0..below.len()).filter(|&a| !wp[a]) {
        let s = below[a];
        if s != NONE && !wp[s] {
            // 1: a stands on s.
            edge(a, s);
        }
        let g = goal.above_of(a);
        if g != NONE {
            // 2: g must stand on a, so a (misplaced) is final before g (misplaced too).
            edge(a, g);
        }
        if s != NONE && wp[s] {
            // 3: a stands on the well-placed s, where another block must go.
            let x = goal.above_of(s);
            if x != NONE {
                edge(a, x);
            }
        }
    }
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
    for_each_edge(below, goal, &wp, |a, b| succ[a] |= 1 << b);
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

/// Which misplaced blocks lie on a cycle of the "moves before" graph (Tarjan's strongly
/// connected components, iteratively; linear in the number of blocks).
pub(crate) fn on_cycle(below: &[usize], goal: &TowerGoal, wp: &[bool]) -> Vec<bool> {
    let n = below.len();
    let mut succ = vec![[NONE; 3]; n];
    let mut degree = vec![0u8; n];
    for_each_edge(below, goal, wp, |a, b| {
        succ[a][degree[a] as usize] = b;
        degree[a] += 1;
    });
    let mut index = vec![NONE; n];
    let mut low = vec![0usize; n];
    let mut on_stack = vec![false; n];
    let mut stack = Vec::new();
    let mut result = vec![false; n];
    let mut next_index = 0;
    // Each frame: the node and how many of its out-edges are done.
    let mut frames: Vec<(usize, u8)> = Vec::new();
    for root in 0..n {
        if wp[root] || index[root] != NONE {
            continue;
        }
        frames.push((root, 0));
        index[root] = next_index;
        low[root] = next_index;
        next_index += 1;
        stack.push(root);
        on_stack[root] = true;
        while let Some(&mut (v, ref mut done)) = frames.last_mut() {
            if *done < degree[v] {
                let w = succ[v][*done as usize];
                *done += 1;
                if index[w] == NONE {
                    index[w] = next_index;
                    low[w] = next_index;
                    next_index += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    frames.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            frames.pop();
            if let Some(&(parent, _)) = frames.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                // v's component is the stack from v up.
                let from = stack.iter().rposition(|&w| w == v).unwrap_or(0);
                let component = stack.split_off(from);
                for &w in &component {
                    on_stack[w] = false;
                    result[w] = component.len() > 1;
                }
            }
        }
    }
    result
}
