//! Two-sample Kolmogorov-Smirnov test, a port of `scipy.stats.ks_2samp`
//! (scipy/stats/_stats_py.py, and `_compute_outer_prob_inside_method` from
//! scipy/stats/_stats_pythran.py) with `alternative='two-sided'` and
//! `method='auto'`.

use super::kolmogorov::kstwo_sf;
use super::{Method, StatsError, TestResult, check_sample, cmp_values};

/// SciPy's `method='auto'` is exact when both samples are at most this long.
const MAX_AUTO_N: usize = 10_000;

/// Two-sided two-sample Kolmogorov-Smirnov test of whether `x` and `y` come
/// from the same continuous distribution.
///
/// Matches `scipy.stats.ks_2samp(x, y)` (SciPy's defaults). The statistic
/// is `D = max |F_x(t) - F_y(t)|` over the pooled values, with `F` the
/// empirical CDFs.
///
/// The p-value follows SciPy's `method='auto'`:
///
/// * [`Method::Exact`] when `max(n1, n2) <= 10000`: `D` is first rounded to
///   a multiple `h / lcm(n1, n2)` (and that rounded value is the reported
///   statistic, as in SciPy). `h = 0` (for instance, identical samples)
///   gives `p = 1` at once. For `n1 == n2` the p-value is the alternating
///   reflection sum for paths leaving the band `|x - y| < h`
///   (`_compute_prob_outside_square`, `O(n)`); otherwise Hodges' lattice
///   path count, in Viehmann's form that directly accumulates the
///   probability of leaving the band (`_compute_outer_prob_inside_method`,
///   `O(n1 * band width)`, at most about 1e8 steps).
/// * [`Method::Asymptotic`] otherwise (or if the exact value were not a
///   probability, which SciPy guards against but which we have not seen):
///   the survival function of the finite-n two-sided one-sample
///   Kolmogorov distribution (SciPy's `kstwo.sf(D, round(en))` with
///   `en = n1 n2 / (n1 + n2)`).
///
/// # Errors
///
/// [`StatsError::EmptySample`] if either sample is empty,
/// [`StatsError::NaN`] if either holds a NaN.
pub fn ks_2samp(x: &[f64], y: &[f64]) -> Result<TestResult, StatsError> {
    check_sample(x)?;
    check_sample(y)?;
    let (n1, n2) = (x.len(), y.len());
    let mut a = x.to_vec();
    let mut b = y.to_vec();
    a.sort_by(cmp_values);
    b.sort_by(cmp_values);
    let gaps = ecdf_gaps(&a, &b);

    if n1.max(n2) <= MAX_AUTO_N {
        // Both at most 10^4, so lcm <= 10^8 fits comfortably.
        let g = gcd(n1, n2);
        let lcm = n1 / g * n2;
        let h = gaps.max_scaled(lcm / n1, lcm / n2);
        let d = h as f64 / lcm as f64;
        if h == 0 {
            return Ok(TestResult {
                statistic: d,
                p_value: 1.0,
                method: Method::Exact,
            });
        }
        let p = if n1 == n2 {
            prob_outside_square(n1, h)
        } else {
            outer_prob_inside(n1, n2, g, h)
        };
        if (0.0..=1.0).contains(&p) {
            return Ok(TestResult {
                statistic: d,
                p_value: p,
                method: Method::Exact,
            });
        }
        // SciPy falls back to the asymptotic p-value (with the rounded D).
        return Ok(asymptotic(d, n1, n2));
    }
    Ok(asymptotic(gaps.max_float(n1, n2), n1, n2))
}

/// The asymptotic p-value: `kstwo.sf(d, round(n1 n2 / (n1 + n2)))`.
fn asymptotic(d: f64, n1: usize, n2: usize) -> TestResult {
    let (m, n) = (n1.max(n2) as f64, n1.min(n2) as f64);
    let en = (m * n / (m + n)).round_ties_even().max(1.0);
    TestResult {
        statistic: d,
        p_value: kstwo_sf(en, d).clamp(0.0, 1.0),
        method: Method::Asymptotic,
    }
}

