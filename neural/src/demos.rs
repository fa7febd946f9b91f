//! Demonstrations for DQfD: episodes of the exact solver or the oracle from seeded starts,
//! or read from a recording, turned into transitions with the learner's reward.
//!
//! - **Planners.** Demonstration `k` plays goal `goals[k % len]` from the start
//!   `reset(episode_seed(demo_seed(seed), k))` ([`demo_seed`]: starts no training game
//!   shares) and follows the planner's plan, carried out by `sim`'s rules.
//! - **Recordings.** A `blockstack-demos` file (what `blockstack demo` and `blockstack
//!   correct` record) is read by `agent`'s reader, which checks every line; its corrections
//!   are demonstrated actions (the large-margin loss applies to them), the agent's own steps
//!   are transitions like any other. A trajectory file (`blockstack run --trajectory`) is
//!   read with `sim::trajectory`'s records; every step is demonstrated, and replaying each
//!   action by the rules must give the recorded state (a file that does not replay is
//!   refused, naming the line).
//!
//! Rewards are always recomputed with the learner's reward model (a recording made under
//! another reward teaches the same actions), and an episode's transitions get their n-step
//! returns from [`NStep`].

use std::io::BufRead;
use std::path::Path;

use agent::correction::{CorrectionRule, Experience};
use agent::demos::{BadLines, DemoLearner, Replay};
use oracle::{ExactSolver, Oracle, Planner};
use rayon::prelude::*;
use sim::reward::Transition as RewardTransition;
use sim::seeding::episode_seed;
use sim::trajectory::Record;
use sim::{Action, Cell, Env, Goal, Grid, GridWorld, Observation, State, World};

use crate::config::{DemoSource, DqnConfig};
use crate::error::{NeuralError, Result};
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
        let (grid, reward) = (config.grid, &config.reward);
        let mut builder = NStep::new(config.n_step, config.gamma);
        let mut out = Vec::with_capacity(self.actions.len());
        let obs = |state: State| Observation {
            grid,
            state,
            goal: self.goal,
            protocol: config.protocol,
        };
        for (k, &action) in self.actions.iter().enumerate() {
            let (before, after) = (&self.states[k], &self.states[k + 1]);
            let r = reward.reward(&RewardTransition {
                grid,
                goal: &self.goal,
                before,
                action,
                previous_action: k.checked_sub(1).map(|p| self.actions[p]),
                after,
            }) as f32;
            let terminal = self.goal.holds(after);
            out.extend(builder.push(obs(*before), action, r, obs(*after), terminal, self.expert[k]));
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
        DemoSource::Exact(k) => planned(config, *k, &ExactSolver::new(config.grid)),
        DemoSource::Oracle(k) => planned(config, *k, &Oracle::new(config.grid)),
        DemoSource::File(path) => read(Path::new(path), config.grid, config.blocks),
    }
}

/// `count` episodes of `planner` (module docs), planned in parallel.
pub fn planned<P: Planner + Sync>(config: &DqnConfig, count: u64, planner: &P) -> Result<Vec<DemoEpisode>> {
    // The starts, drawn as the environment draws them.
    let mut envs = config
        .goals
        .iter()
        .map(|&g| Env::new(config.env_config(g)))
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
        .map(|&(start, goal)| {
            let plan = planner.plan(&start, &goal)?;
            let mut world = GridWorld::new(config.grid, start)?;
            let mut states = vec![start];
            for &a in &plan.actions {
                world.act(a)?;
                states.push(*world.state_ref());
            }
            Ok(DemoEpisode {
                goal,
                states,
                expert: vec![true; plan.actions.len()],
                actions: plan.actions,
            })
        })
        .collect()
}

/// The demonstrations in the file at `path`, a `blockstack-demos` recording or a trajectory
/// file (told apart by the first line), for `blocks` blocks on `grid`.
pub fn read(path: &Path, grid: Grid, blocks: usize) -> Result<Vec<DemoEpisode>> {
    let fail = |reason: String| NeuralError::Demos {
        path: path.display().to_string(),
        reason,
    };
    let open = || -> Result<_> {
        let file = files::open_bounded(path, agent::demos::MAX_RECORDING_BYTES, "a recording")
            .map_err(|e| fail(e.to_string()))?;
        Ok(std::io::BufReader::new(file))
    };
    let mut first = String::new();
    open()?.read_line(&mut first).map_err(|e| fail(e.to_string()))?;
    let value: serde_json::Value = serde_json::from_str(first.trim())
        .map_err(|e| fail(format!("line 1 is not JSON ({e}): is this a recording?")))?;
    match (value["type"].as_str(), value["format"].as_str()) {
        (Some("session"), _) => {
            let mut collector = Collector {
                grid,
                blocks,
                episodes: Vec::new(),
            };
            agent::demos::learn_from_file(&mut collector, path, BadLines::Fail)?;
            Ok(collector.episodes)
        }
        (Some("episode"), None) => {
            trajectory(open()?, grid, blocks).map_err(|(line, reason)| fail(format!("line {line}: {reason}")))
        }
        _ => Err(fail(
            "the first line is neither a blockstack-demos session nor a trajectory episode".into(),
        )),
    }
}

/// Collects the steps of a `blockstack-demos` recording into episodes.
struct Collector {
    grid: Grid,
    blocks: usize,
    episodes: Vec<DemoEpisode>,
}

impl DemoLearner for Collector {
    fn check_world(&self, grid: Grid, blocks: usize) -> agent::Result<()> {
        if grid != self.grid || blocks != self.blocks {
            return Err(agent::AgentError::ModelMismatch(format!(
                "the learner plays {} blocks on a {} grid, the recording has {blocks} blocks on a {grid} grid",
                self.blocks, self.grid
            )));
        }
        Ok(())
    }

