//! Policies chosen by name: the random agent, the planners and the trained models.
//!
//! `blockstack run --agent`, Python's `demonstrations(expert=...)` and the experiments name
//! the agent that plays with a [`PolicyKind`] and build it here, from the world it plays
//! and, for a trained agent, its model, so that a name means one policy wherever it is
//! given. The planners' names and what each plans in either view are
//! [`oracle::PlannerKind`]'s: `exact` is the fewest gripper steps in both views,
//! `exact-moves` the fewest block moves carried out by the gripper (side view),
//! `near-optimal` the near-optimal block-move planner carried out (side view), `optimal`
//! the optimal block-move solver carried out (side view) and `oracle` the view's oracle. `q`,
//! `dqn` and `relational` play a trained model of their kind ([`PlayingModel`]); `dqn`, the
//! name earlier releases gave every model `blockstack dqn` writes, plays a relational policy
//! too ([`PolicyKind::plays`]).
//!
//! A planner plays by planning from the state it sees and following its plan
//! ([`PlannerPolicy`]; in the side view the block-move planners plan again at each move,
//! [`TowersPolicy`]), so every episode it plays takes as many steps as its plan from the
//! episode's start.

use oracle::{ExactSolver, PlannerKind};
use sim::{EnvConfig, View};

use crate::assist::OracleKind;
use crate::error::{AgentError, Result};
use crate::planner_policy::{OraclePolicy, PaperOraclePolicy, PlannerPolicy};
use crate::policy::{Policy, RandomPolicy};
use crate::towers_policy::TowersPolicy;

/// Which agent plays (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PolicyKind {
    /// Uniformly random legal actions.
    Random,
    /// The view's oracle ([`PlannerKind::Oracle`]); from above ours or the paper's
    /// ([`PolicyOptions::oracle`]).
    Oracle,
    /// The fewest gripper steps ([`PlannerKind::Exact`]).
    Exact,
    /// The fewest block moves, carried out by the gripper ([`PlannerKind::ExactMoves`]).
    ExactMoves,
    /// The near-optimal block-move planner, carried out ([`PlannerKind::NearOptimal`]).
    NearOptimal,
    /// The optimal block-move solver, carried out ([`PlannerKind::Optimal`]).
    Optimal,
    /// A trained tabular Q-learner.
    Q,
    /// A trained network.
    Dqn,
    /// A trained relational policy of block moves (`blockstack dqn --preset general`).
    Relational,
}

sim::names!(PolicyKind { Random = "random", Oracle = "oracle", Exact = "exact", ExactMoves = "exact-moves", NearOptimal = "near-optimal", Optimal = "optimal", Q = "q", Dqn = "dqn", Relational = "relational" } unknown(text) -> AgentError {
    AgentError::Config(format!("unknown agent {text:?}: choose one of {}", PolicyKind::NAMES.join(", ")))
});

impl From<PlannerKind> for PolicyKind {
    fn from(planner: PlannerKind) -> PolicyKind {
        match planner {
            PlannerKind::Exact => PolicyKind::Exact,
            PlannerKind::ExactMoves => PolicyKind::ExactMoves,
            PlannerKind::NearOptimal => PolicyKind::NearOptimal,
            PlannerKind::Optimal => PolicyKind::Optimal,
            PlannerKind::Oracle => PolicyKind::Oracle,
        }
    }
}

/// A trained model that plays: what [`PolicyKind::Q`], [`PolicyKind::Dqn`] and
/// [`PolicyKind::Relational`] need. A tabular agent is one; so is `neural`'s model of every
/// kind.
pub trait PlayingModel {
    /// [`PolicyKind::Q`], [`PolicyKind::Dqn`] or [`PolicyKind::Relational`].
    fn kind(&self) -> PolicyKind;

    /// Its name in reports.
    fn model_name(&self) -> String;

    /// The model playing, with a random legal action with probability `epsilon`.
    fn playing(&self, epsilon: f64) -> Result<Box<dyn Policy + '_>>;
}

/// What a policy is built with beside its world and model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolicyOptions {
    /// A trained agent's probability of a random legal action.
    pub epsilon: f64,
    /// The oracle the top view's `oracle` agent is: ours (A*) or the paper's walker.
    pub oracle: OracleKind,
    /// The most states one exact search may store ([`ExactSolver::with_node_budget`]).
    pub node_budget: usize,
}

impl Default for PolicyOptions {
    /// The paper's test epsilon, our oracle, the exact solver's default budget.
    fn default() -> Self {
        PolicyOptions {
            epsilon: crate::profile::TEST_EPSILON,
            oracle: OracleKind::Astar,
            node_budget: oracle::DEFAULT_NODE_BUDGET,
        }
    }
}

impl PolicyOptions {
    /// What an agent of a world of `profile` plays with unless told otherwise: the
    /// profile's test epsilon and oracle (ours under `spec`, the authors' greedy walker under
    /// `original`) and the exact solver's default budget. The one rule `blockstack run`,
    /// Python's `demonstrations` and environments' `oracle_action` share.
    pub fn of_profile(profile: sim::Profile) -> PolicyOptions {
        let learner = crate::LearnerProfile::of(profile);
        PolicyOptions {
            epsilon: learner.test_epsilon,
            oracle: learner.oracle,
            ..PolicyOptions::default()
        }
    }
}

impl PolicyKind {
    /// The planner this agent is, if it is one.
    pub const fn planner(self) -> Option<PlannerKind> {
        match self {
            PolicyKind::Exact => Some(PlannerKind::Exact),
            PolicyKind::ExactMoves => Some(PlannerKind::ExactMoves),
            PolicyKind::NearOptimal => Some(PlannerKind::NearOptimal),
            PolicyKind::Optimal => Some(PlannerKind::Optimal),
            PolicyKind::Oracle => Some(PlannerKind::Oracle),
            PolicyKind::Random | PolicyKind::Q | PolicyKind::Dqn | PolicyKind::Relational => None,
        }
    }

