//! The abstract Blocks World state: towers of blocks on a table, and the block moves
//! between states.
//!
//! A state is what each block stands on (the table or one other block); the columns the
//! towers stand in do not matter to the block-move count, so two states with the same
//! towers in other columns are one state. A [`Table`] of limited width only bounds how
//! many towers may stand at once.

use std::fmt;

use crate::error::Result;

use super::error::{Part, TowersError};

/// The marker for "no block" in the support and on-top arrays: the table below a block,
/// nothing above it.
pub(crate) const NONE: usize = usize::MAX;

/// Where a block goes in a move, or what it stands on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Place {
    /// The table (a free column, in the side view).
    Table,
    /// On top of this block.
    On(usize),
}

impl Place {
    /// The place a support entry names.
    pub(crate) fn from_support(support: usize) -> Self {
        if support == NONE {
            Place::Table
        } else {
            Place::On(support)
        }
    }
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Place::Table => f.write_str("table"),
            Place::On(b) => write!(f, "{b}"),
        }
    }
}

/// One block move: a clear block taken to the table or onto another clear block.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Move {
    /// The block moved; it must be clear.
    pub block: usize,
    /// Where it goes.
    pub to: Place,
}

impl fmt::Display for Move {
    /// `3->table` or `3->5` (block 3 onto block 5).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}->{}", self.block, self.to)
    }
}

/// How many towers the table holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Table {
    /// As many as there are blocks: the literature's table, where a move to the table is
    /// always possible.
    #[default]
    Unbounded,
    /// At most this many towers stand at once (the side view's grid width): a move to the
    /// table needs a free column.
    Columns(usize),
}

impl Table {
    /// Whether a state with `towers` towers leaves a column free.
    pub fn has_free_column(self, towers: usize) -> bool {
        match self {
            Table::Unbounded => true,
            Table::Columns(c) => towers < c,
        }
    }

    /// Checks that `towers` towers of the given part fit.
    pub(crate) fn check(self, part: Part, towers: usize) -> Result<()> {
        match self {
            Table::Columns(columns) if towers > columns => {
                Err(TowersError::TooManyTowers { part, towers, columns }.into())
            }
            _ => Ok(()),
        }
    }
}

/// A Blocks World state of `n` blocks, `0..n`, each standing on the table or on one other
/// block, at most one block on each.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Towers {
    /// What each block stands on ([`NONE`]: the table).
    below: Vec<usize>,
    /// What stands on each block ([`NONE`]: it is clear).
    above: Vec<usize>,
    /// Number of towers (blocks on the table).
    towers: usize,
}

/// Towers (each bottom to top) as links between blocks: what a state and a goal are both
/// read from.
pub(crate) struct Chains {
    /// Whether each block is in a tower.
    pub(crate) named: Vec<bool>,
    /// The block each stands on ([`NONE`]: the table, or not named).
    pub(crate) below: Vec<usize>,
    /// The block standing on each ([`NONE`]: nothing).
    pub(crate) above: Vec<usize>,
}

impl Chains {
    /// The links of `towers` over the block ids `0..len`; an error for an empty tower, a
    /// block not below `len`, or a block named twice, in the `part` it names.
    pub(crate) fn of(towers: &[Vec<usize>], len: usize, part: Part) -> Result<Chains> {
        let mut chains = Chains {
            named: vec![false; len],
            below: vec![NONE; len],
            above: vec![NONE; len],
        };
        for (t, tower) in towers.iter().enumerate() {
            if tower.is_empty() {
                return Err(TowersError::EmptyTower { part, tower: t }.into());
            }
            for (i, &b) in tower.iter().enumerate() {
                if b >= len {
                    return Err(TowersError::UnknownBlock {
                        part,
                        block: b,
                        blocks: len,
                    }
                    .into());
                }
                if std::mem::replace(&mut chains.named[b], true) {
                    return Err(TowersError::DuplicateBlock { part, block: b }.into());
                }
                if i > 0 {
                    chains.below[b] = tower[i - 1];
                    chains.above[tower[i - 1]] = b;
                }
            }
        }
        Ok(chains)
    }
}

impl Towers {
    /// The state with these towers, each listed bottom to top. The blocks must be `0..n`,
    /// each once, and no tower empty.
    pub fn new(towers: &[Vec<usize>]) -> Result<Self> {
        let n: usize = towers.iter().map(Vec::len).sum();
        let chains = Chains::of(towers, n, Part::State)?;
        // n blocks with ids below n, none twice: all of 0..n are there.
        debug_assert!(chains.named.iter().all(|&s| s));
        Ok(Towers {
            below: chains.below,
            above: chains.above,
            towers: towers.len(),
        })
    }

