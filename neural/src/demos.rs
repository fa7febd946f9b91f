//! Demonstrations for DQfD: episodes of the exact solver or the oracle from seeded starts,
//! or read from a recording, turned into transitions with the learner's reward.
//!
//! - **Planners.** Demonstration `k` plays goal `goals[k % len]` from the start
//!   `reset(episode_seed(demo_seed(seed), k))` ([`demo_seed`]: starts no training game
//!   shares) and follows the planner's plan, carried out by `sim`'s rules.
//! - **Files.** A `blockstack-demos` recording (what `blockstack demo` and `blockstack
//!   correct` record) or a trajectory file (`blockstack run --trajectory`), read by
//!   `agent::demos::read_admitted`, the checked reader of each format that the Python
//!   package uses too (a file that does not replay by the rules is refused, naming the
//!   line; so is a recording of another view, protocol, grid or block count than the run's,
//!   and a withdrawn participant's). A recording's corrections are demonstrated actions (the large-margin loss
//!   applies to them), the agent's own steps transitions like any other; every step of a
//!   trajectory file is demonstrated.
//!
//! Rewards are always recomputed with the learner's reward model (a recording made under
//! another reward teaches the same actions), and an episode's transitions get their n-step
//! returns from [`NStep`].

use std::path::Path;

use oracle::{ExactSolver, Oracle, Planner};
use rayon::prelude::*;
use sim::reward::Transition as RewardTransition;
use sim::seeding::episode_seed;
use sim::{Action, Env, Goal, GridWorld, Observation, State};

use agent::demos::{Admission, RunWorld};

use crate::config::{DemoSource, DqnConfig};
use crate::error::Result;
use crate::replay::{NStep, Transition};

/// One demonstrated episode: the states it passed through and the actions between them.
#[derive(Clone, Debug, PartialEq)]
pub struct DemoEpisode {
    /// The goal.
    pub goal: Goal,
    /// `states[0]` the start, `states[k + 1]` the state after `actions[k]`.
    pub states: Vec<State>,
    /// The actions.
    pub actions: Vec<Action>,
    /// Whether a demonstrator chose each action.
    pub expert: Vec<bool>,
}

impl DemoEpisode {
    /// The episode's transitions for a learner with `reward`, discount `gamma` and n-step
    /// `n` on `grid`.
    pub fn transitions(&self, config: &DqnConfig) -> Vec<Transition> {
        let (grid, reward) = (config.world.grid, &config.world.reward);
        let mut builder = NStep::new(config.n_step, config.gamma);
        let mut out = Vec::with_capacity(self.actions.len());
        let obs = |state: State| Observation {
            grid,
            state,
            goal: self.goal.clone(),
            protocol: config.world.protocol,
            view: config.world.view,
        };
        for (k, &action) in self.actions.iter().enumerate() {
            let (before, after) = (&self.states[k], &self.states[k + 1]);
            let r = reward.reward(&RewardTransition {
                grid,
                view: sim::View::Top,
                goal: &self.goal,
                before,
                action,
                previous_action: k.checked_sub(1).map(|p| self.actions[p]),
                after,
            }) as f32;
            let terminal = self.goal.holds(after);
            out.extend(builder.push(
                obs(before.clone()),
                action,
                r,
                obs(after.clone()),
                terminal,
                self.expert[k],
            ));
            if terminal {
                break;
            }
        }
        out.extend(builder.finish());
        out
    }
}

/// The base seed of the demonstrations of a run with seed `seed`.
pub fn demo_seed(seed: u64) -> u64 {
    seed ^ 0xD340_D340_D340_D340
}

/// The demonstrations `config.demos` names (none for [`DemoSource::None`]).
pub fn load(config: &DqnConfig) -> Result<Vec<DemoEpisode>> {
    match &config.demos {
        DemoSource::None => Ok(Vec::new()),
        DemoSource::Exact(k) => planned(config, *k, &ExactSolver::new(config.world.grid)),
        DemoSource::Oracle(k) => planned(config, *k, &Oracle::new(config.world.grid)),
        DemoSource::File(path) => read(Path::new(path), RunWorld::of(&config.world)),
    }
}

/// `count` episodes of `planner` (module docs), planned in parallel.
pub fn planned<P: Planner + Sync>(config: &DqnConfig, count: u64, planner: &P) -> Result<Vec<DemoEpisode>> {
    // The starts, drawn as the environment draws them.
    let mut envs = config
        .goals
        .iter()
        .map(|g| Env::new(config.env_config(g.clone())))
        .collect::<sim::Result<Vec<_>>>()?;
    let base = demo_seed(config.seed);
    let starts: Vec<(State, Goal)> = (0..count)
        .map(|k| {
            let env = &mut envs[(k % config.goals.len() as u64) as usize];
            let obs = env.reset(episode_seed(base, k));
            (obs.state, obs.goal)
        })
        .collect();
    starts
        .par_iter()
        .map(|(start, goal)| {
            let plan = planner.plan(start, goal)?;
            let states = GridWorld::new(config.world.grid, start.clone())?.replay(&plan.actions)?;
            Ok(DemoEpisode {
                goal: goal.clone(),
                states,
                expert: vec![true; plan.actions.len()],
                actions: plan.actions,
            })
        })
        .collect()
}

