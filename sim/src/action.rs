//! The actions and their indices (docs/world.md section 2).

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError};
use crate::grid::Direction;
use crate::state::BlockId;

/// One action. Index order: `0 Up, 1 Down, 2 Left, 3 Right, 4 Drop, 5 + i Pick(i)`.
///
/// Every action costs one step, whether or not anything moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Action {
    /// Move the held block one cell up (`y + 1`).
    Up,
    /// Move the held block one cell down (`y - 1`).
    Down,
    /// Move the held block one cell left (`x - 1`).
    Left,
    /// Move the held block one cell right (`x + 1`).
    Right,
    /// Release the held block where it stands.
    Drop,
    /// Hold this block, releasing any other where it stands.
    Pick(BlockId),
}

impl Action {
    /// The number of actions with `blocks` blocks: `5 + blocks`.
    pub const fn count(blocks: usize) -> usize {
        5 + blocks
    }

    /// The action with index `index` in a world of `blocks` blocks, or an error naming the
    /// valid range.
    pub fn from_index(index: usize, blocks: usize) -> Result<Action> {
        Ok(match index {
            0 => Action::Up,
            1 => Action::Down,
            2 => Action::Left,
            3 => Action::Right,
            4 => Action::Drop,
            i if i < Action::count(blocks) => Action::Pick(BlockId::of(i - 5)),
            _ => return Err(SimError::ActionOutOfRange { index, blocks }),
        })
    }

    /// This action's index.
    pub const fn index(self) -> usize {
        match self {
            Action::Up => 0,
            Action::Down => 1,
            Action::Left => 2,
            Action::Right => 3,
            Action::Drop => 4,
            Action::Pick(b) => 5 + b.0 as usize,
        }
    }

    /// The move action in direction `dir`.
    pub const fn moving(dir: Direction) -> Action {
        match dir {
            Direction::Up => Action::Up,
            Direction::Down => Action::Down,
            Direction::Left => Action::Left,
            Direction::Right => Action::Right,
        }
    }

    /// The direction, if this is a move.
    pub const fn direction(self) -> Option<Direction> {
        match self {
            Action::Up => Some(Direction::Up),
            Action::Down => Some(Direction::Down),
            Action::Left => Some(Direction::Left),
            Action::Right => Some(Direction::Right),
            Action::Drop | Action::Pick(_) => None,
        }
    }

    /// Every action of a world with `blocks` blocks, in index order.
    pub fn all(blocks: usize) -> impl Iterator<Item = Action> {
        (0..Action::count(blocks)).map(move |i| Action::from_index(i, blocks).expect("index in range"))
    }

    /// Reads an action name as [`Display`](fmt::Display) writes it (`up`, `down`, `left`,
    /// `right`, `drop`, `pick 2`; also `pick2` or `pick(2)`), or a bare index.
    pub fn parse(text: &str, blocks: usize) -> Result<Action> {
        let t = text.trim().to_ascii_lowercase();
        let err = |reason: String| SimError::Parse {
            what: "action",
            text: text.to_string(),
            reason,
        };
        let action = match t.as_str() {
            "up" => Action::Up,
            "down" => Action::Down,
            "left" => Action::Left,
            "right" => Action::Right,
            "drop" => Action::Drop,
            _ => {
                if let Ok(i) = t.parse::<usize>() {
                    return Action::from_index(i, blocks);
                }
                let rest = t
                    .strip_prefix("pick")
                    .ok_or_else(|| err("expected up, down, left, right, drop, pick N or an index".into()))?;
                let digits = rest.trim().trim_start_matches('(').trim_end_matches(')').trim();
                let b: usize = digits.parse().map_err(|_| err("pick needs a block number".into()))?;
                if b >= blocks {
                    return Err(SimError::NoSuchBlock { block: b, blocks });
                }
                Action::Pick(BlockId::of(b))
            }
        };
        Ok(action)
    }
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Action::Up => f.write_str("up"),
            Action::Down => f.write_str("down"),
            Action::Left => f.write_str("left"),
            Action::Right => f.write_str("right"),
            Action::Drop => f.write_str("drop"),
            Action::Pick(b) => write!(f, "pick {b}"),
        }
    }
}
