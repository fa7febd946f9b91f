//! The two world kinds: the paper's world seen from above, and the classic Blocks World seen
//! from the side (docs/world.md, "The side view").
//!
//! [`View::Top`] is the paper's: blocks slide on a table seen from above, and a released
//! block stays where it was let go. [`View::Side`] is the Blocks World of the planning and
//! learning literature: `y` is up and row 0 stands on the table, so blocks stand on the table
//! or on one another, only a clear block (nothing on it) can be picked, and a released block
//! falls to the top of the column below it. The rules are still written once, in
//! [`World::act`](crate::World::act); this module holds what the side view adds to them:
//! which blocks are clear, where a released block comes to rest, which states can stand,
//! the mask of legal actions, the start rule (random towers) and the towers of a state that
//! planners search over.

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid};
use crate::protocol::{ActionMask, ActionProtocol};
use crate::seeding::SimRng;
use crate::state::{BlockId, MAX_BLOCKS, State};

/// Which world: seen from above (the paper's) or from the side (the classic Blocks World).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum View {
    /// Seen from above: a released block stays where it is (docs/world.md section 2).
    #[default]
    Top,
    /// Seen from the side: gravity, towers on a table, only clear blocks picked.
    Side,
}

crate::names!(View { Top = "top", Side = "side" } unknown(name) -> SimError {
    SimError::Parse {
        what: "view",
        text: name.to_string(),
        reason: format!("choose one of {}", View::NAMES.join(", ")),
    }
});

impl View {
    /// The legal actions in `state` in this view: `protocol`'s in the top view; in the side
    /// view, whatever the protocol, the picks of clear blocks with nothing held, and the
    /// moves and Drop while holding ([`side_mask`]). (Under the `free` protocol an action
    /// outside the side view's mask may still be taken: the rules make it change nothing.)
    #[inline]
    pub fn legal_actions(self, protocol: ActionProtocol, state: &State) -> ActionMask {
        match self {
            View::Top => protocol.legal_actions(state),
            View::Side => side_mask(state),
        }
    }

    /// `Ok` if `action` is legal in `state` in this view; otherwise the error that names why
    /// ([`SimError::NoSuchBlock`], [`SimError::IllegalAction`] or
    /// [`SimError::IllegalInSideView`]).
    pub fn check(self, protocol: ActionProtocol, state: &State, action: Action) -> Result<()> {
        match self {
            View::Top => protocol.check(state, action),
            View::Side => check_side(state, action),
        }
    }

    /// An error if `state` cannot be a state of this view: in the side view, a block that is
    /// not held must stand on the table or on another block.
    pub fn check_state(self, state: &State) -> Result<()> {
        match self {
            View::Top => Ok(()),
            View::Side => check_stands(state),
        }
    }
}

/// The block standing directly on `block`, if any.
#[inline]
pub fn block_on(state: &State, block: BlockId) -> Option<BlockId> {
    let c = state.cell(block);
    let above = Cell::new(c.x, c.y.wrapping_add(1));
    state.block_at(above)
}

/// Whether nothing stands on `block` (the side view picks only clear blocks).
#[inline]
pub fn is_clear(state: &State, block: BlockId) -> bool {
    block_on(state, block).is_none()
}

/// Where a block released on `from` comes to rest in the side view: the cell above the
/// highest occupied cell below it in its column, or row 0 (the table). `occupied` says
/// whether a cell holds a block; `from` itself is not asked.
#[inline]
pub fn landing_cell(from: Cell, occupied: impl Fn(Cell) -> bool) -> Cell {
    let mut y = from.y;
    while y > 0 && !occupied(Cell::new(from.x, y - 1)) {
        y -= 1;
    }
    Cell::new(from.x, y)
}

/// The side view's legal actions: with nothing held, Pick of every clear block; while
/// holding, the four moves and Drop.
#[inline]
pub fn side_mask(state: &State) -> ActionMask {
    let n = state.block_count();
    if state.held_block().is_some() {
        return ActionMask::from_bits(0b1_1111, n);
    }
    // Bit 5 + b for every block b with nothing on it: the hot path of every side-view step.
    let cells = state.cells();
    let mut bits = 0u32;
    for (b, c) in cells.iter().enumerate() {
        let covered = cells.iter().any(|o| o.x == c.x && o.y == c.y.wrapping_add(1));
        bits |= u32::from(!covered) << (5 + b);
    }
    ActionMask::from_bits(bits, n)
}

