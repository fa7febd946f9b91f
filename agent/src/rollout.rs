//! Playing episodes: the loop every command and experiment shares, and its statistics.
//!
//! What watches an episode (a trajectory file, Python's columns of transitions, the frames
//! of a picture) is an [`EpisodeObserver`] handed to the one loop, [`play_episode`], rather
//! than a copy of the loop with its own additions.

use serde::Serialize;
use sim::seeding::{self, SimRng};
use sim::trajectory::{Record, TrajectoryWriter};
use sim::{Action, Env, EnvConfig, Goal, Observation, State, Step};

use crate::error::Result;
use crate::policy::Policy;

/// How one episode went.
#[derive(Clone, Debug, PartialEq)]
pub struct EpisodeResult {
    /// Episode number in the run.
    pub episode: u64,
    /// The seed the environment was reset with.
    pub seed: u64,
    /// The goal.
    pub goal: Goal,
    /// The start state.
    pub start: State,
    /// Actions taken.
    pub steps: u32,
    /// Whether the goal was reached (otherwise the episode was truncated).
    pub reached_goal: bool,
    /// Sum of the rewards.
    pub total_reward: f64,
}

/// The generator a policy draws from in the episode reset with `episode_seed`: a stream of
/// its own, so the policy's draws never shift the start and every arm of a comparison
/// plays the same starts.
pub fn policy_rng(episode_seed: u64) -> SimRng {
    let mut rng = seeding::rng(episode_seed);
    rng.set_stream(1);
    rng
}

/// What watches episodes as [`play_episode`] plays them. Both methods do nothing unless
/// implemented; an error stops the episode (e.g. [`AgentError::Interrupted`](crate::AgentError)
/// when a person pressed Ctrl-C).
pub trait EpisodeObserver {
    /// Episode `episode` of a world `config` was reset with `seed` to `start`.
    fn start(&mut self, episode: u64, seed: u64, config: &EnvConfig, start: &Observation) -> Result<()> {
        let _ = (episode, seed, config, start);
        Ok(())
    }

    /// `action`, taken in `before`, gave `step`.
    fn step(&mut self, episode: u64, before: &Observation, action: Action, step: &Step) -> Result<()> {
        let _ = (episode, before, action, step);
        Ok(())
    }
}

/// Watches nothing.
impl EpisodeObserver for () {}

/// Writes each episode to the trajectory file: its episode line, then one line per step.
impl EpisodeObserver for TrajectoryWriter {
    fn start(&mut self, episode: u64, seed: u64, config: &EnvConfig, start: &Observation) -> Result<()> {
        Ok(self.write(&Record::episode_in(
            config.view,
            episode,
            seed,
            config.grid,
            start.goal.clone(),
            config.horizon,
            &start.state,
        ))?)
    }

    fn step(&mut self, episode: u64, _: &Observation, action: Action, step: &Step) -> Result<()> {
        Ok(self.write(&Record::step(episode, action.index(), step))?)
    }
}

/// Watches when there is something to watch with.
impl<O: EpisodeObserver> EpisodeObserver for Option<O> {
    fn start(&mut self, episode: u64, seed: u64, config: &EnvConfig, start: &Observation) -> Result<()> {
        self.as_mut().map_or(Ok(()), |o| o.start(episode, seed, config, start))
    }

    fn step(&mut self, episode: u64, before: &Observation, action: Action, step: &Step) -> Result<()> {
        self.as_mut().map_or(Ok(()), |o| o.step(episode, before, action, step))
    }
}

/// Keeps every observation of the episodes, each start first (e.g. for a picture of them).
impl EpisodeObserver for Vec<Observation> {
    fn start(&mut self, _: u64, _: u64, _: &EnvConfig, start: &Observation) -> Result<()> {
        self.push(start.clone());
        Ok(())
    }

    fn step(&mut self, _: u64, _: &Observation, _: Action, step: &Step) -> Result<()> {
        self.push(step.observation.clone());
        Ok(())
    }
}

/// Where an episode starts.
#[derive(Clone, Copy, Debug, Default)]
pub enum EpisodeStart<'a> {
    /// Drawn by [`Env::reset`] with the episode's seed (the config's start rule and goal).
    #[default]
    Drawn,
    /// This state, towards this goal, in every episode (e.g. a PDDL task's,
    /// [`Env::reset_to`]); the episode's seed still seeds the policy's generator.
    Given(&'a State, &'a Goal),
}

