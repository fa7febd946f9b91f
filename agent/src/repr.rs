//! State representations for the tabular Q-learner (docs/world.md section 7).
//!
//! A representation turns a state and a goal into a table key in `0..key_count()`, and
//! maps the world's actions to table columns and back. The paper's three ([`Raw`],
//! [`Pairwise`], [`Chasing`]) lose or keep different parts of the state; ours ([`Role`])
//! keeps all of it but names blocks by their place in the goal, so every goal is the same
//! problem. [`ChasingCode`] is representation 3 as the authors coded it: their state tuple
//! ([`sim::CodedState`]), one row per tuple.
//!
//! Keys are mixed-radix numbers of the representation's fields, so a key count is a product
//! of field sizes; a representation whose key count would not fit in a `u64` cannot be
//! built (an error, e.g. `raw` with 16 blocks on a 16 x 16 grid).

use serde::{Deserialize, Serialize};
use sim::coded_state::{CodedState, Distance, Horizontal, Vertical};
use sim::{Action, ActionMask, BlockId, Goal, Grid, MAX_BLOCKS, MIN_BLOCKS, State};

use crate::error::{AgentError, Result};

/// The representations by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReprKind {
    /// See [`Raw`].
    Raw,
    /// See [`Pairwise`].
    Pairwise,
    /// See [`Chasing`].
    Chasing,
    /// See [`ChasingCode`].
    ChasingCode,
    /// See [`Role`].
    Role,
    /// See [`RoleTowers`].
    RoleTowers,
}

sim::names!(ReprKind { Raw = "raw", Pairwise = "pairwise", Chasing = "chasing", ChasingCode = "chasing-code", Role = "role", RoleTowers = "role-towers" } unknown(text) -> AgentError {
    AgentError::Config(format!("unknown representation {text:?}: choose raw, pairwise, chasing, chasing-code, role or role-towers"))
});

impl ReprKind {
    /// Whether the representation takes goals of towers (docs/world.md section 12); the
    /// others take one tower of every block only.
    pub fn takes_towers(self) -> bool {
        self == ReprKind::RoleTowers
    }
}

/// What every representation offers the Q-table.
pub trait Representation {
    /// How many keys there are: every key is below this.
    fn key_count(&self) -> u64;

    /// The table key of `state` under `goal`. The state must have the representation's
    /// block count and fit its grid (the agent checks this before asking).
    fn key(&self, state: &State, goal: &Goal) -> u64;

    /// The table column of `action`: its index unless the representation renames blocks.
    fn column(&self, _goal: &Goal, action: Action) -> usize {
        action.index()
    }

    /// The action of table column `column` (`column < 5 + N`).
    fn action(&self, _goal: &Goal, column: usize) -> Action {
        action_of_index(column)
    }
}

/// The action with index `index`, for an index known to be in range.
#[inline]
fn action_of_index(index: usize) -> Action {
    match index {
        0 => Action::Up,
        1 => Action::Down,
        2 => Action::Left,
        3 => Action::Right,
        4 => Action::Drop,
        i => Action::Pick(BlockId::of(i - 5)),
    }
}

/// Builds a key from fields, most significant first, and checks the key count fits a u64.
#[derive(Clone, Copy)]
struct KeySpace(Option<u64>);

impl KeySpace {
    fn new() -> Self {
        KeySpace(Some(1))
    }

    /// Adds a field with `size` values.
    fn field(self, size: u64) -> Self {
        KeySpace(self.0.and_then(|n| n.checked_mul(size)))
    }

    /// The key count; an error for an unsupported block count or a count beyond u64.
    fn count(self, kind: ReprKind, grid: Grid, blocks: usize) -> Result<u64> {
        if !(MIN_BLOCKS..=MAX_BLOCKS).contains(&blocks) {
            return Err(sim::SimError::BadBlockCount {
                count: blocks,
                what: "a tabular learner",
                min: MIN_BLOCKS,
                max: MAX_BLOCKS,
            }
            .into());
        }
        self.0.ok_or_else(|| {
            AgentError::Config(format!(
                "the {kind} representation of {blocks} blocks on a {grid} grid has more states than a table can number"
            ))
        })
    }
}

/// Appends digit `digit` of a field with `size` values to `key`.
#[inline]
fn push(key: u64, size: u64, digit: u64) -> u64 {
    key * size + digit
}