    fn identity(&self) -> Option<String> {
        // The network was not the model a session corrected: every session's steps are
        // demonstrations to it.
        None
    }

    fn learn(&mut self, _rule: &CorrectionRule, step: &Experience) -> agent::Result<()> {
        // A step continues the last episode when it starts where that one stopped.
        let continues = self.episodes.last().is_some_and(|e| {
            e.goal == step.obs.goal && e.states.last() == Some(&step.obs.state) && !e.goal.holds(&step.obs.state)
        });
        if !continues {
            self.episodes.push(DemoEpisode {
                goal: step.obs.goal,
                states: vec![step.obs.state],
                actions: Vec::new(),
                expert: Vec::new(),
            });
        }
        let e = self.episodes.last_mut().expect("an episode was just made");
        e.states.push(step.next.state);
        e.actions.push(step.action);
        e.expert.push(step.corrected);
        Ok(())
    }
}

/// The episodes of a trajectory file; an error is the line number and why.
fn trajectory(
    input: impl BufRead,
    grid: Grid,
    blocks: usize,
) -> std::result::Result<Vec<DemoEpisode>, (usize, String)> {
    let mut episodes: Vec<DemoEpisode> = Vec::new();
    let mut world: Option<(u64, GridWorld)> = None;
    for (i, line) in input.lines().enumerate() {
        let n = i + 1;
        let line = line.map_err(|e| (n, e.to_string()))?;
        if line.trim().is_empty() {
            continue;
        }
        let record: Record = serde_json::from_str(&line).map_err(|e| (n, format!("not a trajectory line ({e})")))?;
        match record {
            Record::Episode {
                episode,
                grid: [w, h],
                goal,
                start,
                ..
            } => {
                if [w, h] != [grid.width(), grid.height()] || goal.block_count() != blocks {
                    return Err((
                        n,
                        format!(
                            "the episode has {} blocks on a {w}x{h} grid, the learner plays {blocks} on {grid}",
                            goal.block_count()
                        ),
                    ));
                }
                let cells: Vec<Cell> = start.iter().map(|&[x, y]| Cell::new(x, y)).collect();
                let state = State::new(&cells, None).map_err(|e| (n, e.to_string()))?;
                world = Some((episode, GridWorld::new(grid, state).map_err(|e| (n, e.to_string()))?));
                episodes.push(DemoEpisode {
                    goal,
                    states: vec![state],
                    actions: Vec::new(),
                    expert: Vec::new(),
                });
            }
            Record::Step {
                episode,
                action,
                blocks: cells,
                held,
                ..
            } => {
                let Some((current, w)) = world.as_mut().filter(|(k, _)| *k == episode) else {
                    return Err((n, format!("a step of episode {episode} before its episode line")));
                };
                let _ = current;
                let action = Action::from_index(action, blocks).map_err(|e| (n, e.to_string()))?;
                w.act(action).map_err(|e| (n, e.to_string()))?;
                let recorded: Vec<Cell> = cells.iter().map(|&[x, y]| Cell::new(x, y)).collect();
                let state = *w.state_ref();
                if state.cells() != recorded.as_slice() || state.held_block().map(|b| b.0) != held {
                    return Err((
                        n,
                        "the recorded state is not what the action leads to by the rules".into(),
                    ));
                }
                let e = episodes.last_mut().expect("an episode line came first");
                e.states.push(state);
                e.actions.push(action);
                e.expert.push(true);
            }
        }
    }
    Ok(episodes)
}

/// Every transition of `episodes` for the learner of `config`.
pub fn transitions(episodes: &[DemoEpisode], config: &DqnConfig) -> Vec<Transition> {
    episodes.iter().flat_map(|e| e.transitions(config)).collect()
}

/// Reads a `blockstack-demos` recording from `input` (errors name `name`): for tests and
/// callers that hold a recording in memory.
pub fn read_recording(input: impl BufRead, name: &str, grid: Grid, blocks: usize) -> Result<Vec<DemoEpisode>> {
    let mut collector = Collector {
        grid,
        blocks,
        episodes: Vec::new(),
    };
    let mut replay = Replay::new(&mut collector, BadLines::Fail, name);
    replay.read(input)?;
    Ok(collector.episodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config(demos: DemoSource) -> DqnConfig {
        DqnConfig {
            demos,
            ..DqnConfig::preset("dqfd-planes", 3).unwrap()
        }
    }

    #[test]
    fn exact_demonstrations_are_shortest_and_reach_the_goal() {
        let c = config(DemoSource::Exact(12));
        let episodes = load(&c).unwrap();
        assert_eq!(episodes.len(), 12);
        let solver = ExactSolver::new(c.grid);
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
        let mut env = Env::new(c.env_config(c.goals[1])).unwrap();
        let mut policy = agent::ExactPolicy::new(c.grid);
        let dir = tempfile::tempdir().unwrap();
        let dir = dir.path();
        let path = dir.join("t.jsonl");
        let out = files::OutputPath::check(&path).unwrap();
        let mut writer = sim::trajectory::TrajectoryWriter::create(&out).unwrap();
        let results = agent::play(&mut env, &mut policy, 3, 9, Some(&mut writer)).unwrap();
        writer.finish().unwrap();
        let episodes = read(&path, c.grid, 3).unwrap();
        assert_eq!(episodes.len(), 3);
        for (e, r) in episodes.iter().zip(&results) {
            assert_eq!((e.states[0], e.actions.len() as u32), (r.start, r.steps));
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let broken = text.replacen("\"action\":", "\"action\":1,\"x\":", 1);
        std::fs::write(&path, broken).unwrap();
        let err = read(&path, c.grid, 3).unwrap_err().to_string();
        assert!(err.contains("line 2"), "{err}");
    }
}