impl EpisodeStart<'_> {
    /// Resets `env` to this start for the episode of `seed`.
    fn reset(self, env: &mut Env, seed: u64) -> Result<Observation> {
        Ok(match self {
            EpisodeStart::Drawn => env.reset(seed),
            EpisodeStart::Given(state, goal) => env.reset_to(state, goal)?,
        })
    }
}

/// Plays one episode of `policy` in `env`, reset with `seed`, as episode `episode` of the
/// run, shown to `observer` as it goes.
pub fn play_episode(
    env: &mut Env,
    policy: &mut dyn Policy,
    episode: u64,
    seed: u64,
    observer: &mut dyn EpisodeObserver,
) -> Result<EpisodeResult> {
    play_episode_from(env, policy, EpisodeStart::Drawn, episode, seed, observer)
}

/// [`play_episode`] from `start`.
pub fn play_episode_from(
    env: &mut Env,
    policy: &mut dyn Policy,
    start: EpisodeStart<'_>,
    episode: u64,
    seed: u64,
    observer: &mut dyn EpisodeObserver,
) -> Result<EpisodeResult> {
    let obs = start.reset(env, seed)?;
    let config = env.config().clone();
    observer.start(episode, seed, &config, &obs)?;
    let start = obs.state.clone();
    let mut rng = policy_rng(seed);
    policy.begin_episode(&obs);
    let mut obs = obs;
    let mut total_reward = 0.0;
    // An episode over at its start began with the goal holding (one block in the side
    // view): solved by the empty plan.
    let mut reached_goal = env.is_over() && obs.goal_holds();
    while !env.is_over() {
        let action = policy.act(&obs, &mut rng)?;
        let step = env.step(action)?;
        observer.step(episode, &obs, action, &step)?;
        total_reward += step.reward;
        reached_goal = step.terminated;
        obs = step.observation;
    }
    Ok(EpisodeResult {
        episode,
        seed,
        goal: obs.goal,
        start,
        steps: env.steps(),
        reached_goal,
        total_reward,
    })
}

/// Plays `episodes` episodes of `policy` in `env`, shown to `observer`; episode `k` is
/// reset with [`seeding::episode_seed`]`(base_seed, k)`, so any two policies run with the
/// same base seed play the same starts.
pub fn play(
    env: &mut Env,
    policy: &mut dyn Policy,
    episodes: u64,
    base_seed: u64,
    observer: &mut dyn EpisodeObserver,
) -> Result<Vec<EpisodeResult>> {
    play_observed(
        env,
        policy,
        EpisodeStart::Drawn,
        episodes,
        base_seed,
        observer,
        &mut |_| {},
    )
}

/// [`play`] from `start`, calling `done` after each episode (a progress bar's hook).
pub fn play_observed(
    env: &mut Env,
    policy: &mut dyn Policy,
    start: EpisodeStart<'_>,
    episodes: u64,
    base_seed: u64,
    observer: &mut dyn EpisodeObserver,
    done: &mut dyn FnMut(&EpisodeResult),
) -> Result<Vec<EpisodeResult>> {
    (0..episodes)
        .map(|k| {
            let seed = seeding::episode_seed(base_seed, k);
            let result = play_episode_from(env, policy, start, k, seed, observer)?;
            done(&result);
            Ok(result)
        })
        .collect()
}

/// Failures and steps to goal over a set of episodes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// Episodes played.
    pub episodes: usize,
    /// Episodes truncated without reaching the goal.
    pub failures: usize,
    /// Mean steps to goal over the successful episodes (`None` if there were none).
    pub mean_steps: Option<f64>,
    /// Median steps to goal over the successful episodes (`None` if there were none); the
    /// mean of the two middle values for an even count.
    pub median_steps: Option<f64>,
}

impl Summary {
    /// The summary of `results`.
    pub fn of(results: &[EpisodeResult]) -> Summary {
        let mut steps: Vec<u32> = results.iter().filter(|r| r.reached_goal).map(|r| r.steps).collect();
        steps.sort_unstable();
        let n = steps.len();
        let mean_steps = (n > 0).then(|| steps.iter().map(|&s| f64::from(s)).sum::<f64>() / n as f64);
        let median_steps = (n > 0).then(|| {
            if n % 2 == 1 {
                f64::from(steps[n / 2])
            } else {
                (f64::from(steps[n / 2 - 1]) + f64::from(steps[n / 2])) / 2.0
            }
        });
        Summary {
            episodes: results.len(),
            failures: results.len() - n,
            mean_steps,
            median_steps,
        }
    }
}
