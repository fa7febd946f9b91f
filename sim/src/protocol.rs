//! Action protocols: which actions are legal in a state, and the action mask that says so.
//!
//! docs/world.md section 2 lets an agent take any of the `5 + N` actions at any time: that is the
//! [`ActionProtocol::Free`] protocol, the default. The paper's agents never chose that way.
//! In the authors' code (docs/world.md section 10, "The action protocol"; their `RL.py:50-71`) an agent
//! with nothing held may only pick a block, and an agent holding a block may only move it or
//! drop it: that is [`ActionProtocol::Paper`], and every figure of the paper was measured
//! under it.
//!
//! The legal actions of a state are an [`ActionMask`], a bitset over action indices, the
//! way Gymnasium users read `info["action_mask"]`. Under a restricting protocol
//! [`Env::step`](crate::Env::step) refuses an illegal action with
//! [`SimError::IllegalAction`] instead of treating it as a no-op.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::error::{Result, SimError};
use crate::inline_vec::InlineVec;
use crate::state::{BlockId, State};

/// Indices of the four moves and Drop: bits `0..5`.
pub(crate) const MOVES_AND_DROP: u64 = 0b1_1111;

/// Which actions are legal in a state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ActionProtocol {
    /// docs/world.md section 2: all `5 + N` actions in every state.
    #[default]
    Free,
    /// The authors' code (docs/world.md section 10, `RL.py:50-71`): with nothing held only `Pick(i)`;
    /// holding a block only `Up`, `Down`, `Left`, `Right` and `Drop`.
    Paper,
}

crate::names!(ActionProtocol { Free = "free", Paper = "paper" } unknown(name) -> SimError {
    SimError::Parse {
        what: "action protocol",
        text: name.to_string(),
        reason: format!("choose one of {}", ActionProtocol::NAMES.join(", ")),
    }
});

impl ActionProtocol {
    /// The legal actions in `state`.
    #[inline]
    pub fn legal_actions(self, state: &State) -> ActionMask {
        self.legal_when(state.held_block(), state.block_count())
    }

    /// The legal actions of a world of `blocks` blocks with `held` in hand: all the
    /// protocol looks at.
    #[inline]
    pub(crate) fn legal_when(self, held: Option<BlockId>, blocks: usize) -> ActionMask {
        match self {
            ActionProtocol::Free => ActionMask::all(blocks),
            ActionProtocol::Paper if held.is_some() => ActionMask::with_first_word(MOVES_AND_DROP, blocks),
            ActionProtocol::Paper => {
                let mut picks = ActionMask::all(blocks);
                picks.words[0] &= !MOVES_AND_DROP;
                picks
            }
        }
    }

    /// `Ok` if `action` is legal in `state`. Otherwise [`SimError::NoSuchBlock`] for a pick
    /// of a block that does not exist, and [`SimError::IllegalAction`] for an action this
    /// protocol forbids in this state.
    pub fn check(self, state: &State, action: Action) -> Result<()> {
        self.check_when(state.held_block(), state.block_count(), action)
    }

    /// [`ActionProtocol::check`] for a world of `blocks` blocks with `held` in hand.
    #[inline]
    pub(crate) fn check_when(self, held: Option<BlockId>, blocks: usize, action: Action) -> Result<()> {
        if let Action::Pick(b) = action
            && b.index() >= blocks
        {
            return Err(SimError::NoSuchBlock {
                block: b.index(),
                blocks,
            });
        }
        if self.legal_when(held, blocks).contains(action) {
            Ok(())
        } else {
            Err(SimError::IllegalAction {
                action,
                held,
                protocol: self,
            })
        }
    }

    /// What this protocol allows, in words, with or without a block held (for error
    /// messages).
    pub const fn allowed(self, holding: bool) -> &'static str {
        match (self, holding) {
            (ActionProtocol::Free, _) => "every action is allowed",
            (ActionProtocol::Paper, false) => "only pick N is allowed",
            (ActionProtocol::Paper, true) => "only up, down, left, right and drop are allowed",
        }
    }
}

/// A set of actions of a world with `N` blocks, one bit per action index (docs/world.md
/// section 2's table: `5 + N` actions).
///
/// Up to 59 blocks (64 actions, every top-view world and every learner's) the bits are one
/// word kept inline, so a step returns its mask without allocating; a larger side-view
/// world's mask holds `(5 + N) / 64` words on the heap. It knows how many actions the world
/// has, so it can be written out as a full 0/1 array.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct ActionMask {
    /// Bit `i % 64` of word `i / 64` set: action `i` is in the set. Bits past the world's
    /// actions are never set.
    words: InlineVec<u64, 1>,
    /// `5 + N`: the number of actions of the world.
    actions: u32,
}

/// Words of a mask of `actions` actions.
#[inline]
const fn words_for(actions: usize) -> usize {
    actions.div_ceil(64)
}

