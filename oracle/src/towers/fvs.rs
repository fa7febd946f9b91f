//! The smallest set of vertices that breaks every cycle of a directed graph (a minimum
//! feedback vertex set), with a lower bound when the search is stopped early.
//!
//! # Method
//!
//! 1. Reductions that keep the optimum. On vertices (Levy & Low, 1988): a vertex on a loop
//!    is in every solution; a vertex with no edge in or no edge out is on no cycle; a vertex
//!    with one edge in (or out) is merged into that neighbour, since every cycle through it
//!    passes there too, so a solution never needs it. On edges and cliques (Lin & Jou,
//!    2000): a one-way edge whose every cycle also holds a cycle on fewer of its vertices
//!    (DOME) or a pair of two-way edges (PIE) goes, and the neighbours of a vertex that
//!    closes a clique of two-way edges are taken (CORE). On the competition's tasks the
//!    edge reductions remove about a third of the edges left, and more after each bypass.
//! 2. What is left splits into strongly connected components, solved one by one.
//! 3. Each component is solved by branch and bound: a vertex is either in the set (removed)
//!    or out of it (bypassed: every edge into it joined to every edge out of it), the
//!    reductions applied again after each choice. A node's bound is its linear relaxation:
//!    the vertices' fractional values such that every cycle carries at least one, every
//!    clique of two-way edges all but one, and every odd cycle of `2k + 1` two-way edges
//!    `k + 1` (a set covers each two-way edge), found by pricing (a lightest cycle through
//!    each vertex under the current values, a greedy clique, a lightest odd cycle of two-way
//!    edges) until none is violated. The odd cycles matter: on the competition's hard tasks
//!    the relaxation without them is half-integral (most vertices at one half), two to
//!    seven below the optimum, and they lift it by two or so, which cuts the nodes about
//!    threefold. The relaxation is solved as its dual, a fractional packing (see
//!    `Packing`), whose value is checked from the packing itself, so a bound never rests on
//!    the simplex's arithmetic; a child's simplex starts from its parent's optimal basis,
//!    the rows of the vertices it lost taken out (a few pivots, where rebuilding the basis
//!    cost hundreds), and stops as soon as its packing prunes the node. A greedy set (the
//!    relaxation's heaviest vertices first, those not needed then dropped) gives each
//!    node's upper bound. The search branches on a fractional vertex on the most paths
//!    (in-degree times out-degree).
//!
//! Why this method: on the planning competition's Blocks World tasks the components left by
//! step 1 are dense (a hundred to a few hundred vertices, thousands of edges). A branch and
//! bound whose bound is a packing of disjoint cycles is far too weak there (the packing is
//! several vertices below the optimum), while the relaxation is within a few of it and
//! most often meets it after a few branchings. A general integer-programming crate was
//! tried first (`microlp` 0.5): its simplex stalled on these covering programs past its
//! own time limit, and its bound could not be checked; a native solver (HiGHS) would add a
//! C++ build to every CI run. The relaxation needs only a small dense simplex, written
//! here.
//!
//! Every bound reported is a bound for the whole graph: the vertices the reductions took
//! plus, per component, the search's proven optimum, or (stopped at the deadline) the
//! root's relaxation.

use std::collections::HashSet;
use std::time::Instant;

use super::bitset::BitSet;

/// A minimum feedback vertex set, or the best found when the deadline came first.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Fvs {
    /// The vertices of the set found (it breaks every cycle); `None` if a component was
    /// too large to search ([`MAX_COMPONENT`]).
    pub(crate) set: Option<Vec<usize>>,
    /// A lower bound on the size of every feedback vertex set; `set.len()` when proven.
    pub(crate) lower_bound: usize,
}

/// A graph whose vertices can be removed or merged away, rows as bit sets.
#[derive(Clone)]
struct Graph {
    succ: Vec<BitSet>,
    pred: Vec<BitSet>,
    alive: BitSet,
}

impl Graph {
    fn new(succ: Vec<BitSet>) -> Graph {
        let n = succ.len();
        let mut pred = vec![BitSet::new(n); n];
        for (v, row) in succ.iter().enumerate() {
            for w in row.iter() {
                pred[w].insert(v);
            }
        }
        let mut alive = BitSet::new(n);
        (0..n).for_each(|v| alive.insert(v));
        Graph { succ, pred, alive }
    }

    fn remove(&mut self, v: usize) {
        for w in self.succ[v].iter().collect::<Vec<_>>() {
            self.pred[w].remove(v);
        }
        for w in self.pred[v].iter().collect::<Vec<_>>() {
            self.succ[w].remove(v);
        }
        self.succ[v] = BitSet::new(self.alive_len());
        self.pred[v] = BitSet::new(self.alive_len());
        self.alive.remove(v);
    }

    fn alive_len(&self) -> usize {
        self.succ.len()
    }

    /// Merges `v` into its one predecessor `u` (every cycle through `v` passes `u`).
    fn merge_into_pred(&mut self, v: usize, u: usize) {
        let out = self.succ[v].clone();
        self.remove(v);
        for w in out.iter() {
            self.succ[u].insert(w);
            self.pred[w].insert(u);
        }
    }

    /// Merges `v` into its one successor `u`.
    fn merge_into_succ(&mut self, v: usize, u: usize) {
        let inn = self.pred[v].clone();
        self.remove(v);
        for w in inn.iter() {
            self.pred[u].insert(w);
            self.succ[w].insert(u);
        }
    }

    /// Applies the reductions (module docs, step 1) until none applies; the vertices they
    /// put in the solution are pushed onto `taken`.
    fn reduce(&mut self, taken: &mut Vec<usize>) {
        self.reduce_until(taken, None);
    }

    /// [`Graph::reduce`], stopped at `deadline` if one is given: a graph reduced in part is
    /// the same problem, only larger (thousands of uniform blocks take longer than a time
    /// limit to reduce). Whether it finished.
    fn reduce_until(&mut self, taken: &mut Vec<usize>, deadline: Option<Instant>) -> bool {
        loop {
            if !self.reduce_vertices(taken, deadline) {
                return false;
            }
            // The edge reductions cost a pass over every edge's rows; past the largest part
            // searched (thousands of uniform blocks) they are not worth it.
            if self.alive.len() > MAX_COMPONENT
                || !(self.drop_dominated_edges() | self.drop_acyclic_edges() | self.take_cores(taken))
            {
                return true;
            }
        }
    }

    /// Whether `u` and `v` have edges both ways.
    fn two_way(&self, u: usize, v: usize) -> bool {
        self.succ[u].contains(v) && self.pred[u].contains(v)
    }