/// 0 when nothing is held, `1 + slot` otherwise.
#[inline]
fn held_slot(held: Option<usize>) -> u64 {
    held.map_or(0, |s| s as u64 + 1)
}

/// The sign of `to - from` as a field digit: 0 equal, 1 lower (down or left), 2 higher.
#[inline]
fn sign_digit(from: i32, to: i32) -> u64 {
    match to.cmp(&from) {
        std::cmp::Ordering::Equal => 0,
        std::cmp::Ordering::Less => 1,
        std::cmp::Ordering::Greater => 2,
    }
}

/// Representation 1 of the paper: every block's cell (by block id) and the held block.
///
/// It knows nothing of the goal, so one table serves one goal: trained on several, it
/// learns their average. Key count `C^N (N + 1)` for `C` cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Raw {
    grid: Grid,
    blocks: usize,
    key_count: u64,
}

impl Raw {
    /// The representation of `blocks` blocks on `grid`.
    pub fn new(grid: Grid, blocks: usize) -> Result<Raw> {
        let cells = grid.cell_count() as u64;
        let space = (0..blocks).fold(KeySpace::new(), |s, _| s.field(cells));
        let key_count = space.field(blocks as u64 + 1).count(ReprKind::Raw, grid, blocks)?;
        Ok(Raw {
            grid,
            blocks,
            key_count,
        })
    }
}

impl Representation for Raw {
    fn key_count(&self) -> u64 {
        self.key_count
    }

    #[inline]
    fn key(&self, state: &State, _goal: &Goal) -> u64 {
        let cells = self.grid.cell_count() as u64;
        let key = state
            .cells()
            .iter()
            .fold(0, |k, &c| push(k, cells, self.grid.index(c) as u64));
        push(
            key,
            self.blocks as u64 + 1,
            held_slot(state.held_block().map(BlockId::index)),
        )
    }
}

/// Representation 2 of the paper: the total Manhattan distance over all pairs of blocks,
/// the direction (up/down/level, left/right/level) from the held block to its closest
/// block (lowest id on a tie; level-level when nothing is held), the held block, and the
/// goal (its rank among the `N!` orders).
///
/// Key count `(C(N,2)(W + H - 2) + 1) * 9 * (N + 1) * N!`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pairwise {
    blocks: usize,
    goals: u64,
    key_count: u64,
}

impl Pairwise {
    /// The representation of `blocks` blocks on `grid`.
    pub fn new(grid: Grid, blocks: usize) -> Result<Pairwise> {
        let n = blocks as u64;
        let total_values = n * (n.saturating_sub(1)) / 2 * (grid.width() + grid.height() - 2) as u64 + 1;
        let goals = (1..=n).try_fold(1u64, |f, k| f.checked_mul(k));
        let space = KeySpace::new().field(total_values).field(9).field(n + 1);
        let space = match goals {
            Some(g) => space.field(g),
            None => KeySpace(None),
        };
        let key_count = space.count(ReprKind::Pairwise, grid, blocks)?;
        Ok(Pairwise {
            blocks,
            goals: goals.unwrap_or(u64::MAX),
            key_count,
        })
    }
}

/// The rank of `goal` among the permutations of its blocks in lexicographic order (the
/// Lehmer code), in `0..N!`.
pub fn goal_rank(goal: &Goal) -> u64 {
    let order = goal.order();
    let n = order.len();
    let mut rank = 0u64;
    for i in 0..n {
        let smaller_after = order[i + 1..].iter().filter(|b| b.0 < order[i].0).count() as u64;
        rank = rank * (n - i) as u64 + smaller_after;
    }
    rank
}

impl Representation for Pairwise {
    fn key_count(&self) -> u64 {
        self.key_count
    }

    fn key(&self, state: &State, goal: &Goal) -> u64 {
        let cells = state.cells();
        let mut total = 0u64;
        for (i, a) in cells.iter().enumerate() {
            for b in &cells[i + 1..] {
                total += u64::from(a.manhattan(*b));
            }
        }
        let (dy, dx) = match state.held_block() {
            None => (0, 0),
            Some(h) => {
                let from = state.cell(h);
                let closest = state
                    .blocks()
                    .filter(|&b| b != h)
                    .min_by_key(|&b| (from.manhattan(state.cell(b)), b.0))
                    .map(|b| state.cell(b))
                    .expect("at least two blocks");
                (
                    sign_digit(from.y.into(), closest.y.into()),
                    sign_digit(from.x.into(), closest.x.into()),
                )
            }
        };
        let mut key = total;
        key = push(key, 9, dy * 3 + dx);
        key = push(
            key,
            self.blocks as u64 + 1,
            held_slot(state.held_block().map(BlockId::index)),
        );
        push(key, self.goals, goal_rank(goal))
    }
}

