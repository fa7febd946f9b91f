//! Routes for one block over the occupancy grid, the other blocks standing still as
//! obstacles. Every step is taken with [`sim::World::act`] on a [`GridWorld`], so the
//! routes obey the world's rules by construction.
//!
//! Both searches index cells by [`Grid::index`] into fixed arrays instead of hashing
//! states: the oracle routes a few dozen times per plan, and hashing and allocation were
//! most of its time.

use sim::{Action, BlockId, Cell, Effect, Grid, GridWorld, MAX_CELLS, World};

/// Marks a cell not reached yet.
const UNSEEN: u16 = u16::MAX;

/// The four moves.
const MOVES: [Action; 4] = [Action::Up, Action::Down, Action::Left, Action::Right];

/// Per-cell search records: the best number of moves found to reach each cell, and the
/// cell it was reached from.
struct Records {
    moves: [u16; MAX_CELLS],
    from: [u8; MAX_CELLS],
}

impl Records {
    fn new() -> Self {
        Self {
            moves: [UNSEEN; MAX_CELLS],
            from: [0; MAX_CELLS],
        }
    }

    /// The moves from the start to the cell with index `end`.
    fn path(&self, grid: Grid, start: Cell, end: usize) -> Vec<Action> {
        let mut actions = Vec::with_capacity(usize::from(self.moves[end]));
        let mut at = end;
        while grid.cell_at(at) != start {
            let prev = usize::from(self.from[at]);
            let (a, b) = (grid.cell_at(prev), grid.cell_at(at));
            actions.push(
                match (i32::from(b.x) - i32::from(a.x), i32::from(b.y) - i32::from(a.y)) {
                    (0, 1) => Action::Up,
                    (0, -1) => Action::Down,
                    (-1, 0) => Action::Left,
                    _ => Action::Right,
                },
            );
            at = prev;
        }
        actions.reverse();
        actions
    }
}

/// `world` with `block` held (picked if it was not).
fn holding(world: &GridWorld, block: BlockId) -> GridWorld {
    let mut world = world.clone();
    world.act(Action::Pick(block)).expect("the block exists");
    world
}

/// The worlds one move of the held `block` away, by the rules.
fn next(world: GridWorld) -> impl Iterator<Item = GridWorld> {
    MOVES.into_iter().filter_map(move |a| {
        let mut w = world.clone();
        (w.act(a) == Ok(Effect::Moved)).then_some(w)
    })
}

/// A shortest sequence of moves taking `block` to `target` around the other blocks, or
/// `None` if they wall it off. The moves assume `block` is held; the caller adds the pick.
///
/// A* with the Manhattan distance: a move changes it by one, so `f = moves + distance`
/// stays the same on a move towards the target and grows by two on a move away. Two
/// stacks, the current `f` and the next, make the priority queue.
pub(crate) fn route(world: &GridWorld, block: BlockId, target: Cell) -> Option<Vec<Action>> {
    let grid = world.grid();
    let start = world.state_ref().cell(block);
    if start != target && world.is_occupied(target) {
        return None;
    }
    let mut records = Records::new();
    let goal = grid.index(target);
    records.moves[grid.index(start)] = 0;
    let (mut current, mut later) = (vec![holding(world, block)], Vec::new());
    while !current.is_empty() {
        while let Some(w) = current.pop() {
            let here = w.state_ref().cell(block);
            let i = grid.index(here);
            if i == goal {
                return Some(records.path(grid, start, goal));
            }
            let g = records.moves[i] + 1;
            for n in next(w) {
                let cell = n.state_ref().cell(block);
                let j = grid.index(cell);
                if g < records.moves[j] {
                    records.moves[j] = g;
                    records.from[j] = i as u8;
                    if cell.manhattan(target) < here.manhattan(target) {
                        current.push(n);
                    } else {
                        later.push(n);
                    }
                }
            }
        }
        std::mem::swap(&mut current, &mut later);
    }
    None
}

/// The moves taking `block` to the nearest cell it can reach for which `wanted` is true
/// (ties: the lowest row-major index), or `None` if it can reach none. The choice does not
/// change as the block walks the returned path: every other candidate stays at least as
/// far, and ties keep going the same way.
pub(crate) fn to_nearest(world: &GridWorld, block: BlockId, wanted: impl Fn(Cell) -> bool) -> Option<Vec<Action>> {
    let grid = world.grid();
    let start = world.state_ref().cell(block);
    let mut records = Records::new();
    records.moves[grid.index(start)] = 0;
    // Breadth first, level by level, so each level's wanted cells can be compared by index.
    let mut level = vec![holding(world, block)];
    let mut depth = 0;
    while !level.is_empty() {
        let best = level
            .iter()
            .map(|w| w.state_ref().cell(block))
            .filter(|&c| c != start && wanted(c))
            .map(|c| grid.index(c))
            .min();
        if let Some(end) = best {
            return Some(records.path(grid, start, end));
        }
        depth += 1;
        let mut deeper = Vec::new();
        for w in level {
            let i = grid.index(w.state_ref().cell(block));
            for n in next(w) {
                let j = grid.index(n.state_ref().cell(block));
                if records.moves[j] == UNSEEN {
                    records.moves[j] = depth;
                    records.from[j] = i as u8;
                    deeper.push(n);
                }
            }
        }
        level = deeper;
    }
    None
}