    /// Whether it plays a trained model.
    pub const fn needs_model(self) -> bool {
        matches!(self, PolicyKind::Q | PolicyKind::Dqn | PolicyKind::Relational)
    }

    /// Whether this agent plays a model of kind `model`: its own kind, and for `dqn` (every
    /// model `blockstack dqn` writes, as earlier releases named them) a relational policy too.
    pub fn plays(self, model: PolicyKind) -> bool {
        model == self || (self == PolicyKind::Dqn && model == PolicyKind::Relational)
    }

    /// The random agent or a planner, playing `world` (its grid, view and protocol); an
    /// error for a planner the world's view does not have, or a kind that needs a model.
    pub fn expert(self, world: &EnvConfig, options: &PolicyOptions) -> Result<Box<dyn Policy + Send>> {
        let Some(planner) = self.planner() else {
            return match self {
                PolicyKind::Random => Ok(Box::new(RandomPolicy)),
                _ => Err(AgentError::Config(format!(
                    "the {self} agent plays a trained model: give it one"
                ))),
            };
        };
        planner.check_view(world.view)?;
        Ok(match (planner, world.view) {
            (PlannerKind::Exact, _) => Box::new(PlannerPolicy::with_planner(
                ExactSolver::for_world(world).with_node_budget(options.node_budget),
            )),
            (PlannerKind::Oracle, View::Top) => match options.oracle {
                OracleKind::Astar => Box::new(OraclePolicy::new(world.grid)),
                OracleKind::Paper => Box::new(PaperOraclePolicy::new(world.grid)),
            },
            (_, _) => Box::new(TowersPolicy::new(planner.move_planner())),
        })
    }

    /// This agent playing `world`: [`PolicyKind::expert`], or for a trained agent `model`
    /// playing with [`PolicyOptions::epsilon`] (an error without a model, or with a model it
    /// does not play, [`PolicyKind::plays`]).
    pub fn policy<'a>(
        self,
        world: &EnvConfig,
        model: Option<&'a dyn PlayingModel>,
        options: &PolicyOptions,
    ) -> Result<Box<dyn Policy + 'a>> {
        if !self.needs_model() {
            return Ok(self.expert(world, options)?);
        }
        let Some(model) = model else {
            return Err(AgentError::Config(format!(
                "the {self} agent plays a trained model: give it one"
            )));
        };
        if !self.plays(model.kind()) {
            return Err(AgentError::ModelMismatch(format!(
                "{} is a {} model, not what the {self} agent plays",
                model.model_name(),
                model.kind()
            )));
        }
        model.playing(options.epsilon)
    }
}

impl PlayingModel for crate::QAgent {
    fn kind(&self) -> PolicyKind {
        PolicyKind::Q
    }

    fn model_name(&self) -> String {
        self.name()
    }

    fn playing(&self, epsilon: f64) -> Result<Box<dyn Policy + '_>> {
        Ok(Box::new(self.policy(epsilon)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{Backend, Env, Goal};

    #[test]
    fn every_planner_is_the_agent_of_its_name() {
        for planner in PlannerKind::ALL {
            let kind = PolicyKind::from(planner);
            assert_eq!(kind.name(), planner.name());
            assert_eq!(kind.planner(), Some(planner));
        }
        let planners = PolicyKind::ALL.iter().filter(|k| k.planner().is_some()).count();
        assert_eq!(planners, PlannerKind::ALL.len());
        let err = "human".parse::<PolicyKind>().unwrap_err().to_string();
        assert!(
            err.contains("random, oracle, exact, exact-moves, near-optimal, optimal, q, dqn"),
            "{err}"
        );
    }

    /// In the side view `exact` takes the fewest gripper steps and `exact-moves` the fewest
    /// block moves: each episode as long as its planner's plan from the start.
    #[test]
    fn exact_is_the_fewest_gripper_steps_in_the_side_view_too() {
        let goal = Goal::parse("0,1/2,3", Some(4)).unwrap();
        let world = EnvConfig {
            view: View::Side,
            blocks: 4,
            backend: Backend::Grid,
            ..EnvConfig::with_goal(goal.clone())
        };
        let mut env = Env::new(world.clone()).unwrap();
        let options = PolicyOptions::default();
        let solver = ExactSolver::for_world(&world);
        let mut longer = 0;
        for seed in 0..8 {
            let mut steps = Vec::new();
            for kind in [PolicyKind::Exact, PolicyKind::ExactMoves] {
                let mut policy = kind.expert(&world, &options).unwrap();
                let r = crate::play(&mut env, policy.as_mut(), 1, seed, &mut ())
                    .unwrap()
                    .remove(0);
                assert!(r.reached_goal);
                let planned = kind.planner().unwrap().plan_steps(&solver, &r.start, &goal).unwrap();
                assert_eq!(r.steps as usize, planned.len(), "{kind} seed {seed}");
                steps.push(r.steps);
            }
            assert!(steps[0] <= steps[1]);
            longer += usize::from(steps[0] < steps[1]);
        }
        assert!(longer > 0, "the fewest moves took the fewest steps on every start");
        for kind in [PolicyKind::ExactMoves, PolicyKind::NearOptimal] {
            let err = kind.expert(&EnvConfig::default(), &options).err().unwrap().to_string();
            assert!(err.contains("only the side view has"), "{err}");
        }
        let err = PolicyKind::Q.policy(&world, None, &options).err().unwrap().to_string();
        assert!(err.contains("plays a trained model"), "{err}");
    }
}