/// Representation 3 of the paper, the one its tables use (docs/world.md sections 6 and 7): the held
/// block's Manhattan distance to the cell it chases, the total distance along the goal
/// chain, the direction of the chased cell (up/down/level, left/right/level, and whether it
/// is occupied by another block or lies outside the grid), the held block, and the block it
/// chases. With nothing held, every held-block field is zero.
///
/// It names no goal, only the (held, chased) pair, so what is learnt for a pair serves
/// every goal that contains it: the paper's partial extension to unseen goals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Chasing {
    grid: Grid,
    blocks: usize,
    distance_values: u64,
    chain_values: u64,
    key_count: u64,
}

impl Chasing {
    /// The representation of `blocks` blocks on `grid`.
    pub fn new(grid: Grid, blocks: usize) -> Result<Chasing> {
        let (w, h, n) = (grid.width() as u64, grid.height() as u64, blocks as u64);
        // The chased cell may lie one row outside the grid: distances reach W - 1 + H.
        let distance_values = w + h;
        let chain_values = n.saturating_sub(1) * (w + h - 2) + 1;
        let key_count = KeySpace::new()
            .field(n + 1)
            .field(n)
            .field(distance_values)
            .field(chain_values)
            .field(18)
            .count(ReprKind::Chasing, grid, blocks)?;
        Ok(Chasing {
            grid,
            blocks,
            distance_values,
            chain_values,
            key_count,
        })
    }
}

impl Representation for Chasing {
    fn key_count(&self) -> u64 {
        self.key_count
    }

    fn key(&self, state: &State, goal: &Goal) -> u64 {
        let n = self.blocks as u64;
        let chain = u64::from(goal.chain_distance(state));
        let (slot, target, distance, direction) = match state.held_block() {
            None => (0, 0, 0, 0),
            Some(h) => {
                let p = goal.place_of(h);
                let (chased, dy) = if p + 1 < self.blocks {
                    (goal.block_at_place(p + 1), -1)
                } else {
                    (goal.block_at_place(p - 1), 1)
                };
                let from = state.cell(h);
                let t = state.cell(chased);
                let (tx, ty) = (i32::from(t.x), i32::from(t.y) + dy);
                let occupied = match self.grid.cell(i64::from(tx), i64::from(ty)) {
                    Err(_) => true,
                    Ok(c) => state.block_at(c).is_some_and(|b| b != h),
                };
                let direction =
                    (sign_digit(from.y.into(), ty) * 3 + sign_digit(from.x.into(), tx)) * 2 + u64::from(occupied);
                (
                    held_slot(Some(h.index())),
                    u64::from(chased.0),
                    u64::from(goal.chased_distance(h, state)),
                    direction,
                )
            }
        };
        let mut key = slot;
        key = push(key, n, target);
        key = push(key, self.distance_values, distance);
        key = push(key, self.chain_values, chain);
        push(key, 18, direction)
    }
}

/// Representation 3 as the authors coded it (docs/world.md section 10, "State representation 3 as
/// coded"): the key is the authors' state tuple [`CodedState`], `(d, D, (h, v, '-'), s,
/// (lower, upper))`, and nothing else, so two states with equal tuples share a row and no
/// goal is in the key. With nothing held the tuple is `((d of each goal pair), 0, ('-',
/// '-', '-'), None, (None, None))`.
///
/// Every `d` is `625 (4 a^2 + b^2)` for a column difference `a` and an odd `b` (see
/// [`sim::coded_state::pair_distance`]), so `d / 625` is an integer below
/// `R = 4 (W - 1)^2 + (2H - 1)^2 + 1`, and `D / 625` below `(N - 1)(R - 1) + 1`. Keys `0..R^(N-1)` number
/// the nothing-held tuples (each pair's `d / 625` a digit); the rest number the held ones
/// by (held block, partner, whether the held block is the pair's lower one, `d / 625`,
/// `D / 625`, heading). For 3 blocks on 7 x 7 that is about 21 million keys, most never
/// met: the table keeps only the rows it meets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChasingCode {
    grid: Grid,
    blocks: usize,
    /// `R`: the values of `d / 625`.
    distance_values: u64,
    /// The values of `D / 625`.
    total_values: u64,
    /// `R^(N-1)`: the nothing-held keys, which come first.
    nothing_held: u64,
    key_count: u64,
}