impl ActionMask {
    /// Every action of a world with `blocks` blocks.
    #[inline]
    pub fn all(blocks: usize) -> ActionMask {
        let actions = Action::count(blocks);
        let mut words = InlineVec::from_elem(u64::MAX, words_for(actions));
        if !actions.is_multiple_of(64) {
            let last = words.len() - 1;
            words[last] = (1u64 << (actions % 64)) - 1;
        }
        ActionMask {
            words,
            actions: actions as u32,
        }
    }

    /// No action of a world with `blocks` blocks.
    #[inline]
    pub fn none(blocks: usize) -> ActionMask {
        let actions = Action::count(blocks);
        ActionMask {
            words: InlineVec::from_elem(0, words_for(actions)),
            actions: actions as u32,
        }
    }

    /// The set with the first word `bits` (bit `i`: action `i < 64`) of a world with
    /// `blocks` blocks; the caller keeps to the world's actions.
    #[inline]
    pub(crate) fn with_first_word(bits: u64, blocks: usize) -> ActionMask {
        let mut mask = ActionMask::none(blocks);
        mask.words[0] = bits;
        mask
    }

    /// Adds the action with index `index`, which the caller keeps below
    /// [`ActionMask::action_count`].
    #[inline]
    pub(crate) fn insert_index(&mut self, index: usize) {
        self.words[index / 64] |= 1 << (index % 64);
    }

    /// The set of the given actions of a world with `blocks` blocks; an error for an action
    /// that does not exist there.
    pub fn of(blocks: usize, actions: impl IntoIterator<Item = Action>) -> Result<ActionMask> {
        let mut mask = ActionMask::none(blocks);
        for a in actions {
            let i = a.index();
            if i >= mask.action_count() {
                return Err(SimError::ActionOutOfRange { index: i, blocks });
            }
            mask.insert_index(i);
        }
        Ok(mask)
    }

    /// The number of actions of the world, `5 + N` (the length of [`ActionMask::write_bytes`]'s
    /// output).
    #[inline]
    pub fn action_count(&self) -> usize {
        self.actions as usize
    }

    /// Whether `action` is in the set.
    #[inline]
    pub fn contains(&self, action: Action) -> bool {
        self.contains_index(action.index())
    }

    /// Whether the action with index `index` is in the set (`false` past the world's
    /// actions).
    #[inline]
    pub fn contains_index(&self, index: usize) -> bool {
        self.words.get(index / 64).is_some_and(|w| w & (1 << (index % 64)) != 0)
    }

    /// Number of actions in the set.
    #[inline]
    pub fn count(&self) -> usize {
        self.words.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// Whether the set is empty.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.words.iter().all(|&w| w == 0)
    }

    /// The actions in the set, in index order.
    pub fn iter(&self) -> impl Iterator<Item = Action> + '_ {
        let blocks = self.action_count() - Action::count(0);
        self.indices()
            .map(move |i| Action::from_index(i, blocks).expect("a mask holds only indices of its world"))
    }

    /// The indices in the set, in increasing order.
    pub fn indices(&self) -> impl Iterator<Item = usize> + '_ {
        self.words.iter().enumerate().flat_map(|(w, &word)| {
            let mut bits = word;
            std::iter::from_fn(move || {
                (bits != 0).then(|| {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    w * 64 + i
                })
            })
        })
    }

    /// The `k`-th action of the set in index order (from 0), if the set has more than `k`.
    ///
    /// A uniform draw among legal actions is `mask.nth(rng.random_range(0..mask.count()))`;
    /// with every action legal that is action `k` itself.
    #[inline]
    pub fn nth(&self, k: usize) -> Option<Action> {
        let blocks = self.action_count() - Action::count(0);
        let mut k = k;
        for (w, &word) in self.words.iter().enumerate() {
            let ones = word.count_ones() as usize;
            if k >= ones {
                k -= ones;
                continue;
            }
            let mut bits = word;
            for _ in 0..k {
                bits &= bits - 1;
            }
            let index = w * 64 + bits.trailing_zeros() as usize;
            return Some(Action::from_index(index, blocks).expect("a mask holds only indices of its world"));
        }
        None
    }

    /// The set as the bits of one `u32` (bit `i`: action `i`), for callers that keep a mask
    /// in a word: the learners, whose worlds have at most [`MAX_BLOCKS`](crate::MAX_BLOCKS) blocks (21
    /// actions). `None` for a world of more than 32 actions.
    #[inline]
    pub fn as_u32(&self) -> Option<u32> {
        (self.actions <= 32).then(|| self.words[0] as u32)
    }

    /// Writes the set as `5 + N` bytes, `1` for an action in the set and `0` otherwise,
    /// into `out` (no allocation: for array-based callers such as neural nets and the
    /// Python binding). An error unless `out` has exactly [`ActionMask::action_count`] bytes.
    pub fn write_bytes(&self, out: &mut [u8]) -> Result<()> {
        if out.len() != self.action_count() {
            return Err(SimError::MaskLength {
                expected: self.action_count(),
                found: out.len(),
            });
        }
        for (i, byte) in out.iter_mut().enumerate() {
            *byte = u8::from(self.words[i / 64] & (1 << (i % 64)) != 0);
        }
        Ok(())
    }
}

