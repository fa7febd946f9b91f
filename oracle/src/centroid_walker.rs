//! The paper's oracle as its authors coded it: a greedy walker towards a stack laid around
//! the blocks' centroid (docs/world.md section 10, "Oracle"; the authors' `State.py:25-50`
//! `compute_goal_positions`, `Oracle.py:24-85` `get_oracle_best_action`, and
//! `RL.py:422-430`, which picks a random block when nothing is held).
//!
//! Unlike [`Oracle`](crate::Oracle) it does not plan: each call looks at the state and
//! returns one action, and it can get stuck (walk into a wall of blocks and drop). It is
//! what the paper's Table I assisted its learner with.
//!
//! # The stack's cells, recomputed at every call
//!
//! On the authors' screen (50 px cells, y growing downward; [`sim::coded_state`]):
//!
//! 1. The stack's centre is the blocks' mean centre, each coordinate
//!    `25 + m - m % 50` with `m = (sum of the centres) // N`: the cell of the mean centre,
//!    rounded half-up in screen coordinates (a tie goes to the lower row of the screen).
//! 2. The goal's block at place `i` (0 the bottom) gets the cell `N // 2 - i` rows below
//!    the centre (for 3 blocks: bottom one below, middle on, top one above it).
//! 3. `N` times over: if the top block's cell is off the screen, the whole stack moves one
//!    row down; otherwise, if the bottom block's cell is off the screen, one row up.
//!
//! # The held block's action
//!
//! The first that applies:
//!
//! 1. the goal holds: Drop;
//! 2. the block stands on its target cell: Drop, and the sweep order becomes vertical;
//! 3. the first *good* move towards the target (the cell it enters is on the screen and
//!    holds no block), trying `Left, Right, Down, Up` (horizontal order) or
//!    `Down, Up, Left, Right` (vertical order), each only if the target lies that way;
//! 4. the block stands on another block's target cell and has *allowed* moves (good, and
//!    not entering another block's target cell): a uniformly random one of them, and the
//!    order flips;
//! 5. Drop, and the order flips.
//!
//! The sweep order is the authors' `order` flag: horizontal at first, kept while a move
//! towards the target works, flipped when none does (so the next call tries the other axis
//! first: that is what "alternately" means in their code), vertical after a block reached
//! its target. It lives in the walker from call to call; [`CentroidWalker::begin_episode`]
//! sets it horizontal again (the authors built a fresh trainer, `order = True`, per game).
//!
//! Rule 4 is narrower than docs/world.md section 10's summary ("else a random free move that does not
//! enter another block's target cell"): in the code the random move is taken only by a
//! block standing on another block's target; any other block with no good move drops.
//!
//! # Nothing held
//!
//! A uniformly random block is picked (`random.randint(0, N - 1)`, both ends included).
//!
//! Under the `paper` action protocol every action it returns is legal: Pick with nothing
//! held, a move or Drop while holding.

use rand::RngExt;
use sim::coded_state::{CELL_PX, pixel_centre};
use sim::seeding::SimRng;
use sim::{Action, BlockId, Cell, Goal, Grid, State};

use crate::error::Result;
use crate::placement::check_problem;

/// Which axis the walker tries first (the authors' `order` flag).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SweepOrder {
    /// `order = True`: Left, Right, Down, Up.
    #[default]
    Horizontal,
    /// `order = False`: Down, Up, Left, Right.
    Vertical,
}

impl SweepOrder {
    /// The moves in the order they are tried.
    pub const fn moves(self) -> [Action; 4] {
        match self {
            SweepOrder::Horizontal => [Action::Left, Action::Right, Action::Down, Action::Up],
            SweepOrder::Vertical => [Action::Down, Action::Up, Action::Left, Action::Right],
        }
    }

    /// The other order.
    pub const fn flipped(self) -> SweepOrder {
        match self {
            SweepOrder::Horizontal => SweepOrder::Vertical,
            SweepOrder::Vertical => SweepOrder::Horizontal,
        }
    }
}

/// The paper's oracle (module docs): stateful only in its sweep order.
///
/// ```
/// use oracle::CentroidWalker;
/// use sim::{Action, BlockId, Cell, Goal, Grid, State};
///
/// let mut walker = CentroidWalker::new(Grid::default());
/// let goal: Goal = "0,1".parse()?;
/// // Block 1 held at (5, 3), block 0 at (1, 3): the stack stands around (3, 3), so block 1's
/// // target is (3, 3) and it walks left.
/// let state = State::new(&[Cell::new(1, 3), Cell::new(5, 3)], Some(BlockId(1)))?;
/// assert_eq!(walker.targets(&state, &goal)?, [Cell::new(3, 2), Cell::new(3, 3)]);
/// let mut rng = sim::seeding::rng(0);
/// assert_eq!(walker.next_action(&state, &goal, &mut rng)?, Action::Left);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CentroidWalker {
    grid: Grid,
    order: SweepOrder,
}