/// Empirical CDF counts `(#x <= t, #y <= t)` at every distinct pooled value
/// `t`, the points at which SciPy evaluates the CDF difference.
struct EcdfGaps {
    counts: Vec<(usize, usize)>,
}

impl EcdfGaps {
    /// `max |i1 * s1 - i2 * s2|`: `D * lcm` in exact integer arithmetic when
    /// `s1 = lcm / n1` and `s2 = lcm / n2`.
    fn max_scaled(&self, s1: usize, s2: usize) -> usize {
        self.counts
            .iter()
            .map(|&(i1, i2)| (i1 * s1).abs_diff(i2 * s2))
            .max()
            .unwrap_or(0)
    }

    /// `D` from `i1 / n1 - i2 / n2` in floating point, as SciPy computes it
    /// when it does not round `D` for the exact method.
    fn max_float(&self, n1: usize, n2: usize) -> f64 {
        let (n1, n2) = (n1 as f64, n2 as f64);
        let (mut max_s, mut min_s) = (f64::NEG_INFINITY, f64::INFINITY);
        for &(i1, i2) in &self.counts {
            let diff = i1 as f64 / n1 - i2 as f64 / n2;
            max_s = max_s.max(diff);
            min_s = min_s.min(diff);
        }
        let min_s = (-min_s).clamp(0.0, 1.0);
        if min_s > max_s { min_s } else { max_s }
    }
}