    /// Removes the one-way edges on no cycle that a smallest set needs (Lin & Jou's DOME):
    /// `u -> v` when every one-way predecessor of `u` also reaches `v` directly, or every
    /// one-way successor of `v` is reached from `u` directly. A cycle through such an edge
    /// holds a cycle on fewer of its vertices, so the cycles no proper subset of whose
    /// vertices is a cycle, the only ones a set must break, keep their edges; whether the edge
    /// went is tested against the graph before any went, which that argument needs. Whether
    /// any went.
    fn drop_dominated_edges(&mut self) -> bool {
        let one_way = |rows: &[BitSet], others: &[BitSet], v: usize| {
            let mut row = rows[v].clone();
            row.difference_with(&others[v]);
            row
        };
        let one_way_in: Vec<BitSet> = (0..self.succ.len())
            .map(|v| one_way(&self.pred, &self.succ, v))
            .collect();
        let one_way_out: Vec<BitSet> = (0..self.succ.len())
            .map(|v| one_way(&self.succ, &self.pred, v))
            .collect();
        let mut dominated = Vec::new();
        for u in self.alive.iter() {
            for v in one_way_out[u].iter() {
                if one_way_in[u].is_subset(&self.pred[v]) || one_way_out[v].is_subset(&self.succ[u]) {
                    dominated.push((u, v));
                }
            }
        }
        for &(u, v) in &dominated {
            self.succ[u].remove(v);
            self.pred[v].remove(u);
        }
        !dominated.is_empty()
    }

    /// Removes the one-way edges between the strongly connected components of the graph of
    /// one-way edges (Lin & Jou's PIE): a cycle through one also passes a pair of two-way
    /// edges, a cycle of two vertices among its own, which every set breaks. Whether any went.
    fn drop_acyclic_edges(&mut self) -> bool {
        let n = self.succ.len();
        let adj: Vec<Vec<usize>> = (0..n)
            .map(|v| self.succ[v].iter().filter(|&w| !self.pred[v].contains(w)).collect())
            .collect();
        let mut component = vec![usize::MAX; n];
        for (c, members) in strong_components(&adj, &self.alive.iter().collect::<Vec<_>>())
            .into_iter()
            .enumerate()
        {
            members.into_iter().for_each(|v| component[v] = c);
        }
        let mut dropped = false;
        for (u, outs) in adj.iter().enumerate() {
            for &v in outs.iter().filter(|&&v| component[v] != component[u]) {
                self.succ[u].remove(v);
                self.pred[v].remove(u);
                dropped = true;
            }
        }
        dropped
    }

    /// Takes the neighbours of a vertex all of whose edges go both ways to a clique of two-way
    /// edges (Lin & Jou's CORE): all but one of that clique must go, and keeping the vertex,
    /// whose every cycle passes a neighbour, is never worse. Whether any was taken.
    fn take_cores(&mut self, taken: &mut Vec<usize>) -> bool {
        let mut took = false;
        for v in self.alive.iter().collect::<Vec<_>>() {
            if !self.alive.contains(v) || self.succ[v] != self.pred[v] || self.succ[v].is_empty() {
                continue;
            }
            let neighbours: Vec<usize> = self.succ[v].iter().collect();
            let clique = neighbours
                .iter()
                .all(|&a| neighbours.iter().all(|&b| a == b || self.two_way(a, b)));
            if clique {
                for &a in &neighbours {
                    self.remove(a);
                    taken.push(a);
                }
                self.remove(v);
                took = true;
            }
        }
        took
    }

    /// The reductions on single vertices (loops, no edge in or out, one edge in or out);
    /// whether they finished before `deadline`.
    fn reduce_vertices(&mut self, taken: &mut Vec<usize>, deadline: Option<Instant>) -> bool {
        let mut work: Vec<usize> = self.alive.iter().collect();
        let mut popped = 0usize;
        while let Some(v) = work.pop() {
            popped += 1;
            if popped.is_multiple_of(1024) && deadline.is_some_and(|d| Instant::now() >= d) {
                return false;
            }
            if !self.alive.contains(v) {
                continue;
            }
            if self.succ[v].contains(v) {
                taken.push(v);
                work.extend(self.succ[v].iter().chain(self.pred[v].iter()));
                self.remove(v);
                continue;
            }
            let (ins, outs) = (self.pred[v].len(), self.succ[v].len());
            if ins == 0 || outs == 0 {
                work.extend(self.succ[v].iter().chain(self.pred[v].iter()));
                self.remove(v);
            } else if ins == 1 {
                let u = self.pred[v].first().unwrap_or(v);
                work.extend(self.succ[v].iter());
                work.push(u);
                self.merge_into_pred(v, u);
            } else if outs == 1 {
                let u = self.succ[v].first().unwrap_or(v);
                work.extend(self.pred[v].iter());
                work.push(u);
                self.merge_into_succ(v, u);
            }
        }
        true
    }

    /// Puts `v` out of every solution: every edge into it is joined to every edge out of
    /// it (a cycle through `v` becomes a shorter one), and `v` removed.
    fn bypass(&mut self, v: usize) {
        let (inn, out) = (self.pred[v].clone(), self.succ[v].clone());
        self.remove(v);
        for p in inn.iter() {
            self.succ[p].union_with(&out);
        }
        for w in out.iter() {
            self.pred[w].union_with(&inn);
        }
    }

    /// The living vertices, each with its living successors.
    fn adjacency(&self) -> Vec<Vec<usize>> {
        (0..self.succ.len()).map(|v| self.succ[v].iter().collect()).collect()
    }

    /// The subgraph on `vertices`, renumbered `0..` in their order.
    fn restricted(&self, vertices: &[usize]) -> Graph {
        let mut local = vec![usize::MAX; self.succ.len()];
        for (i, &v) in vertices.iter().enumerate() {
            local[v] = i;
        }
        let k = vertices.len();
        let succ = vertices
            .iter()
            .map(|&v| {
                let mut row = BitSet::new(k);
                self.succ[v]
                    .iter()
                    .filter(|&w| local[w] != usize::MAX)
                    .for_each(|w| row.insert(local[w]));
                row
            })
            .collect();
        Graph::new(succ)
    }

    /// The strongly connected components of more than one vertex among the living
    /// (Tarjan's algorithm, without recursion).
    fn components(&self) -> Vec<Vec<usize>> {
        let n = self.succ.len();
        let adj: Vec<Vec<usize>> = (0..n).map(|v| self.succ[v].iter().collect()).collect();
        strong_components(&adj, &self.alive.iter().collect::<Vec<_>>())
            .into_iter()
            .filter(|c| c.len() > 1)
            .collect()
    }
}

