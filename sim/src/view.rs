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

use std::collections::HashSet;
use std::ops::RangeInclusive;

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::error::{Result, SimError};
use crate::grid::{Cell, Grid, MAX_CELLS};
use crate::protocol::{ActionMask, ActionProtocol, MOVES_AND_DROP};
use crate::seeding::SimRng;
use crate::state::{BlockId, MAX_BLOCKS, MAX_SIDE_BLOCKS, MIN_BLOCKS, MIN_SIDE_BLOCKS, State};
use crate::uniform::UniformStates;

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
    /// The block counts a world of this view takes: 2 to [`MAX_BLOCKS`] from above, 1 to
    /// [`MAX_SIDE_BLOCKS`] from the side.
    pub const fn block_range(self) -> RangeInclusive<usize> {
        match self {
            View::Top => MIN_BLOCKS..=MAX_BLOCKS,
            View::Side => MIN_SIDE_BLOCKS..=MAX_SIDE_BLOCKS,
        }
    }

    /// The view's name in an error message: "the top view", "the side view".
    pub const fn title(self) -> &'static str {
        match self {
            View::Top => "the top view",
            View::Side => "the side view",
        }
    }

    /// An error if a world of `blocks` blocks on `grid` is beyond this view's bounds
    /// (docs/world.md, "The side view at any size"): the top view keeps an occupancy bitset of
    /// at most [`MAX_CELLS`] cells and at most [`MAX_BLOCKS`] blocks; the side view keeps no
    /// `W x H` structure and takes up to [`MAX_SIDE_BLOCKS`] blocks on any grid.
    pub fn check_world(self, grid: Grid, blocks: usize) -> Result<()> {
        if self == View::Top && grid.cell_count() > MAX_CELLS {
            return Err(SimError::BadGrid {
                width: grid.width(),
                height: grid.height(),
                max: MAX_CELLS,
            });
        }
        let range = self.block_range();
        if !range.contains(&blocks) {
            return Err(SimError::BadBlockCount {
                count: blocks,
                what: self.title(),
                min: *range.start(),
                max: *range.end(),
            });
        }
        Ok(())
    }

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

