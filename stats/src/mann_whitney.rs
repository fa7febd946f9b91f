//! Mann-Whitney U test, a port of `scipy.stats.mannwhitneyu`
//! (scipy/stats/_mannwhitneyu.py) with `use_continuity=True`,
//! `alternative='two-sided'` and `method='auto'`.

use super::normal::ndtr;
use super::{Method, StatsError, TestResult, check_sample, rank_average, tie_term};

/// SciPy's `method='auto'` uses the exact distribution only when at least
/// one sample is at most this long (and there are no ties).
const EXACT_MAX_MIN_N: usize = 8;

/// Two-sided Mann-Whitney U test of whether `x` and `y` come from the same
/// distribution.
///
/// Matches `scipy.stats.mannwhitneyu(x, y)` (SciPy's defaults). The
/// statistic is `U1 = R1 - n1(n1+1)/2`, where `R1` is the sum of the
/// average ranks of `x` in the pooled sample: the statistic of the first
/// sample, as SciPy reports it (`U2 = n1 n2 - U1`).
///
/// The p-value follows SciPy's `method='auto'`:
///
/// * [`Method::Exact`] when `min(n1, n2) <= 8` and no value occurs twice in
///   the pooled sample: `2 * P(U <= min(U1, U2))` under the exact null
///   distribution, capped at 1. The distribution is the coefficient list of
///   the Gaussian binomial `[n1 + n2, n1]_q`, built by the product formula
///   in `O(min(n1, n2) * min(U1, U2))` time and `O(min(U1, U2))` memory,
///   so 8 values against 300 (or against 100 000) are quick.
/// * [`Method::Asymptotic`] otherwise: the normal approximation with tie
///   correction and continuity correction,
///   `z = (max(U1, U2) - n1 n2 / 2 - 0.5) / s` with
///   `s^2 = n1 n2 / 12 * (n + 1 - sum(t^3 - t) / (n (n - 1)))`, and
///   `p = min(1, 2 * Phi(-z))`.
///
/// If every pooled value is the same, `s = 0`; SciPy then gets `p = 1`
/// through an infinite `z`, and so do we (explicitly).
///
/// # Errors
///
/// [`StatsError::EmptySample`] if either sample is empty,
/// [`StatsError::NaN`] if either holds a NaN.
pub fn mann_whitney_u(x: &[f64], y: &[f64]) -> Result<TestResult, StatsError> {
    check_sample(x)?;
    check_sample(y)?;
    let (n1, n2) = (x.len(), y.len());
    let pooled: Vec<f64> = x.iter().chain(y).copied().collect();
    let (ranks, ties) = rank_average(&pooled);
    let r1: f64 = ranks[..n1].iter().sum();
    let (n1f, n2f) = (n1 as f64, n2 as f64);
    let u1 = r1 - n1f * (n1f + 1.0) / 2.0;
    let u2 = n1f * n2f - u1;
    let has_ties = ties.iter().any(|&t| t > 1);

    let (p_value, method) = if n1.min(n2) <= EXACT_MAX_MIN_N && !has_ties {
        // Without ties U1 and U2 are integers.
        let smaller = u1.min(u2) as usize;
        (exact_p(smaller, n1, n2), Method::Exact)
    } else {
        (asymptotic_p(u1.max(u2), n1, n2, &ties), Method::Asymptotic)
    };
    Ok(TestResult {
        statistic: u1,
        p_value,
        method,
    })
}

/// Two-sided exact p-value, `2 * P(U <= k)` capped at 1, where `k` is the
/// smaller of `U1` and `U2` (the null distribution is symmetric).
fn exact_p(k: usize, n1: usize, n2: usize) -> f64 {
    let (small, large) = (n1.min(n2), n1.max(n2));
    let counts = u_counts(small, large, k);
    let below: f64 = counts.iter().sum();
    (2.0 * below / binomial(small + large, small)).min(1.0)
}

