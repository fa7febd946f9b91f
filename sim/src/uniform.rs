//! Uniformly random Blocks World states, by Slaney & Thiebaux's counting method ("Blocks
//! World revisited", Artificial Intelligence 125, 2001): the side view's default start
//! ([`StartRule::draw_in`](crate::StartRule::draw_in)), and the generator of random
//! problems (states, and goals naming every block: [`Goal::uniform`](crate::Goal::uniform)).
//!
//! # Why uniform
//!
//! A state of the Blocks World is a set of towers of labelled blocks; the states of `n`
//! blocks number 1, 3, 13, 73, 501, ... (`g(n, 0)` below). Drawing towers by putting blocks
//! one after another on random columns does not draw them uniformly (it favours some shapes
//! over others), and what planners and learners are measured on, in the planning
//! literature, is the uniform distribution: every state as likely as every other.
//!
//! # The method
//!
//! Build the state block by block. Each of the `m` *floating* pieces (towers not yet
//! standing on the table: at first every block alone) is either grounded on the table or put
//! on top of another piece or of one of the `k` grounded towers. The number of states that can
//! be completed from `m` floating pieces over `k` grounded towers is
//!
//! ```text
//! g(0, k) = 1,    g(m, k) = g(m - 1, k + 1) + (m - 1 + k) g(m - 1, k)
//! ```
//!
//! (ground the piece, or put it on one of the `m - 1 + k` others). So take a piece, ground it
//! with probability `g(m - 1, k + 1) / g(m, k)`, otherwise put it on one of the `m - 1 + k`
//! others drawn uniformly; every state comes out with probability `1 / g(n, 0)`.
//!
//! The counts grow like `n!`, far past any float for thousands of blocks, but the draw
//! needs only their ratios `r(m, k) = g(m, k + 1) / g(m, k)`, which stay small and follow
//! from the same recurrence without subtraction:
//!
//! ```text
//! r(0, k) = 1,    r(m, k) = r(m - 1, k) (r(m - 1, k + 1) + m + k) / (r(m - 1, k) + m - 1 + k)
//! ```
//!
//! and the grounding probability is `r(m - 1, k) / (r(m - 1, k) + m - 1 + k)`. The table of
//! ratios is computed row by row (`m` up) and read back row by row (`m` down), so it is
//! kept for the tower counts `k` a draw reaches: a uniform state of `n` blocks has about
//! `sqrt(n)` towers, so [`UniformStates`] keeps `k <= 2 sqrt(n) + 16` and, in the rare draw
//! that goes further, computes the wider table it needs (the draw is the same either way).
//! 10,000 blocks cost about `n^2 / 2` arithmetic operations for the table and `O(n)` for
//! each draw.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, Weak};

use rand::{Rng, RngExt};

/// The marker for "nothing" in the link arrays.
const NONE: usize = usize::MAX;

/// The ratio table of Slaney & Thiebaux's counts for `blocks` blocks (module docs), and the
/// draws it makes. Build it once for a block count and draw from it many times.
#[derive(Clone, Debug)]
pub struct UniformStates {
    blocks: usize,
    table: Ratios,
}

/// `r(m, k)` for `m` in `0..blocks` and `k` in `0..width`.
#[derive(Clone, Debug)]
struct Ratios {
    width: usize,
    values: Vec<f64>,
}

impl Ratios {
    /// The rows `m = 0..rows` of the ratio table, kept for `k < width`.
    fn new(rows: usize, width: usize) -> Ratios {
        let mut values = vec![0.0; rows * width];
        // Row m is needed up to column width - 1, so row m - 1 up to width, and row 0 up to
        // width + rows - 1.
        let mut row = vec![1.0f64; width + rows];
        for m in 0..rows {
            if m > 0 {
                let len = width + rows - m;
                for k in 0..len {
                    let (a, b) = (row[k], row[k + 1]);
                    row[k] = a * (b + (m + k) as f64) / (a + (m - 1 + k) as f64);
                }
            }
            values[m * width..(m + 1) * width].copy_from_slice(&row[..width]);
        }
        Ratios { width, values }
    }

