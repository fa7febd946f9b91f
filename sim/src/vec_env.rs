//! Many environments stepped together, in parallel.

use rayon::prelude::*;

use crate::action::Action;
use crate::env::{Env, EnvConfig, Step};
use crate::error::{Result, SimError};
use crate::observation::Observation;

/// `M` environments of one config, stepped together on a rayon thread pool.
///
/// Seeds: environment `i` is reset with `base_seed + i`, and each continues its own
/// generator from there, so every environment plays its own fixed sequence of episodes.
///
/// Autoreset: Gymnasium's **same-step** mode. When an environment's episode ends on a step,
/// it is reset within that step: the returned `observation` is the new episode's first, the
/// ended episode's last observation is in `info.final_observation`, and `reward`,
/// `terminated` and `truncated` are those of the step that ended it. The next action
/// therefore always applies to the observation just returned, and `info.action_mask` is
/// always that observation's legal actions (the ended episode's are
/// `info.final_observation`'s [`legal_actions`](Observation::legal_actions)).
pub struct VecEnv {
    envs: Vec<Env>,
    /// `None` for one thread: the caller's thread steps the environments itself, which
    /// spares a hand-off to a pool thread and back on every step.
    pool: Option<rayon::ThreadPool>,
}

impl VecEnv {
    /// `count` environments of `config`, stepped on `threads` threads (0: one per core; 1:
    /// on the caller's thread, without a pool).
    pub fn new(config: EnvConfig, count: usize, threads: usize) -> Result<VecEnv> {
        let envs = (0..count).map(|_| Env::new(config)).collect::<Result<Vec<_>>>()?;
        let pool = match threads {
            1 => None,
            _ => Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .map_err(|e| SimError::ThreadPool {
                        threads,
                        reason: e.to_string(),
                    })?,
            ),
        };
        Ok(VecEnv { envs, pool })
    }

    /// Number of environments.
    pub fn len(&self) -> usize {
        self.envs.len()
    }

    /// Whether there are no environments.
    pub fn is_empty(&self) -> bool {
        self.envs.is_empty()
    }

    /// Resets environment `i` with seed `base_seed + i`; returns every first observation.
    pub fn reset(&mut self, base_seed: u64) -> Vec<Observation> {
        let reset = |(i, env): (usize, &mut Env)| env.reset(base_seed.wrapping_add(i as u64));
        match &self.pool {
            None => self.envs.iter_mut().enumerate().map(reset).collect(),
            Some(pool) => pool.install(|| self.envs.par_iter_mut().enumerate().map(reset).collect()),
        }
    }

    /// Steps environment `i` with `actions[i]`, resetting those whose episode ends (see
    /// the type's docs). An error, before any environment steps, if the action count
    /// differs from the environment count or if any environment would refuse its action
    /// (the first such error; see [`Env::check_action`]).
    pub fn step(&mut self, actions: &[Action]) -> Result<Vec<Step>> {
        if actions.len() != self.envs.len() {
            return Err(SimError::ActionCountMismatch {
                envs: self.envs.len(),
                actions: actions.len(),
            });
        }
        for (env, &action) in self.envs.iter().zip(actions) {
            env.check_action(action)?;
        }
        let step = |(env, &action): (&mut Env, &Action)| {
            let mut step = env.step(action)?;
            if step.terminated || step.truncated {
                step.info.final_observation = Some(step.observation);
                step.observation = env.reset(None);
                step.info.action_mask = step.observation.legal_actions();
            }
            Ok(step)
        };
        match &self.pool {
            None => self.envs.iter_mut().zip(actions).map(step).collect(),
            Some(pool) => pool.install(|| self.envs.par_iter_mut().zip(actions.par_iter()).map(step).collect()),
        }
    }

    /// The environments, for reading their state.
    pub fn envs(&self) -> &[Env] {
        &self.envs
    }
}
