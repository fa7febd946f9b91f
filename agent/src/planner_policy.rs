//! The planners as agents: the oracle and the exact solver play episodes like any policy,
//! and so does the paper's greedy oracle.
//!
//! A planner plans once from the episode's start and then follows its plan, replanning only
//! if the world is not in the state the plan expects (say, a learner or a demonstrator took
//! some actions in between). It plans under the observation's action protocol, so every
//! action it takes is legal (under `paper` the exact solver's plans are the shortest legal
//! ones).
//!
//! [`PaperOraclePolicy`] plans nothing: it asks the authors' greedy walker
//! ([`oracle::CentroidWalker`]) at every step.

use oracle::{CentroidWalker, ExactSolver, Oracle, Plan, Planner};
use sim::seeding::SimRng;
use sim::{Action, Goal, Grid, GridWorld, Observation, State};

use crate::error::Result;
use crate::policy::Policy;

/// The rest of a plan: each action with the state it is to be taken from, next one last.
#[derive(Clone, Debug, Default)]
struct PlanCursor {
    goal: Option<Goal>,
    steps: Vec<(State, Action)>,
}

impl PlanCursor {
    /// The plan's next action, if `obs` is the state the plan expects now.
    fn next(&mut self, obs: &Observation) -> Option<Action> {
        match self.steps.last() {
            Some((state, action)) if *state == obs.state && self.goal.as_ref() == Some(&obs.goal) => {
                let action = *action;
                self.steps.pop();
                Some(action)
            }
            _ => None,
        }
    }

    /// Follows `plan` from `obs`, returning its first action.
    fn follow(&mut self, obs: &Observation, plan: Plan) -> Result<Action> {
        // Replayed by the observation's view's rules (in the side view a dropped block falls).
        let states = GridWorld::new_in(obs.view, obs.grid, obs.state.clone())?.replay(&plan.actions)?;
        let mut steps: Vec<(State, Action)> = states.into_iter().zip(plan.actions).collect();
        steps.reverse();
        self.goal = Some(obs.goal.clone());
        self.steps = steps;
        // An empty plan means the goal holds; the oracle says so as an error.
        self.next(obs).map_or_else(
            || {
                Err(oracle::OracleError::GoalAlreadyHolds {
                    goal: obs.goal.to_string(),
                }
                .into())
            },
            Ok,
        )
    }
}

/// A planner as a policy: it plans once, follows its plan, and replans only when the world
/// is not in the state the plan expects. Its name is the planner's (`oracle`, `exact`).
#[derive(Clone, Debug)]
pub struct PlannerPolicy<P> {
    planner: P,
    cursor: PlanCursor,
}

/// The centroid + A* oracle as a policy.
pub type OraclePolicy = PlannerPolicy<Oracle>;

/// The exact solver as a policy: it takes a shortest path to the goal.
pub type ExactPolicy = PlannerPolicy<ExactSolver>;

impl<P: Planner> PlannerPolicy<P> {
    /// A policy that follows `planner`'s plans.
    pub fn with_planner(planner: P) -> Self {
        Self {
            planner,
            cursor: PlanCursor::default(),
        }
    }
}

impl OraclePolicy {
    /// An oracle policy for worlds on `grid`.
    pub fn new(grid: Grid) -> Self {
        Self::with_planner(Oracle::new(grid))
    }
}

impl ExactPolicy {
    /// An exact policy for worlds on `grid`, with the solver's default budget.
    pub fn new(grid: Grid) -> Self {
        Self::with_planner(ExactSolver::new(grid))
    }
}

impl<P: Planner + Clone> Policy for PlannerPolicy<P> {
    fn name(&self) -> String {
        self.planner.name().into()
    }

    fn begin_episode(&mut self, _obs: &Observation) {
        self.cursor = PlanCursor::default();
    }

    fn act(&mut self, obs: &Observation, _rng: &mut SimRng) -> Result<Action> {
        if self.planner.protocol() != obs.protocol {
            self.planner = self.planner.clone().with_protocol(obs.protocol);
            self.cursor = PlanCursor::default();
        }
        match self.cursor.next(obs) {
            Some(action) => Ok(action),
            None => {
                let plan = self.planner.plan(&obs.state, &obs.goal)?;
                self.cursor.follow(obs, plan)
            }
        }
    }
}

/// The paper's oracle as a policy: the authors' greedy centroid walker, asked at every
/// step, a random block when nothing is held (its draws come from the episode's policy
/// generator). It can get stuck, as the authors' could.
#[derive(Clone, Copy, Debug)]
pub struct PaperOraclePolicy {
    walker: CentroidWalker,
}

impl PaperOraclePolicy {
    /// The paper's oracle for worlds on `grid`.
    pub fn new(grid: Grid) -> Self {
        Self {
            walker: CentroidWalker::new(grid),
        }
    }
}

impl Policy for PaperOraclePolicy {
    fn name(&self) -> String {
        "paper-oracle".into()
    }

    fn begin_episode(&mut self, _obs: &Observation) {
        self.walker.begin_episode();
    }

    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> Result<Action> {
        Ok(self.walker.next_action(&obs.state, &obs.goal, rng)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Summary, play};
    use sim::{Backend, Env, EnvConfig};

    #[test]
    fn planners_reach_the_goal_in_the_physics_world_in_their_planned_steps() {
        let config = EnvConfig {
            backend: Backend::Physics,
            ..EnvConfig::default()
        };
        let grid = config.grid;
        let mut env = Env::new(config).unwrap();
        let exact = play(&mut env, &mut ExactPolicy::new(grid), 30, 5, &mut ()).unwrap();
        let oracle = play(&mut env, &mut OraclePolicy::new(grid), 30, 5, &mut ()).unwrap();
        for (e, o) in exact.iter().zip(&oracle) {
            assert!(e.reached_goal && o.reached_goal);
            assert_eq!(e.start, o.start);
            let shortest = ExactSolver::new(grid).distance(&e.start, &e.goal).unwrap();
            assert_eq!(e.steps, shortest);
            assert_eq!(
                o.steps as usize,
                Oracle::new(grid).plan(&o.start, &o.goal).unwrap().len()
            );
        }
        assert_eq!(Summary::of(&oracle).failures, 0);
    }

    #[test]
    fn a_policy_replans_when_the_world_left_its_plan() {
        let goal: Goal = "1,0,2".parse().unwrap();
        let mut env = Env::new(EnvConfig::with_goal(goal.clone())).unwrap();
        let mut policy = OraclePolicy::new(env.config().grid);
        let mut rng = sim::seeding::rng(0);
        let obs = env.reset(3);
        policy.begin_episode(&obs);
        policy.act(&obs, &mut rng).unwrap();
        // Someone else acts instead: pick block 2 and move it.
        env.step(Action::Pick(sim::BlockId(2))).unwrap();
        let mut obs = env.step(Action::Up).unwrap().observation;
        let mut steps = 0;
        while !goal.holds(&obs.state) {
            obs = env.step(policy.act(&obs, &mut rng).unwrap()).unwrap().observation;
            steps += 1;
            assert!(steps < 100);
        }
    }
}
