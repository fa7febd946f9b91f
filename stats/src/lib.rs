//! Non-parametric two-sample tests with p-values that match SciPy.
//!
//! A crate of its own, knowing nothing of blocks, so that anyone comparing two samples
//! (the reproduction's tables, a sweep of hyper-parameters) gets the same p-values as
//! SciPy without a Python run.
//!
//! The paper's tables compare agents by per-episode outcomes (step counts,
//! with failed episodes recorded at the step limit), so the data are discrete
//! and heavily tied. Three two-sided tests are provided, each a port of the
//! corresponding SciPy function with its default arguments (checked against
//! SciPy 1.17.1):
//!
//! | function | SciPy call |
//! | --- | --- |
//! | [`wilcoxon`], [`wilcoxon_diffs`] | `scipy.stats.wilcoxon(x, y, correction=...)` |
//! | [`mann_whitney_u`] | `scipy.stats.mannwhitneyu(x, y)` |
//! | [`ks_2samp`] | `scipy.stats.ks_2samp(x, y)` |
//!
//! Every test returns a [`TestResult`] holding the statistic SciPy reports,
//! the p-value and the [`Method`] used to get it, or a [`StatsError`] for
//! input no test can use (an empty sample, a NaN, paired samples of unequal
//! length). No input makes them panic or hang.
//!
//! # Why not a crate
//!
//! `statrs` 0.19 has Mann-Whitney and two-sample Kolmogorov-Smirnov but no
//! Wilcoxon signed-rank test, and its implementations hang on inputs we meet
//! in practice (8 values against 300; two identical samples of 500 values).
//! `stats-claw` has all three but is young and has a single maintainer. The
//! algorithms below are short, are taken from SciPy's own source, and are
//! tested against SciPy's output (`scripts/scipy_reference.py` regenerates the
//! reference values), so we keep them here with no extra dependency. The normal
//! CDF is a port of Cephes' `ndtr`, the routine SciPy itself calls, so the
//! asymptotic p-values agree to rounding.
//!
//! # Methods, as SciPy chooses them
//!
//! * Wilcoxon: exact null distribution when `n <= 50` and there are neither
//!   ties among `|d|` nor zero differences; when there are ties or zeros and
//!   `n <= 13`, SciPy (since 1.13) runs `permutation_test`, which for
//!   `2^n <= 9999` enumerates every sign flip and so is deterministic and
//!   exact: we enumerate the same distribution; otherwise the normal
//!   approximation with tie correction (and optional continuity correction).
//! * Mann-Whitney: exact when at least one sample has at most 8 values and
//!   there are no ties; otherwise the normal approximation with tie and
//!   continuity correction.
//! * Kolmogorov-Smirnov: exact when both samples have at most 10000 values;
//!   otherwise the finite-n distribution of the one-sample two-sided
//!   statistic (SciPy's `kstwo`) at `n = round(n1 n2 / (n1 + n2))`.

#[cfg(test)]
mod fixtures;
mod kolmogorov;
mod ks;
mod mann_whitney;
mod normal;
mod wilcoxon;

pub use ks::ks_2samp;
pub use mann_whitney::mann_whitney_u;
pub use wilcoxon::{wilcoxon, wilcoxon_diffs};

use std::cmp::Ordering;

/// How a p-value was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// From the exact null distribution of the statistic.
    Exact,
    /// By enumerating every permutation (here: every sign flip) of the data,
    /// as `scipy.stats.permutation_test` does when it can afford all of them.
    /// Deterministic and exact for the observed ranks, ties included.
    Permutation,
    /// From a large-sample approximation (normal for the rank tests, the
    /// finite-n Kolmogorov distribution for Kolmogorov-Smirnov).
    Asymptotic,
}

/// The outcome of a two-sided test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TestResult {
    /// The test statistic as SciPy reports it; see each test for which one.
    pub statistic: f64,
    /// Two-sided p-value, always in `[0, 1]`.
    pub p_value: f64,
    /// How `p_value` was computed.
    pub method: Method,
}

/// Input that none of the tests can use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum StatsError {
    /// A sample has no observations.
    #[error("empty sample: each sample needs at least one observation")]
    EmptySample,
    /// Paired samples must have one `y` for every `x`.
    #[error("paired samples differ in length: x has {x} values, y has {y}")]
    LengthMismatch {
        /// Length of `x`.
        x: usize,
        /// Length of `y`.
        y: usize,
    },
    /// A NaN in the input, or a paired difference that is NaN (`inf - inf`).
    #[error("NaN in input (or a paired difference such as inf - inf)")]
    NaN,
}

/// Rejects empty or NaN-containing samples.
fn check_sample(sample: &[f64]) -> Result<(), StatsError> {
    if sample.is_empty() {
        return Err(StatsError::EmptySample);
    }
    if sample.iter().any(|v| v.is_nan()) {
        return Err(StatsError::NaN);
    }
    Ok(())
}

/// Total order on NaN-free values in which `-0.0 == 0.0`, as in NumPy.
fn cmp_values(a: &f64, b: &f64) -> Ordering {
    // Adding 0.0 maps -0.0 to +0.0, which `total_cmp` would otherwise order
    // below it.
    (a + 0.0).total_cmp(&(b + 0.0))
}

/// Average ("mid") ranks, 1-based, as `scipy.stats.rankdata(..., 'average')`,
/// together with the size of every group of tied values.
///
/// The input must be NaN-free.
fn rank_average(values: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&i, &j| cmp_values(&values[i], &values[j]));
    let mut ranks = vec![0.0; values.len()];
    let mut ties = Vec::new();
    let mut start = 0;
    while start < order.len() {
        let first = values[order[start]];
        let end = start + order[start..].iter().take_while(|&&i| values[i] == first).count();
        let size = end - start;
        // Same expression as SciPy: first ordinal rank + (count - 1) / 2.
        let rank = (start + 1) as f64 + (size as f64 - 1.0) / 2.0;
        for &i in &order[start..end] {
            ranks[i] = rank;
        }
        ties.push(size);
        start = end;
    }
    (ranks, ties)
}

/// `sum(t^3 - t)` over tie-group sizes `t`: the tie correction term shared by
/// the normal approximations of both rank tests.
fn tie_term(ties: &[usize]) -> f64 {
    ties.iter()
        .map(|&t| {
            let t = t as f64;
            t * t * t - t
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranks_match_scipy_rankdata() {
        // scipy.stats.rankdata([3, 2, 1, 2, 2, 2, 1, -0.0, 0.0])
        // -> [9. , 6.5, 3.5, 6.5, 6.5, 6.5, 3.5, 1.5, 1.5]
        let (ranks, ties) = rank_average(&[3.0, 2.0, 1.0, 2.0, 2.0, 2.0, 1.0, -0.0, 0.0]);
        assert_eq!(ranks, [9.0, 6.5, 3.5, 6.5, 6.5, 6.5, 3.5, 1.5, 1.5]);
        assert_eq!(ties, [2, 2, 4, 1]);
        assert_eq!(tie_term(&ties), 6.0 + 6.0 + 60.0);
    }

    #[test]
    fn check_sample_rejects_bad_input() {
        assert_eq!(check_sample(&[]), Err(StatsError::EmptySample));
        assert_eq!(check_sample(&[1.0, f64::NAN]), Err(StatsError::NaN));
        assert_eq!(check_sample(&[f64::INFINITY, 1.0]), Ok(()));
    }
}
