//! Seeded random problems: uniformly random states (Slaney & Thiebaux's counting method,
//! drawn by `sim::uniform`, the one home of the side view's random states), states in the
//! shape of the 2023 planning competition's generator and of Neural Logic Machines', and
//! random goals of a few towers, for tests, benchmarks and experiments.

use rand::seq::SliceRandom;
use rand::seq::index::sample;
use rand::{Rng, RngExt};
use sim::seeding::rng;

use crate::error::Result;

use super::error::TowersError;
use super::goal::TowerGoal;
use super::state::{NONE, Towers};

/// A uniformly random state of `blocks` blocks ([`sim::uniform`]); the same seed gives the
/// same state.
pub fn random_state(blocks: usize, seed: u64) -> Towers {
    let mut below = vec![NONE; blocks];
    for tower in sim::uniform::uniform_towers(blocks, &mut rng(seed)) {
        for pair in tower.windows(2) {
            below[pair[1]] = pair[0];
        }
    }
    Towers::from_below(below)
}

/// A random state of `blocks` blocks in the shape the 2023 planning competition's
/// generator draws (`ipc2023-learning/benchmarks`, `blocksworld/blocksworld.py`): the blocks
/// shuffled and stacked in that order, each starting a new tower with probability 1/10.
/// Not uniform over states: its towers are few and tall (about `blocks / 10`). The same seed
/// gives the same state.
pub fn ipc_state(blocks: usize, seed: u64) -> Towers {
    let mut rng = rng(seed);
    let order = permutation(blocks, &mut rng);
    let mut below = vec![NONE; blocks];
    for pair in order.windows(2) {
        if rng.random_range(0..10) != 0 {
            below[pair[1]] = pair[0];
        }
    }
    Towers::from_below(below)
}

/// A random state of `blocks` blocks drawn as Neural Logic Machines draw theirs (Dong et
/// al., "Neural Logic Machines", ICLR 2019, and their code's `randomly_generate_world`):
/// the blocks in a uniformly random order, each put on the table or on top of one of the
/// towers built so far, the table and each top equally likely. Not uniform over states:
/// tall towers are rarer than among uniform states. The same seed gives the same state.
pub fn nlm_state(blocks: usize, seed: u64) -> Towers {
    let mut rng = rng(seed);
    let mut below = vec![NONE; blocks];
    // The tops of the towers built so far.
    let mut tops: Vec<usize> = Vec::new();
    for b in permutation(blocks, &mut rng) {
        let place = rng.random_range(0..=tops.len());
        if place < tops.len() {
            below[b] = tops[place];
            tops[place] = b;
        } else {
            tops.push(b);
        }
    }
    Towers::from_below(below)
}

/// A random goal of `stacks` towers naming `named` of `blocks` blocks (the others free):
/// a uniform choice of the named blocks, their order, and the cut into towers.
pub fn random_goal(blocks: usize, stacks: usize, named: usize, seed: u64) -> Result<TowerGoal> {
    if stacks == 0 || stacks > named || named > blocks {
        return Err(TowersError::GoalShape { stacks, named, blocks }.into());
    }
    let mut rng = rng(seed);
    let mut chosen = permutation(blocks, &mut rng);
    chosen.truncate(named);
    TowerGoal::new(&cut(&chosen, stacks, &mut rng))
}

/// A uniformly random order of `0..n`.
fn permutation(n: usize, rng: &mut impl Rng) -> Vec<usize> {
    let mut p: Vec<usize> = (0..n).collect();
    p.shuffle(rng);
    p
}

/// `items` cut into `k` non-empty pieces at uniformly chosen points (`1 <= k <= len`).
fn cut(items: &[usize], k: usize, rng: &mut impl Rng) -> Vec<Vec<usize>> {
    let mut points: Vec<usize> = sample(rng, items.len() - 1, k - 1).into_iter().map(|i| i + 1).collect();
    points.sort_unstable();
    points.push(items.len());
    let mut start = 0;
    points
        .into_iter()
        .map(|end| {
            let piece = items[start..end].to_vec();
            start = end;
            piece
        })
        .collect()
}
