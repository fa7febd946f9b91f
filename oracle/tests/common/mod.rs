//! Helpers shared by the oracle's integration tests: an independent breadth-first search
//! over every state, and state enumeration.

use std::collections::VecDeque;

use sim::{Action, ActionProtocol, BlockId, Cell, Goal, Grid, GridWorld, State, World};

/// Distances to the goal of every state of a small world, by breadth-first search from the
/// states where the goal holds, over every action of the rules (drops and no-ops included).
///
/// The state graph is undirected (`every_action_can_be_undone` checks it), so the distance
/// from the goal states is the distance to them.
pub struct BfsTable {
    pub grid: Grid,
    pub blocks: usize,
    dist: Vec<u8>,
}

pub const UNREACHABLE: u8 = u8::MAX;

impl BfsTable {
    /// Distances over every action (the `free` protocol).
    pub fn new(grid: Grid, goal: &Goal) -> Self {
        Self::under(grid, goal, ActionProtocol::Free)
    }

    /// Distances over the actions `protocol` allows. Every legal action has a legal
    /// inverse under both protocols (a Drop undoes a Pick made with nothing held and the
    /// other way round; moves undo each other), so the graph stays undirected.
    pub fn under(grid: Grid, goal: &Goal, protocol: ActionProtocol) -> Self {
        let blocks = goal.block_count();
        let size = grid.cell_count().pow(blocks as u32) * (blocks + 1);
        let mut table = BfsTable {
            grid,
            blocks,
            dist: vec![UNREACHABLE; size],
        };
        let mut queue = VecDeque::new();
        for state in all_states(grid, blocks) {
            if goal.holds(&state) {
                let i = table.index(&state);
                table.dist[i] = 0;
                queue.push_back(state);
            }
        }
        while let Some(state) = queue.pop_front() {
            let d = table.dist[table.index(&state)];
            let world = GridWorld::new(grid, state.clone()).unwrap();
            for action in protocol.legal_actions(&state).iter() {
                let mut w = world.clone();
                w.act(action).unwrap();
                let i = table.index(w.state_ref());
                if table.dist[i] == UNREACHABLE {
                    table.dist[i] = d + 1;
                    queue.push_back(w.state_ref().clone());
                }
            }
        }
        table
    }

    fn index(&self, state: &State) -> usize {
        let cells = self.grid.cell_count();
        let placed = state
            .cells()
            .iter()
            .fold(0usize, |acc, &c| acc * cells + self.grid.index(c));
        placed * (self.blocks + 1) + state.held_block().map_or(0, |b| b.index() + 1)
    }

    /// The shortest distance to the goal, `None` if it cannot be reached.
    pub fn distance(&self, state: &State) -> Option<u32> {
        let d = self.dist[self.index(state)];
        (d != UNREACHABLE).then_some(u32::from(d))
    }
}

/// Every placement of `blocks` blocks on distinct cells of `grid`, nothing held.
pub fn all_placements(grid: Grid, blocks: usize) -> Vec<State> {
    let mut out = Vec::new();
    let mut cells = Vec::with_capacity(blocks);
    fn rec(grid: Grid, blocks: usize, cells: &mut Vec<Cell>, out: &mut Vec<State>) {
        if cells.len() == blocks {
            out.push(State::new(cells, None).unwrap());
            return;
        }
        for c in grid.cells() {
            if !cells.contains(&c) {
                cells.push(c);
                rec(grid, blocks, cells, out);
                cells.pop();
            }
        }
    }
    rec(grid, blocks, &mut cells, &mut out);
    out
}

/// Every state: every placement with nothing held and with each block held.
pub fn all_states(grid: Grid, blocks: usize) -> Vec<State> {
    all_placements(grid, blocks)
        .into_iter()
        .flat_map(|s| {
            std::iter::once(None)
                .chain((0..blocks).map(|b| Some(BlockId::of(b))))
                .map(move |h| s.with_held(h).unwrap())
        })
        .collect()
}

/// The state `actions` lead to from `start`, by the rules of the grid model.
pub fn replay(grid: Grid, start: &State, actions: &[Action]) -> State {
    let mut world = GridWorld::new(grid, start.clone()).unwrap();
    for &a in actions {
        world.act(a).unwrap();
    }
    world.state_ref().clone()
}
