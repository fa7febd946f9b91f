//! The authors' state tuple: the paper's representation 3 as their code computes it.
//!
//! docs/world.md section 10, "State representation 3 as coded"; the authors' `BlockWorld_t.py:279-357`
//! (`get_state_as_tuple_pramodith2` and the next-state code after it). The paper's prose
//! describes the chasing representation one way (our `chasing`, docs/world.md section 7); their code
//! keys its Q-table on a different tuple, and the reward it trained with
//! ([`PaperCode`](crate::reward::PaperCode)) compares that tuple before and after every step.
//! [`CodedState`] is that tuple as a typed value:
//!
//! ```text
//! (d, D, (h, v, '-'), s, (lower, upper))                       a block s held
//! ((d of each goal pair), 0, ('-', '-', '-'), None, (None, None))   nothing held
//! ```
//!
//! - `s` is the held block. Its *pair* is `(s, the block above s in the goal)`, or
//!   `(the block below s, s)` when `s` is the goal's top.
//! - `d` is the pair's squared distance in pixels of the authors' screen (see
//!   [`pair_distance`]): from the lower block's centre to the upper block's bottom-edge
//!   midpoint. 625 when the pair stands in place, 3125 side by side (or the upper one
//!   diagonally above), 5625 with the upper block directly below the lower one or two cells
//!   above it.
//! - `D` is the sum of `d` over the goal's pairs.
//! - `h` says where the partner's centre lies: `l` left of the held block, `r` right, `-`
//!   same column; `v` likewise `u` above, `d` below, `-` same row. The third slot (a "cell
//!   below occupied" flag) is commented out in their code and always `-`.
//! - No goal in the tuple.
//!
//! # Pixel geometry
//!
//! The authors' screen is 50 px per cell, with its y axis growing **downward**; ours grows
//! upward. Cell `(x, y)` of a grid `H` rows high has its centre at pixel
//! `(25 + 50 x, 25 + 50 (H - 1 - y))` ([`pixel_centre`]); a block's bottom edge is 25 px
//! below its centre, at a larger pixel y.

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::state::{BlockId, MAX_BLOCKS, State};

/// Side of a cell on the authors' screen, in pixels.
pub const CELL_PX: i32 = 50;

/// The centre of `cell` on the authors' screen, `(x, y)` in pixels, screen y growing
/// downward: `(25 + 50 x, 25 + 50 (H - 1 - y))`.
pub fn pixel_centre(grid: Grid, cell: Cell) -> (i32, i32) {
    let half = CELL_PX / 2;
    let row_from_top = grid.height() as i32 - 1 - i32::from(cell.y);
    (half + CELL_PX * i32::from(cell.x), half + CELL_PX * row_from_top)
}

/// The authors' pair distance `d`: the squared pixel distance from the centre of `lower`
/// to the midpoint of the bottom edge of `upper` (their `euclidean_dist`). 625 when
/// `upper` stands on `lower`.
pub fn pair_distance(grid: Grid, lower: Cell, upper: Cell) -> u32 {
    let (lx, ly) = pixel_centre(grid, lower);
    let (ux, uy) = pixel_centre(grid, upper);
    let bottom_edge = uy + CELL_PX / 2;
    ((lx - ux).pow(2) + (ly - bottom_edge).pow(2)) as u32
}

/// The first slot of the direction triple: where the partner's column lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Horizontal {
    /// `l`: the partner is left of the held block.
    Left,
    /// `r`: the partner is right of the held block.
    Right,
    /// `-`: same column, or nothing held.
    Level,
}

/// The second slot of the direction triple: where the partner's row lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Vertical {
    /// `u`: the partner is above the held block.
    Up,
    /// `d`: the partner is below the held block.
    Down,
    /// `-`: same row, or nothing held.
    Level,
}

/// The direction triple `(h, v, '-')`; the third slot is always `-` in the authors' code.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Heading {
    /// `h`: `l`, `r` or `-`.
    pub horizontal: Horizontal,
    /// `v`: `u`, `d` or `-`.
    pub vertical: Vertical,
}