/// Number of ways to get `U = u` for `u` in `0..=max_u`, with `small <=
/// large` sample sizes.
///
/// These are the coefficients of the Gaussian binomial
/// `prod_{k=1..small} (1 - q^(large + k)) / (1 - q^k)`, truncated to degree
/// `max_u`. After step `k` the partial product is `[large + k, k]_q`, whose
/// coefficients are non-negative integers, so each division by `1 - q^k` is
/// exact. Multiplying by `1 - q^m` is a strided subtraction and dividing by
/// `1 - q^k` a strided running sum. In `f64` the counts stay exact up to
/// 2^53; beyond that the relative error stays near 1e-15 (checked against
/// exact integers for 8 against 20000), far below what a p-value needs.
fn u_counts(small: usize, large: usize, max_u: usize) -> Vec<f64> {
    let mut c = vec![0.0; max_u + 1];
    c[0] = 1.0;
    for k in 1..=small {
        let m = large + k;
        for u in (m..=max_u).rev() {
            c[u] -= c[u - m];
        }
        for u in k..=max_u {
            c[u] += c[u - k];
        }
    }
    c
}

/// `C(n, k)` in floating point, exact while it fits in 53 bits.
fn binomial(n: usize, k: usize) -> f64 {
    let k = k.min(n - k);
    // Each partial product C(n - k + i, i) is an integer.
    (1..=k).fold(1.0, |acc, i| acc * (n - k + i) as f64 / i as f64)
}

