//! How far played episodes are from the best possible: each start's shortest plan, found
//! by the exact solver, against the steps taken.
//!
//! Under a restricting action protocol the yardstick is the shortest *legal* plan
//! ([`optimal_steps_under`]). A start in which the goal already holds (the `paper` start
//! rule keeps them) has a shortest plan of 0 actions; such episodes count in the mean
//! optimum but have no ratio.

use oracle::ExactSolver;
use serde::Serialize;
use sim::{ActionProtocol, Grid};

use crate::error::Result;
use crate::rollout::EpisodeResult;

/// The length of a shortest plan from each episode's start to its goal, in order (every
/// action legal).
pub fn optimal_steps(grid: Grid, results: &[EpisodeResult]) -> Result<Vec<u32>> {
    optimal_steps_under(grid, ActionProtocol::Free, results)
}

/// The length of a shortest plan legal under `protocol` from each episode's start to its
/// goal, in order.
pub fn optimal_steps_under(grid: Grid, protocol: ActionProtocol, results: &[EpisodeResult]) -> Result<Vec<u32>> {
    optimal_steps_by(&ExactSolver::new(grid).with_protocol(protocol), results)
}

/// The length of the shortest plan `solver` finds (with its protocol and node budget) from
/// each episode's start to its goal, in order.
pub fn optimal_steps_by(solver: &ExactSolver, results: &[EpisodeResult]) -> Result<Vec<u32>> {
    results
        .iter()
        .map(|r| Ok(solver.distance(&r.start, &r.goal)?))
        .collect()
}

/// Steps taken against the shortest plans, over the episodes that reached the goal.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Optimality {
    /// Mean length of the shortest plan from the starts (compare with the mean steps over
    /// the same episodes); `None` if no episode reached the goal.
    pub mean_optimal_steps: Option<f64>,
    /// Mean over the episodes of steps taken / shortest plan's length; `None` if no episode
    /// reached the goal (from a start where the goal did not hold already).
    pub mean_ratio_to_optimum: Option<f64>,
}

impl Optimality {
    /// The figures of `results`, whose shortest plans are `optimal` (as
    /// [`optimal_steps`] gives them).
    pub fn of(results: &[EpisodeResult], optimal: &[u32]) -> Optimality {
        let reached: Vec<(f64, f64)> = results
            .iter()
            .zip(optimal)
            .filter(|(r, _)| r.reached_goal)
            .map(|(r, &best)| (f64::from(r.steps), f64::from(best)))
            .collect();
        let n = reached.len() as f64;
        let ratios: Vec<f64> = reached.iter().filter(|(_, b)| *b > 0.0).map(|(s, b)| s / b).collect();
        Optimality {
            mean_optimal_steps: (n > 0.0).then(|| reached.iter().map(|(_, b)| b).sum::<f64>() / n),
            mean_ratio_to_optimum: (!ratios.is_empty()).then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
        }
    }
}

/// Mean steps over all `results`, an episode that failed counted as `horizon` steps (the
/// paper's figures read this way: 847.7 = 0.7 x 1000 + 0.3 x 492).
pub fn mean_steps_failures_as_horizon(results: &[EpisodeResult], horizon: u32) -> f64 {
    let total: f64 = results
        .iter()
        .map(|r| f64::from(if r.reached_goal { r.steps } else { horizon }))
        .sum();
    total / results.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{Cell, Goal, State};

    fn episode(steps: u32, reached_goal: bool) -> EpisodeResult {
        EpisodeResult {
            episode: 0,
            seed: 0,
            goal: "1,0".parse::<Goal>().unwrap(),
            // Block 0 four cells left of the cell above block 1: pick, four moves.
            start: State::new(&[Cell::new(0, 0), Cell::new(3, 0)], None).unwrap(),
            steps,
            reached_goal,
            total_reward: 0.0,
        }
    }

    #[test]
    fn ratios_count_the_episodes_that_reached_the_goal() {
        let results = [episode(5, true), episode(10, true), episode(1000, false)];
        let optimal = optimal_steps(Grid::default(), &results).unwrap();
        assert_eq!(optimal, vec![5, 5, 5]);
        let o = Optimality::of(&results, &optimal);
        assert_eq!(o.mean_optimal_steps, Some(5.0));
        assert_eq!(o.mean_ratio_to_optimum, Some(1.5));
        assert_eq!(mean_steps_failures_as_horizon(&results, 1000), 1015.0 / 3.0);
        assert_eq!(Optimality::of(&results[2..], &optimal[2..]).mean_ratio_to_optimum, None);
    }
}