impl Heading {
    /// `('-', '-', '-')`: the triple of the nothing-held tuple.
    pub const NONE: Heading = Heading {
        horizontal: Horizontal::Level,
        vertical: Vertical::Level,
    };

    /// Where `partner` lies as seen from `held`.
    pub fn towards(held: Cell, partner: Cell) -> Heading {
        use std::cmp::Ordering::{Equal, Greater, Less};
        Heading {
            horizontal: match partner.x.cmp(&held.x) {
                Less => Horizontal::Left,
                Greater => Horizontal::Right,
                Equal => Horizontal::Level,
            },
            vertical: match partner.y.cmp(&held.y) {
                Greater => Vertical::Up,
                Less => Vertical::Down,
                Equal => Vertical::Level,
            },
        }
    }

    /// The three slots as the authors write them, e.g. `['l', 'u', '-']`.
    pub const fn slots(self) -> [char; 3] {
        let h = match self.horizontal {
            Horizontal::Left => 'l',
            Horizontal::Right => 'r',
            Horizontal::Level => '-',
        };
        let v = match self.vertical {
            Vertical::Up => 'u',
            Vertical::Down => 'd',
            Vertical::Level => '-',
        };
        [h, v, '-']
    }
}

/// `d` of every goal pair, bottom pair first: the first entry of the nothing-held tuple.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct PairDistances {
    /// The values; slots past `len` stay 0 so derived equality and hashing see only them.
    values: [u32; MAX_BLOCKS - 1],
    len: u8,
}

impl PairDistances {
    /// The values, bottom pair first.
    pub fn as_slice(&self) -> &[u32] {
        &self.values[..usize::from(self.len)]
    }
}

impl fmt::Debug for PairDistances {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl Serialize for PairDistances {
    /// Written as the list of values.
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        self.as_slice().serialize(s)
    }
}

impl<'de> Deserialize<'de> for PairDistances {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<PairDistances, D::Error> {
        let list = Vec::<u32>::deserialize(d)?;
        if list.len() > MAX_BLOCKS - 1 {
            return Err(serde::de::Error::custom(format!(
                "{} pair distances: a goal has at most {} pairs",
                list.len(),
                MAX_BLOCKS - 1
            )));
        }
        let mut values = [0; MAX_BLOCKS - 1];
        values[..list.len()].copy_from_slice(&list);
        Ok(PairDistances {
            values,
            len: list.len() as u8,
        })
    }
}

/// The first entry of the tuple: `d` of the held block's pair, or, with nothing held,
/// `d` of every goal pair. The paper's oracle reads the last six of these to detect
/// oscillation (docs/world.md section 10, "Oracle").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Distance {
    /// A block is held: `d` of its pair.
    Held(u32),
    /// Nothing is held: `d` of each goal pair, bottom pair first.
    EachPair(PairDistances),
}

/// The authors' state tuple `(d, D, (h, v, '-'), s, (lower, upper))` (see the module docs).
///
/// `Eq + Hash`: a Q-table can key on it, as the authors' did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct CodedState {
    /// First entry: `d`, or every pair's `d` with nothing held.
    pub distance: Distance,
    /// `D`: the sum of `d` over the goal's pairs; 0 with nothing held.
    pub total: u32,
    /// `(h, v, '-')`: where the held block's partner lies; all `-` with nothing held.
    pub heading: Heading,
    /// `s`: the held block.
    pub held: Option<BlockId>,
    /// `(lower, upper)`: the held block's pair; `None` for `(None, None)`.
    pub pair: Option<(BlockId, BlockId)>,
}

