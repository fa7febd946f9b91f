//! Which actions a network may choose, and the masked argmax every choice goes through.
//!
//! Two things restrict the actions, both decided by `sim`'s rules, never re-implemented here:
//!
//! - **Legal actions** of the world's action protocol ([`sim::ActionProtocol`]):
//!   [`Observation::legal_actions`]. In SPEC's world every action is legal; under the
//!   paper's protocol only picks with nothing held, only moves and drop while holding.
//! - **Actions that change nothing** ([`sim::Effect::Blocked`], [`sim::Effect::NothingHeld`],
//!   [`sim::Effect::Unchanged`]: a move with nothing held, a move into a wall or a block, a
//!   pick of the block already held, a drop with nothing held), found by trying each action
//!   on a copy of the state in a [`GridWorld`]. They cost a step and lead nowhere; with the
//!   learner's `mask_noops` set they are left out of greedy, random and target choices. In a
//!   spike on this machine two thirds of a greedy DQN's failures were such actions.
//!
//! Every choice over actions ([`masked_argmax`], [`ActionSet::random`]) and every maximum
//! over next actions in a learning target looks only at the allowed ones.

use rand::RngExt;
use sim::seeding::SimRng;
use sim::{Action, Effect, GridWorld, Observation, World};

/// A set of action indices (at most 32: `5 + N` with `N <= 16` fits).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ActionSet(u32);

impl ActionSet {
    /// The actions allowed in `obs`: the legal ones, less those that change nothing when
    /// `mask_noops` is set. Never empty: under either protocol some legal action changes
    /// something (a pick with nothing held, a drop while holding).
    pub fn allowed(obs: &Observation, mask_noops: bool) -> ActionSet {
        let blocks = obs.state.block_count();
        let legal = ActionSet(
            obs.legal_actions()
                .as_u32()
                .expect("a network's world has at most 16 blocks"),
        );
        if !mask_noops {
            return legal;
        }
        let world = GridWorld::new(obs.grid, obs.state.clone()).expect("an observation fits its grid");
        let mut set = 0u32;
        for a in Action::all(blocks) {
            let mut trial = world.clone();
            let changes = matches!(
                trial.act(a).expect("every action of Action::all exists"),
                Effect::Moved | Effect::Picked | Effect::Dropped
            );
            if changes && legal.contains(a.index()) {
                set |= 1 << a.index();
            }
        }
        ActionSet(set)
    }

    /// The set of these indices (each below 32).
    pub fn from_indices(indices: impl IntoIterator<Item = usize>) -> ActionSet {
        ActionSet(indices.into_iter().fold(0, |set, a| set | 1 << a))
    }

    /// Whether action index `a` is in the set.
    pub fn contains(self, a: usize) -> bool {
        a < 32 && self.0 & (1 << a) != 0
    }

    /// Number of actions in the set.
    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The action indices, in increasing order.
    pub fn iter(self) -> impl Iterator<Item = usize> {
        (0..32).filter(move |&a| self.contains(a))
    }

    /// A uniformly random action index of the set (`None` if it is empty).
    pub fn random(self, rng: &mut SimRng) -> Option<usize> {
        let n = self.len();
        (n > 0).then(|| self.iter().nth(rng.random_range(0..n)).expect("k < len"))
    }
}

/// The index of the largest of `values` among the actions of `allowed` (the first on a tie;
/// NaNs are never chosen unless every allowed value is NaN); `None` if `allowed` names no
/// action of `values`.
pub fn masked_argmax(values: &[f32], allowed: ActionSet) -> Option<usize> {
    let mut best: Option<(usize, f32)> = None;
    for a in allowed.iter().take_while(|&a| a < values.len()) {
        let v = values[a];
        match best {
            None => best = Some((a, v)),
            Some((_, b)) if v > b || (b.is_nan() && !v.is_nan()) => best = Some((a, v)),
            _ => {}
        }
    }
    best.map(|(a, _)| a)
}

/// The largest of `values` among the actions of `allowed` (see [`masked_argmax`]).
pub fn masked_max(values: &[f32], allowed: ActionSet) -> Option<f32> {
    masked_argmax(values, allowed).map(|a| values[a])
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use sim::{BlockId, Cell, Grid, State};

    #[test]
    fn the_argmax_skips_masked_actions_however_large() {
        let values = [5.0, 1.0, 9.0, 2.0, 2.0];
        let allowed = ActionSet(0b11011);
        assert_eq!(masked_argmax(&values, allowed), Some(0));
        assert_eq!(masked_argmax(&values, ActionSet(0b11000)), Some(3), "first on a tie");
        assert_eq!(masked_argmax(&values, ActionSet(0)), None);
        assert_eq!(masked_argmax(&[f32::NAN, 1.0], ActionSet(0b11)), Some(1));
        assert_eq!(masked_max(&values, allowed), Some(5.0));
    }

    #[test]
    fn no_op_actions_are_masked_only_when_asked() {
        // Block 0 held in the bottom-left corner, block 1 right of it.
        let obs = Observation {
            grid: Grid::default(),
            state: State::new(&[Cell::new(0, 0), Cell::new(1, 0)], Some(BlockId(0))).unwrap(),
            protocol: sim::ActionProtocol::Free,
            goal: "0,1".parse().unwrap(),
            view: sim::View::Top,
        };
        assert_eq!(ActionSet::allowed(&obs, false).len(), 7);
        let allowed: Vec<usize> = ActionSet::allowed(&obs, true).iter().collect();
        // Up, Drop, Pick(1); not Down/Left (wall), Right (block 1), Pick(0) (held).
        assert_eq!(allowed, vec![0, 4, 6]);
        let free = Observation {
            state: obs.state.with_held(None).unwrap(),
            ..obs.clone()
        };
        // Nothing held: only the picks change anything.
        assert_eq!(ActionSet::allowed(&free, true).iter().collect::<Vec<_>>(), vec![5, 6]);
        // The paper's protocol: holding, only moves and drop are legal (Pick(1) is not).
        let paper = Observation {
            protocol: sim::ActionProtocol::Paper,
            ..obs
        };
        assert_eq!(
            ActionSet::allowed(&paper, false).iter().collect::<Vec<_>>(),
            vec![0, 1, 2, 3, 4]
        );
        assert_eq!(ActionSet::allowed(&paper, true).iter().collect::<Vec<_>>(), vec![0, 4]);
    }

    proptest! {
        #[test]
        fn the_masked_argmax_is_allowed_and_maximal(
            values in proptest::collection::vec(-1e3f32..1e3, 1..21),
            bits in any::<u32>(),
        ) {
            let allowed = ActionSet(bits);
            match masked_argmax(&values, allowed) {
                None => prop_assert!((0..values.len()).all(|a| !allowed.contains(a))),
                Some(a) => {
                    prop_assert!(allowed.contains(a) && a < values.len());
                    for b in allowed.iter().filter(|&b| b < values.len()) {
                        prop_assert!(values[b] <= values[a]);
                    }
                }
            }
        }

        #[test]
        fn random_choices_stay_in_the_set(bits in 1u32.., seed in any::<u64>()) {
            let mut rng = sim::seeding::rng(seed);
            let a = ActionSet(bits).random(&mut rng).unwrap();
            prop_assert!(ActionSet(bits).contains(a));
        }
    }
}