/// `d / 625` and `D / 625`: every `d` is a multiple of this.
const PAIR_DISTANCE_UNIT: u32 = 625;

impl ChasingCode {
    /// The representation of `blocks` blocks on `grid`.
    pub fn new(grid: Grid, blocks: usize) -> Result<ChasingCode> {
        let (w, h, n) = (grid.width() as u64, grid.height() as u64, blocks as u64);
        let distance_values = 4 * (w - 1) * (w - 1) + (2 * h - 1) * (2 * h - 1) + 1;
        let total_values = n.saturating_sub(1) * (distance_values - 1) + 1;
        let nothing_held = (1..n).fold(KeySpace::new(), |s, _| s.field(distance_values));
        let held = KeySpace::new()
            .field(n)
            .field(n.saturating_sub(1))
            .field(2)
            .field(distance_values)
            .field(total_values)
            .field(9);
        let count = match (nothing_held.0, held.0) {
            (Some(a), Some(b)) => KeySpace(a.checked_add(b)),
            _ => KeySpace(None),
        };
        let key_count = count.count(ReprKind::ChasingCode, grid, blocks)?;
        Ok(ChasingCode {
            grid,
            blocks,
            distance_values,
            total_values,
            nothing_held: nothing_held.0.expect("below the key count"),
            key_count,
        })
    }

    /// The key of a tuple of this representation's world.
    pub fn key_of(&self, tuple: &CodedState) -> u64 {
        let unit = |d: u32| u64::from(d / PAIR_DISTANCE_UNIT);
        match (&tuple.distance, tuple.held, tuple.pair) {
            (Distance::Held(d), Some(s), Some((lower, upper))) => {
                let partner = if s == lower { upper } else { lower };
                // The partner's index among the other blocks.
                let partner_slot = u64::from(partner.0) - u64::from(partner.0 > s.0);
                let heading = match tuple.heading.horizontal {
                    Horizontal::Left => 0,
                    Horizontal::Right => 1,
                    Horizontal::Level => 2,
                } * 3
                    + match tuple.heading.vertical {
                        Vertical::Up => 0,
                        Vertical::Down => 1,
                        Vertical::Level => 2,
                    };
                let mut key = u64::from(s.0);
                key = push(key, self.blocks as u64 - 1, partner_slot);
                key = push(key, 2, u64::from(s == lower));
                key = push(key, self.distance_values, unit(*d));
                key = push(key, self.total_values, unit(tuple.total));
                self.nothing_held + push(key, 9, heading)
            }
            (Distance::EachPair(list), ..) => list
                .as_slice()
                .iter()
                .fold(0, |k, &d| push(k, self.distance_values, unit(d))),
            _ => unreachable!("a held tuple has its distance and pair"),
        }
    }
}

impl Representation for ChasingCode {
    fn key_count(&self) -> u64 {
        self.key_count
    }

    fn key(&self, state: &State, goal: &Goal) -> u64 {
        self.key_of(&CodedState::of(self.grid, goal, state))
    }
}

/// Ours: every block's cell and the held block, with blocks named by their place in the
/// goal (bottom, second, ...) instead of their id; a Pick column picks the block at a
/// place. Every goal becomes the same problem (build `0, 1, ..., N-1` out of places), so
/// one table serves every goal, unseen ones included, and nothing of the state is lost.
///
/// Key count `C^N (N + 1)` for `C` cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Role {
    grid: Grid,
    blocks: usize,
    key_count: u64,
}

impl Role {
    /// The representation of `blocks` blocks on `grid`.
    pub fn new(grid: Grid, blocks: usize) -> Result<Role> {
        let cells = grid.cell_count() as u64;
        let space = (0..blocks).fold(KeySpace::new(), |s, _| s.field(cells));
        let key_count = space.field(blocks as u64 + 1).count(ReprKind::Role, grid, blocks)?;
        Ok(Role {
            grid,
            blocks,
            key_count,
        })
    }
}

impl Representation for Role {
    fn key_count(&self) -> u64 {
        self.key_count
    }

    #[inline]
    fn key(&self, state: &State, goal: &Goal) -> u64 {
        let cells = self.grid.cell_count() as u64;
        let key = goal
            .order()
            .iter()
            .fold(0, |k, &b| push(k, cells, self.grid.index(state.cell(b)) as u64));
        push(
            key,
            self.blocks as u64 + 1,
            held_slot(state.held_block().map(|b| goal.place_of(b))),
        )
    }

