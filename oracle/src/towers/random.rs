//! Seeded random problems: uniformly random states (as Slaney & Thiebaux draw them), states
//! in the shape of the 2023 planning competition's generator, and random goals of a few
//! towers, for tests, benchmarks and experiments.
//!
//! The states of `n` blocks with `k` towers number `L(n, k) = C(n-1, k-1) n! / k!` (the
//! Lah numbers): each is `k!` of the (permutation, cut of it into `k` pieces) pairs. So a
//! uniform state is a tower count drawn with weights `L(n, k)`, a uniform permutation and
//! a uniform choice of the `k - 1` cut points.

use rand::seq::SliceRandom;
use rand::seq::index::sample;
use rand::{Rng, RngExt};
use sim::seeding::rng;

use crate::error::Result;

use super::error::TowersError;
use super::goal::TowerGoal;
use super::state::{NONE, Towers};

/// A uniformly random state of `blocks` blocks; the same seed gives the same state.
pub fn random_state(blocks: usize, seed: u64) -> Towers {
    let mut rng = rng(seed);
    let mut below = vec![NONE; blocks];
    if blocks > 0 {
        let k = tower_count(blocks, &mut rng);
        for tower in cut(&permutation(blocks, &mut rng), k, &mut rng) {
            for pair in tower.windows(2) {
                below[pair[1]] = pair[0];
            }
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

/// A tower count for `n >= 1` blocks drawn with weights `L(n, k)`, computed in logs.
fn tower_count(n: usize, rng: &mut impl Rng) -> usize {
    let ln_fact: Vec<f64> = std::iter::once(0.0)
        .chain((1..=n).scan(0.0, |acc, i| {
            *acc += (i as f64).ln();
            Some(*acc)
        }))
        .collect();
    // ln L(n, k) without the ln n! every term shares.
    let ln_l = |k: usize| ln_fact[n - 1] - ln_fact[k - 1] - ln_fact[n - k] - ln_fact[k];
    let top = (1..=n).map(ln_l).fold(f64::NEG_INFINITY, f64::max);
    let weights: Vec<f64> = (1..=n).map(|k| (ln_l(k) - top).exp()).collect();
    let mut r = rng.random::<f64>() * weights.iter().sum::<f64>();
    for (i, w) in weights.iter().enumerate() {
        if r < *w {
            return i + 1;
        }
        r -= w;
    }
    n
}
