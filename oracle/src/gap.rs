//! The oracle's optimality gap: its plan lengths against the exact solver's on the same
//! seeded starts.

use sim::seeding::episode_seed;
use sim::{Backend, Env, EnvConfig, Goal, Grid, State};

use crate::error::Result;
use crate::exact::ExactSolver;
use crate::oracle::Oracle;
use crate::plan::Plan;

/// The starts `Env::reset` draws for episodes `0..count` of a run with base seed `seed`
/// (blocks on distinct cells, nothing held, the goal not holding): the same starts every
/// experiment with that seed plays.
pub fn seeded_starts(grid: Grid, goal: &Goal, count: u64, seed: u64) -> Result<Vec<State>> {
    let mut env = Env::new(EnvConfig {
        grid,
        backend: Backend::Grid,
        ..EnvConfig::with_goal(goal.clone())
    })?;
    Ok((0..count).map(|k| env.reset(episode_seed(seed, k)).state).collect())
}

/// One start where the oracle's plan is longer than a shortest one.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GapCase {
    /// The start.
    pub start: State,
    /// The oracle's plan.
    pub oracle: Plan,
    /// A shortest plan.
    pub exact: Plan,
}

/// Oracle steps against exact steps over a set of starts for one goal.
#[derive(Clone, Debug, PartialEq)]
pub struct GapReport {
    /// The goal.
    pub goal: Goal,
    /// Starts compared.
    pub starts: usize,
    /// Mean oracle steps.
    pub mean_oracle_steps: f64,
    /// Mean exact (shortest) steps.
    pub mean_exact_steps: f64,
    /// Mean over starts of oracle steps / exact steps.
    pub mean_ratio: f64,
    /// Largest oracle steps / exact steps.
    pub max_ratio: f64,
    /// Starts where the oracle's plan is longer than a shortest one.
    pub longer: usize,
    /// The start with the largest ratio (then the largest excess), if the oracle was ever
    /// longer.
    pub worst: Option<GapCase>,
}

/// Compares the oracle's plan with a shortest plan from every start in `starts` (none may
/// already satisfy `goal`).
pub fn measure(oracle: &Oracle, exact: &ExactSolver, goal: &Goal, starts: &[State]) -> Result<GapReport> {
    let mut ratios = Vec::with_capacity(starts.len());
    let (mut oracle_steps, mut exact_steps, mut longer) = (0usize, 0usize, 0usize);
    let mut worst: Option<(f64, usize, GapCase)> = None;
    for start in starts {
        let o = oracle.plan(start, goal)?;
        let e = exact.solve(start, goal)?;
        let ratio = o.len() as f64 / e.len() as f64;
        ratios.push(ratio);
        oracle_steps += o.len();
        exact_steps += e.len();
        if o.len() > e.len() {
            longer += 1;
            let excess = o.len() - e.len();
            if worst.as_ref().is_none_or(|(r, x, _)| (ratio, excess) > (*r, *x)) {
                let case = GapCase {
                    start: start.clone(),
                    oracle: o,
                    exact: e,
                };
                worst = Some((ratio, excess, case));
            }
        }
    }
    let n = starts.len().max(1) as f64;
    Ok(GapReport {
        goal: goal.clone(),
        starts: starts.len(),
        mean_oracle_steps: oracle_steps as f64 / n,
        mean_exact_steps: exact_steps as f64 / n,
        mean_ratio: ratios.iter().sum::<f64>() / n,
        max_ratio: ratios.iter().copied().fold(1.0, f64::max),
        longer,
        worst: worst.map(|(_, _, case)| case),
    })
}