    #[inline]
    fn get(&self, m: usize, k: usize) -> f64 {
        self.values[m * self.width + k]
    }
}

impl UniformStates {
    /// The table for `blocks` blocks.
    pub fn new(blocks: usize) -> UniformStates {
        let width = (2.0 * (blocks as f64).sqrt()) as usize + 16;
        UniformStates {
            blocks,
            table: Ratios::new(blocks, width.min(blocks + 1)),
        }
    }

    /// The table for `blocks` blocks, shared by every caller in the process while one holds
    /// it: environments of thousands of blocks build it once, not at every reset or for each
    /// of a vector's environments.
    pub fn shared(blocks: usize) -> Arc<UniformStates> {
        static TABLES: OnceLock<Mutex<HashMap<usize, Weak<UniformStates>>>> = OnceLock::new();
        let mut tables = TABLES
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some(table) = tables.get(&blocks).and_then(Weak::upgrade) {
            return table;
        }
        let table = Arc::new(UniformStates::new(blocks));
        tables.retain(|_, t| t.strong_count() > 0);
        tables.insert(blocks, Arc::downgrade(&table));
        table
    }

    /// The number of blocks its states have.
    pub fn blocks(&self) -> usize {
        self.blocks
    }

    /// A uniformly random state's towers, each bottom to top, in the order they were
    /// grounded; every block `0..blocks` once. Same generator state, same towers.
    pub fn towers(&self, rng: &mut impl Rng) -> Vec<Vec<usize>> {
        let n = self.blocks;
        let mut wider = None;
        // Each piece as (bottom, top); a piece put on another links its bottom below.
        let mut floating: Vec<(usize, usize)> = (0..n).map(|b| (b, b)).collect();
        let mut grounded: Vec<(usize, usize)> = Vec::new();
        let mut below = vec![NONE; n];
        while let Some(piece) = floating.pop() {
            let (m, k) = (floating.len() + 1, grounded.len());
            if k >= self.table.width && wider.is_none() {
                // A rare draw with more towers than the table keeps (module docs).
                wider = Some(Ratios::new(n, n + 1));
            }
            let table = wider.as_ref().unwrap_or(&self.table);
            let r = table.get(m - 1, k);
            let others = m - 1 + k;
            if rng.random::<f64>() * (r + others as f64) < r {
                grounded.push(piece);
                continue;
            }
            let j = rng.random_range(0..others);
            let target = if j < m - 1 {
                &mut floating[j]
            } else {
                &mut grounded[j - (m - 1)]
            };
            below[piece.0] = target.1;
            target.1 = piece.1;
        }
        let mut above = vec![NONE; n];
        for (b, &s) in below.iter().enumerate() {
            if s != NONE {
                above[s] = b;
            }
        }
        grounded
            .iter()
            .map(|&(bottom, _)| {
                let mut tower = vec![bottom];
                while above[*tower.last().expect("a tower has a bottom")] != NONE {
                    tower.push(above[*tower.last().expect("non-empty")]);
                }
                tower
            })
            .collect()
    }
}

/// A uniformly random Blocks World state of `blocks` blocks, as towers each bottom to top
/// ([`UniformStates::towers`]; build a [`UniformStates`] to draw many).
pub fn uniform_towers(blocks: usize, rng: &mut impl Rng) -> Vec<Vec<usize>> {
    UniformStates::new(blocks).towers(rng)
}

/// The number of Blocks World states of `blocks` blocks, `g(blocks, 0)` (module docs): 1, 1,
/// 3, 13, 73, 501, ... for 0, 1, 2, ... blocks; `None` past `u128` (from 26 blocks on).
pub fn state_count(blocks: usize) -> Option<u128> {
    // Row m of g over k = 0..=blocks - m, from row 0 up.
    let mut row = vec![1u128; blocks + 1];
    for m in 1..=blocks {
        for k in 0..=blocks - m {
            row[k] = row[k + 1].checked_add(((m - 1 + k) as u128).checked_mul(row[k])?)?;
        }
    }
    Some(row[0])
}