/// The demonstrations in the file at `path`, a `blockstack-demos` recording or a trajectory
/// file, of the run's `world` (module docs): a withdrawn participant's recording is refused.
pub fn read(path: &Path, world: RunWorld) -> Result<Vec<DemoEpisode>> {
    let admission = Admission {
        world: Some(world),
        include_withdrawn: false,
    };
    Ok(agent::demos::read_admitted(path, &admission)?
        .read
        .into_iter()
        .map(DemoEpisode::from)
        .collect())
}

impl From<agent::demos::DemoEpisode> for DemoEpisode {
    fn from(e: agent::demos::DemoEpisode) -> Self {
        DemoEpisode {
            states: e.states(),
            goal: e.goal,
            actions: e.steps.iter().map(|s| s.action).collect(),
            expert: e.steps.iter().map(|s| s.demonstrated).collect(),
        }
    }
}

/// Every transition of `episodes` for the learner of `config`.
pub fn transitions(episodes: &[DemoEpisode], config: &DqnConfig) -> Vec<Transition> {
    episodes.iter().flat_map(|e| e.transitions(config)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(demos: DemoSource) -> DqnConfig {
        DqnConfig {
            demos,
            ..DqnConfig::preset(crate::preset::Preset::DqfdPlanes, 3).unwrap()
        }
    }

    #[test]
    fn exact_demonstrations_are_shortest_and_reach_the_goal() {
        let c = config(DemoSource::Exact(12));
        let episodes = load(&c).unwrap();
        assert_eq!(episodes.len(), 12);
        let solver = ExactSolver::new(c.world.grid);
        for (k, e) in episodes.iter().enumerate() {
            assert_eq!(e.goal, c.goals[k % c.goals.len()]);
            assert!(e.goal.holds(e.states.last().unwrap()));
            assert_eq!(e.actions.len() as u32, solver.distance(&e.states[0], &e.goal).unwrap());
            let t = e.transitions(&c);
            assert_eq!(t.len(), e.actions.len());
            assert!(t.last().unwrap().terminal && t.iter().all(|t| t.expert));
            assert_eq!(t.last().unwrap().reward, 10.0, "the sparse reward at the goal");
        }
        assert_eq!(load(&c).unwrap(), episodes, "seeded");
    }

    #[test]
    fn a_trajectory_file_replays_into_demonstrations_and_a_wrong_one_is_refused() {
        let c = config(DemoSource::None);
        let mut env = Env::new(c.env_config(c.goals[1].clone())).unwrap();
        let mut policy = agent::ExactPolicy::new(c.world.grid);
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let path = dir.join("t.jsonl");
        let out = files::OutputPath::check(&path).unwrap();
        let mut writer = sim::trajectory::TrajectoryWriter::create(&out).unwrap();
        let results = agent::play(&mut env, &mut policy, 3, 9, &mut writer).unwrap();
        writer.finish().unwrap();
        let episodes = read(&path, RunWorld::of(&c.world)).unwrap();
        assert_eq!(episodes.len(), 3);
        for (e, r) in episodes.iter().zip(&results) {
            assert_eq!(
                (e.states[0].clone(), e.actions.len() as u32),
                (r.start.clone(), r.steps)
            );
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let broken = text.replacen("\"action\":", "\"action\":1,\"x\":", 1);
        std::fs::write(&path, broken).unwrap();
        let err = read(&path, RunWorld::of(&c.world)).unwrap_err().to_string();
        assert!(err.contains("line 2"), "{err}");
    }

    #[test]
    fn files_written_by_the_previous_release_read_as_demonstrations() {
        let world = RunWorld::of(&config(DemoSource::None).world);
        let recording = read(&testkit::fixture("recording-v2.jsonl"), world).unwrap();
        assert_eq!(recording.len(), 2, "one per episode line");
        assert!(recording.iter().any(|e| e.expert.iter().any(|&x| x)), "corrections");
        assert!(recording.iter().all(|e| e.goal.holds(e.states.last().unwrap())));
        let trajectory = read(&testkit::fixture("trajectory.jsonl"), world).unwrap();
        assert_eq!(trajectory.len(), 3);
        assert!(trajectory.iter().all(|e| e.expert.iter().all(|&x| x)));
        // Another world than the learner's is refused.
        let err = read(&testkit::fixture("trajectory-dense.jsonl"), world)
            .unwrap_err()
            .to_string();
        assert!(err.contains("4 blocks on a 5x6 grid"), "{err}");
    }

    #[test]
    fn a_step_after_the_episode_terminated_is_refused() {
        let text = testkit::fixture_text("trajectory.jsonl");
        let lines: Vec<&str> = text.lines().collect();
        let last = lines.iter().position(|l| l.contains("\"terminated\":true")).unwrap();
        let mut after: serde_json::Value = serde_json::from_str(lines[last]).unwrap();
        after["step"] = (after["step"].as_u64().unwrap() + 1).into();
        // Picking the held block again: the rules allow it and change nothing.
        after["action"] = 7.into();
        let broken: String = lines[..=last]
            .iter()
            .map(|l| format!("{l}\n"))
            .chain([after.to_string() + "\n"])
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.jsonl");
        std::fs::write(&path, broken).unwrap();
        let err = read(&path, RunWorld::of(&config(DemoSource::None).world))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("line {}", last + 2)) && err.contains("ended"),
            "{err}"
        );
    }
}