    /// The state whose block `b` stands on `below[b]` ([`NONE`]: the table); the caller
    /// guarantees it is a forest of chains.
    pub(crate) fn from_below(below: Vec<usize>) -> Self {
        let mut above = vec![NONE; below.len()];
        let mut towers = 0;
        for (b, &s) in below.iter().enumerate() {
            if s == NONE {
                towers += 1;
            } else {
                above[s] = b;
            }
        }
        Towers { below, above, towers }
    }

    /// Number of blocks.
    pub fn blocks(&self) -> usize {
        self.below.len()
    }

    /// Number of towers (columns in use).
    pub fn tower_count(&self) -> usize {
        self.towers
    }

    /// What `block` stands on.
    ///
    /// # Panics
    /// If `block` is not below [`Towers::blocks`].
    pub fn support(&self, block: usize) -> Place {
        Place::from_support(self.below[block])
    }

    /// Whether nothing stands on `block`.
    ///
    /// # Panics
    /// If `block` is not below [`Towers::blocks`].
    pub fn is_clear(&self, block: usize) -> bool {
        self.above[block] == NONE
    }

    /// The support array ([`NONE`]: the table).
    pub(crate) fn below(&self) -> &[usize] {
        &self.below
    }

    /// The on-top array ([`NONE`]: clear).
    pub(crate) fn above(&self) -> &[usize] {
        &self.above
    }

    /// The towers, each bottom to top, ordered by their bottom block.
    pub fn towers(&self) -> Vec<Vec<usize>> {
        (0..self.blocks())
            .filter(|&b| self.below[b] == NONE)
            .map(|bottom| {
                let mut tower = vec![bottom];
                let mut b = bottom;
                while self.above[b] != NONE {
                    b = self.above[b];
                    tower.push(b);
                }
                tower
            })
            .collect()
    }

    /// Whether `mv` is legal here on `table`; `Err` says why not.
    pub fn check(&self, mv: Move, table: Table) -> Result<()> {
        let illegal = |reason| {
            Err(TowersError::IllegalMove {
                mv: mv.to_string(),
                reason,
            }
            .into())
        };
        let n = self.blocks();
        if mv.block >= n {
            return illegal("no such block");
        }
        if !self.is_clear(mv.block) {
            return illegal("the block is not clear");
        }
        match mv.to {
            Place::Table if self.below[mv.block] == NONE => illegal("the block is on the table already"),
            Place::Table if !table.has_free_column(self.towers) => illegal("no column of the table is free"),
            Place::Table => Ok(()),
            Place::On(y) if y >= n => illegal("no such destination block"),
            Place::On(y) if y == mv.block => illegal("a block cannot go onto itself"),
            Place::On(y) if !self.is_clear(y) => illegal("the destination block is not clear"),
            Place::On(_) => Ok(()),
        }
    }

    /// Carries out `mv` if it is legal on `table` (see [`Towers::check`]).
    pub fn apply(&mut self, mv: Move, table: Table) -> Result<()> {
        self.check(mv, table)?;
        self.apply_unchecked(mv);
        Ok(())
    }

    /// Carries out a move known to be legal.
    pub(crate) fn apply_unchecked(&mut self, mv: Move) {
        let x = mv.block;
        let from = self.below[x];
        if from == NONE {
            self.towers -= 1;
        } else {
            self.above[from] = NONE;
        }
        match mv.to {
            Place::Table => {
                self.below[x] = NONE;
                self.towers += 1;
            }
            Place::On(y) => {
                self.below[x] = y;
                self.above[y] = x;
            }
        }
    }

    /// Every legal move here on `table`: for each clear block in id order, to the table
    /// first, then onto each other clear block in id order.
    pub fn moves(&self, table: Table) -> Vec<Move> {
        let clear: Vec<usize> = (0..self.blocks()).filter(|&b| self.is_clear(b)).collect();
        let table_free = table.has_free_column(self.towers);
        let mut moves = Vec::new();
        for &x in &clear {
            if table_free && self.below[x] != NONE {
                moves.push(Move {
                    block: x,
                    to: Place::Table,
                });
            }
            moves.extend(clear.iter().filter(|&&y| y != x).map(|&y| Move {
                block: x,
                to: Place::On(y),
            }));
        }
        moves
    }
}

impl fmt::Display for Towers {
    /// The towers bottom to top, `/` between towers: `0,1,2/3,4`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (t, tower) in self.towers().iter().enumerate() {
            if t > 0 {
                f.write_str("/")?;
            }
            for (i, b) in tower.iter().enumerate() {
                if i > 0 {
                    f.write_str(",")?;
                }
                write!(f, "{b}")?;
            }
        }
        Ok(())
    }
}