/// The strongly connected components of the graph `adj` among `roots` (every vertex
/// reached from them is taken, so pass them all).
fn strong_components(adj: &[Vec<usize>], roots: &[usize]) -> Vec<Vec<usize>> {
    const UNSEEN: usize = usize::MAX;
    let n = adj.len();
    let (mut index, mut low) = (vec![UNSEEN; n], vec![0; n]);
    let mut on_stack = vec![false; n];
    let (mut stack, mut out, mut counter) = (Vec::new(), Vec::new(), 0);
    for &root in roots {
        if index[root] != UNSEEN {
            continue;
        }
        let mut calls = vec![(root, 0usize)];
        index[root] = counter;
        low[root] = counter;
        counter += 1;
        stack.push(root);
        on_stack[root] = true;
        while let Some(&mut (v, ref mut i)) = calls.last_mut() {
            if let Some(&w) = adj[v].get(*i) {
                *i += 1;
                if index[w] == UNSEEN {
                    index[w] = counter;
                    low[w] = counter;
                    counter += 1;
                    stack.push(w);
                    on_stack[w] = true;
                    calls.push((w, 0));
                } else if on_stack[w] {
                    low[v] = low[v].min(index[w]);
                }
                continue;
            }
            calls.pop();
            if let Some(&(parent, _)) = calls.last() {
                low[parent] = low[parent].min(low[v]);
            }
            if low[v] == index[v] {
                let mut comp = Vec::new();
                while let Some(w) = stack.pop() {
                    on_stack[w] = false;
                    comp.push(w);
                    if w == v {
                        break;
                    }
                }
                out.push(comp);
            }
        }
    }
    out
}

/// The largest strongly connected component searched: beyond it the covering programs and
/// the greedy set cost too much, and only a packing of disjoint cycles bounds it.
pub const MAX_COMPONENT: usize = 2_000;

/// A minimum feedback vertex set of the graph whose vertex `v` has the successors
/// `succ[v]` (a loop is an edge to itself), searched until `deadline`.
pub(crate) fn minimum_fvs(succ: Vec<BitSet>, deadline: Instant) -> Fvs {
    let mut graph = Graph::new(succ);
    let mut taken = Vec::new();
    // Stopped at the deadline, the graph may keep a loop outside every component searched:
    // no set of its own then, only the bound.
    let reduced = graph.reduce_until(&mut taken, Some(deadline));
    let mut lower_bound = taken.len();
    let mut set = reduced.then_some(taken);
    for comp in graph.components() {
        let local = graph.restricted(&comp);
        if comp.len() > MAX_COMPONENT {
            lower_bound += disjoint_cycles(&local, deadline);
            set = None;
            continue;
        }
        let solved = Search::new(deadline).run(local);
        lower_bound += solved.lower_bound;
        // A component stopped before any set was found leaves the whole without one.
        set = match (set, solved.set) {
            (Some(mut set), Some(more)) => {
                set.extend(more.into_iter().map(|v| comp[v]));
                Some(set)
            }
            _ => None,
        };
    }
    Fvs { set, lower_bound }
}

/// A cycle, as its vertices sorted.
type Cycle = Vec<usize>;

/// The lightest cycle through `v` in `adj` lighter than `limit` among the vertices `rank`
/// puts no earlier than `v`, vertices weighted by `weight` (Dijkstra from `v` back to it, no path as
/// heavy as `limit` followed), with its weight.
fn lightest_cycle(adj: &[Vec<usize>], v: usize, weight: &[f64], limit: f64, rank: &[usize]) -> Option<(f64, Cycle)> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let k = adj.len();
    let mut dist = vec![f64::INFINITY; k];
    let mut parent = vec![usize::MAX; k];
    let mut heap = BinaryHeap::new();
    dist[v] = weight[v];
    heap.push((Reverse(Ordered(weight[v])), v));
    let mut closing: Option<(f64, usize)> = None;
    while let Some((Reverse(Ordered(d)), u)) = heap.pop() {
        if d > dist[u] || closing.is_some_and(|(c, _)| d >= c) {
            continue;
        }
        for &w in &adj[u] {
            if w == v {
                if closing.is_none_or(|(c, _)| d < c) {
                    closing = Some((d, u));
                }
                continue;
            }
            let nd = d + weight[w];
            if nd < dist[w] && nd < limit && rank[w] >= rank[v] {
                dist[w] = nd;
                parent[w] = u;
                heap.push((Reverse(Ordered(nd)), w));
            }
        }
    }
    let (d, mut u) = closing?;
    let mut cycle = vec![u];
    while u != v {
        u = parent[u];
        cycle.push(u);
    }
    cycle.sort_unstable();
    Some((d, cycle))
}

/// How many vertex-disjoint cycles a greedy packing finds in `graph` before `deadline`
/// (at least one: it is strongly connected): a shortest cycle through each vertex in turn,
/// its vertices then removed.
fn disjoint_cycles(graph: &Graph, deadline: Instant) -> usize {
    let mut graph = graph.clone();
    let k = graph.succ.len();
    let ones = vec![1.0; k];
    let mut count = 0;
    for v in 0..k {
        if Instant::now() >= deadline {
            break;
        }
        if !graph.alive.contains(v) {
            continue;
        }
        if let Some((_, c)) = lightest_cycle(&graph.adjacency(), v, &ones, f64::INFINITY, &vec![0; k]) {
            c.iter().for_each(|&u| graph.remove(u));
            count += 1;
        }
    }
    count.max(1)
}

/// Whether the living part of `graph` without `removed` has no cycle (Kahn's algorithm).
fn is_acyclic_without(adj: &[Vec<usize>], live: &[bool]) -> bool {
    let k = adj.len();
    let mut indeg = vec![0usize; k];
    for v in (0..k).filter(|&v| live[v]) {
        for &w in adj[v].iter().filter(|&&w| live[w]) {
            indeg[w] += 1;
        }
    }
    let mut ready: Vec<usize> = (0..k).filter(|&v| live[v] && indeg[v] == 0).collect();
    let mut seen = 0;
    while let Some(v) = ready.pop() {
        seen += 1;
        for &w in adj[v].iter().filter(|&&w| live[w]) {
            indeg[w] -= 1;
            if indeg[w] == 0 {
                ready.push(w);
            }
        }
    }
    seen == live.iter().filter(|&&l| l).count()
}

/// A feedback vertex set of the living part of `graph`: vertices of heaviest `weight`
/// first (ties by in-degree times out-degree), the reductions applied after each, then
/// every vertex that is not needed dropped.
fn greedy(graph: &Graph, weight: &[f64]) -> Vec<usize> {
    let mut g = graph.clone();
    let mut chosen = Vec::new();
    loop {
        g.reduce_vertices(&mut chosen, None);
        let pick = g.alive.iter().max_by(|&a, &b| {
            weight[a]
                .total_cmp(&weight[b])
                .then((g.pred[a].len() * g.succ[a].len()).cmp(&(g.pred[b].len() * g.succ[b].len())))
                .then(b.cmp(&a))
        });
        match pick {
            Some(v) => {
                g.remove(v);
                chosen.push(v);
            }
            None => break,
        }
    }
    // Drop what is not needed, the least weighty first.
    let adj = graph.adjacency();
    let mut live: Vec<bool> = (0..adj.len()).map(|v| graph.alive.contains(v)).collect();
    chosen.iter().for_each(|&v| live[v] = false);
    chosen.sort_by(|&a, &b| weight[a].total_cmp(&weight[b]).then(a.cmp(&b)));
    let mut kept = Vec::new();
    for v in chosen {
        live[v] = true;
        if !is_acyclic_without(&adj, &live) {
            live[v] = false;
            kept.push(v);
        }
    }
    kept.sort_unstable();
    kept
}