/// The probability that a uniformly random state of `blocks` blocks fits a grid `width`
/// columns wide and `height` rows high (no more towers than columns, none taller than the
/// rows): the share of the side view's uniform draws that [`crate::view::uniform_state`]
/// keeps. 1 when the grid holds every state (`width` and `height` at least `blocks`).
///
/// A state with `k` towers is one of the `n! / k!` orders of the blocks cut into `k` parts,
/// so the fitting states number `n!` times the sum over `k <= width` of `c(n, k) / k!`,
/// `c(n, k)` the compositions of `n` into `k` parts of at most `height`, against
/// `sum_k C(n - 1, k - 1) / k!` for all states. O(n min(width, n)), in scaled floats.
pub fn fit_probability(blocks: usize, width: usize, height: usize) -> f64 {
    let n = blocks;
    if n == 0 || (width >= n && height >= n) {
        return 1.0;
    }
    let ln_fact: Vec<f64> = std::iter::once(0.0)
        .chain((1..=n).scan(0.0, |acc, i| {
            *acc += (i as f64).ln();
            Some(*acc)
        }))
        .collect();
    // ln of every term of the total: C(n - 1, k - 1) / k!.
    let ln_all: Vec<f64> = (1..=n)
        .map(|k| ln_fact[n - 1] - ln_fact[k - 1] - ln_fact[n - k] - ln_fact[k])
        .collect();
    // Compositions of m into k parts of 1..=height, row k scaled to a largest value of 1
    // (its log scale kept beside it), from row 1 up.
    let mut row: Vec<f64> = (0..=n)
        .map(|m| f64::from(u8::from((1..=height).contains(&m))))
        .collect();
    let mut scale = 0.0f64;
    let mut ln_fit = Vec::new();
    for (k, ln_k_fact) in ln_fact.iter().enumerate().take(width.min(n) + 1).skip(1) {
        if k > 1 {
            let mut next = vec![0.0; n + 1];
            let mut window = 0.0;
            for m in 0..=n {
                // next[m] = row[m - 1] + ... + row[m - height]
                if m >= 1 {
                    window += row[m - 1];
                }
                if m > height {
                    window -= row[m - 1 - height];
                }
                next[m] = window.max(0.0);
            }
            let top = next.iter().copied().fold(0.0, f64::max);
            if top == 0.0 {
                break;
            }
            next.iter_mut().for_each(|v| *v /= top);
            scale += top.ln();
            row = next;
        }
        if row[n] > 0.0 {
            ln_fit.push(row[n].ln() + scale - ln_k_fact);
        }
    }
    let log_sum = |terms: &[f64]| {
        let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        top + terms.iter().map(|t| (t - top).exp()).sum::<f64>().ln()
    };
    if ln_fit.is_empty() {
        return 0.0;
    }
    (log_sum(&ln_fit) - log_sum(&ln_all)).exp().min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counts_are_the_number_of_states() {
        let counts: Vec<u128> = (0..8).map(|n| state_count(n).unwrap()).collect();
        assert_eq!(counts, [1, 1, 3, 13, 73, 501, 4051, 37633]);
        assert_eq!(state_count(200), None);
    }

    #[test]
    fn the_ratios_are_those_of_the_counts() {
        // g(m, k) exactly for small m, k, against the ratio table.
        let exact = |m: usize, k: usize| {
            let mut row: Vec<f64> = vec![1.0; m + k + 2];
            for i in 1..=m {
                for j in 0..row.len() - i {
                    row[j] = row[j + 1] + (i - 1 + j) as f64 * row[j];
                }
            }
            row[k]
        };
        let table = Ratios::new(8, 6);
        for m in 0..8 {
            for k in 0..6 {
                let want = exact(m, k + 1) / exact(m, k);
                assert!((table.get(m, k) - want).abs() < 1e-9 * want, "r({m}, {k})");
            }
        }
    }

    /// Pearson's chi-square statistic of `draws` draws over `cells` equally likely cells.
    fn chi_square(counts: &HashMap<Vec<Vec<usize>>, u64>, cells: usize, draws: u64) -> f64 {
        let expected = draws as f64 / cells as f64;
        let seen: f64 = counts.values().map(|&c| (c as f64 - expected).powi(2) / expected).sum();
        // Cells never drawn add their expected count.
        seen + (cells - counts.len()) as f64 * expected
    }

    #[test]
    fn states_of_3_and_4_blocks_are_equally_likely() {
        // Chi-square critical values at p = 0.001: 32.91 for 12 degrees of freedom, 116.09
        // for 72. A fixed seed keeps the test from failing one run in a thousand.
        for (blocks, states, critical) in [(3, 13, 32.91), (4, 73, 116.09)] {
            let sampler = UniformStates::new(blocks);
            let mut rng = crate::seeding::rng(2001);
            let draws = 200 * states as u64;
            let mut counts: HashMap<Vec<Vec<usize>>, u64> = HashMap::new();
            for _ in 0..draws {
                let mut towers = sampler.towers(&mut rng);
                let mut all: Vec<usize> = towers.iter().flatten().copied().collect();
                all.sort_unstable();
                assert_eq!(all, (0..blocks).collect::<Vec<_>>());
                towers.sort();
                *counts.entry(towers).or_default() += 1;
            }
            assert_eq!(counts.len(), states, "{blocks} blocks: every state drawn");
            let chi2 = chi_square(&counts, states, draws);
            assert!(chi2 < critical, "{blocks} blocks: chi-square {chi2:.1} >= {critical}");
        }
    }

    #[test]
    fn draws_follow_the_seed_and_a_wider_table_changes_nothing() {
        let narrow = UniformStates::new(30);
        let wide = UniformStates {
            blocks: 30,
            table: Ratios::new(30, 31),
        };
        for seed in 0..200 {
            let a = narrow.towers(&mut crate::seeding::rng(seed));
            assert_eq!(a, narrow.towers(&mut crate::seeding::rng(seed)));
            assert_eq!(a, wide.towers(&mut crate::seeding::rng(seed)));
        }
        // A table as narrow as it can be: every draw past it takes the wider one.
        let tiny = UniformStates {
            blocks: 30,
            table: Ratios::new(30, 1),
        };
        for seed in 0..50 {
            let want = wide.towers(&mut crate::seeding::rng(seed));
            assert_eq!(tiny.towers(&mut crate::seeding::rng(seed)), want);
        }
    }

    #[test]
    fn the_fit_probability_is_the_share_of_states_that_fit() {
        // Every state of n blocks drawn many times: the share that fits against the formula.
        for (n, w, h) in [(3, 2, 2), (4, 3, 3), (4, 1, 4), (5, 2, 3), (5, 5, 2), (6, 3, 2)] {
            let sampler = UniformStates::new(n);
            let mut rng = crate::seeding::rng(7);
            let draws = 40_000;
            let fit = (0..draws)
                .filter(|_| {
                    let t = sampler.towers(&mut rng);
                    t.len() <= w && t.iter().all(|t| t.len() <= h)
                })
                .count();
            let p = fit_probability(n, w, h);
            let seen = fit as f64 / draws as f64;
            assert!((p - seen).abs() < 0.01, "{n} blocks on {w}x{h}: {p} against {seen}");
        }
        // Exactly: 48 of the 73 states of 4 blocks fit 3 x 3 (not 4 towers, not one of 4).
        assert!((fit_probability(4, 3, 3) - 48.0 / 73.0).abs() < 1e-12);
        assert!((fit_probability(3, 2, 2) - 6.0 / 13.0).abs() < 1e-12);
        assert_eq!(fit_probability(50, 50, 60), 1.0);
        assert_eq!(fit_probability(5, 1, 4), 0.0);
        // 100 blocks in towers of at most 3: next to none of the states.
        assert!(fit_probability(100, 100, 3) < 1e-6);
    }

    #[test]
    fn one_block_stands_on_the_table_and_none_is_no_tower() {
        assert_eq!(uniform_towers(1, &mut crate::seeding::rng(0)), vec![vec![0]]);
        assert!(uniform_towers(0, &mut crate::seeding::rng(0)).is_empty());
    }
}
