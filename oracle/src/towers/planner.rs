//! One trait for every planner of block moves, so that whoever plans a task (a PDDL file, a
//! folder of them, the side view, Python) takes any planner through one call and never
//! learns which it is.
//!
//! The exact solver ([`ExactMoves`]), the optimal solver ([`OptimalMoves`]) and the
//! near-optimal planner ([`NearOptimal`]) implement it here; the learned relational policy implements it in `neural`, which
//! depends on this crate. A planner that finds no plan (a budget spent, a policy that does
//! not reach the goal within its move limit) says so as an error; the plan it returns is
//! checked by whoever writes it out ([`crate::pddl::Problem::solve`] replays it over the
//! file's facts).

use crate::error::Result;

use super::{Certificate, CertifiedPlan, ExactMoves, NearOptimal, OptimalMoves, TowerGoal, TowerPlan, Towers};

/// A planner of block moves: a plan from a state to a goal of towers (module docs).
///
/// `Send + Sync` so that a runner over many tasks may share one planner between threads.
pub trait BlockPlanner: Send + Sync {
    /// Its name in reports and on the command line: `exact`, `optimal`, `near-optimal`, or
    /// what a learned policy calls itself.
    fn name(&self) -> &str;

    /// A plan from `start` to `goal`; an error if the planner finds none.
    fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan>;

    /// A plan with the lower bound it is measured against, so that every plan has a gap:
    /// by default the plan and the bound that takes no search ([`Certificate::quick`]);
    /// the optimal solver returns its own certificate, the exact solver its proof.
    fn plan_certified(&self, start: &Towers, goal: &TowerGoal) -> Result<CertifiedPlan> {
        let plan = self.plan(start, goal)?;
        Ok(CertifiedPlan::new(plan, Certificate::quick(start, goal)?))
    }
}

impl BlockPlanner for ExactMoves {
    fn name(&self) -> &str {
        "exact"
    }

    fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        self.solve(start, goal)
    }

    /// The plan is shortest (A* with an admissible bound proves it), so its length is the
    /// lower bound.
    fn plan_certified(&self, start: &Towers, goal: &TowerGoal) -> Result<CertifiedPlan> {
        let plan = self.solve(start, goal)?;
        Ok(CertifiedPlan::proven(plan, Certificate::quick(start, goal)?))
    }
}

impl BlockPlanner for OptimalMoves {
    fn name(&self) -> &str {
        "optimal"
    }

    fn plan(&self, start: &Towers, goal: &TowerGoal) -> Result<TowerPlan> {
        Ok(self.solve(start, goal)?.plan)
    }

    fn plan_certified(&self, start: &Towers, goal: &TowerGoal) -> Result<CertifiedPlan> {
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
        let planners: [&dyn BlockPlanner; 3] = [&ExactMoves::new(), &NearOptimal::new(), &OptimalMoves::new()];
        for planner in planners {
            let plan = planner.plan(&start, &goal).unwrap();
            let end = plan.replay(&start, super::super::Table::Unbounded).unwrap();
            assert!(goal.holds(&end), "{}", planner.name());
            let certified = planner.plan_certified(&start, &goal).unwrap();
            assert_eq!(certified.plan, plan, "{}", planner.name());
            assert!(certified.lower_bound <= plan.len());
        }
        assert_eq!(planners[0].plan(&start, &goal).unwrap().len(), 4);
        // The exact and the optimal solvers prove their plans; the bound that takes no
        // search meets this one too (one block is forced to move twice).
        assert!(
            planners
                .iter()
                .all(|p| p.plan_certified(&start, &goal).unwrap().is_optimal())
        );
    }
}
