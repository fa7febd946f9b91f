//! Many environments stepped together, in parallel.

use std::ops::Range;

use crate::action::Action;
use crate::env::{Env, EnvConfig, Outcome, Refusal, Step};
use crate::error::{Result, SimError};
use crate::observation::Observation;
use crate::protocol::ActionMask;
use crate::team::Team;

/// How a [`VecEnv`] starts the next episode of an environment whose episode ended: the
/// two modes of Gymnasium 1.x's `AutoresetMode`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Autoreset {
    /// `SAME_STEP`: the step that ends an episode also resets the environment. It returns
    /// the new episode's first observation, the ended episode's last one in
    /// `info.final_observation`, and the reward and flags of the step that ended it; the
    /// next action applies to the observation just returned, and `info.action_mask` is that
    /// observation's legal actions (the ended episode's are `info.final_observation`'s
    /// [`legal_actions`](Observation::legal_actions)).
    #[default]
    SameStep,
    /// `NEXT_STEP` (Gymnasium's default): the step that ends an episode returns its last
    /// observation; the environment's next step ignores its action and resets it,
    /// returning the new episode's first observation with reward 0 and neither flag set.
    NextStep,
}

/// What one environment of a [`VecEnv`] did in a vectorised step.
#[derive(Clone, Debug, PartialEq)]
pub enum VecStep {
    /// It took its action (under [`Autoreset::SameStep`] a step that ended the episode has
    /// already reset it: see [`Autoreset`]).
    Stepped(Step),
    /// Under [`Autoreset::NextStep`], its episode had ended: it ignored its action and
    /// reset, continuing its generator; this is the new episode's first observation.
    Reset(Observation),
}

impl VecStep {
    /// The observation the agent acts on next.
    pub fn observation(&self) -> &Observation {
        match self {
            VecStep::Stepped(step) => &step.observation,
            VecStep::Reset(obs) => obs,
        }
    }
}

/// One environment's result in a batched call, borrowed from the environment: what
/// [`VecEnv::step_chunks`] and [`VecEnv::reset_chunks`] hand their writer. A batch of
/// thousands copies each result into its buffers from here, in place, rather than building
/// an owned [`VecStep`] per environment (a copy of the observation and the step's moves
/// were a third of the grid backend's batched step: docs/performance.md).
#[derive(Clone, Debug)]
pub struct VecStepRef<'a> {
    /// The observation the agent acts on next (after a reset, the new episode's first).
    pub observation: &'a Observation,
    /// Its legal actions (Gymnasium's `info["action_mask"]`).
    pub action_mask: ActionMask,
    /// What the step did; `None` when the environment was reset instead (by
    /// [`VecEnv::reset_chunks`], or ignoring its action under [`Autoreset::NextStep`]).
    pub outcome: Option<Outcome>,
    /// Under [`Autoreset::SameStep`], the last observation of the episode this step ended
    /// (`observation` is then the next episode's first).
    pub final_observation: Option<&'a Observation>,
}

impl VecStepRef<'_> {
    /// How many of the goal's consecutive pairs stand in place in `observation`: the
    /// outcome's count when it describes `observation`, counted otherwise (after a reset,
    /// and after a same-step reset, whose outcome counts the ended episode's last state).
    pub fn pairs_in_place(&self) -> usize {
        match self.outcome {
            Some(outcome) if self.final_observation.is_none() => outcome.pairs_in_place,
            _ => self.observation.goal.pairs_in_place(&self.observation.state),
        }
    }

    /// The owned result, as [`VecEnv::step`] returns it.
    pub fn to_vec_step(&self) -> VecStep {
        match self.outcome {
            None => VecStep::Reset(self.observation.clone()),
            Some(outcome) => {
                let mut step = outcome.into_step(self.observation.clone(), self.action_mask.clone());
                step.info.final_observation = self.final_observation.map(|last| Box::new(last.clone()));
                VecStep::Stepped(step)
            }
        }
    }
}

/// Below this many environments a [`VecEnv`] steps and resets on the caller's thread
/// whatever its thread count. Through Python (`python/benchmarks/throughput.py`, where
/// every call also reads the actions and lends the buffers on one thread), with the
/// caller's thread stepping a chunk and the workers kept awake between calls, two threads
/// first beat one at 512 envs of either backend on a quiet 2-core machine, and tied at 256
/// (docs/performance.md).
pub const PARALLEL_FROM_ENVS: usize = 512;

/// The team and the environments per chunk when a batch of `envs` is stepped in parallel;
/// `None` when the caller's thread steps it alone (one thread, or fewer than
/// [`PARALLEL_FROM_ENVS`] environments).
fn parallel(team: Option<&Team>, envs: usize) -> Option<(&Team, usize)> {
    let team = team?;
    (envs >= PARALLEL_FROM_ENVS).then(|| (team, envs.div_ceil(team.threads())))
}

