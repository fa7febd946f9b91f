//! Is the paper's figure an ordinary draw of ours? Its place against the spread of our
//! replicates.
//!
//! A replicate repeats the paper's experiment once: a learner arm's replicate is one agent
//! (its own training seed) playing the test games, the random agent's is one set of the
//! paper's number of games (E1). The paper ran each experiment once, so its figure is one
//! such draw. The **spread** of a figure is the range of its values over our `R`
//! replicates, smallest to largest; the paper's figure is **inside** when it lies in that
//! range, ends included. If the paper's figure were one more draw of the same distribution
//! as ours, it would land inside the range of `R` draws with probability `(R - 1) / (R + 1)`
//! (each of the `R + 1` draws is equally likely to be the smallest or the largest; ties only
//! raise it): [`Spread::coverage`], printed with every reading. An outside figure is
//! therefore evidence that the paper measured something else, the more so the higher the
//! coverage.
//!
//! Failures are compared as shares of the games played (the paper's failures of its games
//! against each replicate's of its games), mean steps over the games the paper's mean is
//! over ([`MeanOver`]: a failure counted as the horizon in every table, the successes in
//! E2).

use serde::Serialize;

use super::paper::MeanOver;

/// The range of one figure over our replicates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Spread {
    /// The smallest replicate's value.
    pub low: f64,
    /// The largest replicate's value.
    pub high: f64,
    /// Replicates behind it.
    pub replicates: usize,
}

impl Spread {
    /// The spread of `values` (`None` for none).
    pub fn of(values: &[f64]) -> Option<Spread> {
        let low = values.iter().copied().reduce(f64::min)?;
        let high = values.iter().copied().reduce(f64::max)?;
        Some(Spread {
            low,
            high,
            replicates: values.len(),
        })
    }

    /// Whether `value` lies in the range, ends included.
    pub fn contains(&self, value: f64) -> bool {
        (self.low..=self.high).contains(&value)
    }

    /// The probability that one more draw of the replicates' distribution lands inside the
    /// range: [`Spread::coverage_of`] its replicates.
    pub fn coverage(&self) -> f64 {
        Self::coverage_of(self.replicates)
    }

    /// The probability that one more draw of a distribution lands inside the range of
    /// `replicates` draws of it: `(R - 1) / (R + 1)` (module docs).
    pub fn coverage_of(replicates: usize) -> f64 {
        let r = replicates as f64;
        ((r - 1.0) / (r + 1.0)).max(0.0)
    }
}

/// One of the paper's figures placed against our spread.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Placement {
    /// The paper's figure.
    pub paper: f64,
    /// Ours, replicate by replicate.
    pub spread: Spread,
    /// Whether the paper's figure lies inside the spread.
    pub inside: bool,
}

impl Placement {
    pub(super) fn of(paper: f64, ours: &[f64]) -> Option<Placement> {
        let spread = Spread::of(ours)?;
        Some(Placement {
            paper,
            spread,
            inside: spread.contains(paper),
        })
    }
}

/// Where a row of the paper falls against the replicates of one of our arms.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PaperInside {
    /// The share of games failed (the paper's failures over its games), if the paper gives
    /// both.
    pub failure_rate: Option<Placement>,
    /// Mean steps, if the paper gives a mean, over the games `mean_over` says.
    pub mean_steps: Option<Placement>,
    /// Which games the means are over (the paper's reading).
    pub mean_over: MeanOver,
}

impl PaperInside {
    /// The placements there are: failure rate, then mean steps.
    pub fn placements(&self) -> impl Iterator<Item = Placement> + '_ {
        self.failure_rate.iter().chain(&self.mean_steps).copied()
    }

    /// Whether every figure of the paper lies inside our spread.
    pub fn all_inside(&self) -> bool {
        self.placements().all(|p| p.inside)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_range_holds_its_ends_and_its_coverage_grows_with_replicates() {
        let s = Spread::of(&[3.0, 1.0, 2.0]).unwrap();
        assert_eq!((s.low, s.high, s.replicates), (1.0, 3.0, 3));
        assert!(s.contains(1.0) && s.contains(3.0) && !s.contains(3.5) && !s.contains(0.99));
        assert_eq!(s.coverage(), 0.5);
        assert_eq!(Spread::of(&[0.0; 19]).unwrap().coverage(), 0.9);
        assert_eq!(Spread::of(&[7.0]).unwrap().coverage(), 0.0);
        assert_eq!(Spread::coverage_of(39), 0.95);
        assert_eq!(Spread::of(&[]), None);
    }
}
