//! Simulated demonstrators: stand-ins for the paper's three people, so that correction runs
//! headless and reproducibly.
//!
//! A demonstrator watches the agent's proposed action at every step and decides whether to
//! step in (its *attentiveness*), and if so what to do instead (its *skill*):
//!
//! - **Off a shortest path.** With probability [`DemonstratorProfile::attention`] it looks
//!   closely at the proposal, and steps in if the proposal is not on a shortest path: the
//!   exact solver's distance to the goal after it is not one less than before.
//! - **Going in circles.** With [`DemonstratorProfile::notices_loops`] it steps in whenever
//!   the proposal would bring back a state of the last [`LOOP_WINDOW`] steps of the episode
//!   (picking and dropping the same block, moving back and forth), even when not looking
//!   closely: that is what a person notices first.
//! - **Impatience.** With probability [`DemonstratorProfile::takeover`] it takes the step
//!   whatever the agent proposed.
//!
//! When it steps in it chooses its [`DemonstratorPlanner`]'s next action, except that with probability
//! [`DemonstratorProfile::slip`] it presses a wrong key: a uniformly drawn other action.
//!
//! It plays by the observation's action protocol like the agent: its planners plan under it
//! (shortest paths are shortest legal paths), and a wrong key is a uniformly drawn other
//! *legal* action. Under `free` every action is legal and the draws are the same as before
//! protocols existed.
//! Its draws come from a generator of its own per episode (stream 2 of the episode's seed),
//! so they never shift the starts or the agent's draws.
//!
//! The three presets ([`DemonstratorProfile::preset`]):
//!
//! | preset | name | attention | notices loops | takeover | planner | slip |
//! |---|---|---|---|---|---|---|
//! | 1 | careful expert | 1.0 | yes | 0 | exact | 0 |
//! | 2 | attentive amateur | 0.5 | yes | 0.02 | oracle | 0.05 |
//! | 3 | distracted | 0.15 | yes | 0.05 | oracle | 0.15 |

use std::collections::HashMap;

use oracle::Planner;
use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::seeding::SimRng;
use sim::{Action, ActionProtocol, Goal, Grid, GridWorld, Observation, State, World};

use crate::error::{AgentError, Result};

/// How many recent states of the episode a demonstrator that notices loops remembers.
pub const LOOP_WINDOW: usize = 8;

/// The planner a demonstrator takes its own gripper steps from, step by step under the
/// world's protocol: two of [`oracle::PlannerKind`]'s, the only ones that plan single steps
/// in the top view, where demonstrators correct.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DemonstratorPlanner {
    /// The exact solver's shortest plan.
    Exact,
    /// The centroid + A* oracle (sound, a few steps longer than shortest at times).
    Oracle,
}

/// A simulated demonstrator's attentiveness and skill (module docs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DemonstratorProfile {
    /// A short name for reports.
    pub name: String,
    /// Probability of checking a proposal against the shortest paths, in `[0, 1]`.
    pub attention: f64,
    /// Whether it steps in when the agent is about to revisit a recent state.
    pub notices_loops: bool,
    /// Probability of taking a step whatever the proposal, in `[0, 1]`.
    pub takeover: f64,
    /// What it plans its own actions with.
    pub planner: DemonstratorPlanner,
    /// Probability that a chosen action is a wrong one, in `[0, 1]`.
    pub slip: f64,
}

impl DemonstratorProfile {
    /// Preset 1, 2 or 3 (module docs: the table); an error for any other number.
    pub fn preset(number: u8) -> Result<DemonstratorProfile> {
        let profile = |name: &str, attention, takeover, planner, slip| DemonstratorProfile {
            name: name.into(),
            attention,
            notices_loops: true,
            takeover,
            planner,
            slip,
        };
        match number {
            1 => Ok(profile("careful expert", 1.0, 0.0, DemonstratorPlanner::Exact, 0.0)),
            2 => Ok(profile(
                "attentive amateur",
                0.5,
                0.02,
                DemonstratorPlanner::Oracle,
                0.05,
            )),
            3 => Ok(profile("distracted", 0.15, 0.05, DemonstratorPlanner::Oracle, 0.15)),
            _ => Err(AgentError::Config(format!(
                "there is no demonstrator {number}: choose 1, 2 or 3"
            ))),
        }
    }