/// The branch and bound over one component (module docs, step 3).
struct Search {
    deadline: Instant,
    /// The smallest set found (component vertices).
    best: Option<Vec<usize>>,
    /// Whether the deadline stopped the search.
    stopped: bool,
}

impl Search {
    fn new(deadline: Instant) -> Search {
        Search {
            deadline,
            best: None,
            stopped: false,
        }
    }

    /// The minimum of `graph` (strongly connected, reduced), or the best set and the root's
    /// bound if the deadline comes first.
    fn run(mut self, graph: Graph) -> Fvs {
        let root = self.node(graph, Vec::new(), None);
        match self.best {
            Some(best) if !self.stopped => Fvs {
                lower_bound: best.len(),
                set: Some(best),
            },
            best => Fvs {
                lower_bound: root.min(best.as_ref().map_or(usize::MAX, Vec::len)),
                set: best,
            },
        }
    }

    /// Searches below a node whose graph is `graph` and whose set so far is `taken`, from
    /// its parent's optimal packing (none at the root); returns the node's lower bound (for
    /// the root's report). The constraints a node finds hold in its graph and in every graph
    /// below it, but not in its siblings' (a bypass adds edges): each child starts from its
    /// own copy of the parent's packing.
    fn node(&mut self, mut graph: Graph, mut taken: Vec<usize>, parent: Option<Packing>) -> usize {
        graph.reduce(&mut taken);
        let best = self.best.as_ref().map_or(usize::MAX, Vec::len);
        if graph.alive.is_empty() {
            if taken.len() < best {
                self.best = Some(taken.clone());
            }
            return taken.len();
        }
        if Instant::now() >= self.deadline {
            self.stopped = true;
            return taken.len() + 1;
        }
        // A packing worth `best - taken` (rounded up) prunes the node: the simplex stops there.
        let cutoff = match best {
            usize::MAX => f64::INFINITY,
            best => (best - taken.len()) as f64 - 1.0 + 1e-5,
        };
        let lp = self.relaxation(&graph, &taken, parent, cutoff);
        let Some(lp) = lp else {
            self.stopped = true;
            return taken.len() + 1;
        };
        let bound = taken.len() + (lp.bound - 1e-6).ceil().max(1.0) as usize;
        if bound >= best {
            return bound;
        }
        let mut candidate = taken.clone();
        candidate.extend(greedy(&graph, &lp.values));
        if candidate.len() < best {
            self.best = Some(candidate);
        }
        if bound >= self.best.as_ref().map_or(usize::MAX, Vec::len) {
            return bound;
        }
        // Branch on a vertex the relaxation leaves fractional, the one on most paths through
        // it (in-degree times out-degree): in the set, or bypassed. Measured on the
        // competition's hard tasks, this needs a few times fewer nodes than the value
        // nearest one half, and far fewer than the heaviest value.
        let paths = |a: usize| graph.pred[a].len() * graph.succ[a].len();
        let fractional = |a: &usize| lp.values[*a] > 1e-6 && lp.values[*a] < 1.0 - 1e-6;
        let most_paths = |a: &usize, b: &usize| paths(*a).cmp(&paths(*b)).then(b.cmp(a));
        let v = graph
            .alive
            .iter()
            .filter(fractional)
            .max_by(most_paths)
            .or_else(|| graph.alive.iter().max_by(most_paths))
            .unwrap_or(0);
        let mut with = graph.clone();
        with.remove(v);
        let mut with_taken = taken.clone();
        with_taken.push(v);
        let mut without = graph;
        without.bypass(v);
        let copy = lp.packing.clone();
        if lp.values[v] >= 0.5 {
            self.node(with, with_taken, Some(copy));
            self.node(without, taken, Some(lp.packing));
        } else {
            self.node(without, taken, Some(copy));
            self.node(with, with_taken, Some(lp.packing));
        }
        bound
    }

    /// The linear relaxation at a node (see [`Packing`]): the parent's packing restricted to
    /// the node's graph (its constraints with what `taken` meets removed), then priced
    /// until no cycle, clique or odd cycle of two-way edges is covered too little; `None` at
    /// the deadline. Stops early once the packing reaches `cutoff`.
    fn relaxation(&mut self, graph: &Graph, taken: &[usize], parent: Option<Packing>, cutoff: f64) -> Option<Relaxed> {
        let adj = graph.adjacency();
        let k = adj.len();
        let mut is_taken = vec![false; k];
        taken.iter().for_each(|&v| is_taken[v] = true);
        let restricted = parent.and_then(|mut packing| packing.restrict(&graph.alive, &is_taken).map(|()| packing));
        let mut packing = restricted.unwrap_or_else(|| Packing::new(graph.alive.iter().collect(), k));
        let two_way: Vec<BitSet> = (0..k)
            .map(|v| {
                let mut both = graph.succ[v].clone();
                both.intersect_with(&graph.pred[v]);
                both
            })
            .collect();
        let mut afresh = false;
        loop {
            let reached = packing.optimize(self.deadline, cutoff);
            // A simplex that did not settle, or whose arithmetic drifted, starts once afresh.
            let reached = match reached {
                Some(reached) => reached,
                None if !afresh && Instant::now() < self.deadline => {
                    afresh = true;
                    packing = Packing::new(graph.alive.iter().collect(), k);
                    continue;
                }
                None => return None,
            };
            if reached {
                return Some(Relaxed {
                    bound: packing.verified_bound(),
                    values: Vec::new(),
                    packing,
                });
            }
            let weight = packing.vertex_values();
            let mut added = false;
            // Each cycle lighter than one is found from its first vertex in the order of
            // weight, through the vertices after it only: the vertices of weight zero, first,
            // are the only ones searched through widely.
            let mut order: Vec<usize> = graph.alive.iter().collect();
            order.sort_by(|&a, &b| weight[a].total_cmp(&weight[b]).then(a.cmp(&b)));
            let mut rank = vec![0; k];
            order.iter().enumerate().for_each(|(i, &v)| rank[v] = i);
            // Once a cycle is found, this round looks for cycles only: cliques and odd
            // cycles, dearer to search, wait for a round with no cycle to add.
            let mut cycles_only = false;
            for v in graph.alive.iter() {
                if weight[v] < 1.0 - 1e-7
                    && let Some((w, c)) = lightest_cycle(&adj, v, &weight, 1.0 - 1e-7, &rank)
                    && w < 1.0 - 1e-7
                {
                    added |= packing.add_column(c, Shape::Cycle, &is_taken);
                    cycles_only = true;
                }
                if cycles_only {
                    continue;
                }
                let clique = greedy_clique(&two_way, v, &weight);
                let need = clique.len() as f64 - 1.0;
                if clique.len() >= 3 && clique.iter().map(|&u| weight[u]).sum::<f64>() < need - 1e-7 {
                    added |= packing.add_column(clique, Shape::Clique, &is_taken);
                }
                if let Some(odd) = lightest_odd_cycle(&two_way, v, &weight, &rank) {
                    let need = odd.len().div_ceil(2) as f64;
                    if odd.len() >= 5 && odd.iter().map(|&u| weight[u]).sum::<f64>() < need - 1e-7 {
                        added |= packing.add_column(odd, Shape::OddCycle, &is_taken);
                    }
                }
            }
            if !added {
                return Some(Relaxed {
                    bound: packing.verified_bound(),
                    values: weight,
                    packing,
                });
            }
        }
    }
}