    #[inline]
    fn column(&self, goal: &Goal, action: Action) -> usize {
        match action {
            Action::Pick(b) => 5 + goal.place_of(b),
            a => a.index(),
        }
    }

    #[inline]
    fn action(&self, goal: &Goal, column: usize) -> Action {
        if column >= 5 {
            Action::Pick(goal.block_at_place(column - 5))
        } else {
            action_of_index(column)
        }
    }
}

/// [`Role`] for goals of towers (docs/world.md section 12): every block's cell and the
/// held block, blocks named by their place, where the places run through the goal's towers
/// longest first (then the free blocks, by id); and one more field, the goal's shape (how
/// many blocks it names and where its towers end). Goals of the same shape are the same
/// problem under the renaming ("0,1/2" and "2,0/1" alike), so one table serves every goal
/// of a shape, and a table trained on every shape serves every goal.
///
/// Key count `C^N (N + 1) N 2^(N-1)` for `C` cells: 5.6 million keys for 3 blocks on 7 x 7,
/// of which a side-view game meets few (blocks stand in towers), so the table keeps the
/// rows it meets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RoleTowers {
    role: Role,
    key_count: u64,
}

/// A goal of towers as [`RoleTowers`] reads it: which block has which place, and the shape.
struct Places {
    block_at: [BlockId; MAX_BLOCKS],
    place_of: [u8; MAX_BLOCKS],
    shape: u64,
}

impl Places {
    #[inline]
    fn of(goal: &Goal) -> Places {
        let blocks = goal.block_count();
        let mut towers: [&[BlockId]; MAX_BLOCKS] = [&[]; MAX_BLOCKS];
        let mut count = 0;
        for t in goal.towers() {
            towers[count] = t;
            count += 1;
        }
        // Longest first; a stable sort keeps the goal's order among towers of one length.
        towers[..count].sort_by_key(|t| std::cmp::Reverse(t.len()));
        let mut places = Places {
            block_at: [BlockId::default(); MAX_BLOCKS],
            place_of: [0; MAX_BLOCKS],
            shape: 0,
        };
        let (mut next, mut tops) = (0usize, 0u64);
        for t in &towers[..count] {
            for &b in *t {
                places.block_at[next] = b;
                places.place_of[b.index()] = next as u8;
                next += 1;
            }
            tops |= 1 << (next - 1);
        }
        let named = next;
        for b in (0..blocks).map(BlockId::of).filter(|&b| !goal.names(b)) {
            places.block_at[next] = b;
            places.place_of[b.index()] = next as u8;
            next += 1;
        }
        // The last named place always ends a tower: the other ends and the named count
        // say the shape.
        let ends = tops & !(1 << (named - 1));
        places.shape = (((named - 1) as u64) << (blocks - 1)) | ends;
        places
    }
}

impl RoleTowers {
    /// The representation of `blocks` blocks on `grid`.
    pub fn new(grid: Grid, blocks: usize) -> Result<RoleTowers> {
        let cells = grid.cell_count() as u64;
        let role = (0..blocks)
            .fold(KeySpace::new(), |s, _| s.field(cells))
            .field(blocks as u64 + 1);
        let shapes = blocks as u64 * (1u64 << blocks.saturating_sub(1).min(63));
        let key_count = role.field(shapes).count(ReprKind::RoleTowers, grid, blocks)?;
        let role = Role {
            grid,
            blocks,
            // A factor of a count that fits fits too.
            key_count: role.0.expect("checked with the shapes"),
        };
        Ok(RoleTowers { role, key_count })
    }
}

impl Representation for RoleTowers {
    fn key_count(&self) -> u64 {
        self.key_count
    }

    #[inline]
    fn key(&self, state: &State, goal: &Goal) -> u64 {
        let places = Places::of(goal);
        let cells = self.role.grid.cell_count() as u64;
        let key = places.block_at[..self.role.blocks]
            .iter()
            .fold(0, |k, &b| push(k, cells, self.role.grid.index(state.cell(b)) as u64));
        let key = push(
            key,
            self.role.blocks as u64 + 1,
            held_slot(state.held_block().map(|b| places.place_of[b.index()] as usize)),
        );
        places.shape * self.role.key_count + key
    }

