//! The side view's planners as agents: block-move plans carried out by the gripper.
//!
//! In the side view (docs/world.md section 12) the planners of [`oracle::towers`] plan block
//! moves over the towers standing in a state. [`TowersPolicy`] plays such a plan in the
//! gripper's world: at each block-move boundary (nothing held, no gripper action pending) it
//! plans from the state it sees and takes the plan's first move, which
//! [`sim::block_move::expand`] turns into the gripper actions that carry it out. Planning
//! again at every move, rather than once, keeps it right whatever happened in between, and
//! costs little: a plan of 10 blocks takes milliseconds exactly, microseconds near-optimally.
//!
//! A move to the table goes to the leftmost empty column, and the table is as wide as the
//! grid, so every plan it follows fits.

use std::collections::VecDeque;

use oracle::towers::{MovePlanner, block_move_of, plan_side};
use sim::block_move::{self, BlockMove};
use sim::seeding::SimRng;
use sim::{Action, Observation};

use crate::error::{AgentError, Result};
use crate::policy::Policy;

/// A block-move planner ([`MovePlanner`]) as a side-view policy (module docs). Its name is
/// the agent's ([`crate::PolicyKind`]): `exact-moves` (the fewest block moves; `exact` is the
/// fewest gripper steps) or `near-optimal`.
#[derive(Clone, Debug)]
pub struct TowersPolicy {
    planner: MovePlanner,
    pending: VecDeque<Action>,
}

impl TowersPolicy {
    /// A policy that follows `planner`'s plans.
    pub fn new(planner: MovePlanner) -> Self {
        Self {
            planner,
            pending: VecDeque::new(),
        }
    }

    /// The next block move from `obs`, planned afresh.
    fn next_move(&self, obs: &Observation) -> Result<BlockMove> {
        let plan = plan_side(self.planner, obs.grid, &obs.state, &obs.goal)?;
        let Some(first) = plan.moves.first() else {
            return Err(oracle::OracleError::GoalAlreadyHolds {
                goal: obs.goal.to_string(),
            }
            .into());
        };
        Ok(block_move_of(&obs.state, obs.grid, *first)?)
    }
}

impl Policy for TowersPolicy {
    fn name(&self) -> String {
        match self.planner {
            MovePlanner::Exact => oracle::PlannerKind::ExactMoves.name().into(),
            MovePlanner::NearOptimal => oracle::PlannerKind::NearOptimal.name().into(),
            MovePlanner::Optimal => oracle::PlannerKind::Optimal.name().into(),
        }
    }

    fn begin_episode(&mut self, _obs: &Observation) {
        self.pending.clear();
    }

    fn act(&mut self, obs: &Observation, _rng: &mut SimRng) -> Result<Action> {
        if self.pending.is_empty() {
            let mv = self.next_move(obs)?;
            self.pending.extend(block_move::expand(&obs.state, obs.grid, mv)?);
        }
        self.pending
            .pop_front()
            .ok_or_else(|| AgentError::Config("a block move expanded into no gripper action".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use oracle::towers::{ExactMoves, Table, TowerGoal, Towers};
    use sim::{Backend, Env, EnvConfig, Goal, View, view};

    /// Every goal of 3 blocks, one tower or two, from seeded side-view starts on both
    /// backends: the goal is reached, and by the exact planner in the fewest block moves.
    #[test]
    fn the_planners_reach_every_goal_in_the_side_view() {
        let mut goals: Vec<Goal> = Goal::all(3).unwrap();
        for text in ["0,1/2", "2,0/1", "1/0,2", "0/1/2"] {
            goals.push(Goal::parse(text, Some(3)).unwrap());
        }
        for backend in [Backend::Grid, Backend::Physics] {
            for goal in &goals {
                let mut env = Env::new(EnvConfig {
                    view: View::Side,
                    backend,
                    ..EnvConfig::with_goal(goal.clone())
                })
                .unwrap();
                for planner in [MovePlanner::Exact, MovePlanner::NearOptimal] {
                    let mut policy = TowersPolicy::new(planner);
                    let results = crate::play(&mut env, &mut policy, 5, 11, &mut ()).unwrap();
                    assert!(results.iter().all(|r| r.reached_goal), "{goal} {planner:?} {backend:?}");
                }
            }
        }
    }

    /// The exact planner's episode takes as many block moves as its plan from the start has:
    /// counted as the number of Drops.
    #[test]
    fn the_exact_planner_takes_the_fewest_block_moves() {
        let goal = Goal::parse("1,2,0/", Some(4)).unwrap();
        let mut env = Env::new(EnvConfig {
            view: View::Side,
            blocks: 4,
            backend: Backend::Grid,
            ..EnvConfig::with_goal(goal.clone())
        })
        .unwrap();
        for k in 0..10 {
            let obs = env.reset(k);
            let start = Towers::new(&view::towers(&obs.state).unwrap()).unwrap();
            let fewest = ExactMoves::new()
                .with_table(Table::Columns(7))
                .solve(&start, &TowerGoal::new(&goal.tower_lists()).unwrap())
                .unwrap()
                .len();
            let mut policy = TowersPolicy::new(MovePlanner::Exact);
            policy.begin_episode(&obs);
            let (mut obs, mut drops) = (obs, 0);
            let mut rng = sim::seeding::rng(k);
            while !env.is_over() {
                let action = policy.act(&obs, &mut rng).unwrap();
                drops += usize::from(action == Action::Drop);
                obs = env.step(action).unwrap().observation;
            }
            assert!(goal.holds_in(View::Side, &obs.state));
            assert_eq!(drops, fewest, "start {k}");
        }
    }
}