/// `M` environments of one config, stepped together on the caller's thread and a pool's.
///
/// Threads: a batch of [`PARALLEL_FROM_ENVS`] or more is cut into one contiguous chunk per
/// thread, so each thread hands off once per call and walks its environments in memory
/// order; the caller's thread steps the first chunk, and the pool's workers stay awake for
/// a moment after a call, so the next finds them ready (the `team` module). A smaller batch
/// stays on the caller's thread.
///
/// Seeds: environment `i` is reset with `base_seed + i`, and each continues its own
/// generator from there, so every environment plays its own fixed sequence of episodes.
///
/// Autoreset: [`Autoreset::SameStep`] unless [`VecEnv::with_autoreset`] says otherwise.
///
/// Refused actions: an error that steps nothing, unless [`VecEnv::with_refusal`] makes each
/// a step that changes nothing ([`Refusal`]), as one [`Env`] does.
pub struct VecEnv {
    envs: Vec<Env>,
    /// `None` for one thread: the caller's thread steps the environments itself, which
    /// spares a hand-off to a pool thread and back on every step.
    team: Option<Team>,
    autoreset: Autoreset,
    /// Under [`Autoreset::NextStep`]: whose episode ended on the last step.
    ended: Vec<bool>,
}

impl VecEnv {
    /// `count` environments of `config`, stepped on `threads` threads (0: one per core; 1:
    /// on the caller's thread, without a pool).
    pub fn new(config: EnvConfig, count: usize, threads: usize) -> Result<VecEnv> {
        let envs = (0..count)
            .map(|_| Env::new(config.clone()))
            .collect::<Result<Vec<_>>>()?;
        let threads = match threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        let team = (threads > 1).then(|| Team::new(threads)).transpose()?;
        Ok(VecEnv {
            envs,
            team,
            autoreset: Autoreset::default(),
            ended: vec![false; count],
        })
    }

    /// This vector environment with autoreset mode `mode`.
    pub fn with_autoreset(mut self, mode: Autoreset) -> VecEnv {
        self.autoreset = mode;
        self
    }

    /// The autoreset mode.
    pub fn autoreset(&self) -> Autoreset {
        self.autoreset
    }

    /// This vector environment, every environment doing with an action the world's rules
    /// refuse what `refusal` says ([`Env::with_refusal`]).
    pub fn with_refusal(mut self, refusal: Refusal) -> VecEnv {
        self.envs = self.envs.into_iter().map(|env| env.with_refusal(refusal)).collect();
        self
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
        let seeds: Vec<Option<u64>> = (0..self.len() as u64)
            .map(|i| Some(base_seed.wrapping_add(i)))
            .collect();
        let mut out = vec![None; self.len()];
        self.reset_with(&seeds, &mut out, |obs, slot| *slot = Some(obs.clone()));
        out.into_iter()
            .map(|o| o.expect("every environment was reset"))
            .collect()
    }

    /// The environments each batch call hands to one thread, as consecutive index ranges in
    /// order: one range covering every environment when the caller's thread steps the batch
    /// (one thread, or fewer than [`PARALLEL_FROM_ENVS`] environments), otherwise one
    /// contiguous range per thread. [`VecEnv::step_chunks`] and [`VecEnv::reset_chunks`] take
    /// one chunk of the caller's per range.
    pub fn chunks(&self) -> Vec<Range<usize>> {
        let (n, len) = (self.envs.len(), self.chunk_len());
        (0..n).step_by(len).map(|start| start..(start + len).min(n)).collect()
    }

    /// The environments per range of [`VecEnv::chunks`] (the last may hold fewer).
    fn chunk_len(&self) -> usize {
        let n = self.envs.len();
        parallel(self.team.as_ref(), n).map_or(n, |(_, chunk)| chunk).max(1)
    }

    /// How many ranges [`VecEnv::chunks`] has, counted without building them: the batch
    /// calls check their caller's chunks against it on every call.
    fn chunk_count(&self) -> usize {
        self.envs.len().div_ceil(self.chunk_len())
    }

    /// Resets environment `i` with `seeds[i]` (`None` continues its generator, as
    /// [`Env::reset`] does) and hands its first observation to `write` with `slots[i]`, on
    /// the thread that reset it.
    ///
    /// # Panics
    ///
    /// Unless there is one seed and one slot per environment.
    pub fn reset_with<T: Send>(
        &mut self,
        seeds: &[Option<u64>],
        slots: &mut [T],
        write: impl Fn(&Observation, &mut T) + Sync,
    ) {
        assert_eq!(slots.len(), self.len(), "one slot per environment");
        let mut parts = split(slots, &self.chunks());
        self.reset_chunks(seeds, &mut parts, |part, i, result| {
            write(result.observation, &mut part[i])
        });
    }