/// Walks the two sorted samples together, recording the CDF counts after
/// each distinct value.
fn ecdf_gaps(a: &[f64], b: &[f64]) -> EcdfGaps {
    let (mut i, mut j) = (0, 0);
    let mut counts = Vec::with_capacity(a.len() + b.len());
    while i < a.len() || j < b.len() {
        let t = match (a.get(i), b.get(j)) {
            (Some(&u), Some(&v)) => u.min(v),
            (Some(&u), None) => u,
            (None, Some(&v)) => v,
            (None, None) => break,
        };
        // `==` treats -0.0 and 0.0 as one value, as the sort order does.
        while i < a.len() && a[i] == t {
            i += 1;
        }
        while j < b.len() && b[j] == t {
            j += 1;
        }
        counts.push((i, j));
    }
    EcdfGaps { counts }
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// `P(D_{n,n} >= h / n)`: SciPy's `_compute_prob_outside_square`.
///
/// The reflection-principle sum `2 * sum_k (-1)^(k+1) C(2n, n - k h) /
/// C(2n, n)` cancels badly, so SciPy (and we) evaluate it as
/// `2 * A0 (1 - A1 (1 - A2 (...)))` with each ratio a product of `h` terms.
fn prob_outside_square(n: usize, h: usize) -> f64 {
    let (nf, hf) = (n as f64, h as f64);
    let mut p = 0.0;
    for k in (0..=n / h).rev() {
        let kh = k as f64 * hf;
        let mut p1 = 1.0;
        for j in 0..h {
            let j = j as f64;
            p1 = (nf - kh - j) * p1 / (nf + kh + j + 1.0);
        }
        p = p1 * (1.0 - p);
    }
    2.0 * p
}

/// Proportion of lattice paths from `(0, 0)` to `(m, n)` that touch the
/// band edge `|n x / g - m y / g| >= h`: SciPy's
/// `_compute_outer_prob_inside_method` (Hodges 1958, with Viehmann's 2021
/// recursion for `1 - p`).
///
/// One column of the path-count table is kept, restricted to the window of
/// `y` inside the band. Each entry is the proportion of paths reaching that
/// cell that have already left the band, so values stay in `[0, 1]` and no
/// rescaling is needed.
fn outer_prob_inside(m: usize, n: usize, g: usize, h: usize) -> f64 {
    // Symmetric in m and n; the recursion wants m >= n.
    let (m, n) = (m.max(n) as i64, m.min(n) as i64);
    let (mg, ng, h) = (m / g as i64, n / g as i64, h as i64);
    let ceil_div = |a: i64, b: i64| -(-a).div_euclid(b);

    let mut minj: i64 = 0;
    let mut maxj = ceil_div(h, mg).min(n + 1);
    let mut curlen = maxj - minj;
    // SciPy sizes this min(2 maxj + 2, n + 1); n + 2 covers every index the
    // loop can touch and so cannot go out of bounds. The extra entries start
    // at 1 like SciPy's and are never read before being written.
    let mut a = vec![1.0; (n + 2) as usize];
    for v in &mut a[..maxj as usize] {
        *v = 0.0;
    }
    for i in 1..=m {
        let (lastminj, lastlen) = (minj, curlen);
        minj = ((ng * i - h).div_euclid(mg) + 1).max(0).min(n);
        maxj = ceil_div(ng * i + h, mg).min(n + 1);
        if maxj <= minj {
            return 1.0;
        }
        let mut val = if minj == 0 { 0.0 } else { 1.0 };
        let (fi, shift) = (i as f64, (minj - lastminj) as usize);
        for jj in 0..(maxj - minj) as usize {
            let j = (jj as i64 + minj) as f64;
            val = (a[jj + shift] * fi + val * j) / (fi + j);
            a[jj] = val;
        }
        curlen = maxj - minj;
        if lastlen > curlen {
            // Cells that left the window: all their paths are outside.
            for v in &mut a[curlen as usize..lastlen as usize] {
                *v = 1.0;
            }
        }
    }
    a[(maxj - minj - 1) as usize]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures::{STEPS_8, STEPS_200, STEPS_300, STEPS_500_A, STEPS_500_B, assert_close};
    use proptest::prelude::*;
    use std::time::{Duration, Instant};

    /// Checks against SciPy's statistic and p-value. Exact cases run the
    /// same float recursions as SciPy, so 1e-9 relative is generous. The
    /// asymptotic ones get the tolerance given by the caller (see there).
    fn check(x: &[f64], y: &[f64], statistic: f64, p: f64, method: Method, rel: f64) {
        let res = ks_2samp(x, y).unwrap();
        assert_eq!(res.method, method, "method");
        assert_close(res.statistic, statistic, 1e-12, "statistic");
        assert_close(res.p_value, p, rel, "p-value");
    }

    const A10: [f64; 10] = [0.61, 0.29, 0.06, 0.59, -1.73, -0.74, 0.51, -0.56, 0.39, 1.64];
    const B10: [f64; 10] = [-0.1, 1.2, 0.81, 1.5, 0.3, 2.1, 0.95, 0.71, 1.33, 0.02];

    #[test]
    fn exact_equal_sizes() {
        // scipy.stats.ks_2samp(A10, B10) -> statistic=0.6, pvalue=0.05244755244755244
        check(&A10, &B10, 0.6, 0.05244755244755244, Method::Exact, 1e-9);
        check(&B10, &A10, 0.6, 0.05244755244755244, Method::Exact, 1e-9);
        // scipy.stats.ks_2samp([1.0], [2.0]) -> statistic=1.0, pvalue=1.0
        check(&[1.0], &[2.0], 1.0, 1.0, Method::Exact, 1e-9);
    }

    #[test]
    fn exact_unequal_sizes() {
        // scipy.stats.ks_2samp(A10[:8], B10 + [1.7])
        //   -> statistic=0.7272727272727273, pvalue=0.007435632822629727
        let mut b11 = B10.to_vec();
        b11.push(1.7);
        check(
            &A10[..8],
            &b11,
            0.7272727272727273,
            0.007435632822629727,
            Method::Exact,
            1e-9,
        );
    }

    #[test]
    fn exact_with_ties() {
        // scipy.stats.ks_2samp([1, 2, 2, 3, 3, 3, 4], [2, 3, 3, 4, 4, 5, 5, 5, 6])
        //   -> statistic=0.5238095238095238, pvalue=0.1687062937062937
        let x = [1.0, 2.0, 2.0, 3.0, 3.0, 3.0, 4.0];
        let y = [2.0, 3.0, 3.0, 4.0, 4.0, 5.0, 5.0, 5.0, 6.0];
        check(&x, &y, 0.5238095238095238, 0.1687062937062937, Method::Exact, 1e-9);
    }

    #[test]
    fn identical_samples_are_immediate() {
        // statrs hangs here: two agents that never fail.
        // scipy.stats.ks_2samp([1000.0] * 500, [1000.0] * 500)
        //   -> statistic=0.0, pvalue=1.0
        let start = Instant::now();
        check(&[1000.0; 500], &[1000.0; 500], 0.0, 1.0, Method::Exact, 0.0);
        // scipy.stats.ks_2samp([1000.0] * 500, [1000.0] * 499 + [999.0])
        //   -> statistic=0.002, pvalue=0.9999999999999998
        let mut one_off = vec![1000.0; 500];
        one_off[499] = 999.0;
        check(&[1000.0; 500], &one_off, 0.002, 0.9999999999999998, Method::Exact, 1e-9);
        assert!(start.elapsed() < Duration::from_secs(1));
    }

    #[test]
    fn realistic_step_counts() {
        // scipy.stats.ks_2samp(STEPS_200, STEPS_300)
        //   -> statistic=0.155, pvalue=0.0057556086682506126
        check(
            &STEPS_200,
            &STEPS_300,
            0.155,
            0.0057556086682506126,
            Method::Exact,
            1e-9,
        );
        // scipy.stats.ks_2samp(STEPS_500_A, STEPS_500_B)
        //   -> statistic=0.116, pvalue=0.0023738215453611602
        check(
            &STEPS_500_A,
            &STEPS_500_B,
            0.116,
            0.0023738215453611602,
            Method::Exact,
            1e-9,
        );
        // scipy.stats.ks_2samp(STEPS_8, STEPS_300)
        //   -> statistic=0.33666666666666667, pvalue=0.2744224692286659
        check(
            &STEPS_8,
            &STEPS_300,
            0.33666666666666667,
            0.2744224692286659,
            Method::Exact,
            1e-9,
        );
    }

    /// `big_x(n)` of stats/scripts/scipy_reference.py:
    /// `(i * 7919 + 13) % 10007` for `i` in `0..n` (many ties).
    fn big_x(n: u64) -> Vec<f64> {
        (0..n).map(|i| ((i * 7919 + 13) % 10007) as f64).collect()
    }

    /// `big_y(n, scale)`: `((i * 104729 + 7) % 9973) * scale`.
    fn big_y(n: u64, scale: f64) -> Vec<f64> {
        (0..n).map(|i| ((i * 104729 + 7) % 9973) as f64 * scale).collect()
    }

    /// `near_y(n, offset, scale)`: `(((i + offset) * 7919 + 13) % 10007) * scale`.
    fn near_y(n: u64, offset: u64, scale: f64) -> Vec<f64> {
        (0..n)
            .map(|i| (((i + offset) * 7919 + 13) % 10007) as f64 * scale)
            .collect()
    }

    #[test]
    fn asymptotic_beyond_ten_thousand() {
        // Tolerance 1e-9 except where noted: the kstwo methods are the same
        // float algorithms as SciPy's except `smirnov`, which SciPy runs in
        // double-double arithmetic and we in f64 (at most ~1e-13 apart).
        let x = big_x(12_000);
        // en = round(n1 n2 / (n1 + n2)); the comments name the kstwo method.
        let cases = [
            // scipy.stats.ks_2samp(big_x(12000), big_y(50, 1.0))  # en=50: smirnov
            //   -> (0.43975, 2.5448487855324576e-09)
            (big_y(50, 1.0), 0.43975, 2.5448487855324576e-09),
            // scipy.stats.ks_2samp(big_x(12000), big_y(50, 1.2))  # en=50: smirnov
            //   -> (0.4271666666666667, 8.469854568421509e-09)
            (big_y(50, 1.2), 0.4271666666666667, 8.469854568421509e-09),
            // scipy.stats.ks_2samp(big_x(12000), near_y(50, 1000, 1.1))  # en=50: DMTW
            //   -> (0.08699999999999997, 0.8120563697031828)
            (near_y(50, 1000, 1.1), 0.08699999999999997, 0.8120563697031828),
            // scipy.stats.ks_2samp(big_x(12000), near_y(50, 0, 1.3))  # en=50: Pomeranz
            //   -> (0.2642500000000001, 0.0014307051527585601)
            (near_y(50, 0, 1.3), 0.2642500000000001, 0.0014307051527585601),
            // scipy.stats.ks_2samp(big_x(12000), near_y(100, 0, 1.1))  # en=99: Pomeranz
            //   -> (0.10083333333333333, 0.24926781708216783)
            (near_y(100, 0, 1.1), 0.10083333333333333, 0.24926781708216783),
            // scipy.stats.ks_2samp(big_x(12000), big_y(300, 1.1))  # en=293: smirnov
            //   -> (0.08966666666666667, 0.01685465177689444)
            (big_y(300, 1.1), 0.08966666666666667, 0.01685465177689444),
            // scipy.stats.ks_2samp(big_x(12000), big_y(11000, 1.0))  # en=5739: Pelz-Good
            //   -> (0.00734090909090912, 0.9142398796625582)
            (big_y(11_000, 1.0), 0.00734090909090912, 0.9142398796625582),
            // scipy.stats.ks_2samp(big_x(12000), big_y(11000, 1.01))  # en=5739: Pelz-Good
            //   -> (0.006590909090909092, 0.962991212485241)
            (big_y(11_000, 1.01), 0.006590909090909092, 0.962991212485241),
        ];
        for (y, d, p) in &cases {
            check(&x, y, *d, *p, Method::Asymptotic, 1e-9);
        }
        // scipy.stats.ks_2samp(big_x(10001), big_y(10000, 1.0))  # en=5000: DMTW
        //   -> (0.00339966003399661, 0.9999999917309427)
        let (x, y) = (big_x(10_001), big_y(10_000, 1.0));
        check(
            &x,
            &y,
            0.00339966003399661,
            0.9999999917309427,
            Method::Asymptotic,
            1e-9,
        );
    }

    #[test]
    fn bad_input_is_an_error() {
        assert_eq!(ks_2samp(&[], &[1.0]), Err(StatsError::EmptySample));
        assert_eq!(ks_2samp(&[1.0], &[]), Err(StatsError::EmptySample));
        assert_eq!(ks_2samp(&[f64::NAN], &[1.0]), Err(StatsError::NaN));
        assert_eq!(ks_2samp(&[1.0], &[2.0, f64::NAN]), Err(StatsError::NaN));
    }

    #[test]
    fn square_matches_inside_method() {
        // For n1 == n2 SciPy uses the reflection sum; the lattice recursion
        // must agree with it where both apply.
        for n in [1, 2, 5, 17, 40] {
            for h in 1..=n {
                let square = prob_outside_square(n, h);
                let inside = outer_prob_inside(n, n, n, h);
                assert!((square - inside).abs() < 1e-12, "n={n} h={h}: {square} vs {inside}");
            }
        }
    }

    fn sample() -> impl Strategy<Value = Vec<f64>> {
        prop::collection::vec((0i32..30).prop_map(f64::from), 1..60)
    }

    proptest! {
        #[test]
        fn p_value_is_a_probability(x in sample(), y in sample()) {
            let res = ks_2samp(&x, &y).unwrap();
            prop_assert!((0.0..=1.0).contains(&res.p_value), "{res:?}");
            prop_assert!((0.0..=1.0).contains(&res.statistic));
        }

        #[test]
        fn swapping_samples_keeps_result(x in sample(), y in sample()) {
            prop_assert_eq!(ks_2samp(&x, &y).unwrap(), ks_2samp(&y, &x).unwrap());
        }

        #[test]
        fn identical_samples_give_p_one(x in sample()) {
            let mut shuffled = x.clone();
            shuffled.reverse();
            let res = ks_2samp(&x, &shuffled).unwrap();
            prop_assert_eq!(res.statistic, 0.0);
            prop_assert_eq!(res.p_value, 1.0);
        }
    }
}
