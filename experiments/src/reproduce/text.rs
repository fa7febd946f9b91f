//! Numbers and phrases for the report's tables and readings, so that every section writes
//! them alike.

use sim::Profile;

use super::arms::Row;
use super::paper::MeanOver;
use super::spread::{PaperInside, Placement};

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

/// Failures per replicate: "171.4 (126-248)" for several, "171" for one.
pub fn failures(per_replicate: &[usize], mean: f64) -> String {
    match (per_replicate.iter().min(), per_replicate.iter().max()) {
        (Some(lo), Some(hi)) if per_replicate.len() > 1 => format!("{mean:.1} ({lo}-{hi})"),
        _ => format!("{mean:.0}"),
    }
}

/// A share as a percentage: "4.5%".
pub fn percent(share: f64) -> String {
    format!("{:.1}%", 100.0 * share)
}

/// The name of `profile`'s world in a sentence.
pub fn world_name(profile: Profile) -> &'static str {
    match profile {
        Profile::Original => "the original world",
        Profile::Spec => "the SPEC world",
    }
}

/// What a mean over `over` is called in the report: "mean steps*" (a failure counted as
/// the horizon) or "mean steps over successes".
pub fn mean_name(over: MeanOver) -> &'static str {
    match over {
        MeanOver::FailuresAtHorizon => "mean steps*",
        MeanOver::Successes => "mean steps over successes",
    }
}

/// "inside", "outside", or "partly inside" the spread.
pub fn verdict(inside: &PaperInside) -> &'static str {
    let placed: Vec<bool> = inside.placements().map(|p| p.inside).collect();
    if placed.iter().all(|&i| i) {
        "inside"
    } else if placed.iter().all(|&i| !i) {
        "outside"
    } else {
        "partly inside"
    }
}

/// Our range of each of the paper's figures: "failures 1.0%-9.0% (in), mean steps* 190.2-333.1
/// (out)"; each marked only when the verdict is mixed.
fn ranges(inside: &PaperInside) -> String {
    let mixed = verdict(inside) == "partly inside";
    let mark = |p: &Placement| match (mixed, p.inside) {
        (false, _) => "",
        (true, true) => " (in)",
        (true, false) => " (out)",
    };
    let failures = inside.failure_rate.map(|p| {
        format!(
            "failures {}-{}{}",
            percent(p.spread.low),
            percent(p.spread.high),
            mark(&p)
        )
    });
    let steps = inside.mean_steps.map(|p| {
        format!(
            "{} {}-{}{}",
            mean_name(inside.mean_over),
            num(Some(p.spread.low), 1),
            num(Some(p.spread.high), 1),
            mark(&p)
        )
    });
    failures.into_iter().chain(steps).collect::<Vec<_>>().join(", ")
}

/// Where the paper's figures of `row` lie against the spread of our replicates in each
/// world: "The paper's 4.0% failures and 263.55 mean steps* lie inside the spread of our 20
/// replicates in the original world (failures ..., mean steps* ...) and outside it in the
/// SPEC world (...); a further draw of ours lands inside such a range with probability 90%."
/// Empty when the row has nothing to place.
pub fn paper_against(row: &Row) -> String {
    if row.paper.is_none() {
        return String::new();
    }
    let placed: Vec<(Profile, PaperInside, usize)> = [Profile::Original, Profile::Spec]
        .into_iter()
        .filter_map(|p| {
            let m = row.in_world(p)?;
            Some((p, m.paper_inside?, m.arm.replicates))
        })
        .collect();
    let Some(&(_, first, replicates)) = placed.first() else {
        return String::new();
    };
    let figures: Vec<String> = first
        .failure_rate
        .map(|p| format!("{} failures", percent(p.paper)))
        .into_iter()
        .chain(
            first
                .mean_steps
                .map(|p| format!("{} {}", num(Some(p.paper), 2), mean_name(first.mean_over))),
        )
        .collect();
    let worlds: Vec<String> = placed
        .iter()
        .map(|(p, inside, r)| {
            format!(
                "{} the spread of our {r} replicates in {} ({})",
                verdict(inside),
                world_name(*p),
                ranges(inside)
            )
        })
        .collect();
    let coverage = first.placements().next().map_or(0.0, |p| p.spread.coverage());
    format!(
        "The paper's {} lie {}; a further draw of ours would land inside the range of {replicates} with \
         probability {:.0}%.",
        figures.join(" and "),
        worlds.join(", and "),
        100.0 * coverage
    )
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
        assert!(significance(0.01).starts_with("significant"));
        assert!(significance(0.5).starts_with("not significant"));
        assert_eq!(p_is(0.0), "p < 1e-300");
        assert_eq!(p_is(0.5), "p = 0.500");
        assert_eq!(failures(&[126, 248, 140], 171.33), "171.3 (126-248)");
        assert_eq!(failures(&[4], 4.0), "4");
        assert_eq!(percent(0.045), "4.5%");
    }
}