    #[inline]
    fn column(&self, goal: &Goal, action: Action) -> usize {
        match action {
            Action::Pick(b) => 5 + Places::of(goal).place_of[b.index()] as usize,
            a => a.index(),
        }
    }

    #[inline]
    fn action(&self, goal: &Goal, column: usize) -> Action {
        if column >= 5 {
            Action::Pick(Places::of(goal).block_at[column - 5])
        } else {
            action_of_index(column)
        }
    }
}

/// Any of the representations, chosen at run time, for a given grid and block count.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Repr {
    /// See [`Raw`].
    Raw(Raw),
    /// See [`Pairwise`].
    Pairwise(Pairwise),
    /// See [`Chasing`].
    Chasing(Chasing),
    /// See [`ChasingCode`].
    ChasingCode(ChasingCode),
    /// See [`Role`].
    Role(Role),
    /// See [`RoleTowers`].
    RoleTowers(RoleTowers),
}

impl Repr {
    /// Representation `kind` of `blocks` blocks on `grid`; an error if its key count does
    /// not fit a u64.
    pub fn new(kind: ReprKind, grid: Grid, blocks: usize) -> Result<Repr> {
        Ok(match kind {
            ReprKind::Raw => Repr::Raw(Raw::new(grid, blocks)?),
            ReprKind::Pairwise => Repr::Pairwise(Pairwise::new(grid, blocks)?),
            ReprKind::Chasing => Repr::Chasing(Chasing::new(grid, blocks)?),
            ReprKind::ChasingCode => Repr::ChasingCode(ChasingCode::new(grid, blocks)?),
            ReprKind::Role => Repr::Role(Role::new(grid, blocks)?),
            ReprKind::RoleTowers => Repr::RoleTowers(RoleTowers::new(grid, blocks)?),
        })
    }

    /// Which representation this is.
    pub fn kind(&self) -> ReprKind {
        match self {
            Repr::Raw(_) => ReprKind::Raw,
            Repr::Pairwise(_) => ReprKind::Pairwise,
            Repr::Chasing(_) => ReprKind::Chasing,
            Repr::ChasingCode(_) => ReprKind::ChasingCode,
            Repr::Role(_) => ReprKind::Role,
            Repr::RoleTowers(_) => ReprKind::RoleTowers,
        }
    }

    /// The table columns of the actions in `mask` under `goal`, as bits (bit `c`: column
    /// `c`): the mask itself unless the representation renames blocks.
    #[inline]
    pub fn column_mask(&self, goal: &Goal, mask: ActionMask) -> u32 {
        match self {
            // Every action legal is every column, whatever the renaming.
            Repr::Role(r) if mask.count() < mask.action_count() => {
                mask.iter().fold(0, |bits, a| bits | 1 << r.column(goal, a))
            }
            Repr::RoleTowers(r) if mask.count() < mask.action_count() => {
                mask.iter().fold(0, |bits, a| bits | 1 << r.column(goal, a))
            }
            _ => mask.as_u32().expect("a table's world has at most 16 blocks"),
        }
    }
}

impl Representation for Repr {
    fn key_count(&self) -> u64 {
        match self {
            Repr::Raw(r) => r.key_count(),
            Repr::Pairwise(r) => r.key_count(),
            Repr::Chasing(r) => r.key_count(),
            Repr::ChasingCode(r) => r.key_count(),
            Repr::Role(r) => r.key_count(),
            Repr::RoleTowers(r) => r.key_count(),
        }
    }

    #[inline]
    fn key(&self, state: &State, goal: &Goal) -> u64 {
        match self {
            Repr::Raw(r) => r.key(state, goal),
            Repr::Pairwise(r) => r.key(state, goal),
            Repr::Chasing(r) => r.key(state, goal),
            Repr::ChasingCode(r) => r.key(state, goal),
            Repr::Role(r) => r.key(state, goal),
            Repr::RoleTowers(r) => r.key(state, goal),
        }
    }

    #[inline]
    fn column(&self, goal: &Goal, action: Action) -> usize {
        match self {
            Repr::Role(r) => r.column(goal, action),
            Repr::RoleTowers(r) => r.column(goal, action),
            _ => action.index(),
        }
    }

    #[inline]
    fn action(&self, goal: &Goal, column: usize) -> Action {
        match self {
            Repr::Role(r) => r.action(goal, column),
            Repr::RoleTowers(r) => r.action(goal, column),
            _ => action_of_index(column),
        }
    }
}