impl CodedState {
    /// The tuple of `state` under `goal` on `grid`.
    pub fn of(grid: Grid, goal: &Goal, state: &State) -> CodedState {
        let d = |(lower, upper): (BlockId, BlockId)| pair_distance(grid, state.cell(lower), state.cell(upper));
        let Some(s) = state.held_block() else {
            let mut values = [0; MAX_BLOCKS - 1];
            let mut len = 0;
            for pair in goal.pairs() {
                values[len] = d(pair);
                len += 1;
            }
            return CodedState {
                distance: Distance::EachPair(PairDistances { values, len: len as u8 }),
                total: 0,
                heading: Heading::NONE,
                held: None,
                pair: None,
            };
        };
        let place = goal.place_of(s);
        let (pair, partner) = if place + 1 < goal.block_count() {
            let upper = goal.block_at_place(place + 1);
            ((s, upper), upper)
        } else {
            let lower = goal.block_at_place(place - 1);
            ((lower, s), lower)
        };
        CodedState {
            distance: Distance::Held(d(pair)),
            total: goal.pairs().map(d).sum(),
            heading: Heading::towards(state.cell(s), state.cell(partner)),
            held: Some(s),
            pair: Some(pair),
        }
    }

    /// `d` of the held block's pair, if a block is held.
    pub fn held_distance(&self) -> Option<u32> {
        match self.distance {
            Distance::Held(d) => Some(d),
            Distance::EachPair(_) => None,
        }
    }
}

