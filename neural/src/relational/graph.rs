//! Problems as the relations the relational network reads, a batch of them at once.
//!
//! A problem is a state ([`Towers`]) and a goal ([`TowerGoal`]). What the network is given
//! of it is the raw relations and nothing computed from several of them: for each block,
//! what it stands `on` (a block, or the table: `on-table`), what stands on it (none:
//! `clear`), and the goal's `on` / `on-table` for it (none: the goal leaves it free). Held
//! blocks never occur: the policy acts between block moves, with nothing held.
//!
//! The graph also lists each problem's legal moves (a clear block onto another clear block,
//! or to the table from a block), and two orders of its blocks for the network's passes
//! along the towers: bottom to top (by height) and top to bottom (by depth under the top).

use oracle::towers::{Move, Place, TowerGoal, Towers};

/// "No block": the table below a block, nothing above it, or no goal fact.
pub const NONE: u32 = u32::MAX;
/// In a goal's "below" relation and a move's destination: the table.
pub const TABLE: u32 = u32::MAX - 1;

/// Where one problem's blocks and moves lie in a [`Graph`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// Its first block's node.
    pub first_node: usize,
    /// Its number of blocks.
    pub nodes: usize,
    /// Its first move in [`Graph::moves`].
    pub first_move: usize,
    /// Its number of legal moves.
    pub moves: usize,
}

/// A batch of problems as relations (module docs): problem after problem, block `b` of a
/// problem is node `first_node + b`.
#[derive(Clone, Debug, Default)]
pub struct Graph {
    /// The block each node stands on ([`NONE`]: the table).
    pub below: Vec<u32>,
    /// The block standing on each node ([`NONE`]: it is clear).
    pub above: Vec<u32>,
    /// What the goal puts each node on ([`TABLE`], a block, or [`NONE`]: nothing).
    pub goal_below: Vec<u32>,
    /// The block the goal puts on each node ([`NONE`]: none).
    pub goal_above: Vec<u32>,
    /// The nodes bottom to top: every table block first, then the blocks on them, and so on.
    pub up_order: Vec<u32>,
    /// Where each height begins in `up_order` (one more entry than heights).
    pub up_levels: Vec<u32>,
    /// The nodes top to bottom: every clear block first, then the blocks under them, ...
    pub down_order: Vec<u32>,
    /// Where each depth begins in `down_order` (one more entry than depths).
    pub down_levels: Vec<u32>,
    /// Every problem's legal moves, when listed ([`Graph::with_moves`]): (block node,
    /// destination node or [`TABLE`]), each problem's in [`Towers::moves`] order.
    pub moves: Vec<(u32, u32)>,
    /// The problems.
    pub spans: Vec<Span>,
}