    /// An error naming the first probability out of `[0, 1]`.
    pub fn validate(&self) -> Result<()> {
        for (what, p) in [
            ("attention", self.attention),
            ("takeover", self.takeover),
            ("slip", self.slip),
        ] {
            if !(0.0..=1.0).contains(&p) {
                return Err(AgentError::Config(format!(
                    "the demonstrator's {what} {p} is not in [0, 1]"
                )));
            }
        }
        Ok(())
    }
}

/// A simulated demonstrator at work: a profile, its planners, and what it remembers of the
/// current episode.
#[derive(Clone, Debug)]
pub struct Demonstrator {
    profile: DemonstratorProfile,
    grid: Grid,
    exact: oracle::ExactSolver,
    oracle: oracle::Oracle,
    rng: SimRng,
    /// The states of the episode so far, last one last (at most [`LOOP_WINDOW`] + 1).
    recent: Vec<State>,
    /// Exact distances to the current goal under the current protocol, by state.
    distances: HashMap<State, u32>,
    goal: Option<(Goal, ActionProtocol)>,
}

impl Demonstrator {
    /// A demonstrator with `profile` for worlds on `grid`.
    pub fn new(profile: DemonstratorProfile, grid: Grid) -> Demonstrator {
        Demonstrator {
            profile,
            grid,
            exact: oracle::ExactSolver::new(grid),
            oracle: oracle::Oracle::new(grid),
            rng: sim::seeding::rng(0),
            recent: Vec::new(),
            distances: HashMap::new(),
            goal: None,
        }
    }

    /// The profile.
    pub fn profile(&self) -> &DemonstratorProfile {
        &self.profile
    }

    /// Starts watching an episode that begins at `obs` and was reset with `episode_seed`.
    pub fn begin_episode(&mut self, obs: &Observation, episode_seed: u64) {
        self.rng = sim::seeding::rng(episode_seed);
        self.rng.set_stream(2);
        self.recent.clear();
        self.recent.push(obs.state.clone());
        self.watch_goal(obs);
    }

    /// Forgets the distances when `obs` has another goal or protocol than those measured.
    fn watch_goal(&mut self, obs: &Observation) {
        if self.goal != Some((obs.goal.clone(), obs.protocol)) {
            self.distances.clear();
            self.goal = Some((obs.goal.clone(), obs.protocol));
        }
    }

    /// Looks at the agent's `proposed` action in `obs`: the action to take instead, or
    /// `None` to let the agent's stand.
    pub fn review(&mut self, obs: &Observation, proposed: Action) -> Result<Option<Action>> {
        self.watch_goal(obs);
        if self.recent.last() != Some(&obs.state) {
            self.recent.push(obs.state.clone());
            if self.recent.len() > LOOP_WINDOW + 1 {
                self.recent.remove(0);
            }
        }
        let p = &self.profile;
        let (attention, takeover, notices_loops) = (p.attention, p.takeover, p.notices_loops);
        // Every draw is made at every step, whatever the outcome, so one decision never
        // shifts the draws of the next.
        let looks = self.rng.random_bool(attention);
        let takes_over = self.rng.random_bool(takeover);
        let mut after = GridWorld::new(self.grid, obs.state.clone())?;
        after.act(proposed)?;
        let after = after.state_ref().clone();
        let loops = notices_loops && self.recent.contains(&after);
        let off_path = looks && !obs.goal.holds(&after) && {
            let now = self.distance(&obs.state, obs)?;
            self.distance(&after, obs)? + 1 != now
        };
        if !(takes_over || loops || off_path) {
            return Ok(None);
        }
        self.choose(obs).map(Some)
    }

    /// The demonstrator's own action in `obs`: its planner's, or a slip.
    fn choose(&mut self, obs: &Observation) -> Result<Action> {
        let planned = match self.profile.planner {
            DemonstratorPlanner::Exact => self
                .exact
                .with_protocol(obs.protocol)
                .next_action(&obs.state, &obs.goal)?,
            DemonstratorPlanner::Oracle => self
                .oracle
                .with_protocol(obs.protocol)
                .next_action(&obs.state, &obs.goal)?,
        };
        if self.rng.random_bool(self.profile.slip) {
            let legal = obs.legal_actions();
            if legal.count() < 2 {
                return Ok(planned);
            }
            // A uniformly drawn legal action other than the planned one (under `free`, by
            // index, the draw made before protocols existed).
            let at = legal
                .indices()
                .position(|i| i == planned.index())
                .expect("planned actions are legal");
            let k = self.rng.random_range(0..legal.count() - 1);
            let pick = if k >= at { k + 1 } else { k };
            return Ok(legal.nth(pick).expect("pick < the legal actions"));
        }
        Ok(planned)
    }

