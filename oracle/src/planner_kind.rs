//! Planners chosen by name: one name per planner, one meaning in both views.
//!
//! `blockstack solve --solver`, `blockstack run --agent`, Python's `solve(solver=...)` and
//! `demonstrations(expert=...)` name a planner with a [`PlannerKind`], and plan with it
//! here, so that a name means the same planner wherever it is given:
//!
//! | name | top view | side view |
//! |---|---|---|
//! | `exact` | the fewest gripper steps ([`ExactSolver`]) | the fewest gripper steps ([`ExactSolver::with_view`]) |
//! | `exact-moves` | refused | the fewest block moves ([`MovePlanner::Exact`]), carried out by the gripper |
//! | `near-optimal` | refused | at most twice the fewest block moves ([`MovePlanner::NearOptimal`]), carried out |
//! | `optimal` | refused | the fewest block moves at any size, with its proof ([`MovePlanner::Optimal`]), carried out |
//! | `oracle` | the centroid + A* [`Oracle`] | the view's oracle: `near-optimal` |
//!
//! Counted in gripper steps (what an environment counts, and what every agent plays), `exact`
//! is the shortest plan in both views. A plan counted in block moves (`solve --view side
//! --cost moves`) is the block-move planner's own plan: there `exact` and `exact-moves` are
//! both the fewest moves, `near-optimal` and `oracle` the near-optimal planner's, and
//! `optimal` the fewest too (where its time limit lets it prove so; see
//! [`crate::towers::optimal`]).
//!
//! A problem of block moves on the literature's unbounded table (a PDDL task) takes the
//! planner as a [`BlockPlanner`] ([`PlannerKind::block_planner`]), with the options that
//! apply to it ([`PlanOptions`]).

use sim::{Goal, State, View};

use crate::error::{OracleError, Result};
use crate::exact::ExactSolver;
use crate::oracle::Oracle;
use crate::plan::Plan;
use crate::towers::{
    BlockPlanner, CertifiedPlan, DEFAULT_MOVE_BUDGET, ExactMoves, MovePlanner, NearOptimal, OptimalMoves,
    gripper_actions, plan_side_certified,
};

/// The options of a block-move planner ([`PlannerKind::block_planner`]); each applies to
/// one planner, and `None` takes its default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PlanOptions {
    /// The most states the exact search generates
    /// ([`DEFAULT_MOVE_BUDGET`] by default).
    pub budget: Option<usize>,
    /// How long the optimal solver searches for its proof
    /// ([`DEFAULT_TIME_LIMIT`](crate::towers::optimal::DEFAULT_TIME_LIMIT) by default).
    pub time_limit: Option<std::time::Duration>,
}

/// What a plan's length counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cost {
    /// Gripper actions (pick, moves, drop): the environment's steps.
    Steps,
    /// Block moves (a clear block onto the table or onto another): the planning
    /// literature's count, in the side view.
    Moves,
}

sim::names!(Cost { Steps = "steps", Moves = "moves" } unknown(text) -> OracleError {
    OracleError::UnknownCost { name: text.to_string() }
});

impl Cost {
    /// The count a plan of `view` has unless asked for another: steps from above (the only
    /// count there), block moves from the side.
    pub const fn default_in(view: View) -> Cost {
        match view {
            View::Top => Cost::Steps,
            View::Side => Cost::Moves,
        }
    }
}

/// A plan, counted as asked ([`PlannerKind::plan`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CountedPlan {
    /// Gripper actions.
    Steps(Plan),
    /// Block moves, with the lower bound they are measured against.
    Moves(CertifiedPlan),
}

impl CountedPlan {
    /// Its length in its own count.
    pub fn len(&self) -> usize {
        match self {
            CountedPlan::Steps(p) => p.len(),
            CountedPlan::Moves(p) => p.plan.len(),
        }
    }

    /// Whether it is empty (the goal held already).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Which planner (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PlannerKind {
    /// The fewest gripper steps, in either view.
    Exact,
    /// The fewest block moves, carried out by the gripper (side view).
    ExactMoves,
    /// The near-optimal block-move planner, carried out by the gripper (side view).
    NearOptimal,
    /// The optimal block-move solver with its certificate, carried out (side view).
    Optimal,
    /// The view's oracle: centroid + A* from above, the near-optimal planner from the side.
    Oracle,
}