/// Two-sided normal-approximation p-value with tie and continuity
/// correction, in SciPy's operation order.
fn asymptotic_p(u: f64, n1: usize, n2: usize, ties: &[usize]) -> f64 {
    let (n1f, n2f) = (n1 as f64, n2 as f64);
    let n = n1f + n2f;
    let mu = n1f * n2f / 2.0;
    let s = (n1f * n2f / 12.0 * ((n + 1.0) - tie_term(ties) / (n * (n - 1.0)))).sqrt();
    // All values tied: U1 = U2 = mu and nothing separates the samples.
    // (Rounding can leave s slightly negative inside the root, giving NaN.)
    if s.is_nan() || s <= 0.0 {
        return 1.0;
    }
    // SciPy always subtracts 0.5: U is the larger of U1 and U2.
    let z = (u - mu - 0.5) / s;
    (2.0 * ndtr(-z)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{
        DISTINCT_8, DISTINCT_300, STEPS_8, STEPS_200, STEPS_250, STEPS_300, STEPS_500_A, STEPS_500_B, assert_close,
    };
    use proptest::prelude::*;
    use std::time::{Duration, Instant};

    /// Checks a result against SciPy's statistic and p-value, to 1e-9
    /// relative everywhere: exact p-values are ratios of exactly counted
    /// integers on both sides (SciPy's float path beyond 2^64 configurations
    /// is still accurate to ~1e-15), and the asymptotic ones use SciPy's
    /// formula with the same `ndtr`.
    fn check(x: &[f64], y: &[f64], statistic: f64, p: f64, method: Method) {
        let res = mann_whitney_u(x, y).unwrap();
        assert_eq!(res.method, method, "method");
        assert_close(res.statistic, statistic, 1e-12, "statistic");
        assert_close(res.p_value, p, 1e-9, "p-value");
    }

    #[test]
    fn exact_small() {
        // SciPy's docstring example.
        // scipy.stats.mannwhitneyu([19, 22, 16, 29, 24], [20, 11, 17, 12])
        //   -> statistic=17.0, pvalue=0.1111111111111111
        let males = [19.0, 22.0, 16.0, 29.0, 24.0];
        let females = [20.0, 11.0, 17.0, 12.0];
        check(&males, &females, 17.0, 0.1111111111111111, Method::Exact);
        // scipy.stats.mannwhitneyu([20, 11, 17, 12], [19, 22, 16, 29, 24])
        //   -> statistic=3.0, pvalue=0.1111111111111111
        check(&females, &males, 3.0, 0.1111111111111111, Method::Exact);
    }

    #[test]
    fn exact_extremes() {
        // scipy.stats.mannwhitneyu([1, 2, 3, 4, 5], [6, 7, 8, 9, 10])
        //   -> statistic=0.0, pvalue=0.007936507936507936 (= 2 / C(10, 5))
        let low = [1.0, 2.0, 3.0, 4.0, 5.0];
        let high = [6.0, 7.0, 8.0, 9.0, 10.0];
        check(&low, &high, 0.0, 0.007936507936507936, Method::Exact);
        // scipy.stats.mannwhitneyu([1.0], [2.0]) -> statistic=0.0, pvalue=1.0
        check(&[1.0], &[2.0], 0.0, 1.0, Method::Exact);
    }

    #[test]
    fn exact_when_only_one_sample_is_small() {
        // scipy.stats.mannwhitneyu([1.5, 7.25, 3.0],
        //                          [2.0, 4.0, 5.0, 6.0, 8.0, 9.0, 10.0, 11.0, 12.0])
        //   -> statistic=5.0, pvalue=0.14545454545454545
        let x = [1.5, 7.25, 3.0];
        let y = [2.0, 4.0, 5.0, 6.0, 8.0, 9.0, 10.0, 11.0, 12.0];
        check(&x, &y, 5.0, 0.14545454545454545, Method::Exact);
    }

    #[test]
    fn exact_eight_against_three_hundred() {
        // statrs hangs here. No ties, so SciPy uses the exact distribution.
        // scipy.stats.mannwhitneyu(DISTINCT_8, DISTINCT_300)
        //   -> statistic=979.0, pvalue=0.38192991206302285
        check(&DISTINCT_8, &DISTINCT_300, 979.0, 0.38192991206302285, Method::Exact);
        // scipy.stats.mannwhitneyu(DISTINCT_300, DISTINCT_8)
        //   -> statistic=1421.0, pvalue=0.38192991206302285
        check(&DISTINCT_300, &DISTINCT_8, 1421.0, 0.38192991206302285, Method::Exact);
    }

    #[test]
    fn exact_eight_against_twenty_thousand_is_quick() {
        // scipy.stats.mannwhitneyu(X8, np.arange(20000) * 0.5)
        //   -> statistic=56208.0, pvalue=0.14761129573859752
        // 2^64 < C(20008, 8), so SciPy counts in floats here; the two agree
        // to about 1e-13.
        let x8 = [10.25, 100.25, 1000.25, 2000.25, 3000.25, 5000.25, 7000.25, 9990.25];
        let y: Vec<f64> = (0..20_000).map(|i| f64::from(i) * 0.5).collect();
        let start = Instant::now();
        check(&x8, &y, 56208.0, 0.14761129573859752, Method::Exact);
        assert!(start.elapsed() < Duration::from_secs(5));
    }

    #[test]
    fn asymptotic_with_ties() {
        // scipy.stats.mannwhitneyu([1, 2, 2, 3], [2, 3, 4])
        //   -> statistic=2.5, pvalue=0.2663799233424825
        check(
            &[1.0, 2.0, 2.0, 3.0],
            &[2.0, 3.0, 4.0],
            2.5,
            0.2663799233424825,
            Method::Asymptotic,
        );
        // Eight step counts against 300, tied: asymptotic, and quick.
        // scipy.stats.mannwhitneyu(STEPS_8, STEPS_300)
        //   -> statistic=1011.5, pvalue=0.44484557416433823
        check(&STEPS_8, &STEPS_300, 1011.5, 0.44484557416433823, Method::Asymptotic);
    }

    #[test]
    fn asymptotic_when_both_samples_exceed_eight() {
        // scipy.stats.mannwhitneyu([1, 3, 5, 7, 9, 11, 13, 15, 17],
        //                          [2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24])
        //   -> statistic=36.0, pvalue=0.2136207303090525
        let odd: Vec<f64> = (0..9).map(|i| f64::from(2 * i + 1)).collect();
        let even = [2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0, 16.0, 18.0, 20.0, 22.0, 24.0];
        check(&odd, &even, 36.0, 0.2136207303090525, Method::Asymptotic);
    }

    #[test]
    fn realistic_step_counts() {
        // scipy.stats.mannwhitneyu(STEPS_200, STEPS_250)
        //   -> statistic=28921.0, pvalue=0.003483959527869681
        check(
            &STEPS_200,
            &STEPS_250,
            28921.0,
            0.003483959527869681,
            Method::Asymptotic,
        );
        // scipy.stats.mannwhitneyu(STEPS_500_A, STEPS_500_B)
        //   -> statistic=142069.0, pvalue=0.00016555764729030376
        check(
            &STEPS_500_A,
            &STEPS_500_B,
            142069.0,
            0.00016555764729030376,
            Method::Asymptotic,
        );
    }

    #[test]
    fn all_values_tied() {
        // scipy.stats.mannwhitneyu([7.0] * 30, [7.0] * 40) -> statistic=600.0, pvalue=1.0
        check(&[7.0; 30], &[7.0; 40], 600.0, 1.0, Method::Asymptotic);
        // Two agents that never finish: 500 failures each.
        // scipy.stats.mannwhitneyu([1000.0] * 500, [1000.0] * 500)
        //   -> statistic=125000.0, pvalue=1.0
        check(&[1000.0; 500], &[1000.0; 500], 125000.0, 1.0, Method::Asymptotic);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert_eq!(mann_whitney_u(&[], &[1.0]), Err(StatsError::EmptySample));
        assert_eq!(mann_whitney_u(&[1.0], &[]), Err(StatsError::EmptySample));
        assert_eq!(mann_whitney_u(&[1.0, f64::NAN], &[2.0]), Err(StatsError::NaN));
        assert_eq!(mann_whitney_u(&[1.0], &[f64::NAN]), Err(StatsError::NaN));
    }

    #[test]
    fn exact_counts_match_direct_recursion() {
        // Compare the product formula with the textbook recursion
        // f(m, n, u) = f(m - 1, n, u - n) + f(m, n - 1, u).
        fn direct(m: usize, n: usize, u: usize) -> u64 {
            if u > m * n {
                return 0;
            }
            if m == 0 || n == 0 {
                return u64::from(u == 0);
            }
            let with_top = if u >= n { direct(m - 1, n, u - n) } else { 0 };
            with_top + direct(m, n - 1, u)
        }
        for (m, n) in [(1, 1), (3, 5), (4, 7), (6, 6), (8, 9)] {
            let max_u = m * n;
            let counts = u_counts(m, n, max_u);
            for (u, &c) in counts.iter().enumerate() {
                assert_eq!(c, direct(m, n, u) as f64, "m={m} n={n} u={u}");
            }
            assert_eq!(counts.iter().sum::<f64>(), binomial(m + n, m));
        }
    }

    fn sample() -> impl Strategy<Value = Vec<f64>> {
        // Small integers give ties; halves and offsets give tie-free samples.
        prop_oneof![
            prop::collection::vec((0i32..15).prop_map(f64::from), 1..40),
            prop::collection::vec((0i32..10_000).prop_map(|v| f64::from(v) + 0.5), 1..12),
        ]
    }

    proptest! {
        #[test]
        fn p_value_is_a_probability(x in sample(), y in sample()) {
            let res = mann_whitney_u(&x, &y).unwrap();
            prop_assert!((0.0..=1.0).contains(&res.p_value), "{res:?}");
            let n1n2 = (x.len() * y.len()) as f64;
            prop_assert!((0.0..=n1n2).contains(&res.statistic));
        }

        #[test]
        fn swapping_samples_keeps_p(x in sample(), y in sample()) {
            let xy = mann_whitney_u(&x, &y).unwrap();
            let yx = mann_whitney_u(&y, &x).unwrap();
            prop_assert_eq!(xy.p_value, yx.p_value);
            prop_assert_eq!(xy.method, yx.method);
            prop_assert_eq!(xy.statistic + yx.statistic, (x.len() * y.len()) as f64);
        }

        #[test]
        fn shifting_both_samples_keeps_result(x in sample(), y in sample(), c in -100i32..100) {
            let shift = |s: &[f64]| s.iter().map(|v| v + f64::from(c)).collect::<Vec<_>>();
            prop_assert_eq!(mann_whitney_u(&x, &y).unwrap(), mann_whitney_u(&shift(&x), &shift(&y)).unwrap());
        }
    }
}