/// `Ok` if `action` is legal in the side view in `state`, otherwise the error naming why.
fn check_side(state: &State, action: Action) -> Result<()> {
    let illegal = |reason: String| Err(SimError::IllegalInSideView { action, reason });
    match (action, state.held_block()) {
        (Action::Pick(b), _) if b.index() >= state.block_count() => Err(SimError::NoSuchBlock {
            block: b.index(),
            blocks: state.block_count(),
        }),
        (Action::Pick(_), Some(h)) => illegal(format!("block {h} is held; drop it first")),
        (Action::Pick(b), None) => match block_on(state, b) {
            Some(top) => illegal(format!(
                "block {top} stands on block {b}; only a clear block can be picked"
            )),
            None => Ok(()),
        },
        (_, None) => illegal("nothing is held; pick a clear block first".into()),
        (_, Some(_)) => Ok(()),
    }
}

/// An error naming the first block that is not held and stands neither on the table (row
/// 0) nor on another block.
pub fn check_stands(state: &State) -> Result<()> {
    for b in state.blocks() {
        let c = state.cell(b);
        if state.held_block() == Some(b) || c.y == 0 {
            continue;
        }
        let below = Cell::new(c.x, c.y - 1);
        if state.block_at(below).is_none_or(|u| state.held_block() == Some(u)) {
            return Err(SimError::Floating {
                block: b.index(),
                x: c.x,
                y: c.y,
            });
        }
    }
    Ok(())
}

/// The towers of a side-view state, each bottom to top, by column from the left (empty
/// columns left out): the abstract state the block-move planners search over. An error if a
/// block is held or a block stands on nothing ([`check_stands`]).
pub fn towers(state: &State) -> Result<Vec<Vec<usize>>> {
    if let Some(b) = state.held_block() {
        return Err(SimError::HeldInTowers { block: b.index() });
    }
    check_stands(state)?;
    let mut by_cell: Vec<(Cell, usize)> = state.cells().iter().enumerate().map(|(i, &c)| (c, i)).collect();
    by_cell.sort_unstable_by_key(|&(c, _)| (c.x, c.y));
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut column = None;
    for (c, b) in by_cell {
        if column != Some(c.x) {
            out.push(Vec::new());
            column = Some(c.x);
        }
        out.last_mut().expect("a tower was opened").push(b);
    }
    Ok(out)
}

/// The side-view state, nothing held, with `towers` (each bottom to top) standing on
/// columns `0, 1, ...` of `grid`: how a planner's abstract state becomes a world. An error
/// unless the towers name every block `0..N` once and fit the grid (no more towers than
/// columns, none taller than the rows).
pub fn state_of_towers(grid: Grid, towers: &[Vec<usize>]) -> Result<State> {
    let n: usize = towers.iter().map(Vec::len).sum();
    let mut cells = vec![None; n];
    for (x, tower) in towers.iter().enumerate() {
        for (y, &b) in tower.iter().enumerate() {
            let cell = grid.cell(x as i64, y as i64)?;
            match cells.get_mut(b) {
                Some(slot @ None) => *slot = Some(cell),
                Some(Some(_)) => return Err(towers_error(towers, format!("block {b} appears twice"))),
                None => return Err(towers_error(towers, format!("block {b} does not exist"))),
            }
        }
    }
    let cells: Vec<Cell> = cells
        .into_iter()
        .map(|c| c.expect("n blocks placed once each"))
        .collect();
    let state = State::new(&cells, None)?;
    state.check_fits(grid)?;
    Ok(state)
}

fn towers_error(towers: &[Vec<usize>], reason: String) -> SimError {
    let text = towers
        .iter()
        .map(|t| t.iter().map(|b| b.to_string()).collect::<Vec<_>>().join(","))
        .collect::<Vec<_>>()
        .join("/");
    SimError::Parse {
        what: "towers",
        text,
        reason,
    }
}

