//! Wilcoxon signed-rank test, a port of `scipy.stats.wilcoxon`
//! (scipy/stats/_wilcoxon.py) with `zero_method='wilcox'`,
//! `alternative='two-sided'` and `method='auto'`.

use super::normal::ndtr;
use super::{Method, StatsError, TestResult, rank_average, tie_term};

/// Largest `n` for which SciPy's `method='auto'` considers the exact null
/// distribution.
const EXACT_MAX_N: usize = 50;

/// Largest `n` for which SciPy's `method='auto'` falls back to an exhaustive
/// permutation test when there are ties or zeros: `2^13 = 8192` sign flips
/// fit within `permutation_test`'s default 9999 resamples, so SciPy then
/// enumerates them all.
const PERMUTATION_MAX_N: usize = 13;

/// Two-sided Wilcoxon signed-rank test on paired samples, testing whether
/// the differences `x[i] - y[i]` are symmetric about zero.
///
/// Matches `scipy.stats.wilcoxon(x, y, correction=correction)` with SciPy's
/// other defaults (SciPy's default is `correction=False`); see
/// [`wilcoxon_diffs`] for the method chosen and the degenerate cases.
///
/// # Errors
///
/// [`StatsError::LengthMismatch`] if `x` and `y` differ in length,
/// [`StatsError::EmptySample`] if they are empty, and [`StatsError::NaN`] if
/// either holds a NaN or a difference is NaN (`inf - inf`).
pub fn wilcoxon(x: &[f64], y: &[f64], correction: bool) -> Result<TestResult, StatsError> {
    if x.len() != y.len() {
        return Err(StatsError::LengthMismatch {
            x: x.len(),
            y: y.len(),
        });
    }
    if x.iter().chain(y).any(|v| v.is_nan()) {
        return Err(StatsError::NaN);
    }
    let d: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    wilcoxon_diffs(&d, correction)
}

/// Two-sided Wilcoxon signed-rank test on paired differences `d`.
///
/// Matches `scipy.stats.wilcoxon(d, correction=correction)`. Zero
/// differences are dropped before ranking (SciPy's default
/// `zero_method='wilcox'`), and `|d|` is ranked with average ranks for ties.
///
/// The statistic is `min(W+, W-)`, the smaller of the rank sums of the
/// positive and of the negative differences, as SciPy reports it for a
/// two-sided test.
///
/// The p-value follows SciPy's `method='auto'`, with `n = d.len()` counting
/// zeros:
///
/// * [`Method::Exact`] when `n <= 50` and there are no zeros and no ties in
///   `|d|`: twice the smaller tail of the exact null distribution of `W+`,
///   computed with integer counts (so it is exact; `correction` is unused).
/// * [`Method::Permutation`] when there are zeros or ties and `n <= 13`:
///   SciPy then runs `permutation_test`, which enumerates all `2^n` sign
///   flips; we enumerate the same null distribution of `W+` given the
///   observed ranks and take twice the smaller tail (`correction` unused).
/// * [`Method::Asymptotic`] otherwise: `z = (W+ - n'(n'+1)/4) / se` with
///   `se^2 = (n'(n'+1)(2n'+1) - sum(t^3 - t)/2) / 24`, where `n'` is the
///   number of non-zero differences and `t` runs over tie-group sizes. With
///   `correction`, `|z|` is reduced by `0.5 / se` (SciPy's
///   `correction=True`). `p = 2 * Phi(-|z|)`.
///
/// When every difference is zero there is no evidence of a shift and we
/// return statistic 0 and p-value 1. That is what SciPy returns for
/// `n <= 13`; for larger `n` SciPy returns a NaN p-value with a warning, and
/// we deliberately return 1 instead.
///
/// # Errors
///
/// [`StatsError::EmptySample`] if `d` is empty, [`StatsError::NaN`] if it
/// holds a NaN.
pub fn wilcoxon_diffs(d: &[f64], correction: bool) -> Result<TestResult, StatsError> {
    super::check_sample(d)?;
    let n = d.len();
    let nonzero: Vec<f64> = d.iter().copied().filter(|&v| v != 0.0).collect();
    let has_zeros = nonzero.len() < n;

    if nonzero.is_empty() {
        return Ok(TestResult {
            statistic: 0.0,
            p_value: 1.0,
            method: if n <= PERMUTATION_MAX_N {
                Method::Permutation
            } else {
                Method::Asymptotic
            },
        });
    }

    let abs: Vec<f64> = nonzero.iter().map(|v| v.abs()).collect();
    let (ranks, ties) = rank_average(&abs);
    let has_ties = ties.iter().any(|&t| t > 1);
    let (mut r_plus, mut r_minus) = (0.0, 0.0);
    for (v, r) in nonzero.iter().zip(&ranks) {
        if *v > 0.0 {
            r_plus += r;
        } else {
            r_minus += r;
        }
    }
    let statistic = f64::min(r_plus, r_minus);

    let (p_value, method) = if n > EXACT_MAX_N {
        (asymptotic_p(r_plus, nonzero.len(), &ties, correction), Method::Asymptotic)
    } else if !has_ties && !has_zeros {
        // No ties and no zeros: ranks are 1..=n and W+ is an integer.
        (exact_p(r_plus as u64, n), Method::Exact)
    } else if n <= PERMUTATION_MAX_N {
        (permutation_p(&nonzero, &ranks), Method::Permutation)
    } else {
        (asymptotic_p(r_plus, nonzero.len(), &ties, correction), Method::Asymptotic)
    };
    Ok(TestResult {
        statistic,
        p_value,
        method,
    })
}

