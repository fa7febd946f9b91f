//! The rules of the world (docs/world.md section 2), in one place, over any backend.
//!
//! A backend ([`GridWorld`](crate::GridWorld), [`PhysicsWorld`](crate::PhysicsWorld)) only
//! knows how to read its blocks back and how to decide and carry out a one-cell move of a
//! block, and (in the side view) where a released block comes to rest; [`World::act`] is
//! the only code that says what an action does, in both views ([`View`]).

use crate::action::Action;
use crate::error::{Result, SimError};
use crate::grid::{Cell, Direction, Grid};
use crate::state::{BlockId, State};
use crate::view::{self, View};

/// What an action did to the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// The held block moved one cell.
    Moved,
    /// A block was held but the wall or another block stopped the move.
    Blocked,
    /// A move with no block held: nothing moves.
    NothingHeld,
    /// A block became the held one (any other held block was released where it stood).
    Picked,
    /// The held block was released.
    Dropped,
    /// A pick of the block already held, or a drop with nothing held: nothing changes.
    Unchanged,
    /// The world's rules refused the action (a restricting action protocol's, or a block
    /// move that cannot be carried out) and an [`Env`](crate::Env) under
    /// [`Refusal::Step`](crate::Refusal::Step) took it as a step that changes nothing.
    Refused,
}

/// A world backend: blocks on a grid, one of them perhaps held.
///
/// Implementors supply the primitives; the rules live in the provided [`World::act`].
pub trait World {
    /// The grid the blocks stand on.
    fn grid(&self) -> Grid;

    /// Which world: seen from above or from the side.
    fn view(&self) -> View;

    /// Number of blocks.
    fn block_count(&self) -> usize;

    /// The cell `block` stands on, read from the backend itself.
    fn cell_of(&self, block: BlockId) -> Cell;

    /// The held block, if any.
    fn held_block(&self) -> Option<BlockId>;

    /// Sets the held block; the caller has checked that it exists.
    fn set_held(&mut self, held: Option<BlockId>);

    /// Moves `block` one cell in `dir` if the backend finds the way free (inside the grid
    /// and not occupied); returns whether it moved.
    fn try_move(&mut self, block: BlockId, dir: Direction) -> bool;

    /// Side view: lets the just released `block` fall until it comes to rest, on the top of
    /// the column below it. An error only if the backend finds it resting off a cell.
    fn settle(&mut self, block: BlockId) -> Result<()>;

    /// Whether a block stands on `cell`.
    fn is_occupied(&self, cell: Cell) -> bool {
        (0..self.block_count()).any(|i| self.cell_of(BlockId::of(i)) == cell)
    }

    /// Puts every block where `state` says and holds what it holds; `state` has been
    /// checked to fit this world. Callers use [`World::place`], which checks.
    fn put(&mut self, state: &State);

    /// Puts every block where `state` says and holds what it holds; an error if `state`
    /// does not fit this world (block count, grid bounds; in the side view, a block that is
    /// not held standing on nothing).
    fn place(&mut self, state: &State) -> Result<()> {
        if state.block_count() != self.block_count() {
            return Err(SimError::BlockCountMismatch {
                expected: self.block_count(),
                what: "the state",
                found: state.block_count(),
            });
        }
        self.view().check_world(self.grid(), state.block_count())?;
        state.check_fits(self.grid())?;
        self.view().check_state(state)?;
        self.put(state);
        Ok(())
    }

    /// The whole logical state, read back from the backend.
    fn state(&self) -> State;

    /// Brings `state`, this world's state before its last action, up to date after that
    /// action had `effect`, reading back only what the action can have changed. In the top
    /// view nothing moves but the held block, and only when it [`Effect::Moved`], so a
    /// physics world reads one body instead of every block's: the read-back was the largest
    /// share of a batched physics step (docs/performance.md). In the side view a drop lets
    /// every block settle, so the whole state is read ([`World::state`]).
    #[inline]
    fn read_back(&self, state: &mut State, effect: Effect) {
        if self.view() == View::Side {
            *state = self.state();
            return;
        }
        let held = self.held_block();
        state.set_held(held);
        if let (Effect::Moved, Some(block)) = (effect, held) {
            state.set_cell(block, self.cell_of(block));
        }
    }

    /// Carries out `action` by the rules of docs/world.md section 2 and, in the side view,
    /// its section "The side view": a pick only with nothing held and only of a clear block
    /// (otherwise nothing changes), and a released block falls to the top of the column
    /// below it. An error only for a pick of a block that does not exist (and for a drop the
    /// physics does not bring to rest on a cell).
    #[inline]
    fn act(&mut self, action: Action) -> Result<Effect> {
        let held = self.held_block();
        let side = self.view() == View::Side;
        Ok(match action {
            Action::Pick(b) if b.index() >= self.block_count() => {
                return Err(SimError::NoSuchBlock {
                    block: b.index(),
                    blocks: self.block_count(),
                });
            }
            Action::Pick(b) if held == Some(b) => Effect::Unchanged,
            Action::Pick(b) if side && (held.is_some() || !self.is_clear(b)) => Effect::Unchanged,
            Action::Pick(b) => {
                self.set_held(Some(b));
                Effect::Picked
            }
            Action::Drop => match held {
                None => Effect::Unchanged,
                Some(b) => {
                    self.set_held(None);
                    if side {
                        self.settle(b)?;
                    }
                    Effect::Dropped
                }
            },
            Action::Up | Action::Down | Action::Left | Action::Right => {
                let dir = action.direction().expect("a move has a direction");
                match held {
                    None => Effect::NothingHeld,
                    Some(b) if self.try_move(b, dir) => Effect::Moved,
                    Some(_) => Effect::Blocked,
                }
            }
        })
    }

    /// Whether nothing stands on `block`.
    #[inline]
    fn is_clear(&self, block: BlockId) -> bool {
        let c = self.cell_of(block);
        c.y as usize + 1 >= self.grid().height() || !self.is_occupied(Cell::new(c.x, c.y + 1))
    }

    /// Side view: the cell a block released on `from` comes to rest on (the top of the
    /// column below it), as the occupancy predicts it.
    #[inline]
    fn landing_cell(&self, from: Cell) -> Cell {
        view::landing_cell(from, |c| self.is_occupied(c))
    }
}