/// What a constraint of the covering is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Shape {
    /// A cycle: at least one of its vertices goes.
    Cycle,
    /// A clique of two-way edges: all but one go.
    Clique,
    /// A cycle of two-way edges of odd length `2k + 1`: `k + 1` of its vertices go (every
    /// set covers each of its two-way edges).
    OddCycle,
}

/// The lightest odd cycle of two-way edges through `v` (`two_way[v]`: the vertices with an
/// edge to and from `v`), an edge `a b` weighing `weight[a] + weight[b] - 1` (at least zero
/// where every two-way edge is covered): one lighter than one is an odd cycle the values
/// cover too little. Found as a lightest path from `v` back to itself through an odd number
/// of edges (Dijkstra over vertex and parity); the closed walk found holds an odd simple
/// cycle no heavier, which is returned, its vertices sorted. Only the vertices `rank` puts
/// no earlier than `v` are passed through: every odd cycle lighter than one is still found,
/// from its first vertex.
fn lightest_odd_cycle(two_way: &[BitSet], v: usize, weight: &[f64], rank: &[usize]) -> Option<Cycle> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let k = two_way.len();
    let mut dist = vec![f64::INFINITY; 2 * k];
    let mut parent = vec![usize::MAX; 2 * k];
    let mut heap = BinaryHeap::new();
    dist[2 * v] = 0.0;
    heap.push((Reverse(Ordered(0.0)), 2 * v));
    let target = 2 * v + 1;
    while let Some((Reverse(Ordered(d)), state)) = heap.pop() {
        if d > dist[state] || d >= 1.0 {
            continue;
        }
        if state == target {
            break;
        }
        let (u, parity) = (state / 2, state % 2);
        for w in two_way[u].iter().filter(|&w| rank[w] >= rank[v]) {
            let next = 2 * w + (1 - parity);
            let nd = d + (weight[u] + weight[w] - 1.0).max(0.0);
            if nd < dist[next] {
                dist[next] = nd;
                parent[next] = state;
                heap.push((Reverse(Ordered(nd)), next));
            }
        }
    }
    if dist[target] >= 1.0 {
        return None;
    }
    let mut walk = Vec::new();
    let mut state = target;
    while state != 2 * v {
        walk.push(state / 2);
        state = parent[state];
    }
    // `walk` is the closed walk's vertices (v once), of odd length: cut it at a repeated
    // vertex into two closed walks, keep the odd one, until no vertex repeats.
    loop {
        let mut first = vec![usize::MAX; k];
        let repeat = walk.iter().enumerate().find_map(|(j, &u)| {
            let i = first[u];
            first[u] = j;
            (i != usize::MAX).then_some((i, j))
        });
        match repeat {
            None => break,
            Some((i, j)) => {
                if (j - i) % 2 == 1 {
                    walk = walk[i..j].to_vec();
                } else {
                    walk.drain(i..j);
                }
            }
        }
    }
    walk.sort_unstable();
    Some(walk)
}

/// A clique of two-way edges (`two_way[v]`: the vertices with an edge to and from `v`)
/// through `v`, grown greedily by the lightest vertex that keeps it one.
fn greedy_clique(two_way: &[BitSet], v: usize, weight: &[f64]) -> Vec<usize> {
    let mut clique = vec![v];
    let mut candidates = two_way[v].clone();
    while let Some(c) = candidates
        .iter()
        .min_by(|&a, &b| weight[a].total_cmp(&weight[b]).then(a.cmp(&b)))
    {
        clique.push(c);
        candidates.intersect_with(&two_way[c]);
    }
    clique.sort_unstable();
    clique
}

/// A node's linear relaxation: its bound, the vertices' fractional values (empty when the
/// bound pruned the node before the optimum), and its packing (the children's start).
struct Relaxed {
    bound: f64,
    values: Vec<f64>,
    packing: Packing,
}

/// A constraint of the covering, a column of the packing.
#[derive(Clone)]
struct Column {
    /// Its vertices when it was found (component vertices, sorted).
    vertices: Cycle,
    shape: Shape,
    /// The rows of its living vertices.
    rows: Vec<usize>,
    /// How many of its living vertices must go.
    need: f64,
}

impl Column {
    /// How many of `vertices`' living ones must go, given which vertices the set has taken.
    fn need(vertices: &[usize], shape: Shape, living: usize, is_taken: &[bool]) -> usize {
        match shape {
            Shape::Cycle if vertices.iter().any(|&v| is_taken[v]) => 0,
            Shape::Cycle => 1,
            Shape::Clique => living.saturating_sub(1),
            Shape::OddCycle => {
                let met = vertices.iter().filter(|&&v| is_taken[v]).count();
                vertices.len().div_ceil(2).saturating_sub(met)
            }
        }
    }
}

/// The linear relaxation of a covering by cycles, cliques and odd cycles of two-way edges,
/// solved as its dual: the largest fractional packing of them in which each vertex carries
/// at most one (maximise `sum need_C y_C` subject to `sum_{C ∋ v} y_C <= 1`, `y >= 0`, where
/// a cycle needs one vertex, a clique of two-way edges all but one and an odd cycle of
/// `2k + 1` two-way edges `k + 1`), by a revised simplex with a dense basis inverse (rows:
/// the living vertices, at most [`MAX_COMPONENT`]) whose columns are added as pricing finds
/// them. Any packing is a lower bound on every feedback vertex set (each set needs `need`
/// of its vertices, each vertex serves at most one unit), and [`Packing::verified_bound`]
/// recomputes it from the packing itself, so the bound does not rest on the simplex's
/// arithmetic. The dual values of the rows are the covering's fractional vertices.
///
/// A child node starts from its parent's optimal basis ([`Packing::restrict`]): the rows of
/// the vertices it no longer has leave with their slacks, and the columns its set meets
/// lose their worth, so the simplex goes on from a packing that is nearly optimal already;
/// rebuilding the basis column by column cost each node hundreds of pivots more.
#[derive(Clone)]
struct Packing {
    /// The row of each vertex (`usize::MAX`: not a row).
    row_of: Vec<usize>,
    /// The vertex of each row.
    vertices: Vec<usize>,
    /// The rows' dual values, `c_B B^-1`, kept up to date at each pivot.
    pi: Vec<f64>,
    m: usize,
    columns: Vec<Column>,
    /// The columns' rows, so that none is added twice.
    known: HashSet<Vec<usize>>,
    /// Basis inverse, `m x m`, row-major: a row per basis position, a column per row.
    inverse: Vec<f64>,
    /// The basic variable of each position: `Err(r)` the slack of row `r`, `Ok(j)` column `j`.
    basis: Vec<std::result::Result<usize, usize>>,
    /// The basic variables' values.
    values: Vec<f64>,
    /// The right-hand sides, perturbed slightly so that ties in the ratio test are rare.
    rhs: Vec<f64>,
    pivots: usize,
}