/// Number of sign assignments of ranks `1..=n` giving each value of `W+`,
/// indexed by `W+` in `0..=n(n+1)/2`. Requires `n <= 63` to fit `u64`.
fn signed_rank_counts(n: usize) -> Vec<u64> {
    let max = n * (n + 1) / 2;
    let mut counts = vec![0u64; max + 1];
    counts[0] = 1;
    for k in 1..=n {
        // Either rank k is positive (W+ grows by k) or it is not.
        let top = k * (k + 1) / 2;
        for w in (k..=top).rev() {
            counts[w] += counts[w - k];
        }
    }
    counts
}

/// Two-sided exact p-value for `W+ = w` with `n` untied, non-zero
/// differences: `2 * min(P(W+ <= w), P(W+ >= w))`, capped at 1.
fn exact_p(w: u64, n: usize) -> f64 {
    debug_assert!(n <= EXACT_MAX_N);
    let counts = signed_rank_counts(n);
    let w = usize::try_from(w).unwrap_or(usize::MAX).min(counts.len() - 1);
    let lower: u64 = counts[..=w].iter().sum();
    let upper: u64 = counts[w..].iter().sum();
    // Counts are below 2^51, so these conversions and the division by the
    // power of two 2^n are exact.
    let tail = 2 * lower.min(upper);
    (tail as f64 / (n as f64).exp2()).min(1.0)
}

/// Two-sided p-value from all `2^n'` sign flips of the non-zero differences
/// with their observed (possibly tied) ranks: `2 * min(P(W+ <= w),
/// P(W+ >= w))`, capped at 1.
///
/// This is SciPy's exhaustive `permutation_test` for `n <= 13`. Flipping a
/// zero difference does not change `W+`, so enumerating the `n'` non-zero
/// ones gives the same proportions as SciPy's `2^n`.
fn permutation_p(nonzero: &[f64], ranks: &[f64]) -> f64 {
    // Average ranks are multiples of 1/2: work with doubled ranks as integers
    // so that comparisons with the observed W+ are exact.
    let doubled: Vec<usize> = ranks.iter().map(|r| (2.0 * r) as usize).collect();
    let observed: usize = nonzero
        .iter()
        .zip(&doubled)
        .filter(|(v, _)| **v > 0.0)
        .map(|(_, r)| r)
        .sum();
    let total: usize = doubled.iter().sum();
    let mut counts = vec![0u64; total + 1];
    counts[0] = 1;
    let mut reach = 0;
    for &r in &doubled {
        reach += r;
        for w in (r..=reach).rev() {
            counts[w] += counts[w - r];
        }
    }
    let lower: u64 = counts[..=observed].iter().sum();
    let upper: u64 = counts[observed..].iter().sum();
    let tail = 2 * lower.min(upper);
    (tail as f64 / (nonzero.len() as f64).exp2()).min(1.0)
}

/// Two-sided normal-approximation p-value, with SciPy's tie correction and
/// optional continuity correction, written in SciPy's operation order.
fn asymptotic_p(r_plus: f64, count: usize, ties: &[usize], correction: bool) -> f64 {
    let count = count as f64;
    let mean = count * (count + 1.0) * 0.25;
    let var24 = count * (count + 1.0) * (2.0 * count + 1.0);
    let se = ((var24 - tie_term(ties) / 2.0) / 24.0).sqrt();
    let mut z = (r_plus - mean) / se;
    if correction {
        // SciPy subtracts sign(z) * 0.5 / se (no correction when z == 0).
        let sign = if z > 0.0 {
            1.0
        } else if z < 0.0 {
            -1.0
        } else {
            0.0
        };
        z -= sign * 0.5 / se;
    }
    let p = 2.0 * ndtr(-z.abs());
    if p.is_nan() { 1.0 } else { p.clamp(0.0, 1.0) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn assert_close(got: f64, want: f64, rel: f64, what: &str) {
        let err = if got == want {
            0.0
        } else {
            (got - want).abs() / want.abs().max(f64::MIN_POSITIVE)
        };
        assert!(err <= rel, "{what}: got {got:e}, scipy {want:e} (rel err {err:e})");
    }

    /// Checks a result against SciPy's statistic and p-value. All Wilcoxon
    /// cases use the same 1e-9 relative tolerance: exact and permutation
    /// p-values are computed exactly here and in SciPy to a few ulps, and the
    /// asymptotic ones use the same formula and the same `ndtr` as SciPy.
    fn check(res: TestResult, statistic: f64, p: f64, method: Method) {
        assert_eq!(res.method, method);
        assert_close(res.statistic, statistic, 1e-12, "statistic");
        assert_close(res.p_value, p, 1e-9, "p-value");
    }

    const SMALL_X: [f64; 10] = [
        125.0, 115.0, 130.0, 140.0, 140.0, 115.0, 140.0, 125.0, 140.0, 135.0,
    ];
    const SMALL_Y: [f64; 10] = [
        110.0, 122.0, 125.0, 120.0, 141.0, 124.0, 123.0, 137.0, 135.0, 145.0,
    ];

    #[test]
    fn exact_small() {
        // d = SMALL_X - SMALL_Y = [15, -7, 5, 20, -1, -9, 17, -12, 5, -10]:
        // |d| has a tie (5, 5), so this is the permutation branch; see
        // `exact_no_ties` for the exact one.
        // scipy.stats.wilcoxon(x, y) -> statistic=27.0, pvalue=1.0 ...
        let res = wilcoxon(&SMALL_X, &SMALL_Y, false).unwrap();
        check(res, 27.0, 1.0, Method::Permutation);
    }
}