sim::names!(PlannerKind { Exact = "exact", ExactMoves = "exact-moves", NearOptimal = "near-optimal", Optimal = "optimal", Oracle = "oracle" } unknown(text) -> OracleError {
    OracleError::UnknownPlanner { name: text.to_string() }
});

impl PlannerKind {
    /// What the planner does, in a few words (help texts).
    pub const fn about(self) -> &'static str {
        match self {
            PlannerKind::Exact => "the fewest gripper steps, in either view",
            PlannerKind::ExactMoves => "the fewest block moves carried out by the gripper (side view)",
            PlannerKind::NearOptimal => "at most twice the fewest block moves, carried out by the gripper (side view)",
            PlannerKind::Optimal => {
                "the fewest block moves at any size with its proof, carried out by the gripper (side view)"
            }
            PlannerKind::Oracle => {
                "the view's oracle: centroid + A* from above, the near-optimal planner from the side"
            }
        }
    }

    /// An error unless the planner plans in `view`: `exact-moves` and `near-optimal` plan
    /// block moves, which only the side view has.
    pub fn check_view(self, view: View) -> Result<()> {
        match (self, view) {
            (PlannerKind::ExactMoves | PlannerKind::NearOptimal | PlannerKind::Optimal, View::Top) => {
                Err(OracleError::PlannerNotInView { planner: self.name() })
            }
            _ => Ok(()),
        }
    }

    /// The block-move planner this one plans with in the side view: the exact one for
    /// `exact` and `exact-moves`, the near-optimal one for `near-optimal` and `oracle`, the
    /// optimal one for `optimal`.
    pub const fn move_planner(self) -> MovePlanner {
        match self {
            PlannerKind::Exact | PlannerKind::ExactMoves => MovePlanner::Exact,
            PlannerKind::NearOptimal | PlannerKind::Oracle => MovePlanner::NearOptimal,
            PlannerKind::Optimal => MovePlanner::Optimal,
        }
    }

    /// The planner of block moves on the literature's unbounded table (a PDDL task, a folder
    /// of them) that this name means ([`PlannerKind::move_planner`]), with `options`; an
    /// error for an option that does not apply to it.
    pub fn block_planner(self, options: &PlanOptions) -> Result<Box<dyn BlockPlanner>> {
        let planner = self.move_planner();
        let refuse = |option, owner| {
            Err(OracleError::OptionNotApplicable {
                option,
                owner,
                planner: planner.name(),
            })
        };
        if options.budget.is_some() && planner != MovePlanner::Exact {
            return refuse("search budget", "exact solver");
        }
        if options.time_limit.is_some() && planner != MovePlanner::Optimal {
            return refuse("time limit", "optimal solver");
        }
        Ok(match planner {
            MovePlanner::Exact => {
                Box::new(ExactMoves::new().with_budget(options.budget.unwrap_or(DEFAULT_MOVE_BUDGET)))
            }
            MovePlanner::NearOptimal => Box::new(NearOptimal::new()),
            MovePlanner::Optimal => Box::new(match options.time_limit {
                Some(limit) => OptimalMoves::new().with_time_limit(limit),
                None => OptimalMoves::new(),
            }),
        })
    }

    /// A plan in gripper steps from `state` to `goal` in the world of `solver` (its grid,
    /// view and protocol; its node budget bounds `exact`). Empty when the goal holds.
    pub fn plan_steps(self, solver: &ExactSolver, state: &State, goal: &Goal) -> Result<Plan> {
        let view = solver.view();
        self.check_view(view)?;
        match (self, view) {
            (PlannerKind::Exact, _) => solver.solve(state, goal),
            (PlannerKind::Oracle, View::Top) => Oracle::new(solver.grid())
                .with_protocol(solver.protocol())
                .plan(state, goal),
            (_, _) => {
                let moves = self.plan_moves(solver.grid(), state, goal)?.plan;
                Ok(Plan {
                    actions: gripper_actions(solver.grid(), state, &moves)?,
                })
            }
        }
    }

    /// A plan from `state` to `goal` in the world of `solver`, counted in `cost`: in gripper
    /// steps ([`PlannerKind::plan_steps`]) or, in the side view only, in block moves
    /// ([`PlannerKind::plan_moves`]).
    pub fn plan(self, solver: &ExactSolver, cost: Cost, state: &State, goal: &Goal) -> Result<CountedPlan> {
        match cost {
            Cost::Steps => self.plan_steps(solver, state, goal).map(CountedPlan::Steps),
            Cost::Moves if solver.view() == View::Top => Err(OracleError::CostNotInView),
            Cost::Moves => {
                self.check_view(solver.view())?;
                self.plan_moves(solver.grid(), state, goal).map(CountedPlan::Moves)
            }
        }
    }

    /// A plan in block moves from the side-view `state` to `goal` on a table as wide as
    /// `grid`, with its lower bound (module docs: `exact` and `exact-moves` are both the
    /// fewest moves).
    pub fn plan_moves(self, grid: sim::Grid, state: &State, goal: &Goal) -> Result<CertifiedPlan> {
        plan_side_certified(self.move_planner(), grid, state, goal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::Grid;

    fn side_problem() -> (State, Goal) {
        // 1 on 0, 2 on 1; 3 alone. The goal: 1 on the table, 3 on 1, 2 on 3.
        let state = State::parse("0,0;0,1;0,2;1,0", None, Grid::default()).unwrap();
        (state, Goal::parse("1,3,2/", Some(4)).unwrap())
    }

    #[test]
    fn exact_is_the_fewest_gripper_steps_in_both_views() {
        let grid = Grid::default();
        let (state, goal) = side_problem();
        let side = ExactSolver::new(grid).with_view(View::Side);
        let fewest = side.distance(&state, &goal).unwrap() as usize;
        for kind in PlannerKind::ALL {
            let plan = kind.plan_steps(&side, &state, &goal).unwrap();
            assert!(plan.len() >= fewest, "{kind}");
            if kind == PlannerKind::Exact {
                assert_eq!(plan.len(), fewest);
            }
        }
        // Counted in moves, exact and exact-moves are the same planner.
        let moves = |k: PlannerKind| k.plan_moves(grid, &state, &goal).unwrap().plan;
        assert_eq!(moves(PlannerKind::Exact), moves(PlannerKind::ExactMoves));
        assert_eq!(moves(PlannerKind::Oracle), moves(PlannerKind::NearOptimal));
        assert_eq!(moves(PlannerKind::Optimal).len(), moves(PlannerKind::Exact).len());
        // The fewest moves, carried out, take more gripper steps than the fewest steps here.
        let carried = PlannerKind::ExactMoves.plan_steps(&side, &state, &goal).unwrap();
        assert_eq!(moves(PlannerKind::ExactMoves).len(), 4);
        assert!(carried.len() >= fewest);
    }

    #[test]
    fn block_move_planners_are_refused_in_the_top_view_and_names_read_back() {
        let top = ExactSolver::new(Grid::default());
        let state = State::parse("0,0;3,0;5,2", None, Grid::default()).unwrap();
        let goal: Goal = "1,0,2".parse().unwrap();
        for kind in [PlannerKind::ExactMoves, PlannerKind::NearOptimal, PlannerKind::Optimal] {
            let err = kind.plan_steps(&top, &state, &goal).unwrap_err().to_string();
            assert!(err.contains("side view"), "{err}");
        }
        let exact = PlannerKind::Exact.plan_steps(&top, &state, &goal).unwrap();
        assert_eq!(exact, top.solve(&state, &goal).unwrap());
        for name in PlannerKind::NAMES {
            assert_eq!(name.parse::<PlannerKind>().unwrap().name(), name);
        }
        let err = "greedy".parse::<PlannerKind>().unwrap_err().to_string();
        assert!(
            err.contains("exact, exact-moves, near-optimal, optimal, oracle"),
            "{err}"
        );
    }

    #[test]
    fn a_block_planner_takes_only_its_own_options() {
        let limit = PlanOptions {
            time_limit: Some(std::time::Duration::from_secs(1)),
            ..PlanOptions::default()
        };
        let budget = PlanOptions {
            budget: Some(10),
            ..PlanOptions::default()
        };
        assert_eq!(PlannerKind::Optimal.block_planner(&limit).unwrap().name(), "optimal");
        assert_eq!(PlannerKind::ExactMoves.block_planner(&budget).unwrap().name(), "exact");
        assert_eq!(
            PlannerKind::Oracle
                .block_planner(&PlanOptions::default())
                .unwrap()
                .name(),
            "near-optimal"
        );
        let err = PlannerKind::NearOptimal
            .block_planner(&limit)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("time limit is the optimal solver's"), "{err}");
        let err = PlannerKind::Optimal.block_planner(&budget).err().unwrap().to_string();
        assert!(err.contains("search budget is the exact solver's"), "{err}");
    }
}