impl fmt::Display for CodedState {
    /// The tuple as the authors' Python prints it, e.g.
    /// `(3125, 3750, ('r', '-', '-'), 0, (0, 1))` or
    /// `((3125, 625), 0, ('-', '-', '-'), None, (None, None))`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let opt = |b: Option<BlockId>| b.map_or_else(|| "None".to_string(), |b| b.to_string());
        f.write_str("(")?;
        match &self.distance {
            Distance::Held(d) => write!(f, "{d}")?,
            Distance::EachPair(list) => {
                let items: Vec<String> = list.as_slice().iter().map(u32::to_string).collect();
                match items.len() {
                    1 => write!(f, "({},)", items[0])?,
                    _ => write!(f, "({})", items.join(", "))?,
                }
            }
        }
        let [h, v, third] = self.heading.slots();
        let (lower, upper) = match self.pair {
            Some((l, u)) => (Some(l), Some(u)),
            None => (None, None),
        };
        write!(
            f,
            ", {}, ('{h}', '{v}', '{third}'), {}, ({}, {}))",
            self.total,
            opt(self.held),
            opt(lower),
            opt(upper)
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state(cells: &[(u16, u16)], held: Option<u16>) -> State {
        let cells: Vec<Cell> = cells.iter().map(|&(x, y)| Cell::new(x, y)).collect();
        State::new(&cells, held.map(BlockId)).unwrap()
    }

    #[test]
    fn pixel_centres_put_row_zero_at_the_bottom_of_the_screen() {
        let grid = Grid::default();
        assert_eq!(pixel_centre(grid, Cell::new(0, 6)), (25, 25));
        assert_eq!(pixel_centre(grid, Cell::new(0, 0)), (25, 325));
        assert_eq!(pixel_centre(grid, Cell::new(6, 0)), (325, 325));
        assert_eq!(pixel_centre(Grid::new(4, 3).unwrap(), Cell::new(1, 2)), (75, 25));
    }

    #[test]
    fn pair_distances_of_the_authors_screen() {
        let grid = Grid::default();
        let at = |x, y| Cell::new(x, y);
        // Stacked: the bottom edge of the upper block is 25 px above the lower centre.
        assert_eq!(pair_distance(grid, at(3, 2), at(3, 3)), 625);
        // Side by side: 50 px across, 25 px down.
        assert_eq!(pair_distance(grid, at(3, 2), at(4, 2)), 3125);
        assert_eq!(pair_distance(grid, at(3, 2), at(2, 2)), 3125);
        // Upper diagonally above: 50 across, 25 up.
        assert_eq!(pair_distance(grid, at(3, 2), at(4, 3)), 3125);
        // Upper directly below the lower one, or two cells above it: 75 px.
        assert_eq!(pair_distance(grid, at(3, 2), at(3, 1)), 5625);
        assert_eq!(pair_distance(grid, at(3, 2), at(3, 4)), 5625);
        // Far apart: (100)^2 + (50 * 3 - 25)^2.
        assert_eq!(pair_distance(grid, at(0, 0), at(2, 3)), 10_000 + 125 * 125);
    }

    #[test]
    fn a_held_lower_block_pairs_with_the_block_above_it_in_the_goal() {
        // Goal 1,0,2; block 0 held at (4, 2); block 2 (above 0 in the goal) at (2, 2);
        // block 1 (below 0) at (4, 1), so the pair (1, 0) stands in place.
        let goal: Goal = "1,0,2".parse().unwrap();
        let s = CodedState::of(Grid::default(), &goal, &state(&[(4, 2), (4, 1), (2, 2)], Some(0)));
        assert_eq!(s.held, Some(BlockId(0)));
        assert_eq!(s.pair, Some((BlockId(0), BlockId(2))));
        assert_eq!(s.distance, Distance::Held(100 * 100 + 625));
        assert_eq!(s.total, 625 + 100 * 100 + 625);
        assert_eq!(s.heading.slots(), ['l', '-', '-']);
        assert_eq!(s.to_string(), "(10625, 11250, ('l', '-', '-'), 0, (0, 2))");
    }

    #[test]
    fn the_goal_s_top_block_pairs_with_the_block_below_it() {
        // Goal 0,1: block 1 held at (2, 5), block 0 at (3, 2): 1 is the top, its pair (0, 1),
        // its partner down and to the right.
        let goal: Goal = "0,1".parse().unwrap();
        let s = CodedState::of(Grid::default(), &goal, &state(&[(3, 2), (2, 5)], Some(1)));
        assert_eq!(s.pair, Some((BlockId(0), BlockId(1))));
        assert_eq!(s.held_distance(), Some(50 * 50 + 125 * 125));
        assert_eq!(s.total, 50 * 50 + 125 * 125);
        assert_eq!(s.heading.slots(), ['r', 'd', '-']);
        // Held while stacked: d = 625, the partner straight below.
        let stacked = CodedState::of(Grid::default(), &goal, &state(&[(3, 2), (3, 3)], Some(1)));
        assert_eq!(stacked.distance, Distance::Held(625));
        assert_eq!(stacked.heading.slots(), ['-', 'd', '-']);
        let from_below = CodedState::of(Grid::default(), &goal, &state(&[(3, 2), (3, 3)], Some(0)));
        assert_eq!(from_below.heading.slots(), ['-', 'u', '-']);
    }

    #[test]
    fn with_nothing_held_the_tuple_lists_every_pair_s_distance() {
        let goal: Goal = "2,0,1".parse().unwrap();
        // Pair (2, 0): 0 beside 2; pair (0, 1): 1 on 0.
        let s = CodedState::of(Grid::default(), &goal, &state(&[(1, 1), (1, 2), (0, 1)], None));
        let Distance::EachPair(list) = s.distance else {
            panic!("nothing held")
        };
        assert_eq!(list.as_slice(), [3125, 625]);
        assert_eq!((s.total, s.heading, s.held, s.pair), (0, Heading::NONE, None, None));
        assert_eq!(s.to_string(), "((3125, 625), 0, ('-', '-', '-'), None, (None, None))");
        let two: Goal = "0,1".parse().unwrap();
        let s = CodedState::of(Grid::default(), &two, &state(&[(1, 1), (1, 2)], None));
        assert_eq!(s.to_string(), "((625,), 0, ('-', '-', '-'), None, (None, None))");
        assert_eq!(s.held_distance(), None);
    }

    #[test]
    fn tuples_serialise_and_read_back() {
        let goal: Goal = "2,0,1".parse().unwrap();
        for held in [None, Some(0)] {
            let s = CodedState::of(Grid::default(), &goal, &state(&[(1, 1), (1, 2), (0, 1)], held));
            let json = serde_json::to_string(&s).unwrap();
            assert_eq!(serde_json::from_str::<CodedState>(&json).unwrap(), s);
        }
        assert!(serde_json::from_str::<PairDistances>(&format!("{:?}", [1u32; 16])).is_err());
    }
}