impl Packing {
    /// The empty packing over `vertices` (of a graph of `k`).
    fn new(vertices: Vec<usize>, k: usize) -> Packing {
        let m = vertices.len();
        let mut row_of = vec![usize::MAX; k];
        for (r, &v) in vertices.iter().enumerate() {
            row_of[v] = r;
        }
        let mut inverse = vec![0.0; m * m];
        (0..m).for_each(|r| inverse[r * m + r] = 1.0);
        let rhs: Vec<f64> = vertices
            .iter()
            .map(|&v| 1.0 + 1e-9 * ((v * 7919) % 1000) as f64)
            .collect();
        Packing {
            row_of,
            vertices,
            pi: vec![0.0; m],
            m,
            columns: Vec::new(),
            known: HashSet::new(),
            inverse,
            basis: (0..m).map(Err).collect(),
            values: rhs.clone(),
            rhs,
            pivots: 0,
        }
    }

    /// Adds the constraint on `vertices` (sorted) of `shape` as a column, unless its
    /// living vertices are one already or it needs none of them; whether it was added.
    fn add_column(&mut self, vertices: Cycle, shape: Shape, is_taken: &[bool]) -> bool {
        let rows: Vec<usize> = vertices
            .iter()
            .map(|&v| self.row_of[v])
            .filter(|&r| r != usize::MAX)
            .collect();
        let need = Column::need(&vertices, shape, rows.len(), is_taken);
        if rows.is_empty() || need == 0 || !self.known.insert(rows.clone()) {
            return false;
        }
        self.columns.push(Column {
            vertices,
            shape,
            rows,
            need: need as f64,
        });
        true
    }

    /// This packing, a parent's, made the packing of a child whose living vertices are
    /// `alive` and whose set holds those of `is_taken`: each row of a vertex gone first
    /// gets its slack into the basis (a pivot that keeps the packing feasible), then leaves
    /// with it (the basis inverse without that row and that position is the smaller basis'
    /// inverse); each column's worth is counted again (a column the set meets is worth
    /// nothing, and leaves unless it is basic). `None` if a pivot fails (the caller starts
    /// afresh).
    fn restrict(&mut self, alive: &BitSet, is_taken: &[bool]) -> Option<()> {
        let m = self.m;
        let keep_row: Vec<bool> = (0..m).map(|r| alive.contains(self.vertices[r])).collect();
        let gone: Vec<usize> = (0..m).filter(|&r| !keep_row[r]).collect();
        for &r in &gone {
            if self.basis.contains(&Err(r)) {
                continue;
            }
            // A slack of a row that goes leaves no more: its row bounds nothing.
            let mut u = self.direction(Err(r));
            for (p, b) in self.basis.iter().enumerate() {
                if matches!(*b, Err(s) if !keep_row[s]) {
                    u[p] = u[p].min(0.0);
                }
            }
            let (theta, p) = self.ratio_test(&u)?;
            let u = self.direction(Err(r));
            self.pivot(Err(r), p, &u, theta);
        }
        let rows: Vec<usize> = (0..m).filter(|&r| keep_row[r]).collect();
        let positions: Vec<usize> = (0..m)
            .filter(|&p| !matches!(self.basis[p], Err(r) if !keep_row[r]))
            .collect();
        let mut new_row = vec![usize::MAX; m];
        rows.iter().enumerate().for_each(|(i, &r)| new_row[r] = i);
        let n = rows.len();
        let mut inverse = Vec::with_capacity(n * n);
        for &p in &positions {
            let row = &self.inverse[p * m..(p + 1) * m];
            inverse.extend(rows.iter().map(|&r| row[r]));
        }
        // The columns: their rows and worth again; the ones not basic that are worth
        // nothing go.
        let mut basic = vec![false; self.columns.len()];
        for b in &self.basis {
            if let Ok(j) = *b {
                basic[j] = true;
            }
        }
        let mut new_column = vec![usize::MAX; self.columns.len()];
        let mut columns = Vec::with_capacity(self.columns.len());
        for (j, mut column) in std::mem::take(&mut self.columns).into_iter().enumerate() {
            column.rows = column
                .rows
                .iter()
                .map(|&r| new_row[r])
                .filter(|&r| r != usize::MAX)
                .collect();
            column.need = Column::need(&column.vertices, column.shape, column.rows.len(), is_taken) as f64;
            if basic[j] || (column.need > 0.0 && !column.rows.is_empty()) {
                new_column[j] = columns.len();
                columns.push(column);
            }
        }
        self.columns = columns;
        self.basis = positions
            .iter()
            .map(|&p| match self.basis[p] {
                Ok(j) => Ok(new_column[j]),
                Err(r) => Err(new_row[r]),
            })
            .collect();
        self.vertices = rows.iter().map(|&r| self.vertices[r]).collect();
        self.row_of.iter_mut().for_each(|r| *r = usize::MAX);
        for (i, &v) in self.vertices.iter().enumerate() {
            self.row_of[v] = i;
        }
        self.rhs = rows.iter().map(|&r| self.rhs[r]).collect();
        self.m = n;
        self.inverse = inverse;
        self.known = self.columns.iter().map(|c| c.rows.clone()).collect();
        self.refresh_values();
        self.pi = self.duals();
        self.is_sound().then_some(())
    }

    /// Whether the basic values are a packing (none negative) that meets the right-hand
    /// sides: the basis inverse, carried down the search through many pivots, has not
    /// drifted.
    fn is_sound(&self) -> bool {
        let mut load = vec![0.0; self.m];
        for (b, &x) in self.basis.iter().zip(&self.values) {
            if x < -1e-7 {
                return false;
            }
            match *b {
                Ok(j) => self.columns[j].rows.iter().for_each(|&r| load[r] += x),
                Err(r) => load[r] += x,
            }
        }
        load.iter().zip(&self.rhs).all(|(a, b)| (a - b).abs() < 1e-6)
    }

    /// `B^-1 a`, for the column or slack `enter`.
    fn direction(&self, enter: std::result::Result<usize, usize>) -> Vec<f64> {
        let m = self.m;
        (0..m)
            .map(|p| {
                let row = &self.inverse[p * m..(p + 1) * m];
                match enter {
                    Ok(j) => self.columns[j].rows.iter().map(|&s| row[s]).sum(),
                    Err(s) => row[s],
                }
            })
            .collect()
    }