/// The block standing directly on `block`, if any (a scan of the blocks).
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
/// holding, the four moves and Drop. O(N): up to [`MAX_BLOCKS`] blocks by comparing cells
/// (no allocation), beyond through a set of the occupied cells.
#[inline]
pub fn side_mask(state: &State) -> ActionMask {
    let n = state.block_count();
    if state.held_block().is_some() {
        return ActionMask::with_first_word(MOVES_AND_DROP, n);
    }
    let cells = state.cells();
    if n <= MAX_BLOCKS {
        // Bit 5 + b for every block b with nothing on it: the hot path of every side-view step.
        let mut bits = 0u64;
        for (b, c) in cells.iter().enumerate() {
            let covered = cells.iter().any(|o| o.x == c.x && o.y == c.y.wrapping_add(1));
            bits |= u64::from(!covered) << (5 + b);
        }
        return ActionMask::with_first_word(bits, n);
    }
    let occupied: HashSet<Cell> = cells.iter().copied().collect();
    let mut mask = ActionMask::none(n);
    for (b, c) in cells.iter().enumerate() {
        if !occupied.contains(&Cell::new(c.x, c.y.wrapping_add(1))) {
            mask.insert_index(5 + b);
        }
    }
    mask
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
/// 0) nor on another block. O(N): up to [`MAX_BLOCKS`] blocks by comparing cells, beyond
/// through a set of the cells of the blocks not held.
pub fn check_stands(state: &State) -> Result<()> {
    let held = state.held_block();
    let standing: Option<HashSet<Cell>> = (state.block_count() > MAX_BLOCKS).then(|| {
        state
            .blocks()
            .filter(|&b| held != Some(b))
            .map(|b| state.cell(b))
            .collect()
    });
    for b in state.blocks() {
        let c = state.cell(b);
        if held == Some(b) || c.y == 0 {
            continue;
        }
        let below = Cell::new(c.x, c.y - 1);
        let supported = match &standing {
            Some(cells) => cells.contains(&below),
            None => state.block_at(below).is_some_and(|u| held != Some(u)),
        };
        if !supported {
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

/// A side-view state drawn uniformly over the Blocks World states of `states.blocks()`
/// blocks that fit `grid` ([`crate::uniform`]): towers drawn uniformly, drawn again while
/// there are more towers than columns or a tower taller than the rows, then stood on distinct
/// columns drawn uniformly (the tower drawn first on the first column drawn). Nothing held.
/// The config checks that the grid holds some state (the blocks fit its cells); on a grid
/// too small for most states the draws can take long (docs/world.md, "The side view at any
/// size").
pub fn uniform_state(grid: Grid, states: &UniformStates, rng: &mut SimRng) -> State {
    let (w, h) = (grid.width(), grid.height());
    let towers = loop {
        let towers = states.towers(rng);
        if towers.len() <= w && towers.iter().all(|t| t.len() <= h) {
            break towers;
        }
    };
    // The first `towers.len()` entries of a partial Fisher-Yates shuffle of the columns.
    let mut columns: Vec<u16> = (0..w as u16).collect();
    let mut cells = vec![Cell::default(); states.blocks()];
    for (i, tower) in towers.iter().enumerate() {
        let j = rng.random_range(i..w);
        columns.swap(i, j);
        for (y, &b) in tower.iter().enumerate() {
            cells[b] = Cell::new(columns[i], y as u16);
        }
    }
    State::new(&cells, None).expect("distinct cells")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
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
    fn uniform_states_stand_fit_the_grid_and_follow_the_seed() {
        let grid = Grid::new(4, 3).unwrap();
        let states = UniformStates::new(5);
        for seed in 0..200 {
            let s = uniform_state(grid, &states, &mut crate::seeding::rng(seed));
            check_stands(&s).unwrap();
            s.check_fits(grid).unwrap();
            assert_eq!(s, uniform_state(grid, &states, &mut crate::seeding::rng(seed)));
        }
    }

    /// Random standing states of `n` blocks on `grid`, some with a block held in the air
    /// and some with a block lifted off its tower (floating).
    fn random_state(n: usize, grid: Grid, seed: u64) -> State {
        let mut rng = crate::seeding::rng(seed);
        let mut s = uniform_state(grid, &UniformStates::new(n), &mut rng);
        let mut cells = s.cells().to_vec();
        match rng.random_range(0..3) {
            0 => {}
            kind => {
                // A clear block lifted one row (held, or left floating).
                let b = side_mask(&s).indices().next().expect("some block is clear") - 5;
                cells[b].y += 1;
                s = State::new(&cells, (kind == 1).then_some(BlockId::of(b))).unwrap();
            }
        }
        s
    }

    #[test]
    fn the_large_world_paths_agree_with_the_small_ones() {
        // Past MAX_BLOCKS the mask and the standing check go through sets of cells; the
        // cell-by-cell answer (the small path's) is the reference.
        for seed in 0..300 {
            let n = 17 + (seed as usize % 20);
            let s = random_state(n, Grid::new(n, n + 1).unwrap(), seed);
            let clear: Vec<usize> = if s.held_block().is_some() {
                vec![0, 1, 2, 3, 4]
            } else {
                s.blocks().filter(|&b| is_clear(&s, b)).map(|b| 5 + b.index()).collect()
            };
            assert_eq!(side_mask(&s).indices().collect::<Vec<_>>(), clear);
            let floating = s.blocks().find(|&b| {
                let c = s.cell(b);
                s.held_block() != Some(b)
                    && c.y > 0
                    && s.block_at(Cell::new(c.x, c.y - 1))
                        .is_none_or(|u| s.held_block() == Some(u))
            });
            match floating {
                None => assert!(check_stands(&s).is_ok()),
                Some(b) => {
                    assert!(matches!(check_stands(&s), Err(SimError::Floating { block, .. }) if block == b.index()))
                }
            }
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
