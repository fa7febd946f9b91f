//! One trait for every planner of block moves, so that whoever plans a task (a PDDL file, a
//! folder of them, the side view, Python) takes any planner through one call and never
//! learns which it is.
//!
//! The exact solver ([`ExactMoves`]) and the near-optimal planner ([`NearOptimal`])
//! implement it here; the learned relational policy implements it in `neural`, which
//! depends on this crate. A planner that finds no plan (a budget spent, a policy that does
//! not reach the goal within its move limit) says so as an error; the plan it returns is
//! checked by whoever writes it out ([`crate::pddl::Problem::solve`] replays it over the
//! file's facts).

use crate::error::Result;

use super::{ExactMoves, NearOptimal, TowerGoal, TowerPlan, Towers};

/// A planner of block moves: a plan from a state to a goal of towers (module docs).
///
/// `Send + Sync` so that a runner over many tasks may share one planner between threads.
pub trait BlockPlanner: Send + Sync {
    /// Its name in reports and on the command line: `exact`, `near-optimal`, or what a
    /// learned policy calls itself.
    fn name(&self) -> &str;

    /// A plan from `start` to `goal`; an error if the planner finds none.
    fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan>;
}

impl BlockPlanner for ExactMoves {
    fn name(&self) -> &str {
        "exact"
    }

    fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        self.solve(start, goal)
    }
}

impl BlockPlanner for NearOptimal {
    fn name(&self) -> &str {
        "near-optimal"
    }

    fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        NearOptimal::plan(self, start, goal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_planner_is_reached_through_the_trait() {
        let start = Towers::new(&[vec![0, 1, 2], vec![3]]).unwrap();
        let goal = TowerGoal::new(&[vec![1, 3, 2]]).unwrap();
        let planners: [&dyn BlockPlanner; 2] = [&ExactMoves::new(), &NearOptimal::new()];
        for planner in planners {
            let plan = planner.plan(&start, &goal).unwrap();
            let end = plan.replay(&start, super::super::Table::Unbounded).unwrap();
            assert!(goal.holds(&end), "{}", planner.name());
        }
        assert_eq!(planners[0].plan(&start, &goal).unwrap().len(), 4);
    }
}