    /// The step and the position that leaves when a variable of direction `u` enters: of
    /// the positions within a hair of the smallest ratio, the one of the largest entry
    /// (Harris's ratio test), so that no pivot divides by a speck.
    fn ratio_test(&self, u: &[f64]) -> Option<(f64, usize)> {
        const PIVOT: f64 = 1e-7;
        let limit = u
            .iter()
            .zip(&self.values)
            .filter(|(up, _)| **up > PIVOT)
            .map(|(up, value)| (value.max(0.0) + 1e-9) / up)
            .fold(f64::INFINITY, f64::min);
        let mut leave: Option<(f64, usize)> = None;
        for (p, (&up, &value)) in u.iter().zip(&self.values).enumerate() {
            if up > PIVOT && value.max(0.0) / up <= limit && leave.is_none_or(|(best, _)| up > best) {
                leave = Some((up, p));
            }
        }
        leave.map(|(up, p)| (self.values[p].max(0.0) / up, p))
    }

    /// Enters `enter` (direction `u`) at position `p` with the value `theta`.
    fn pivot(&mut self, enter: std::result::Result<usize, usize>, p: usize, u: &[f64], theta: f64) {
        let m = self.m;
        for (value, &up) in self.values.iter_mut().zip(u) {
            *value -= theta * up;
        }
        self.values[p] = theta;
        let pivot_row: Vec<f64> = self.inverse[p * m..(p + 1) * m].iter().map(|x| x / u[p]).collect();
        for (r, &f) in u.iter().enumerate() {
            if r == p || f == 0.0 {
                continue;
            }
            let row = &mut self.inverse[r * m..(r + 1) * m];
            row.iter_mut().zip(&pivot_row).for_each(|(x, y)| *x -= f * y);
        }
        self.inverse[p * m..(p + 1) * m].copy_from_slice(&pivot_row);
        self.basis[p] = enter;
        self.pivots += 1;
    }

    /// The rows' dual values, `c_B B^-1`.
    fn duals(&self) -> Vec<f64> {
        let m = self.m;
        let mut pi = vec![0.0; m];
        for (r, b) in self.basis.iter().enumerate() {
            if let Ok(j) = *b {
                let cost = self.columns[j].need;
                let row = &self.inverse[r * m..(r + 1) * m];
                pi.iter_mut().zip(row).for_each(|(p, x)| *p += cost * x);
            }
        }
        pi
    }

    /// The vertices' values (the duals, clipped to `[0, 1]`), indexed by vertex.
    fn vertex_values(&self) -> Vec<f64> {
        let pi = self.duals();
        self.row_of
            .iter()
            .map(|&r| if r == usize::MAX { 0.0 } else { pi[r].clamp(0.0, 1.0) })
            .collect()
    }

    /// The packing's objective, `c_B x_B`.
    fn objective(&self) -> f64 {
        self.basis
            .iter()
            .zip(&self.values)
            .map(|(b, &y)| match *b {
                Ok(j) => self.columns[j].need * y,
                Err(_) => 0.0,
            })
            .sum()
    }

    /// Pivots until no column improves the packing (`Some(false)`) or until its verified
    /// worth reaches `cutoff` (`Some(true)`); `None` at the deadline or if the simplex does
    /// not settle.
    fn optimize(&mut self, deadline: Instant, mut cutoff: f64) -> Option<bool> {
        let m = self.m;
        let mut objective = self.objective();
        let mut pivots = 0usize;
        loop {
            if pivots.is_multiple_of(64) && Instant::now() >= deadline {
                return None;
            }
            if pivots > 200 * (m + 10) {
                return None;
            }
            let pi = &self.pi;
            // The entering column: the largest reduced cost squared over the column's length
            // (its norm at the start: a cheap stand-in for the steepest edge, a quarter fewer
            // pivots than Dantzig's rule on the competition's hard tasks and half the time),
            // a slack entering if its row's dual is negative.
            let mut entering: Option<(f64, f64, std::result::Result<usize, usize>)> = None;
            for (j, column) in self.columns.iter().enumerate() {
                let d = column.need - column.rows.iter().map(|&r| pi[r]).sum::<f64>();
                let score = d * d / (column.rows.len() as f64);
                if d > 1e-9 && entering.is_none_or(|(e, _, _)| score > e) {
                    entering = Some((score, d, Ok(j)));
                }
            }
            for (r, &p) in pi.iter().enumerate() {
                if -p > 1e-9 && entering.is_none_or(|(e, _, _)| p * p > e) {
                    entering = Some((p * p, -p, Err(r)));
                }
            }
            let Some((_, gain, enter)) = entering else {
                return Some(false);
            };
            let u = self.direction(enter);
            let (theta, p) = self.ratio_test(&u)?;
            self.pivot(enter, p, &u, theta);
            pivots += 1;
            let new_row = &self.inverse[p * m..(p + 1) * m];
            self.pi.iter_mut().zip(new_row).for_each(|(d, x)| *d += gain * x);
            objective += gain * theta;
            if objective >= cutoff {
                if self.verified_bound() >= cutoff {
                    return Some(true);
                }
                cutoff = f64::INFINITY;
            }
            if pivots.is_multiple_of(100) {
                self.refresh_values();
                self.pi = self.duals();
                if !self.is_sound() {
                    return None;
                }
            }
        }
    }

    /// Recomputes the basic values from the right-hand sides, `B^-1 b`.
    fn refresh_values(&mut self) {
        let m = self.m;
        for r in 0..m {
            let row = &self.inverse[r * m..(r + 1) * m];
            self.values[r] = row.iter().zip(&self.rhs).map(|(x, b)| x * b).sum();
        }
    }

    /// The packing's size, made feasible for right-hand sides of exactly one: the columns'
    /// values (clipped at zero) divided by the largest load of a row, if above one.
    fn verified_bound(&mut self) -> f64 {
        self.refresh_values();
        let mut load = vec![0.0; self.m];
        let mut total = 0.0;
        for (r, b) in self.basis.iter().enumerate() {
            if let Ok(j) = *b {
                let y = self.values[r].max(0.0);
                total += y * self.columns[j].need;
                self.columns[j].rows.iter().for_each(|&s| load[s] += y);
            }
        }
        let worst = load.iter().copied().fold(1.0, f64::max);
        total / worst
    }
}