impl CentroidWalker {
    /// A walker on `grid`, its sweep order horizontal.
    pub fn new(grid: Grid) -> Self {
        Self {
            grid,
            order: SweepOrder::Horizontal,
        }
    }

    /// The grid it walks on.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The sweep order the next call starts with.
    pub fn order(&self) -> SweepOrder {
        self.order
    }

    /// Starts an episode: the sweep order is horizontal again.
    pub fn begin_episode(&mut self) {
        self.order = SweepOrder::Horizontal;
    }

    /// Every block's target cell, by block id: the stack laid around the blocks' centroid
    /// and shifted onto the screen (module docs). An error if `state` and `goal` do not fit
    /// the grid or each other.
    pub fn targets(&self, state: &State, goal: &Goal) -> Result<Vec<Cell>> {
        check_problem(self.grid, state, goal)?;
        Ok(self.stack_cells(state, goal))
    }

    /// [`CentroidWalker::targets`] for a checked problem.
    fn stack_cells(&self, state: &State, goal: &Goal) -> Vec<Cell> {
        let grid = self.grid;
        let n = state.block_count() as i32;
        let half = CELL_PX / 2;
        let snap = |sum: i32| {
            let m = sum / n;
            half + m - m % CELL_PX
        };
        let (sx, sy) = state.cells().iter().fold((0, 0), |(sx, sy), &c| {
            let (x, y) = pixel_centre(grid, c);
            (sx + x, sy + y)
        });
        let (mx, my) = (snap(sx), snap(sy));
        // Pixel centre of each place, bottom (place 0) first.
        let mut ys: Vec<i32> = (0..n).map(|place| my + CELL_PX * (n / 2 - place)).collect();
        let height = CELL_PX * grid.height() as i32;
        let on_screen = |y: i32| half <= y && y <= height - half;
        for _ in 0..n {
            let shift = if !on_screen(ys[ys.len() - 1]) {
                CELL_PX
            } else if !on_screen(ys[0]) {
                -CELL_PX
            } else {
                0
            };
            ys.iter_mut().for_each(|y| *y += shift);
        }
        let column = ((mx - half) / CELL_PX) as u16;
        let mut cells = vec![Cell::new(0, 0); state.block_count()];
        for (place, &y) in ys.iter().enumerate() {
            let row_from_top = (y - half) / CELL_PX;
            let row = (grid.height() as i32 - 1 - row_from_top) as u16;
            cells[goal.block_at_place(place).index()] = Cell::new(column, row);
        }
        cells
    }

    /// The walker's action in `state` (module docs); draws from `rng` to pick a block with
    /// nothing held, and for the random move of rule 4. An error if `state` and `goal` do not
    /// fit the grid or each other.
    pub fn next_action(&mut self, state: &State, goal: &Goal, rng: &mut SimRng) -> Result<Action> {
        check_problem(self.grid, state, goal)?;
        let Some(held) = state.held_block() else {
            let block = rng.random_range(0..state.block_count());
            return Ok(Action::Pick(BlockId::of(block)));
        };
        if goal.holds(state) {
            return Ok(Action::Drop);
        }
        let targets = self.stack_cells(state, goal);
        let here = state.cell(held);
        let target = targets[held.index()];
        if here == target {
            self.order = SweepOrder::Vertical;
            return Ok(Action::Drop);
        }
        let entered = |action: Action| {
            let dir = action.direction().expect("a move");
            self.grid.neighbour(here, dir)
        };
        // Good: on the screen, and no block stands there.
        let good = |action: Action| entered(action).filter(|&c| state.block_at(c).is_none());
        let towards = |action: Action| match action {
            Action::Left => target.x < here.x,
            Action::Right => target.x > here.x,
            Action::Down => target.y < here.y,
            _ => target.y > here.y,
        };
        if let Some(action) = self
            .order
            .moves()
            .into_iter()
            .find(|&a| towards(a) && good(a).is_some())
        {
            return Ok(action);
        }
        let another_target = |c: Cell| targets.iter().enumerate().any(|(b, &t)| b != held.index() && t == c);
        let order = self.order;
        self.order = order.flipped();
        if another_target(here) {
            let allowed: Vec<Action> = SweepOrder::Horizontal
                .moves()
                .into_iter()
                .filter(|&a| good(a).is_some_and(|c| !another_target(c)))
                .collect();
            if !allowed.is_empty() {
                return Ok(allowed[rng.random_range(0..allowed.len())]);
            }
        }
        Ok(Action::Drop)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
        let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
        State::new(&cells, held.map(BlockId)).unwrap()
    }

