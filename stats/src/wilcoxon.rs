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
        return Err(StatsError::LengthMismatch { x: x.len(), y: y.len() });
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
        (
            asymptotic_p(r_plus, nonzero.len(), &ties, correction),
            Method::Asymptotic,
        )
    } else if !has_ties && !has_zeros {
        // No ties and no zeros: ranks are 1..=n and W+ is an integer.
        (exact_p(r_plus as usize, n), Method::Exact)
    } else if n <= PERMUTATION_MAX_N {
        (permutation_p(&nonzero, &ranks), Method::Permutation)
    } else {
        (
            asymptotic_p(r_plus, nonzero.len(), &ties, correction),
            Method::Asymptotic,
        )
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
fn exact_p(w: usize, n: usize) -> f64 {
    debug_assert!(n <= EXACT_MAX_N);
    let counts = signed_rank_counts(n);
    let w = w.min(counts.len() - 1);
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
    use crate::fixtures::{D_60, PAIRED_A, PAIRED_B, assert_close};
    use proptest::prelude::*;

    /// Checks a result against SciPy's statistic and p-value.
    ///
    /// One relative tolerance, 1e-9, for every case: exact and permutation
    /// p-values are exact dyadic fractions here and in SciPy within a few
    /// ulps (SciPy sums float pmfs; for its upper tail it computes
    /// `1 - cdf`, which costs it about 1e-16 absolute), and asymptotic ones
    /// use SciPy's formula in SciPy's operation order with the same `ndtr`.
    fn check(res: TestResult, statistic: f64, p: f64, method: Method) {
        assert_eq!(res.method, method, "method");
        assert_close(res.statistic, statistic, 1e-12, "statistic");
        assert_close(res.p_value, p, 1e-9, "p-value");
    }

    /// Runs the differences with and without continuity correction.
    fn check_both(d: &[f64], statistic: f64, p: f64, p_corrected: f64, method: Method) {
        check(wilcoxon_diffs(d, false).unwrap(), statistic, p, method);
        check(wilcoxon_diffs(d, true).unwrap(), statistic, p_corrected, method);
    }

    /// `k * sign` for `k` in `1..=n`, negative where `k % 7 == 0`.
    fn sevens_negative(n: usize) -> Vec<f64> {
        (1..=n)
            .map(|k| if k % 7 == 0 { -(k as f64) } else { k as f64 })
            .collect()
    }

    const X10: [f64; 10] = [125.0, 115.0, 130.0, 140.0, 141.0, 115.0, 140.0, 125.0, 140.0, 135.0];
    const Y10: [f64; 10] = [110.0, 122.0, 125.0, 120.0, 140.0, 124.0, 123.0, 137.0, 134.0, 145.0];

    #[test]
    fn exact_small_no_ties() {
        // d = [15, -7, 5, 20, 1, -9, 17, -12, 6, -10]
        // scipy.stats.wilcoxon(X10, Y10, correction=False)
        //   -> statistic=22.0, pvalue=0.625 (same with correction=True)
        for correction in [false, true] {
            check(wilcoxon(&X10, &Y10, correction).unwrap(), 22.0, 0.625, Method::Exact);
            // scipy.stats.wilcoxon(Y10, X10) -> same: W+ is now above its mean.
            check(wilcoxon(&Y10, &X10, correction).unwrap(), 22.0, 0.625, Method::Exact);
        }
    }

    #[test]
    fn paired_and_differences_agree() {
        let d: Vec<f64> = X10.iter().zip(&Y10).map(|(x, y)| x - y).collect();
        assert_eq!(wilcoxon(&X10, &Y10, false), wilcoxon_diffs(&d, false));
    }

    #[test]
    fn exact_twenty_small_p() {
        // scipy.stats.wilcoxon(np.arange(1, 21) * [1,1,1,-1,1,1,1,1,1,1,1,1,-1,1,1,1,1,1,1,1])
        //   -> statistic=17.0, pvalue=0.0003948211669921875 (either correction)
        let d: Vec<f64> = (1..=20)
            .map(|k| if k == 4 || k == 13 { -(k as f64) } else { k as f64 })
            .collect();
        check_both(&d, 17.0, 0.0003948211669921875, 0.0003948211669921875, Method::Exact);
    }

    #[test]
    fn exact_up_to_fifty_then_asymptotic() {
        // scipy.stats.wilcoxon(np.arange(1, 51) * np.where(np.arange(1, 51) % 7 == 0, -1, 1))
        //   -> statistic=196.0, pvalue=6.725303951071737e-06 (either correction)
        check_both(
            &sevens_negative(50),
            196.0,
            6.725303951071737e-06,
            6.725303951071737e-06,
            Method::Exact,
        );
        // scipy.stats.wilcoxon(np.arange(1, 52) * np.where(np.arange(1, 52) % 7 == 0, -1, 1),
        //                      correction=False / True)
        //   -> statistic=196.0, pvalue=1.2009846283141958e-05 / 1.2270677073752492e-05
        check_both(
            &sevens_negative(51),
            196.0,
            1.2009846283141958e-05,
            1.2270677073752492e-05,
            Method::Asymptotic,
        );
    }

    #[test]
    fn permutation_with_ties() {
        // scipy.stats.wilcoxon([3, -1, 4, 1, -5, 9, 2, 6, 5, 3])
        //   -> statistic=9.0, pvalue=0.068359375 (either correction)
        let d = [3.0, -1.0, 4.0, 1.0, -5.0, 9.0, 2.0, 6.0, 5.0, 3.0];
        check_both(&d, 9.0, 0.068359375, 0.068359375, Method::Permutation);
    }

    #[test]
    fn permutation_with_zeros_and_ties() {
        // d = [1, 0, 2, 0, -2, 3, 3, 7]
        // scipy.stats.wilcoxon([1, 2, 3, 4, 5, 6, 7, 8], [0, 2, 1, 4, 7, 3, 4, 1])
        //   -> statistic=2.5, pvalue=0.125 (either correction)
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let y = [0.0, 2.0, 1.0, 4.0, 7.0, 3.0, 4.0, 1.0];
        for correction in [false, true] {
            check(wilcoxon(&x, &y, correction).unwrap(), 2.5, 0.125, Method::Permutation);
        }
    }

    #[test]
    fn zeros_switch_to_asymptotic_after_thirteen() {
        // scipy.stats.wilcoxon([0, 0, 2, -2, 3, 3, 5, 6, 7, -8, 9, 10, 11])
        //   -> statistic=9.5, pvalue=0.033203125 (either correction)
        let d13 = [0.0, 0.0, 2.0, -2.0, 3.0, 3.0, 5.0, 6.0, 7.0, -8.0, 9.0, 10.0, 11.0];
        check_both(&d13, 9.5, 0.033203125, 0.033203125, Method::Permutation);
        // scipy.stats.wilcoxon([0, 0, 2, -2, 3, 3, 5, 6, 7, -8, 9, 10, 11, 12],
        //                      correction=False / True)
        //   -> statistic=9.5, pvalue=0.020560857843039838 / 0.022804197398267025
        let mut d14 = d13.to_vec();
        d14.push(12.0);
        check_both(
            &d14,
            9.5,
            0.020560857843039838,
            0.022804197398267025,
            Method::Asymptotic,
        );
    }

    #[test]
    fn asymptotic_with_zeros_and_ties() {
        // scipy.stats.wilcoxon([0, 1, -1, 2, 2, -3, 4, 4, 4, 5, -5, 6, 0, 7, 8, 8, -9, 10,
        //                       11, 12, 0, 13, 14, -14, 15, 16, 17, 17, 18, 19],
        //                      correction=False / True)
        //   -> statistic=51.5, pvalue=0.0009510195261284628 / 0.0009926103984138972
        let d = [
            0.0, 1.0, -1.0, 2.0, 2.0, -3.0, 4.0, 4.0, 4.0, 5.0, -5.0, 6.0, 0.0, 7.0, 8.0, 8.0, -9.0, 10.0, 11.0, 12.0,
            0.0, 13.0, 14.0, -14.0, 15.0, 16.0, 17.0, 17.0, 18.0, 19.0,
        ];
        check_both(
            &d,
            51.5,
            0.0009510195261284628,
            0.0009926103984138972,
            Method::Asymptotic,
        );
    }

    #[test]
    fn asymptotic_sixty_without_ties() {
        // scipy.stats.wilcoxon(D_60, correction=False / True)
        //   -> statistic=456.0, pvalue=0.0007275641822625827 / 0.0007373661058458664
        check_both(
            &D_60,
            456.0,
            0.0007275641822625827,
            0.0007373661058458664,
            Method::Asymptotic,
        );
    }

    #[test]
    fn realistic_paired_step_counts() {
        // 200 paired episodes, step counts 5..1000 with failures at 1000: many
        // zero differences (both failed) and many ties.
        // scipy.stats.wilcoxon(PAIRED_A, PAIRED_B, correction=False / True)
        //   -> statistic=1921.5, pvalue=0.2408876290008607 / 0.24164477624326064
        let plain = wilcoxon(&PAIRED_A, &PAIRED_B, false).unwrap();
        check(plain, 1921.5, 0.2408876290008607, Method::Asymptotic);
        let corrected = wilcoxon(&PAIRED_A, &PAIRED_B, true).unwrap();
        check(corrected, 1921.5, 0.24164477624326064, Method::Asymptotic);
    }

    #[test]
    fn all_zero_differences() {
        // scipy.stats.wilcoxon([0, 0, 0, 0, 0]) -> statistic=0.0, pvalue=1.0
        check_both(&[0.0; 5], 0.0, 1.0, 1.0, Method::Permutation);
        // scipy.stats.wilcoxon(np.zeros(20)) -> statistic=0.0, pvalue=nan (with a
        // RuntimeWarning); we return 1.0 by design (see `wilcoxon_diffs`).
        check_both(&[0.0; 20], 0.0, 1.0, 1.0, Method::Asymptotic);
        // Two identical agents over 500 episodes.
        let same = [1000.0; 500];
        check(wilcoxon(&same, &same, false).unwrap(), 0.0, 1.0, Method::Asymptotic);
    }

    #[test]
    fn tiny_samples_and_signed_zero() {
        // scipy.stats.wilcoxon([-0.5]) -> statistic=0.0, pvalue=1.0
        check_both(&[-0.5], 0.0, 1.0, 1.0, Method::Exact);
        // -0.0 is a zero difference too.
        // scipy.stats.wilcoxon([0.0, -0.0, 1.0, 2.0, -3.0]) -> statistic=3.0, pvalue=1.0
        check_both(&[0.0, -0.0, 1.0, 2.0, -3.0], 3.0, 1.0, 1.0, Method::Permutation);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert_eq!(
            wilcoxon(&[1.0, 2.0], &[1.0], false),
            Err(StatsError::LengthMismatch { x: 2, y: 1 })
        );
        assert_eq!(wilcoxon(&[], &[], false), Err(StatsError::EmptySample));
        assert_eq!(wilcoxon_diffs(&[], true), Err(StatsError::EmptySample));
        assert_eq!(wilcoxon(&[1.0, f64::NAN], &[0.0, 0.0], false), Err(StatsError::NaN));
        assert_eq!(wilcoxon(&[0.0, 1.0], &[0.0, f64::NAN], false), Err(StatsError::NaN));
        // inf - inf is NaN
        let inf = f64::INFINITY;
        assert_eq!(wilcoxon(&[inf, 1.0], &[inf, 0.0], false), Err(StatsError::NaN));
        assert_eq!(wilcoxon_diffs(&[f64::NAN], false), Err(StatsError::NaN));
    }

    #[test]
    fn exact_distribution_sums_to_one() {
        for n in [1, 2, 10, 50] {
            let counts = signed_rank_counts(n);
            assert_eq!(counts.iter().sum::<u64>(), 1u64 << n);
            // Symmetric about n(n+1)/4.
            assert!(counts.iter().eq(counts.iter().rev()));
        }
    }

    /// Small integer differences, so that ties and zeros are common.
    fn diffs() -> impl Strategy<Value = Vec<f64>> {
        prop::collection::vec((-6i32..=6).prop_map(f64::from), 1..70)
    }

    proptest! {
        #[test]
        fn p_value_is_a_probability(d in diffs(), correction in any::<bool>()) {
            let res = wilcoxon_diffs(&d, correction).unwrap();
            prop_assert!((0.0..=1.0).contains(&res.p_value), "{res:?}");
            let n = d.len() as f64;
            prop_assert!(res.statistic >= 0.0 && res.statistic <= n * (n + 1.0) / 4.0);
        }

        #[test]
        fn swapping_samples_keeps_p(
            pairs in prop::collection::vec((0i32..20, 0i32..20), 1..70),
            correction in any::<bool>(),
        ) {
            let x: Vec<f64> = pairs.iter().map(|p| f64::from(p.0)).collect();
            let y: Vec<f64> = pairs.iter().map(|p| f64::from(p.1)).collect();
            let xy = wilcoxon(&x, &y, correction).unwrap();
            let yx = wilcoxon(&y, &x, correction).unwrap();
            prop_assert_eq!(xy, yx);
        }

        #[test]
        fn rescaling_differences_keeps_result(d in diffs(), correction in any::<bool>()) {
            // Ranks are unchanged by a positive scale (a power of two keeps
            // the arithmetic exact).
            let scaled: Vec<f64> = d.iter().map(|v| v * 4.0).collect();
            prop_assert_eq!(
                wilcoxon_diffs(&d, correction).unwrap(),
                wilcoxon_diffs(&scaled, correction).unwrap()
            );
        }

        #[test]
        fn constant_shift_is_the_most_extreme(
            x in prop::collection::vec(0i32..1000, 1..70),
            c in 1i32..100,
        ) {
            // x vs x + c: every difference is -c, so W+ = 0, and the p-value is
            // that of n equal negative differences whatever x and c are.
            let xs: Vec<f64> = x.iter().map(|&v| f64::from(v)).collect();
            let shifted: Vec<f64> = x.iter().map(|&v| f64::from(v + c)).collect();
            let res = wilcoxon(&xs, &shifted, false).unwrap();
            prop_assert_eq!(res.statistic, 0.0);
            let reference = wilcoxon_diffs(&vec![-1.0; x.len()], false).unwrap();
            prop_assert_eq!(res.p_value, reference.p_value);
            // Moving one difference to the positive side does not do better.
            let mixed: Vec<f64> = (0..x.len()).map(|i| if i == 0 { 1.0 } else { -1.0 }).collect();
            prop_assert!(wilcoxon_diffs(&mixed, false).unwrap().p_value >= res.p_value);
        }
    }
}
