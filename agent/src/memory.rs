//! Replay memory: the last transition seen from every state-action, in table coordinates,
//! for experience replay (Lin, 1992) at the end of training.
//!
//! Laid out like the [`QTable`](crate::QTable) it serves: dense arrays where the table is
//! dense, a hash map where not.

use std::collections::HashMap;

use crate::qtable::DENSE_LIMIT;

/// Marks a dense entry never seen.
const UNSEEN: u32 = u32::MAX;
/// Marks a dense entry whose transition reached the goal.
const GOAL: u32 = u32::MAX - 1;

/// A remembered transition: the reward, and the next key (`None` when it reached the goal).
type Remembered = (f32, Option<u64>);

/// The last transition from every state-action seen.
#[derive(Clone, Debug)]
pub struct ReplayMemory {
    columns: usize,
    store: Store,
}

#[derive(Clone, Debug)]
enum Store {
    /// Entry `key * columns + column`: the next key (or [`UNSEEN`], [`GOAL`]) and reward.
    Dense {
        next: Vec<u32>,
        reward: Vec<f32>,
    },
    Sparse(HashMap<(u64, usize), Remembered>),
}

impl ReplayMemory {
    /// An empty memory for keys `0..key_count` and `columns` actions; dense when a table of
    /// that size is and every key fits the dense encoding.
    pub fn new(key_count: u64, columns: usize) -> ReplayMemory {
        let entries = key_count.checked_mul(columns as u64);
        let store = match entries {
            Some(e) if e <= DENSE_LIMIT && key_count < u64::from(GOAL) => Store::Dense {
                next: vec![UNSEEN; e as usize],
                reward: vec![0.0; e as usize],
            },
            _ => Store::Sparse(HashMap::new()),
        };
        ReplayMemory { columns, store }
    }

    /// Remembers that `column` taken at `key` gave `reward` and led to `next` (`None`: the
    /// goal), replacing what was remembered before.
    #[inline]
    pub fn remember(&mut self, key: u64, column: usize, reward: f64, next: Option<u64>) {
        match &mut self.store {
            Store::Dense {
                next: nexts,
                reward: rewards,
            } => {
                let i = key as usize * self.columns + column;
                nexts[i] = next.map_or(GOAL, |k| k as u32);
                rewards[i] = reward as f32;
            }
            Store::Sparse(map) => {
                map.insert((key, column), (reward as f32, next));
            }
        }
    }

    /// Calls `f(key, column, reward, next)` for every remembered transition, by increasing
    /// key and column.
    pub fn for_each(&self, mut f: impl FnMut(u64, usize, f32, Option<u64>)) {
        match &self.store {
            Store::Dense { next, reward } => {
                for (i, (&n, &r)) in next.iter().zip(reward).enumerate() {
                    if n != UNSEEN {
                        let next = (n != GOAL).then_some(u64::from(n));
                        f((i / self.columns) as u64, i % self.columns, r, next);
                    }
                }
            }
            Store::Sparse(map) => {
                let mut all: Vec<_> = map.iter().map(|(&(k, c), &t)| (k, c, t)).collect();
                all.sort_unstable_by_key(|&(k, c, _)| (k, c));
                for (k, c, (r, next)) in all {
                    f(k, c, r, next);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contents(m: &ReplayMemory) -> Vec<(u64, usize, f32, Option<u64>)> {
        let mut out = Vec::new();
        m.for_each(|k, c, r, n| out.push((k, c, r, n)));
        out
    }

    #[test]
    fn remembers_the_last_transition_of_each_state_action_in_key_order() {
        // 100 keys x 8 columns is dense; 2^40 keys is not.
        for keys in [100, 1 << 40] {
            let mut m = ReplayMemory::new(keys, 8);
            m.remember(7, 3, -1.0, Some(9));
            m.remember(2, 5, -1.0, None);
            m.remember(7, 3, -2.0, Some(2));
            m.remember(7, 0, 0.5, Some(7));
            assert_eq!(
                contents(&m),
                vec![(2, 5, -1.0, None), (7, 0, 0.5, Some(7)), (7, 3, -2.0, Some(2))],
                "{keys} keys"
            );
        }
    }
}