    fn column(x: u16, rows: &[u16]) -> Vec<Cell> {
        rows.iter().map(|&y| Cell::new(x, y)).collect()
    }

    #[test]
    fn the_authors_own_test_of_the_stack_cells() {
        // The authors' `test_get_goal_position` (State.py): five blocks in a row at the top of
        // a 350 x 350 screen, then at its bottom, goal 3,2,0,1,4; their expected pixel centres
        // (175, 125), (175, 75), (175, 175), (175, 225), (175, 25) by block id are, in our
        // cells, column 3 and rows 4, 5, 3, 2, 6.
        let w = CentroidWalker::new(Grid::default());
        let goal: Goal = "3,2,0,1,4".parse().unwrap();
        let top = state(&[(1, 6), (2, 6), (3, 6), (4, 6), (5, 6)], None);
        assert_eq!(w.targets(&top, &goal).unwrap(), column(3, &[4, 5, 3, 2, 6]));
        // (175, 225), (175, 175), (175, 275), (175, 325), (175, 125): rows 2, 3, 1, 0, 4.
        let bottom = state(&[(1, 0), (2, 0), (3, 0), (4, 0), (5, 0)], None);
        assert_eq!(w.targets(&bottom, &goal).unwrap(), column(3, &[2, 3, 1, 0, 4]));
    }

    #[test]
    fn the_centre_is_the_mean_cell_rounded_half_up_on_the_screen() {
        let w = CentroidWalker::new(Grid::default());
        let goal: Goal = "0,1".parse().unwrap();
        // Mean column 2.5 rounds to 3; mean row 3 (screen row 3): the bottom block one row
        // below the centre, the top one on it.
        let s = state(&[(2, 3), (3, 3)], None);
        assert_eq!(w.targets(&s, &goal).unwrap(), [Cell::new(3, 2), Cell::new(3, 3)]);
        // Rows 3 and 4 (screen rows 3 and 2): mean screen row 2.5 rounds half-up to screen row
        // 3, our row 3: on the screen, a tie goes downward.
        let s = state(&[(2, 3), (2, 4)], None);
        assert_eq!(w.targets(&s, &goal).unwrap(), [Cell::new(2, 2), Cell::new(2, 3)]);
        // Three blocks: bottom below the centre, middle on it, top above.
        let goal: Goal = "2,0,1".parse().unwrap();
        let s = state(&[(0, 1), (6, 1), (3, 1)], None);
        assert_eq!(
            w.targets(&s, &goal).unwrap(),
            [Cell::new(3, 1), Cell::new(3, 2), Cell::new(3, 0)]
        );
        // On the bottom row the stack is shifted up onto the screen.
        let s = state(&[(0, 0), (6, 0), (3, 0)], None);
        assert_eq!(
            w.targets(&s, &goal).unwrap(),
            [Cell::new(3, 1), Cell::new(3, 2), Cell::new(3, 0)]
        );
    }

    #[test]
    fn with_nothing_held_a_uniformly_random_block_is_picked() {
        let mut w = CentroidWalker::new(Grid::default());
        let goal: Goal = "0,1,2".parse().unwrap();
        let s = state(&[(0, 0), (3, 3), (6, 6)], None);
        let mut rng = sim::seeding::rng(5);
        let mut counts = [0; 3];
        for _ in 0..3000 {
            match w.next_action(&s, &goal, &mut rng).unwrap() {
                Action::Pick(b) => counts[b.index()] += 1,
                other => panic!("{other} with nothing held"),
            }
        }
        assert!(counts.iter().all(|&c| (900..1100).contains(&c)), "{counts:?}");
    }

