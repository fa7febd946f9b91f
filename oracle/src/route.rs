//! Routes for one block over the occupancy grid, the other blocks standing still as
//! obstacles. Every step is taken with [`sim::World::act`] on a [`GridWorld`], so the
//! routes obey the world's rules by construction.

use std::hash::{Hash, Hasher};

use pathfinding::directed::astar::astar;
use pathfinding::directed::dijkstra::{build_path, dijkstra_all};
use sim::{Action, BlockId, Cell, Effect, Grid, GridWorld, World};

/// A world in which one block is held and moving; only that block's cell tells two of
/// them apart, since nothing else moves while it is routed.
#[derive(Clone, Copy, Debug)]
struct Moving {
    world: GridWorld,
    block: BlockId,
}

impl Moving {
    fn cell(&self) -> Cell {
        self.world.state_ref().cell(self.block)
    }

    /// The worlds one move away, by the rules.
    fn next(&self) -> impl Iterator<Item = (Moving, u32)> + use<> {
        let this = *self;
        [Action::Up, Action::Down, Action::Left, Action::Right]
            .into_iter()
            .filter_map(move |a| {
                let mut world = this.world;
                (world.act(a) == Ok(Effect::Moved)).then_some((Moving { world, ..this }, 1))
            })
    }
}

impl PartialEq for Moving {
    fn eq(&self, other: &Self) -> bool {
        self.cell() == other.cell()
    }
}

impl Eq for Moving {}

impl Hash for Moving {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.cell().hash(state);
    }
}

/// `world` with `block` held (picked if it was not).
fn holding(world: &GridWorld, block: BlockId) -> Moving {
    let mut world = *world;
    world.act(Action::Pick(block)).expect("the block exists");
    Moving { world, block }
}

/// The moves along a path of worlds.
fn moves(path: &[Moving]) -> Vec<Action> {
    path.windows(2)
        .map(|w| {
            let (a, b) = (w[0].cell(), w[1].cell());
            match (i16::from(b.x) - i16::from(a.x), i16::from(b.y) - i16::from(a.y)) {
                (0, 1) => Action::Up,
                (0, -1) => Action::Down,
                (-1, 0) => Action::Left,
                _ => Action::Right,
            }
        })
        .collect()
}

/// A shortest sequence of moves taking `block` to `target` around the other blocks (A*
/// with the Manhattan distance), or `None` if they wall it off. The moves assume `block` is
/// held; the caller adds the pick.
pub(crate) fn route(world: &GridWorld, block: BlockId, target: Cell) -> Option<Vec<Action>> {
    let start = holding(world, block);
    if start.cell() != target && world.is_occupied(target) {
        return None;
    }
    let (path, _) = astar(
        &start,
        Moving::next,
        |m| m.cell().manhattan(target),
        |m| m.cell() == target,
    )?;
    Some(moves(&path))
}

/// The moves taking `block` to the nearest cell it can reach for which `wanted` is true
/// (ties: the lowest row-major index), or `None` if it can reach none. The choice does not
/// change as the block walks the returned path: every other candidate stays at least as
/// far, and ties keep going the same way.
pub(crate) fn to_nearest(world: &GridWorld, block: BlockId, wanted: impl Fn(Cell) -> bool) -> Option<Vec<Action>> {
    let start = holding(world, block);
    let grid: Grid = world.grid();
    let reached = dijkstra_all(&start, Moving::next);
    let (goal, _) = reached
        .iter()
        .filter(|(m, _)| wanted(m.cell()))
        .min_by_key(|(m, (_, cost))| (*cost, grid.index(m.cell())))?;
    Some(moves(&build_path(goal, &reached)))
}
