//! A goal of several towers, and which blocks of a state already stand where the goal
//! wants them.
//!
//! The goal names some blocks in towers, each listed bottom to top; a named tower holds
//! when it stands from the table up in that order, whatever it carries on top. So the goal
//! is a set of facts "block `b` stands on `s`" (`s` the table for a bottom block), one per
//! named block; the blocks it does not name are free.

use std::fmt;

use crate::error::Result;

use super::error::{Part, TowersError};
use super::state::{Chains, NONE, Place, Towers};

/// A goal: towers of named blocks, each bottom to top; unnamed blocks are free.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct TowerGoal {
    /// The towers as given.
    towers: Vec<Vec<usize>>,
    /// Whether each block (by id, up to the largest named) is named.
    named: Vec<bool>,
    /// What each named block must stand on ([`NONE`]: the table).
    below: Vec<usize>,
    /// The named block that must stand on each block ([`NONE`]: none).
    above: Vec<usize>,
}

impl TowerGoal {
    /// The goal with these towers, each bottom to top. No tower may be empty and no block
    /// named twice; whether the blocks exist is checked against a state
    /// ([`TowerGoal::check_blocks`]).
    pub fn new(towers: &[Vec<usize>]) -> Result<Self> {
        // Every block it names is below this bound, so only empty towers and blocks named
        // twice are errors here.
        let len = towers.iter().flatten().max().map_or(0, |&m| m + 1);
        let Chains { named, below, above } = Chains::of(towers, len, Part::Goal)?;
        Ok(TowerGoal {
            towers: towers.to_vec(),
            named,
            below,
            above,
        })
    }

    /// The towers, each bottom to top.
    pub fn towers(&self) -> &[Vec<usize>] {
        &self.towers
    }

    /// Checks that every named block is one of a state's `blocks` blocks.
    pub fn check_blocks(&self, blocks: usize) -> Result<()> {
        match self.towers.iter().flatten().find(|&&b| b >= blocks) {
            Some(&block) => Err(TowersError::UnknownBlock {
                part: Part::Goal,
                block,
                blocks,
            }
            .into()),
            None => Ok(()),
        }
    }

    /// Whether the goal names `block`.
    pub fn is_named(&self, block: usize) -> bool {
        self.named.get(block).copied().unwrap_or(false)
    }

    /// What `block` must stand on, if the goal names it.
    pub fn support(&self, block: usize) -> Option<Place> {
        self.is_named(block).then(|| Place::from_support(self.below[block]))
    }

    /// What a named block must stand on ([`NONE`]: the table); [`NONE`] for a free block,
    /// so callers check [`TowerGoal::is_named`] first where it matters.
    pub(crate) fn below_of(&self, block: usize) -> usize {
        self.below.get(block).copied().unwrap_or(NONE)
    }

    /// The named block that must stand on `block` ([`NONE`]: none).
    pub(crate) fn above_of(&self, block: usize) -> usize {
        self.above.get(block).copied().unwrap_or(NONE)
    }

    /// Whether every named tower stands in `state` (false if it names a block the state
    /// does not have).
    pub fn holds(&self, state: &Towers) -> bool {
        self.check_blocks(state.blocks()).is_ok()
            && self.towers.iter().flatten().all(|&b| state.below()[b] == self.below[b])
    }

    /// Which blocks are well placed: a block is well placed when it and everything below
    /// it stand as the goal wants for good. A named block must stand on its goal support,
    /// itself well placed; a free block must stand on the table, or on a well-placed block
    /// that no named block must stand on. A block that is not well placed moves at least
    /// once in every plan (it stands where the goal forbids, or something below it must
    /// move, and only a clear block moves), and one that is needs never move.
    pub(crate) fn well_placed(&self, below: &[usize], above: &[usize]) -> Vec<bool> {
        let mut wp = vec![false; below.len()];
        for bottom in (0..below.len()).filter(|&b| below[b] == NONE) {
            let mut ok = !self.is_named(bottom) || self.below[bottom] == NONE;
            wp[bottom] = ok;
            let mut s = bottom;
            while above[s] != NONE {
                let b = above[s];
                ok = ok
                    && if self.is_named(b) {
                        self.below[b] == s
                    } else {
                        self.above_of(s) == NONE
                    };
                wp[b] = ok;
                s = b;
            }
        }
        wp
    }
}

impl fmt::Display for TowerGoal {
    /// The towers bottom to top, `/` between towers: `0,1,2/3,4`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (t, tower) in self.towers.iter().enumerate() {
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