impl fmt::Display for ActionMask {
    /// The actions in the set, comma-separated (`up, down, left, right, drop`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, a) in self.iter().enumerate() {
            if k > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{a}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Cell;

    fn state(held: Option<u16>) -> State {
        State::new(&[Cell::new(0, 0), Cell::new(2, 3), Cell::new(5, 1)], held.map(BlockId)).unwrap()
    }

    #[test]
    fn free_allows_every_action() {
        for held in [None, Some(1)] {
            let mask = ActionProtocol::Free.legal_actions(&state(held));
            assert_eq!(mask, ActionMask::all(3));
            assert_eq!(mask.count(), 8);
            assert_eq!(mask.iter().collect::<Vec<_>>(), Action::all(3).collect::<Vec<_>>());
        }
    }

    #[test]
    fn paper_allows_picks_when_empty_and_moves_and_drop_when_holding() {
        let empty = ActionProtocol::Paper.legal_actions(&state(None));
        assert_eq!(empty.indices().collect::<Vec<_>>(), [5, 6, 7]);
        let holding = ActionProtocol::Paper.legal_actions(&state(Some(2)));
        assert_eq!(
            holding.iter().collect::<Vec<_>>(),
            [Action::Up, Action::Down, Action::Left, Action::Right, Action::Drop]
        );
        assert_eq!(holding.to_string(), "up, down, left, right, drop");
    }

    #[test]
    fn nth_walks_the_set_in_index_order() {
        let mask = ActionProtocol::Paper.legal_actions(&state(None));
        assert_eq!(mask.nth(0), Some(Action::Pick(BlockId(0))));
        assert_eq!(mask.nth(2), Some(Action::Pick(BlockId(2))));
        assert_eq!(mask.nth(3), None);
        let all = ActionMask::all(16);
        for k in 0..21 {
            assert_eq!(all.nth(k).map(Action::index), Some(k));
        }
        assert_eq!(all.nth(21), None);
    }

    #[test]
    fn masks_write_as_bytes_of_the_world_s_length() {
        let mask = ActionProtocol::Paper.legal_actions(&state(Some(0)));
        let mut out = [9u8; 8];
        mask.write_bytes(&mut out).unwrap();
        assert_eq!(out, [1, 1, 1, 1, 1, 0, 0, 0]);
        assert_eq!(
            mask.write_bytes(&mut [0u8; 7]),
            Err(SimError::MaskLength { expected: 8, found: 7 })
        );
    }

    #[test]
    fn masks_built_from_actions_check_them() {
        let mask = ActionMask::of(2, [Action::Drop, Action::Pick(BlockId(1))]).unwrap();
        assert_eq!(mask.indices().collect::<Vec<_>>(), [4, 6]);
        assert!(mask.contains(Action::Drop) && !mask.contains_index(5) && !mask.contains_index(30));
        assert_eq!(
            ActionMask::of(2, [Action::Pick(BlockId(2))]),
            Err(SimError::ActionOutOfRange { index: 7, blocks: 2 })
        );
        assert!(ActionMask::none(2).is_empty());
    }

    #[test]
    fn protocols_parse_and_print_by_name() {
        for name in ActionProtocol::NAMES {
            assert_eq!(name.parse::<ActionProtocol>().unwrap().to_string(), name);
        }
        let err = "strict".parse::<ActionProtocol>().unwrap_err();
        assert!(err.to_string().contains("free, paper"), "{err}");
        assert_eq!(serde_json::to_string(&ActionProtocol::Paper).unwrap(), "\"paper\"");
    }

    #[test]
    fn illegal_actions_are_named_with_the_held_block_and_the_protocol() {
        let err = ActionProtocol::Paper
            .check(&state(Some(1)), Action::Pick(BlockId(0)))
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "pick 0 is not legal under the paper action protocol while block 1 is held: only up, down, left, right and drop are allowed"
        );
        let err = ActionProtocol::Paper.check(&state(None), Action::Up).unwrap_err();
        assert_eq!(
            err.to_string(),
            "up is not legal under the paper action protocol while nothing is held: only pick N is allowed"
        );
        assert_eq!(
            ActionProtocol::Paper.check(&state(None), Action::Pick(BlockId(3))),
            Err(SimError::NoSuchBlock { block: 3, blocks: 3 })
        );
        assert_eq!(ActionProtocol::Free.check(&state(None), Action::Up), Ok(()));
    }
}