    /// The exact distance from `state` to the goal of `obs` under its protocol, remembered.
    fn distance(&mut self, state: &State, obs: &Observation) -> Result<u32> {
        if let Some(&d) = self.distances.get(state) {
            return Ok(d);
        }
        let d = self.exact.with_protocol(obs.protocol).distance(state, &obs.goal)?;
        self.distances.insert(state.clone(), d);
        Ok(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sim::{BlockId, Env, EnvConfig};

    fn start(goal: &str, seed: u64) -> Observation {
        let goal: Goal = goal.parse().unwrap();
        Env::new(EnvConfig::with_goal(goal)).unwrap().reset(seed)
    }

    #[test]
    fn presets_are_valid_and_there_are_three() {
        for n in 1..=3 {
            DemonstratorProfile::preset(n).unwrap().validate().unwrap();
        }
        assert!(DemonstratorProfile::preset(0).is_err());
        assert!(DemonstratorProfile::preset(4).is_err());
        let mut bad = DemonstratorProfile::preset(2).unwrap();
        bad.slip = 1.5;
        assert!(bad.validate().is_err());
    }

    #[test]
    fn the_expert_lets_shortest_path_actions_stand_and_corrects_the_others() {
        let obs = start("1,0,2", 11);
        let grid = obs.grid;
        let exact = oracle::ExactSolver::new(grid);
        let mut expert = Demonstrator::new(DemonstratorProfile::preset(1).unwrap(), grid);
        expert.begin_episode(&obs, 1);
        let d = exact.distance(&obs.state, &obs.goal).unwrap();
        let mut corrected = 0;
        for action in Action::all(3) {
            let mut w = GridWorld::new(grid, obs.state.clone()).unwrap();
            w.act(action).unwrap();
            let on_path = exact.distance(w.state_ref(), &obs.goal).unwrap() + 1 == d;
            let review = expert.review(&obs, action).unwrap();
            assert_eq!(review.is_none(), on_path, "{action}");
            if let Some(better) = review {
                corrected += 1;
                let mut w = GridWorld::new(grid, obs.state.clone()).unwrap();
                w.act(better).unwrap();
                assert_eq!(exact.distance(w.state_ref(), &obs.goal).unwrap() + 1, d);
            }
        }
        assert!(corrected > 0);
    }

    #[test]
    fn a_demonstrator_that_notices_loops_stops_a_pick_and_drop() {
        let obs = start("0,1,2", 3);
        let mut never_looks = DemonstratorProfile::preset(3).unwrap();
        never_looks.attention = 0.0;
        never_looks.takeover = 0.0;
        let mut d = Demonstrator::new(never_looks, obs.grid);
        d.begin_episode(&obs, 9);
        let pick = Action::Pick(BlockId(1));
        assert_eq!(d.review(&obs, pick).unwrap(), None);
        let mut w = GridWorld::new(obs.grid, obs.state).unwrap();
        w.act(pick).unwrap();
        let held = Observation {
            state: w.state_ref().clone(),
            ..obs
        };
        assert!(d.review(&held, Action::Drop).unwrap().is_some());
    }

    #[test]
    fn reviews_are_fixed_by_the_seed() {
        let obs = start("2,1,0", 5);
        let run = || {
            let mut d = Demonstrator::new(DemonstratorProfile::preset(3).unwrap(), obs.grid);
            d.begin_episode(&obs, 77);
            (0..200)
                .map(|i| d.review(&obs, Action::from_index(i % 8, 3).unwrap()).unwrap())
                .collect::<Vec<_>>()
        };
        let first = run();
        assert_eq!(first, run());
        assert!(first.iter().any(Option::is_some) && first.iter().any(Option::is_none));
    }
}
