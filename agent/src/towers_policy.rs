//! The side view's planners as agents: block-move plans carried out by the gripper.
//!
//! In the side view (docs/world.md section 12) the planners of [`oracle::towers`] plan block
//! moves over the towers standing in a state. [`TowersPolicy`] plays such a plan in the
//! gripper's world: it plans once, from the state it first sees, and at each block-move
//! boundary (nothing held, no gripper action pending) takes the plan's next move, which
//! [`sim::block_move::expand`] turns into the gripper actions that carry it out. It plans
//! again only when the world has left the plan: when the state it sees at a boundary is not
//! the one the moves so far should have made (something else moved a block). Planning at
//! every move instead made an episode cost a plan per move, quadratic in the blocks (44 ms
//! a move at 10,000 blocks); checking the state costs one comparison of the blocks' cells.
//!
//! A move to the table goes to the leftmost empty column, and the table is as wide as the
//! grid, so every plan it follows fits.

use std::collections::VecDeque;

use oracle::towers::{Move, MovePlanner, block_move_of, plan_side};
use sim::block_move::{self, BlockMove};
use sim::seeding::SimRng;
use sim::{Action, Cell, Observation};

use crate::error::{AgentError, Result};
use crate::policy::Policy;

/// A block-move planner ([`MovePlanner`]) as a side-view policy (module docs). Its name is
/// the agent's ([`crate::PolicyKind`]): `exact-moves` (the fewest block moves; `exact` is the
/// fewest gripper steps) or `near-optimal`.
#[derive(Clone, Debug)]
pub struct TowersPolicy {
    planner: MovePlanner,
    pending: VecDeque<Action>,
    /// The rest of the plan being followed, next move first.
    plan: VecDeque<Move>,
    /// The blocks' cells the plan's moves so far should leave at the next boundary.
    expected: Vec<Cell>,
    /// How many plans it has made.
    plans: usize,
}

impl TowersPolicy {
    /// A policy that follows `planner`'s plans.
    pub fn new(planner: MovePlanner) -> Self {
        Self {
            planner,
            pending: VecDeque::new(),
            plan: VecDeque::new(),
            expected: Vec::new(),
            plans: 0,
        }
    }

    /// How many plans it has made since it was created: one an episode while nothing but
    /// its own moves changes the world.
    pub fn plans_made(&self) -> usize {
        self.plans
    }

    /// The next block move from `obs`: the plan's next one while the world is where the
    /// plan left it, else the first of a new plan.
    fn next_move(&mut self, obs: &Observation) -> Result<BlockMove> {
        if self.plan.is_empty() || obs.state.cells() != self.expected.as_slice() {
            self.plan = plan_side(self.planner, obs.grid, &obs.state, &obs.goal)?.moves.into();
            self.plans += 1;
        }
        let Some(next) = self.plan.pop_front() else {
            return Err(oracle::OracleError::GoalAlreadyHolds {
                goal: obs.goal.to_string(),
            }
            .into());
        };
        let mv = block_move_of(&obs.state, obs.grid, next)?;
        // Where the block lands: on its target, or at the foot of the column it is put in.
        let landing = match mv {
            BlockMove::Onto { target, .. } => {
                let below = obs.state.cell(target);
                Cell::new(below.x, below.y + 1)
            }
            BlockMove::ToTable { column, .. } => Cell::new(column, 0),
        };
        self.expected.clear();
        self.expected.extend_from_slice(obs.state.cells());
        self.expected[next.block] = landing;
        Ok(mv)
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
        self.plan.clear();
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

    /// Plays `policy` in `env` from `obs` to the episode's end; `disturb_after` block moves
    /// in (counted as Drops), something else moves a block: the first legal block move. The
    /// last observation, and whether the policy acted after the disturbance.
    fn play_disturbed(
        env: &mut Env,
        policy: &mut TowersPolicy,
        obs: Observation,
        disturb_after: Option<usize>,
    ) -> (Observation, bool) {
        let mut acted_after = false;
        let mut rng = sim::seeding::rng(3);
        policy.begin_episode(&obs);
        let (mut obs, mut drops) = (obs, 0);
        while !env.is_over() {
            let action = policy.act(&obs, &mut rng).unwrap();
            acted_after |= disturb_after.is_some_and(|d| drops >= d);
            drops += usize::from(action == Action::Drop);
            obs = env.step(action).unwrap().observation;
            if action == Action::Drop && disturb_after == Some(drops) && !env.is_over() {
                let blocks = obs.state.block_count();
                let legal = block_move::legal_moves(&obs.state, obs.grid);
                let index = legal.iter().position(|&l| l).unwrap();
                let mv = BlockMove::from_index(index, blocks, obs.grid).unwrap();
                for a in block_move::expand(&obs.state, obs.grid, mv).unwrap() {
                    obs = env.step(a).unwrap().observation;
                }
            }
        }
        (obs, acted_after)
    }

    fn side_env(blocks: usize) -> Env {
        let goal = Goal::parse("3,1,0/2,4,5", Some(blocks)).unwrap();
        Env::new(EnvConfig {
            view: View::Side,
            blocks,
            backend: Backend::Grid,
            ..EnvConfig::with_goal(goal)
        })
        .unwrap()
    }

    /// On an episode nothing disturbs, the policy plans once and follows that plan to the
    /// goal.
    #[test]
    fn an_undisturbed_episode_is_planned_once() {
        let mut env = side_env(6);
        for planner in [MovePlanner::NearOptimal, MovePlanner::Optimal] {
            for k in 0..5 {
                let obs = env.reset(k);
                let mut policy = TowersPolicy::new(planner);
                let (last, _) = play_disturbed(&mut env, &mut policy, obs, None);
                assert!(env.goal().holds_in(View::Side, &last.state), "{planner:?} {k}");
                assert_eq!(policy.plans_made(), 1, "{planner:?} {k}");
            }
        }
    }

    /// When something else moves a block in the middle of the episode, the policy sees the
    /// world left its plan, plans again, and still reaches the goal.
    #[test]
    fn a_disturbed_episode_is_planned_again_and_reaches_the_goal() {
        let mut env = side_env(6);
        let mut disturbed = 0;
        for k in 0..10 {
            let obs = env.reset(k);
            let mut policy = TowersPolicy::new(MovePlanner::NearOptimal);
            let plan = plan_side(MovePlanner::NearOptimal, obs.grid, &obs.state, &obs.goal).unwrap();
            if plan.len() < 2 {
                continue;
            }
            let (last, acted_after) = play_disturbed(&mut env, &mut policy, obs, Some(1));
            assert!(env.goal().holds_in(View::Side, &last.state), "start {k}");
            // The disturbing move may itself reach the goal, leaving nothing to plan.
            if !acted_after {
                continue;
            }
            disturbed += 1;
            assert!(policy.plans_made() >= 2, "start {k}");
        }
        assert!(disturbed > 0);
    }
}
