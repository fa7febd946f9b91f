//! Numbers and phrases for the report's tables and readings, so that every section writes
//! them alike.

/// The significance level the readings use.
pub const ALPHA: f64 = 0.05;

/// A figure with `decimals` decimals; "-" for none.
pub fn num(value: Option<f64>, decimals: usize) -> String {
    value.map_or_else(|| "-".into(), |v| format!("{v:.decimals$}"))
}

/// A p-value: three significant digits, in scientific notation below 0.001.
pub fn p_value(p: f64) -> String {
    if p == 0.0 {
        // Below the smallest double: the normal approximation's tail underflowed.
        "< 1e-300".into()
    } else if p < 1e-3 {
        format!("{p:.2e}")
    } else {
        format!("{p:.3}")
    }
}

/// "p = 0.012", or "p < 1e-300" for a p-value that underflowed.
pub fn p_is(p: f64) -> String {
    let text = p_value(p);
    if text.starts_with('<') {
        format!("p {text}")
    } else {
        format!("p = {text}")
    }
}

/// "significant at the 5% level (p = 0.012)" or "not significant at the 5% level (p =
/// 0.34)".
pub fn significance(p: f64) -> String {
    if p < ALPHA {
        format!("significant at the 5% level ({})", p_is(p))
    } else {
        format!("not significant at the 5% level ({})", p_is(p))
    }
}

/// How `ours` compares with `theirs`: "12% below", "3% above", "equal".
pub fn relative(ours: f64, theirs: f64) -> String {
    if theirs == 0.0 {
        return if ours == 0.0 { "equal".into() } else { "above".into() };
    }
    let change = (ours - theirs) / theirs * 100.0;
    if change.abs() < 0.5 {
        "within 0.5% of".into()
    } else if change < 0.0 {
        format!("{:.0}% below", -change)
    } else {
        format!("{change:.0}% above")
    }
}

/// "fewer" / "more" / "as many", for failures or steps of `a` against `b`.
pub fn fewer_or_more(a: f64, b: f64) -> &'static str {
    if a < b {
        "fewer"
    } else if a > b {
        "more"
    } else {
        "as many"
    }
}

/// Failures per replicate: "171.4 (126-248)" for several, "171" for one.
pub fn failures(per_replicate: &[usize], mean: f64) -> String {
    match (per_replicate.iter().min(), per_replicate.iter().max()) {
        (Some(lo), Some(hi)) if per_replicate.len() > 1 => format!("{mean:.1} ({lo}-{hi})"),
        _ => format!("{mean:.0}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_read_as_written() {
        assert_eq!(num(Some(2.345), 1), "2.3");
        assert_eq!(num(None, 1), "-");
        assert_eq!(p_value(0.016), "0.016");
        assert_eq!(p_value(1.16e-5), "1.16e-5");
        assert_eq!(relative(80.0, 100.0), "20% below");
        assert_eq!(relative(110.0, 100.0), "10% above");
        assert_eq!(relative(100.2, 100.0), "within 0.5% of");
        assert!(significance(0.01).starts_with("significant"));
        assert!(significance(0.5).starts_with("not significant"));
        assert_eq!(p_is(0.0), "p < 1e-300");
        assert_eq!(p_is(0.5), "p = 0.500");
        assert_eq!(failures(&[126, 248, 140], 171.33), "171.3 (126-248)");
        assert_eq!(failures(&[4], 4.0), "4");
    }
}