impl Graph {
    /// The graph of `problems`, in order, without their moves (a policy finds the best
    /// move without listing them all: [`super::net::RelationalNet::best_move`]).
    pub fn of<'a>(problems: impl IntoIterator<Item = (&'a Towers, &'a TowerGoal)>) -> Graph {
        Graph::build(problems, false)
    }

    /// The graph of `problems` with every legal move listed, as training scores them.
    pub fn with_moves<'a>(problems: impl IntoIterator<Item = (&'a Towers, &'a TowerGoal)>) -> Graph {
        Graph::build(problems, true)
    }

    fn build<'a>(problems: impl IntoIterator<Item = (&'a Towers, &'a TowerGoal)>, moves: bool) -> Graph {
        let mut g = Graph::default();
        for (state, goal) in problems {
            g.push(state, goal, moves);
        }
        g.order();
        g
    }

    /// Number of nodes (blocks of every problem).
    pub fn nodes(&self) -> usize {
        self.below.len()
    }

    /// Whether node `b` stands where the goal puts it (on the same block, or both on the
    /// table): the goal's `on` / `on-table` read on the pair the state's `on` links.
    pub fn stands_as_goal(&self, b: usize) -> bool {
        let support = if self.below[b] == NONE { TABLE } else { self.below[b] };
        self.goal_below[b] == support
    }

    /// Whether the goal puts node `x` on `to` (a node or [`TABLE`]).
    pub fn goal_on(&self, x: usize, to: u32) -> bool {
        self.goal_below[x] == to
    }

    /// The move a graph move is, in its problem's block numbers.
    pub fn move_of(&self, problem: usize, m: usize) -> Move {
        let first = self.spans[problem].first_node as u32;
        let (x, to) = self.moves[self.spans[problem].first_move + m];
        Move {
            block: (x - first) as usize,
            to: if to == TABLE {
                Place::Table
            } else {
                Place::On((to - first) as usize)
            },
        }
    }

    /// Appends one problem's relations and legal moves.
    fn push(&mut self, state: &Towers, goal: &TowerGoal, list_moves: bool) {
        let first = self.nodes();
        let n = state.blocks();
        let node = |b: usize| (first + b) as u32;
        for b in 0..n {
            self.below.push(match state.support(b) {
                Place::Table => NONE,
                Place::On(s) => node(s),
            });
            self.above.push(NONE);
            self.goal_below.push(match goal.support(b) {
                None => NONE,
                Some(Place::Table) => TABLE,
                Some(Place::On(s)) => node(s),
            });
            self.goal_above.push(NONE);
        }
        for b in first..first + n {
            if self.below[b] != NONE {
                self.above[self.below[b] as usize] = b as u32;
            }
            if self.goal_below[b] != NONE && self.goal_below[b] != TABLE {
                self.goal_above[self.goal_below[b] as usize] = b as u32;
            }
        }
        let first_move = self.moves.len();
        let clear: Vec<u32> = if !list_moves {
            Vec::new()
        } else {
            (first..first + n)
                .filter(|&b| self.above[b] == NONE)
                .map(|b| b as u32)
                .collect()
        };
        for &x in &clear {
            if self.below[x as usize] != NONE {
                self.moves.push((x, TABLE));
            }
            self.moves.extend(clear.iter().filter(|&&y| y != x).map(|&y| (x, y)));
        }
        self.spans.push(Span {
            first_node: first,
            nodes: n,
            first_move,
            moves: self.moves.len() - first_move,
        });
    }

    /// Fills the two orders: a counting sort of the nodes by height and by depth.
    fn order(&mut self) {
        let n = self.nodes();
        let (mut height, mut depth) = (vec![0u32; n], vec![0u32; n]);
        for bottom in (0..n).filter(|&b| self.below[b] == NONE) {
            let mut tower = vec![bottom];
            while let Some(&b) = tower.last().filter(|&&b| self.above[b] != NONE) {
                tower.push(self.above[b] as usize);
            }
            let top = tower.len() - 1;
            for (h, &b) in tower.iter().enumerate() {
                height[b] = h as u32;
                depth[b] = (top - h) as u32;
            }
        }
        (self.up_order, self.up_levels) = counting_sort(&height);
        (self.down_order, self.down_levels) = counting_sort(&depth);
    }
}

/// The nodes sorted by `key` (stable), and where each key begins (one more entry than keys).
fn counting_sort(key: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let levels = key.iter().max().map_or(0, |&m| m as usize + 1);
    let mut starts = vec![0u32; levels + 1];
    for &k in key {
        starts[k as usize + 1] += 1;
    }
    for l in 0..levels {
        starts[l + 1] += starts[l];
    }
    let mut next = starts.clone();
    let mut order = vec![0u32; key.len()];
    for (b, &k) in key.iter().enumerate() {
        order[next[k as usize] as usize] = b as u32;
        next[k as usize] += 1;
    }
    (order, starts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use oracle::towers::Table;

    #[test]
    fn a_problem_becomes_its_relations_orders_and_legal_moves() {
        // 1 on 0, 2 on 1; 3 alone. Goal: 3 on the table, 0 on 3; 1 and 2 free.
        let state = Towers::new(&[vec![0, 1, 2], vec![3]]).unwrap();
        let goal = TowerGoal::new(&[vec![3, 0]]).unwrap();
        let other = Towers::new(&[vec![1], vec![0]]).unwrap();
        let other_goal = TowerGoal::new(&[vec![0, 1]]).unwrap();
        let g = Graph::with_moves([(&state, &goal), (&other, &other_goal)]);
        assert_eq!(g.below[..4], [NONE, 0, 1, NONE]);
        assert_eq!(g.above[..4], [1, 2, NONE, NONE]);
        assert_eq!(g.goal_below[..4], [3, NONE, NONE, TABLE]);
        assert_eq!(g.goal_above[..4], [NONE, NONE, NONE, 0]);
        // The second problem's blocks are nodes 4 and 5.
        assert_eq!((g.goal_below[5], g.goal_above[4]), (4, 5));
        assert!(g.stands_as_goal(3) && !g.stands_as_goal(0) && !g.stands_as_goal(1));
        assert_eq!(g.up_order, [0, 3, 4, 5, 1, 2]);
        assert_eq!(g.up_levels, [0, 4, 5, 6]);
        assert_eq!(g.down_order, [2, 3, 4, 5, 1, 0]);
        assert_eq!(g.down_levels, [0, 4, 5, 6]);
        for (p, (s, _)) in [(&state, &goal), (&other, &other_goal)].into_iter().enumerate() {
            let moves: Vec<Move> = (0..g.spans[p].moves).map(|m| g.move_of(p, m)).collect();
            assert_eq!(moves, s.moves(Table::Unbounded), "problem {p}");
        }
    }
}