/// An `f64` ordered by `total_cmp`, for the heap.
#[derive(Clone, Copy, PartialEq)]
struct Ordered(f64);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The smallest feedback vertex set by trying every subset, smallest first.
    fn brute_force(adj: &[Vec<usize>]) -> usize {
        let k = adj.len();
        let mut best = k;
        for mask in 0u32..(1 << k) {
            let size = mask.count_ones() as usize;
            if size >= best {
                continue;
            }
            let live: Vec<bool> = (0..k).map(|v| mask >> v & 1 == 0).collect();
            // A loop is a cycle of one vertex.
            let looped = (0..k).any(|v| live[v] && adj[v].contains(&v));
            if !looped && is_acyclic_without(adj, &live) {
                best = size;
            }
        }
        best
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// On random graphs dense enough to branch, the search finds a smallest set,
        /// proves it, and the set breaks every cycle.
        #[test]
        fn the_search_finds_the_minimum(
            k in 1usize..=18,
            density in 0.1f64..0.45,
            seed in any::<u64>(),
        ) {
            let mut rng = sim::seeding::rng(seed);
            let adj: Vec<Vec<usize>> = (0..k)
                .map(|_| (0..k).filter(|_| rand::RngExt::random_bool(&mut rng, density)).collect())
                .collect();
            let succ = rows(&adj);
            let far = Instant::now() + std::time::Duration::from_secs(60);
            let found = minimum_fvs(succ, far);
            let set = found.set.unwrap();
            let fewest = brute_force(&adj);
            prop_assert_eq!(set.len(), fewest);
            prop_assert_eq!(found.lower_bound, fewest);
            let mut live = vec![true; k];
            set.iter().for_each(|&v| live[v] = false);
            prop_assert!((0..k).all(|v| !live[v] || !adj[v].contains(&v)));
            prop_assert!(is_acyclic_without(&adj, &live));
        }
    }

    /// The graph of `adj` as the search's rows.
    fn rows(adj: &[Vec<usize>]) -> Vec<BitSet> {
        adj.iter()
            .map(|row| {
                let mut set = BitSet::new(adj.len());
                row.iter().for_each(|&w| set.insert(w));
                set
            })
            .collect()
    }

    /// A graph on which the two branches of a node meet the same cycles differently: the
    /// branch that bypasses a vertex finds cycles through the edges the bypass joined, which
    /// are no cycles where its sibling took that vertex. A search that kept a branch's
    /// cycles for its sibling bounded that sibling too high and returned a set of 10 (found
    /// by searching random graphs with that mistake put back); the smallest set has 9.
    #[test]
    fn a_branch_s_cycles_do_not_bound_its_sibling() {
        let adj: Vec<Vec<usize>> = vec![
            vec![0, 2, 4, 5, 6, 7, 9],
            vec![2, 8, 10, 13, 14],
            vec![5, 6, 11, 12],
            vec![5, 6, 7, 9, 10, 11],
            vec![1, 2, 3, 10, 14],
            vec![1, 3, 4, 7, 9, 14],
            vec![0, 3, 6, 7, 10, 12],
            vec![0, 4, 9, 10, 12],
            vec![3, 5, 7, 10],
            vec![1, 2, 3, 4, 6, 7, 8, 9, 12, 13],
            vec![1, 3, 4, 12, 13, 14],
            vec![4, 5, 8, 12],
            vec![0, 4, 5, 8, 11, 13, 14],
            vec![0, 1, 3, 4, 6, 7, 9, 10, 11, 13],
            vec![2, 3, 4, 5, 8, 9, 10, 12, 14],
        ];
        assert_eq!(brute_force(&adj), 9);
        let far = Instant::now() + std::time::Duration::from_secs(60);
        let found = minimum_fvs(rows(&adj), far);
        assert_eq!(found.lower_bound, 9);
        let set = found.set.unwrap();
        assert_eq!(set.len(), 9);
        let mut live = vec![true; adj.len()];
        set.iter().for_each(|&v| live[v] = false);
        assert!(is_acyclic_without(&adj, &live));
    }

    /// Five vertices in a ring of two-way edges: every set covers the ring's five edges,
    /// so it takes three vertices, while the cycles and cliques alone allow one half each
    /// (two and a half). The odd cycle is found and lifts the root's bound to three.
    #[test]
    fn an_odd_ring_of_two_way_edges_needs_more_than_half_its_vertices() {
        let adj: Vec<Vec<usize>> = (0..5).map(|v| vec![(v + 1) % 5, (v + 4) % 5]).collect();
        assert_eq!(brute_force(&adj), 3);
        let weight = vec![0.5; 5];
        let two_way = rows(&adj);
        assert_eq!(
            lightest_odd_cycle(&two_way, 2, &weight, &[0; 5]),
            Some(vec![0, 1, 2, 3, 4])
        );
        // A ring of six is covered by half its vertices: no odd cycle to find.
        let even: Vec<Vec<usize>> = (0..6).map(|v| vec![(v + 1) % 6, (v + 5) % 6]).collect();
        assert_eq!(lightest_odd_cycle(&rows(&even), 0, &[0.5; 6], &[0; 6]), None);
        let far = Instant::now() + std::time::Duration::from_secs(60);
        let mut graph = Graph::new(rows(&adj));
        graph.reduce(&mut Vec::new());
        assert_eq!(graph.alive.len(), 5);
        let root = Search::new(far).relaxation(&graph, &[], None, f64::INFINITY).unwrap();
        // The right-hand sides are perturbed by up to a millionth (ties in the ratio test).
        assert!(root.bound > 3.0 - 1e-5, "bound {}", root.bound);
        let found = minimum_fvs(rows(&adj), far);
        assert_eq!((found.lower_bound, found.set.map(|s| s.len())), (3, Some(3)));
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// A child's relaxation started from its parent's packing (a vertex taken or
        /// bypassed, the reductions applied) bounds no higher than the child's smallest set,
        /// and its packing stays sound.
        #[test]
        fn a_packing_carried_to_a_child_still_bounds_it(
            k in 5usize..=12,
            density in 0.3f64..0.6,
            seed in any::<u64>(),
            pick in any::<usize>(),
            take in any::<bool>(),
        ) {
            let mut rng = sim::seeding::rng(seed);
            let adj: Vec<Vec<usize>> = (0..k)
                .map(|_| (0..k).filter(|_| rand::RngExt::random_bool(&mut rng, density)).collect())
                .collect();
            let far = Instant::now() + std::time::Duration::from_secs(60);
            let mut graph = Graph::new(rows(&adj));
            let mut taken = Vec::new();
            graph.reduce(&mut taken);
            let alive: Vec<usize> = graph.alive.iter().collect();
            if alive.is_empty() {
                return Ok(());
            }
            let parent = Search::new(far).relaxation(&graph, &taken, None, f64::INFINITY).unwrap();
            let v = alive[pick % alive.len()];
            let mut child = graph.clone();
            if take {
                child.remove(v);
                taken.push(v);
            } else {
                child.bypass(v);
            }
            child.reduce(&mut taken);
            // The child's smallest set: its taken vertices and the rest of its graph's.
            let rest: Vec<Vec<usize>> = (0..k)
                .map(|u| if child.alive.contains(u) { child.succ[u].iter().collect() } else { Vec::new() })
                .collect();
            let fewest = taken.len() + brute_force(&rest);
            if child.alive.is_empty() {
                return Ok(());
            }
            let lp = Search::new(far).relaxation(&child, &taken, Some(parent.packing), f64::INFINITY).unwrap();
            prop_assert!(taken.len() as f64 + lp.bound <= fewest as f64 + 1e-6);
            prop_assert!(lp.packing.is_sound());
        }
    }
}