    #[test]
    fn the_held_block_walks_towards_its_target_and_drops_on_it() {
        let mut w = CentroidWalker::new(Grid::default());
        let mut rng = sim::seeding::rng(0);
        let goal: Goal = "0,1".parse().unwrap();
        // Block 1 held at (5, 5), block 0 at (1, 1): centre (3, 3), targets (3, 2), (3, 3).
        // Left and down lead there; the horizontal order tries left first.
        let s = state(&[(1, 1), (5, 5)], Some(1));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(3, &[2, 3]));
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Left);
        assert_eq!(w.order(), SweepOrder::Horizontal);
        // In its target's column: down.
        let s = state(&[(3, 1), (3, 5)], Some(1));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(3, &[2, 3]));
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Down);
        // Side by side on row 3: the mean column 2.5 rounds to 3, where block 1 stands, on
        // its target: Drop, and the order turns vertical.
        let s = state(&[(2, 3), (3, 3)], Some(1));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(3, &[2, 3]));
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Drop);
        assert_eq!(w.order(), SweepOrder::Vertical);
        // Vertical order: down before left.
        let s = state(&[(5, 1), (1, 5)], Some(1));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(3, &[2, 3]));
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Down);
        w.begin_episode();
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Right);
    }

    #[test]
    fn with_the_goal_holding_it_drops_and_keeps_its_order() {
        let mut w = CentroidWalker::new(Grid::default());
        let goal: Goal = "0,1".parse().unwrap();
        let s = state(&[(0, 0), (0, 1)], Some(0));
        let mut rng = sim::seeding::rng(0);
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Drop);
        assert_eq!(w.order(), SweepOrder::Horizontal);
    }

    #[test]
    fn a_good_move_on_the_other_axis_comes_before_giving_up() {
        let mut w = CentroidWalker::new(Grid::default());
        let mut rng = sim::seeding::rng(0);
        let goal: Goal = "0,1,2".parse().unwrap();
        // Centre (4, 3): targets 0 (4, 2), 1 (4, 3), 2 (4, 4). Block 2 held at (5, 3) goes
        // left and up; left is taken by block 1, so up.
        let s = state(&[(3, 3), (4, 3), (5, 3)], Some(2));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(4, &[2, 3, 4]));
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Up);
        assert_eq!(w.order(), SweepOrder::Horizontal);
    }

    #[test]
    fn a_blocked_block_drops_and_flips_its_order() {
        let mut w = CentroidWalker::new(Grid::default());
        let mut rng = sim::seeding::rng(0);
        let goal: Goal = "0,1".parse().unwrap();
        // Both on the bottom row: centre (4, 0), the stack shifted up onto the screen:
        // targets 0 (4, 0), 1 (4, 1). Block 0 held at (3, 0) must go right, where block 1
        // stands; it stands on no other block's target: Drop, and the order flips.
        let s = state(&[(3, 0), (4, 0)], Some(0));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(4, &[0, 1]));
        assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Drop);
        assert_eq!(w.order(), SweepOrder::Vertical);
    }

    #[test]
    fn a_block_on_another_blocks_target_moves_off_it_at_random() {
        let goal: Goal = "0,1,2".parse().unwrap();
        // Centre (5, 3): targets 0 (5, 2), 1 (5, 3), 2 (5, 4). Block 2 held at (5, 3), on
        // block 1's target; up (its way) is taken by block 0. Allowed moves: left is taken,
        // down enters block 0's target, right is free: always right.
        let s = state(&[(5, 4), (4, 3), (5, 3)], Some(2));
        let mut w = CentroidWalker::new(Grid::default());
        assert_eq!(w.targets(&s, &goal).unwrap(), column(5, &[2, 3, 4]));
        for seed in 0..20 {
            w.begin_episode();
            let mut rng = sim::seeding::rng(seed);
            assert_eq!(w.next_action(&s, &goal, &mut rng).unwrap(), Action::Right);
            assert_eq!(w.order(), SweepOrder::Vertical);
        }
        // Two allowed moves (left and right free, not targets): both are drawn.
        // Centre (3, 3): targets 0 (3, 2), 1 (3, 3), 2 (3, 4). Block 0 held at (3, 3), on
        // block 1's target; its way down is taken by block 1, up by block 2.
        let s = state(&[(3, 3), (3, 2), (3, 4)], Some(0));
        assert_eq!(w.targets(&s, &goal).unwrap(), column(3, &[2, 3, 4]));
        let mut drawn = std::collections::BTreeSet::new();
        let mut rng = sim::seeding::rng(1);
        for _ in 0..50 {
            w.begin_episode();
            drawn.insert(w.next_action(&s, &goal, &mut rng).unwrap());
        }
        assert_eq!(drawn.into_iter().collect::<Vec<_>>(), [Action::Left, Action::Right]);
    }

    #[test]
    fn problems_that_do_not_fit_are_errors() {
        let mut w = CentroidWalker::new(Grid::default());
        let s = state(&[(0, 0), (1, 1)], None);
        let goal: Goal = "0,1,2".parse().unwrap();
        assert!(w.next_action(&s, &goal, &mut sim::seeding::rng(0)).is_err());
    }
}