/// The side view's start (docs/world.md, "The side view"): the blocks, in an order drawn
/// uniformly (Fisher-Yates), each put on top of a column drawn uniformly among those not yet
/// full. Nothing held; every block stands on the table or on another block. `blocks` is
/// below `grid`'s cell count (the config checks it).
pub fn random_towers(grid: Grid, blocks: usize, rng: &mut SimRng) -> State {
    let mut order: [usize; MAX_BLOCKS] = std::array::from_fn(|i| i);
    for i in (1..blocks).rev() {
        let j = rng.random_range(0..=i);
        order.swap(i, j);
    }
    let mut heights = [0u8; 256];
    let mut cells = [Cell::default(); MAX_BLOCKS];
    for &b in &order[..blocks] {
        let x = loop {
            let x = rng.random_range(0..grid.width());
            if usize::from(heights[x]) < grid.height() {
                break x;
            }
        };
        cells[b] = Cell::new(x as u8, heights[x]);
        heights[x] += 1;
    }
    State::new(&cells[..blocks], None).expect("distinct cells")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(cells: &[(u8, u8)], held: Option<u8>) -> State {
        let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
        State::new(&cells, held.map(BlockId)).unwrap()
    }

    #[test]
    fn only_clear_blocks_are_picked_and_only_a_held_block_moves() {
        // 0 on the table, 1 on 0, 2 alone.
        let s = state(&[(0, 0), (0, 1), (3, 0)], None);
        assert_eq!(
            side_mask(&s).iter().collect::<Vec<_>>(),
            [Action::Pick(BlockId(1)), Action::Pick(BlockId(2))]
        );
        let err = View::Side
            .check(ActionProtocol::Free, &s, Action::Pick(BlockId(0)))
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "pick 0 is not legal in the side view: block 1 stands on block 0; only a clear block can be picked"
        );
        assert!(View::Side.check(ActionProtocol::Free, &s, Action::Up).is_err());
        let held = state(&[(0, 0), (0, 1), (3, 0)], Some(1));
        assert_eq!(side_mask(&held).indices().collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
        assert!(
            View::Side
                .check(ActionProtocol::Free, &held, Action::Pick(BlockId(2)))
                .is_err()
        );
        assert_eq!(
            View::Side.check(ActionProtocol::Free, &s, Action::Pick(BlockId(5))),
            Err(SimError::NoSuchBlock { block: 5, blocks: 3 })
        );
    }

    #[test]
    fn a_released_block_lands_on_the_top_of_its_column() {
        let s = state(&[(2, 0), (2, 1), (2, 5)], None);
        let occupied = |c: Cell| s.block_at(c).is_some();
        assert_eq!(landing_cell(Cell::new(2, 5), occupied), Cell::new(2, 2));
        assert_eq!(landing_cell(Cell::new(4, 6), occupied), Cell::new(4, 0));
        assert_eq!(landing_cell(Cell::new(2, 2), occupied), Cell::new(2, 2));
    }

    #[test]
    fn floating_blocks_are_refused_unless_held() {
        assert!(check_stands(&state(&[(0, 0), (0, 1), (3, 0)], None)).is_ok());
        assert!(check_stands(&state(&[(0, 0), (0, 2), (3, 0)], Some(1))).is_ok());
        let err = check_stands(&state(&[(0, 0), (0, 2), (3, 0)], None)).unwrap_err();
        assert_eq!(
            err.to_string(),
            "block 1 floats at (0, 2) in the side view: a block that is not held must stand on the table or on another block"
        );
        // A block standing on the held block floats once it is let go.
        assert!(check_stands(&state(&[(0, 0), (0, 1), (3, 0)], Some(0))).is_err());
    }

    #[test]
    fn towers_read_back_and_rebuild() {
        let grid = Grid::new(5, 4).unwrap();
        let s = state(&[(3, 1), (1, 0), (3, 0), (0, 0)], None);
        let t = towers(&s).unwrap();
        assert_eq!(t, vec![vec![3], vec![1], vec![2, 0]]);
        let rebuilt = state_of_towers(grid, &t).unwrap();
        assert_eq!(towers(&rebuilt).unwrap(), t);
        assert!(state_of_towers(grid, &[vec![0, 1], vec![1]]).is_err());
        assert!(state_of_towers(grid, &[vec![0, 3]]).is_err());
        assert!(towers(&s.with_held(Some(BlockId(0))).unwrap()).is_err());
    }

    #[test]
    fn random_towers_stand_and_follow_the_seed() {
        let grid = Grid::new(4, 3).unwrap();
        for seed in 0..200 {
            let s = random_towers(grid, 5, &mut crate::seeding::rng(seed));
            check_stands(&s).unwrap();
            assert_eq!(s, random_towers(grid, 5, &mut crate::seeding::rng(seed)));
        }
    }

    #[test]
    fn views_parse_and_print_by_name() {
        for name in View::NAMES {
            assert_eq!(name.parse::<View>().unwrap().to_string(), name);
        }
        assert!("front".parse::<View>().unwrap_err().to_string().contains("top, side"));
        assert_eq!(serde_json::to_string(&View::Side).unwrap(), "\"side\"");
    }
}