    /// Resets environment `i` with `seeds[i]` as [`VecEnv::reset_with`] does, handing its
    /// first observation (a [`VecStepRef`] with no outcome) to `write` with the chunk of
    /// [`VecEnv::chunks`] it belongs to and its index in that chunk, on the thread that
    /// reset it: a caller that writes into its own buffers cuts them once per chunk rather
    /// than once per environment.
    ///
    /// # Panics
    ///
    /// Unless there is one seed per environment and one chunk per range of
    /// [`VecEnv::chunks`].
    pub fn reset_chunks<C: Send>(
        &mut self,
        seeds: &[Option<u64>],
        chunks: &mut [C],
        write: impl Fn(&mut C, usize, &VecStepRef<'_>) + Sync,
    ) {
        assert_eq!(seeds.len(), self.len(), "one seed per environment");
        assert_eq!(
            chunks.len(),
            self.chunk_count(),
            "one chunk per range of VecEnv::chunks"
        );
        self.ended.fill(false);
        let reset = |(envs, seeds, chunk): (&mut [Env], &[Option<u64>], &mut C)| {
            for (i, (env, &seed)) in envs.iter_mut().zip(seeds).enumerate() {
                env.reset(seed);
                write(chunk, i, &first(env));
            }
        };
        match parallel(self.team.as_ref(), self.envs.len()) {
            None => {
                if let Some(chunk) = chunks.first_mut() {
                    reset((&mut self.envs, seeds, chunk));
                }
            }
            Some((team, len)) => {
                let parts = self.envs.chunks_mut(len).zip(seeds.chunks(len)).zip(chunks.iter_mut());
                team.run(
                    parts.map(|((envs, seeds), chunk)| (envs, seeds, chunk)).collect(),
                    reset,
                );
            }
        }
    }

    /// Steps environment `i` with `actions[i]`, resetting those whose episode ends as the
    /// autoreset mode says. An error if the action count differs from the environment
    /// count, or if any step fails (the first such error).
    pub fn step(&mut self, actions: &[Action]) -> Result<Vec<VecStep>> {
        let mut out = vec![None; self.len()];
        self.step_with(actions, &mut out, |step, slot| *slot = Some(step.to_vec_step()))?;
        Ok(out
            .into_iter()
            .map(|s| s.expect("every environment was stepped"))
            .collect())
    }

    /// Steps every environment as [`VecEnv::step`] does and hands environment `i`'s result,
    /// borrowed ([`VecStepRef`]), to `write` with `slots[i]`, on the thread that stepped it:
    /// a caller that copies results into its own buffers does so in parallel, with nothing
    /// built or collected in between.
    ///
    /// Nothing is stepped unless every environment can be: an error first if the action
    /// count differs from the environment count, or if an environment would refuse its
    /// action (the first such error; see [`Env::check_action`]).
    ///
    /// # Panics
    ///
    /// Unless there is one slot per environment.
    pub fn step_with<T: Send>(
        &mut self,
        actions: &[Action],
        slots: &mut [T],
        write: impl Fn(&VecStepRef<'_>, &mut T) + Sync,
    ) -> Result<()> {
        assert_eq!(slots.len(), self.len(), "one slot per environment");
        let mut parts = split(slots, &self.chunks());
        self.step_chunks(actions, &mut parts, |part, i, result| write(result, &mut part[i]))
    }

    /// Steps every environment as [`VecEnv::step_with`] does, handing environment `i`'s
    /// result to `write` with the chunk of [`VecEnv::chunks`] it belongs to and its index in
    /// that chunk, on the thread that stepped it. A caller with thousands of environments
    /// builds one writer per thread this way, not one per environment on the calling thread
    /// (the Python vector env: docs/performance.md).
    ///
    /// # Panics
    ///
    /// Unless there is one chunk per range of [`VecEnv::chunks`].
    pub fn step_chunks<C: Send>(
        &mut self,
        actions: &[Action],
        chunks: &mut [C],
        write: impl Fn(&mut C, usize, &VecStepRef<'_>) + Sync,
    ) -> Result<()> {
        self.step_chunks_of(actions, |&action| Ok::<_, SimError>(action), chunks, write)
    }

    /// [`VecEnv::step_chunks`] with the actions given as values that `action` turns into
    /// [`Action`]s, on the thread that steps them: a caller holding action indices
    /// (Python's arrays of integers) spares its own thread a pass over the whole batch
    /// before the others can start. Every value is converted, an environment about to reset
    /// included; the first refusal in environment order, of a value or of its action, is
    /// the error, and nothing is stepped.
    ///
    /// # Panics
    ///
    /// Unless there is one chunk per range of [`VecEnv::chunks`].
    pub fn step_chunks_of<A: Sync, C: Send, E: From<SimError> + Send>(
        &mut self,
        actions: &[A],
        action: impl Fn(&A) -> std::result::Result<Action, E> + Sync,
        chunks: &mut [C],
        write: impl Fn(&mut C, usize, &VecStepRef<'_>) + Sync,
    ) -> std::result::Result<(), E> {
        if actions.len() != self.len() {
            return Err(SimError::ActionCountMismatch {
                envs: self.len(),
                actions: actions.len(),
            }
            .into());
        }
        assert_eq!(
            chunks.len(),
            self.chunk_count(),
            "one chunk per range of VecEnv::chunks"
        );
        // Every environment that takes its action must accept it (running, the block
        // exists, legal under the protocol); one about to reset ignores its action. The
        // first refusal in environment order, as a serial check would find it.
        let check = |(envs, actions, ended): (&[Env], &[A], &[bool])| -> std::result::Result<(), E> {
            for ((env, raw), &ended) in envs.iter().zip(actions).zip(ended) {
                let action = action(raw)?;
                if !ended {
                    env.check_action(action)?;
                }
            }
            Ok(())
        };
        let mode = self.autoreset;
        // Steps each environment of a chunk (or resets one whose episode ended under next-step
        // autoreset) and lends its result to `write`; `last` holds the observation a same-step
        // reset replaced.
        let step_chunk = |(envs, actions, ended, chunk): (&mut [Env], &[A], &mut [bool], &mut C)| {
            for (i, ((env, raw), ended)) in envs.iter_mut().zip(actions).zip(ended.iter_mut()).enumerate() {
                if *ended {
                    *ended = false;
                    env.reset(None);
                    write(chunk, i, &first(env));
                    continue;
                }
                // The batch's check pass has converted and accepted the action; one the rules
                // refuse is accepted only to be taken as a step that changes nothing, which
                // `advance` decides.
                let action = action(raw)?;
                let outcome = match env.refusal() {
                    Refusal::Error => env.advance_checked(action)?,
                    Refusal::Step => env.advance(action)?,
                };
                let mut last = None;
                if outcome.terminated || outcome.truncated {
                    match mode {
                        Autoreset::SameStep => {
                            last = Some(env.observation());
                            env.reset(None);
                        }
                        Autoreset::NextStep => *ended = true,
                    }
                }
                let result = VecStepRef {
                    observation: env.current_observation(),
                    action_mask: env.legal_actions(),
                    outcome: Some(outcome),
                    final_observation: last.as_ref(),
                };
                write(chunk, i, &result);
            }
            Ok(())
        };
        match parallel(self.team.as_ref(), self.envs.len()) {
            None => {
                check((&self.envs, actions, &self.ended))?;
                match chunks.first_mut() {
                    Some(chunk) => step_chunk((&mut self.envs, actions, &mut self.ended, chunk)),
                    None => Ok(()),
                }
            }
            Some((team, len)) => {
                // Each chunk checked on its thread, then stepped only once every chunk has
                // passed: the refusals in chunk order give the first, as a serial check would.
                let parts = self
                    .envs
                    .chunks_mut(len)
                    .zip(actions.chunks(len))
                    .zip(self.ended.chunks_mut(len))
                    .zip(chunks.iter_mut());
                let parts = parts.map(|(((envs, actions), ended), chunk)| (envs, actions, ended, chunk));
                let checked =
                    |(envs, actions, ended, _): &(&mut [Env], &[A], &mut [bool], &mut C)| check((envs, actions, ended));
                team.run_checked(parts.collect(), checked, step_chunk)?
                    .into_iter()
                    .collect()
            }
        }
    }

    /// The environments, for reading their state.
    pub fn envs(&self) -> &[Env] {
        &self.envs
    }
}

/// `env`'s result right after a reset: its first observation, no outcome.
fn first(env: &Env) -> VecStepRef<'_> {
    VecStepRef {
        observation: env.current_observation(),
        action_mask: env.legal_actions(),
        outcome: None,
        final_observation: None,
    }
}

/// `slots` cut at `ranges` (consecutive, covering every slot).
fn split<'a, T>(mut slots: &'a mut [T], ranges: &[Range<usize>]) -> Vec<&'a mut [T]> {
    ranges
        .iter()
        .map(|r| {
            let (head, tail) = std::mem::take(&mut slots).split_at_mut(r.len());
            slots = tail;
            head
        })
        .collect()
}
