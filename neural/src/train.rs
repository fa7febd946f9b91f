//! Training: DQfD pre-training on the demonstrations, then self-play with experience
//! replay, a target network and an epsilon schedule; fixed by the config's seed.
//!
//! Self-play game `k` plays goal `goals[k % len]` from the start
//! `reset(episode_seed(seed, k))`, as the tabular trainer's games do. The weights, the
//! exploration and the batches come from the seed's own streams. Same seed, same network,
//! on the same machine and number of threads (a matrix product's sums may be split
//! differently on another thread count).

use std::collections::{HashSet, VecDeque};

use oracle::{ExactSolver, Oracle, Planner};
use rand::RngExt;
use sim::seeding::{self, SimRng, episode_seed};
use sim::{Action, Env, GridWorld, Observation, State};

use crate::config::{DemoSource, DqnConfig, TargetEvery};
use crate::demos::{self, DemoEpisode};
use crate::error::{NeuralError, Result};
use crate::hindsight::{self, Step};
use crate::learner::{Learner, Losses};
use crate::mask::ActionSet;
use crate::model::{Dqn, TrainReport};
use crate::net::QNet;
use crate::replay::{NStep, ReplayBuffer};

/// Games the progress's success rate is taken over.
pub const RECENT_GAMES: usize = 100;

/// Which part of training a progress report is from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Gradient steps on the demonstrations alone.
    Pretrain,
    /// Playing and learning.
    SelfPlay,
}

/// How training is going.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// The phase.
    pub phase: Phase,
    /// Steps of this phase done (gradient steps in pre-training, environment steps in
    /// self-play).
    pub done: u64,
    /// Steps of this phase asked for, counting from the start of the run.
    pub target: u64,
    /// Self-play games begun.
    pub games: u64,
    /// Of the last (at most [`RECENT_GAMES`]) finished games, how many.
    pub recent_games: usize,
    /// Of those, how many reached the goal.
    pub recent_successes: usize,
    /// The last gradient step's loss.
    pub loss: Losses,
    /// Gradient steps in all.
    pub gradient_steps: u64,
}

impl Progress {
    /// The share of recent games that reached the goal (0 before any game ended).
    pub fn recent_success_rate(&self) -> f64 {
        if self.recent_games == 0 {
            0.0
        } else {
            self.recent_successes as f64 / self.recent_games as f64
        }
    }
}

/// A training run in progress: pre-train, play some steps, look at (or evaluate) the
/// network, play more.
pub struct Trainer {
    pub(crate) config: DqnConfig,
    pub(crate) learner: Learner,
    pub(crate) buffer: ReplayBuffer,
    pub(crate) envs: Vec<Env>,
    /// Exploration and batch draws.
    pub(crate) rng: SimRng,
    pub(crate) report: TrainReport,
    pub(crate) recent: VecDeque<bool>,
    /// The game being played: its environment and current observation.
    pub(crate) current: Option<(usize, Observation)>,
    pub(crate) n_step: NStep,
    pub(crate) last_loss: Losses,
    /// Games when the target network was last refreshed.
    pub(crate) target_games: u64,
    /// The states of the current game, to see it come back to one.
    pub(crate) visited: HashSet<State>,
    /// Whether a demonstrator has demonstrated from a loop of the current game.
    pub(crate) corrected: bool,
    /// Who corrects loops.
    corrector: Box<dyn Planner + Send + Sync>,
    /// The current game's steps, for hindsight relabelling (kept only with it).
    pub(crate) game: Vec<Step>,
    /// The current game's actions: what a checkpoint replays to put its environment back
    /// where it was ([`crate::checkpoint`]).
    pub(crate) actions: Vec<Action>,
}

impl Trainer {
    /// A run of `config` with the demonstrations it names (read or planned now).
    pub fn new(config: DqnConfig) -> Result<Trainer> {
        config.validate()?;
        let episodes = demos::load(&config)?;
        Trainer::with_demos(config, &episodes)
    }

    /// A run of `config` with these demonstrations (whatever `config.demos` says).
    pub fn with_demos(config: DqnConfig, episodes: &[DemoEpisode]) -> Result<Trainer> {
        config.validate()?;
        let input = config.net.input(config.world.grid, config.world.blocks)?;
        let mut init = seeding::rng(config.seed);
        init.set_stream(2);
        let net = QNet::new(config.net, input, &mut init)?;
        let learner = Learner::new(net, &config)?;
        let mut buffer = ReplayBuffer::new(config.buffer);
        for t in demos::transitions(episodes, &config) {
            buffer.push_demo(t);
        }
        if config.pretrain_steps > 0 && buffer.demo_len() == 0 {
            return Err(NeuralError::Config(
                "pre-training needs demonstrations, and none were found".into(),
            ));
        }
        let mut rng = seeding::rng(config.seed);
        rng.set_stream(3);
        let report = TrainReport {
            demo_episodes: episodes.len() as u64,
            demo_transitions: buffer.demo_len() as u64,
            ..TrainReport::default()
        };
        Trainer::assemble(config, learner, buffer, rng, report)
    }

    /// A run of `config` at the point these parts describe, between two steps with no game
    /// going on: the environments and the corrector made for it.
    pub(crate) fn assemble(
        config: DqnConfig,
        learner: Learner,
        buffer: ReplayBuffer,
        rng: SimRng,
        report: TrainReport,
    ) -> Result<Trainer> {
        let envs = config
            .goals
            .iter()
            .map(|g| Env::new(config.env_config(g.clone())))
            .collect::<sim::Result<Vec<_>>>()?;
        Ok(Trainer {
            n_step: NStep::new(config.n_step, config.gamma),
            learner,
            buffer,
            envs,
            rng,
            report,
            recent: VecDeque::new(),
            current: None,
            last_loss: Losses::default(),
            target_games: 0,
            visited: HashSet::new(),
            corrected: false,
            game: Vec::new(),
            actions: Vec::new(),
            corrector: match config.demos {
                DemoSource::Oracle(_) => Box::new(Oracle::new(config.world.grid)),
                _ => Box::new(ExactSolver::new(config.world.grid)),
            },
            config,
        })
    }

    /// The config.
    pub fn config(&self) -> &DqnConfig {
        &self.config
    }

    /// The totals so far.
    pub fn report(&self) -> TrainReport {
        TrainReport {
            gradient_steps: self.learner.gradient_steps(),
            ..self.report
        }
    }

    /// The network being trained.
    pub fn net(&self) -> &QNet {
        self.learner.online()
    }

    /// Runs what is left of the config (all of it for a new run, the rest for one resumed
    /// from a checkpoint): pre-training, then self-play, telling `progress` after every step.
    pub fn run(mut self, progress: &mut dyn FnMut(&Progress)) -> Result<Dqn> {
        self.train_until(self.total_steps(), progress)?;
        self.finish()
    }

    /// The steps of the whole run: pre-training gradient steps, then self-play environment
    /// steps.
    pub fn total_steps(&self) -> u64 {
        self.config.pretrain_steps + self.config.steps
    }

    /// The steps of the run done ([`Trainer::total_steps`]' count).
    pub fn steps_done(&self) -> u64 {
        self.report.pretrain_steps + self.report.steps
    }

    /// Trains until `done` steps of the run are done (at most [`Trainer::total_steps`]):
    /// pre-training first, then self-play. Nothing if that many are done already.
    pub fn train_until(&mut self, done: u64, progress: &mut dyn FnMut(&Progress)) -> Result<()> {
        let done = done.min(self.total_steps());
        let pretrain = done.min(self.config.pretrain_steps);
        self.pretrain(pretrain.saturating_sub(self.report.pretrain_steps), progress)?;
        let play = done - pretrain;
        self.play(play.saturating_sub(self.report.steps), progress)
    }

    /// `count` more gradient steps on the demonstrations alone.
    pub fn pretrain(&mut self, count: u64, progress: &mut dyn FnMut(&Progress)) -> Result<()> {
        let target = self.report.pretrain_steps + count;
        for _ in 0..count {
            self.pretrain_step()?;
            progress(&self.progress(Phase::Pretrain, self.report.pretrain_steps, target));
        }
        Ok(())
    }

    /// `count` more environment steps of self-play, learning as configured.
    pub fn play(&mut self, count: u64, progress: &mut dyn FnMut(&Progress)) -> Result<()> {
        let target = self.report.steps + count;
        for _ in 0..count {
            self.play_step()?;
            progress(&self.progress(Phase::SelfPlay, self.report.steps, target));
        }
        Ok(())
    }

    /// Trains until `total` steps of the run are done (at most [`Trainer::total_steps`]),
    /// the one loop of a whole run for the command line and Python: after each step, every
    /// [`TrainHooks::checkpoint_every`] steps of the run (counted from its first) and after
    /// the last, [`TrainHooks::checkpoint`]; then [`TrainHooks::after_step`] (progress, and
    /// stopping: its error ends the run). A run with nothing left to train still writes its
    /// checkpoint. An error if `total` is below the steps done already.
    pub fn run_until(&mut self, total: u64, hooks: &mut dyn TrainHooks) -> Result<()> {
        let total = total.min(self.total_steps());
        let done = self.steps_done();
        if total < done {
            return Err(NeuralError::Config(format!(
                "{total} steps in all: the run has done {done} already"
            )));
        }
        let every = hooks.checkpoint_every().filter(|&n| n > 0);
        let due = |steps: u64| every.is_some_and(|n| steps.is_multiple_of(n) || steps == total);
        // Each phase's progress counts towards the phase's part of `total`.
        let pretrain_target = total.min(self.config.pretrain_steps);
        let play_target = total - pretrain_target;
        while self.steps_done() < total {
            let progress = if self.report.pretrain_steps < pretrain_target {
                self.pretrain_step()?;
                self.progress(Phase::Pretrain, self.report.pretrain_steps, pretrain_target)
            } else {
                self.play_step()?;
                self.progress(Phase::SelfPlay, self.report.steps, play_target)
            };
            // The checkpoint first: a run stopped by the hook keeps the one it was due.
            if due(self.steps_done()) {
                hooks.checkpoint(self)?;
            }
            hooks.after_step(&progress)?;
        }
        if done == total && every.is_some() {
            hooks.checkpoint(self)?;
        }
        Ok(())
    }

    /// [`Trainer::run_until`] on a thread of rayon's global pool while the pool's other
    /// threads stay awake to take the second halves of its splits
    /// ([`crate::kernels::on_pool_awake`]), for a caller outside every pool (the command
    /// line's main thread, Python's trainer); the same steps, so the same bits.
    ///
    /// Why: a network's passes are split in two halves ([`crate::kernels::join`]). Called
    /// from outside a pool, each split hands both halves to the pool and puts the caller to
    /// sleep until they end: two thread wake-ups a split, several splits a step. On a pool
    /// thread the caller runs one half while the other thread takes the second, and that
    /// thread, kept awake, takes it at once (docs/performance.md measures both). The
    /// hooks run on that thread, so they must be `Send`, and cannot look for Ctrl-C, which
    /// only the main thread sees: Python's trainer looks for it on its own thread meanwhile.
    pub fn run_until_on_pool(&mut self, total: u64, hooks: &mut (dyn TrainHooks + Send)) -> Result<()> {
        crate::kernels::on_pool_awake(|| self.run_until(total, hooks))
    }

    /// One gradient step on the demonstrations alone.
    fn pretrain_step(&mut self) -> Result<()> {
        let batch = self.buffer.sample_demos(self.config.batch, &mut self.rng);
        self.last_loss = self.learner.step(&batch, &self.config)?;
        self.report.pretrain_steps += 1;
        self.after_gradient_step()
    }

    /// One environment step of self-play, and a gradient step when one is due.
    fn play_step(&mut self) -> Result<()> {
        self.env_step()?;
        let learning = self.buffer.agent_len() as u64 >= self.config.learning_starts.max(1);
        if learning && self.report.steps.is_multiple_of(self.config.train_every) {
            let batch = self
                .buffer
                .sample(self.config.batch, self.config.demo_share, &mut self.rng);
            self.last_loss = self.learner.step(&batch, &self.config)?;
            self.after_gradient_step()?;
        }
        Ok(())
    }

    /// The trained network, with the totals.
    pub fn finish(self) -> Result<Dqn> {
        let report = self.report();
        Ok(Dqn::new(self.learner.online().try_clone()?, self.config, report))
    }

    /// A copy of the network as it is now, to evaluate while training goes on.
    pub fn snapshot(&self) -> Result<Dqn> {
        Ok(Dqn::new(
            self.learner.online().try_clone()?,
            self.config.clone(),
            self.report(),
        ))
    }

    /// The learning rate after `done` gradient steps: linear from `lr` to `lr_final` over
    /// the run's planned gradient steps.
    fn learning_rate(&self, done: u64) -> f64 {
        let c = &self.config;
        let planned = c.pretrain_steps + c.steps.saturating_sub(c.learning_starts) / c.train_every;
        let t = (done as f64 / planned.max(1) as f64).min(1.0);
        c.lr + (c.lr_final - c.lr) * t
    }

    fn after_gradient_step(&mut self) -> Result<()> {
        let lr = self.learning_rate(self.learner.gradient_steps());
        self.learner.set_lr(lr);
        if let TargetEvery::Steps(n) = self.config.target_every
            && self.learner.gradient_steps().is_multiple_of(n)
        {
            self.learner.refresh_target()?;
        }
        Ok(())
    }

    fn progress(&self, phase: Phase, done: u64, target: u64) -> Progress {
        Progress {
            phase,
            done,
            target,
            games: self.report.games,
            recent_games: self.recent.len(),
            recent_successes: self.recent.iter().filter(|&&s| s).count(),
            loss: self.last_loss,
            gradient_steps: self.learner.gradient_steps(),
        }
    }

    /// One step of the current game (beginning one if none is going on).
    fn env_step(&mut self) -> Result<()> {
        let (env_index, obs) = match self.current.clone() {
            Some(c) => c,
            None => {
                let k = self.report.games;
                let i = (k % self.envs.len() as u64) as usize;
                let obs = self.envs[i].reset(episode_seed(self.config.seed, k));
                self.report.games += 1;
                self.visited.clear();
                self.corrected = false;
                self.game.clear();
                self.actions.clear();
                (i, obs)
            }
        };
        if self.config.correct_loops && !self.visited.insert(obs.state.clone()) && !self.corrected {
            self.correct(&obs)?;
            self.corrected = true;
        }
        let action = self.choose(&obs)?;
        let step = self.envs[env_index].step(action)?;
        self.actions.push(action);
        self.report.steps += 1;
        let done = step.terminated || step.truncated;
        if self.config.hindsight > 0 {
            self.game.push(Step {
                obs: obs.clone(),
                action,
                next: step.observation.clone(),
            });
        }
        if let Some(t) = self.n_step.push(
            obs,
            action,
            step.reward as f32,
            step.observation.clone(),
            step.terminated,
            false,
        ) {
            self.buffer.push(t);
        }
        if done {
            for t in self.n_step.finish() {
                self.buffer.push(t);
            }
            for t in hindsight::relabel(&self.game, self.config.hindsight, &self.config, &mut self.rng) {
                self.buffer.push(t);
                self.report.relabelled += 1;
            }
            self.recent.push_back(step.terminated);
            if self.recent.len() > RECENT_GAMES {
                self.recent.pop_front();
            }
            self.report.successes += u64::from(step.terminated);
            self.current = None;
            self.actions.clear();
            if let TargetEvery::Games(n) = self.config.target_every
                && self.report.games - self.target_games >= n
            {
                self.learner.refresh_target()?;
                self.target_games = self.report.games;
            }
        } else {
            self.current = Some((env_index, step.observation));
        }
        Ok(())
    }

    /// The agent came back to `obs`: the demonstrator plans from there and its plan joins
    /// the demonstrations; the agent plays on.
    fn correct(&mut self, obs: &Observation) -> Result<()> {
        let plan = self.corrector.plan(&obs.state, &obs.goal)?;
        let states = GridWorld::new(obs.grid, obs.state.clone())?.replay(&plan.actions)?;
        let episode = DemoEpisode {
            goal: obs.goal.clone(),
            states,
            expert: vec![true; plan.actions.len()],
            actions: plan.actions,
        };
        for t in episode.transitions(&self.config) {
            self.buffer.push_demo(t);
        }
        self.report.demo_transitions = self.buffer.demo_len() as u64;
        self.report.corrections += 1;
        Ok(())
    }

    /// Epsilon-greedy over the allowed actions.
    fn choose(&mut self, obs: &Observation) -> Result<Action> {
        let epsilon = self.config.epsilon.at(self.report.steps);
        if epsilon > 0.0 && self.rng.random_bool(epsilon) {
            let allowed = ActionSet::allowed(obs, self.config.mask_noops);
            let a = allowed.random(&mut self.rng).expect("some action is always allowed");
            return Ok(Action::from_index(a, self.config.world.blocks)?);
        }
        self.learner.online().greedy_action(obs, self.config.mask_noops)
    }
}

/// What a run does beside training ([`Trainer::run_until`]): show progress, stop on the
/// caller's word, write checkpoints. Every method has a default that does nothing.
pub trait TrainHooks {
    /// Called after every step with the run's progress; an error (say, Ctrl-C seen) stops
    /// the run before the next step.
    fn after_step(&mut self, _progress: &Progress) -> Result<()> {
        Ok(())
    }

    /// Steps between two checkpoints, counted from the run's first step; `None` (the
    /// default) writes none.
    fn checkpoint_every(&self) -> Option<u64> {
        None
    }

    /// Writes a checkpoint of `trainer` ([`Trainer::write_checkpoint`]).
    fn checkpoint(&mut self, _trainer: &Trainer) -> Result<()> {
        Ok(())
    }
}

/// No hooks: a run that only trains.
impl TrainHooks for () {}

/// Trains as `config` says; `progress` is told after every step.
pub fn train(config: DqnConfig, progress: &mut dyn FnMut(&Progress)) -> Result<Dqn> {
    Trainer::new(config)?.run(progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::NetConfig;
    use crate::preset::Preset;

    /// DQfD on 2 blocks, shrunk to a few dozen steps of each phase.
    fn small() -> DqnConfig {
        DqnConfig {
            seed: 3,
            demos: DemoSource::Exact(6),
            pretrain_steps: 12,
            steps: 30,
            learning_starts: 10,
            batch: 8,
            net: NetConfig {
                hidden: 16,
                ..NetConfig::small()
            },
            ..DqnConfig::preset(Preset::DqfdPlanes, 2).unwrap()
        }
    }

    /// Hooks that note the steps at each checkpoint and each progress report, and stop the
    /// run after `stop_after` steps.
    #[derive(Default)]
    struct Notes {
        every: Option<u64>,
        stop_after: Option<u64>,
        checkpoints: Vec<u64>,
        reports: Vec<(Phase, u64, u64)>,
    }

    impl TrainHooks for Notes {
        fn after_step(&mut self, p: &Progress) -> Result<()> {
            self.reports.push((p.phase, p.done, p.target));
            match self.stop_after {
                Some(n) if self.reports.len() as u64 == n => Err(agent::AgentError::Interrupted.into()),
                _ => Ok(()),
            }
        }

        fn checkpoint_every(&self) -> Option<u64> {
            self.every
        }

        fn checkpoint(&mut self, trainer: &Trainer) -> Result<()> {
            self.checkpoints.push(trainer.steps_done());
            Ok(())
        }
    }

    fn weights(trainer: &Trainer) -> Vec<Vec<f32>> {
        trainer.net().tensors().map(|t| t.values.to_vec()).collect()
    }

    #[test]
    fn run_until_checkpoints_every_n_steps_and_at_the_end() {
        let mut trainer = Trainer::new(small()).unwrap();
        let mut notes = Notes {
            every: Some(10),
            ..Notes::default()
        };
        trainer.run_until(trainer.total_steps(), &mut notes).unwrap();
        assert_eq!(notes.checkpoints, [10, 20, 30, 40, 42]);
        // Each phase's progress counts towards the phase's own end.
        assert_eq!(notes.reports.len(), 42);
        assert_eq!(notes.reports[0], (Phase::Pretrain, 1, 12));
        assert_eq!(notes.reports[11], (Phase::Pretrain, 12, 12));
        assert_eq!(notes.reports[12], (Phase::SelfPlay, 1, 30));
        assert_eq!(notes.reports[41], (Phase::SelfPlay, 30, 30));
        // The steps are the ones `run` takes.
        let mut whole = Trainer::new(small()).unwrap();
        whole.train_until(whole.total_steps(), &mut |_| {}).unwrap();
        assert_eq!(weights(&trainer), weights(&whole));
        assert_eq!(trainer.report(), whole.report());
    }

    #[test]
    fn a_resumed_run_keeps_the_cadence_and_one_with_nothing_left_still_checkpoints() {
        let mut trainer = Trainer::new(small()).unwrap();
        trainer.run_until(20, &mut ()).unwrap();
        let mut notes = Notes {
            every: Some(10),
            ..Notes::default()
        };
        trainer.run_until(trainer.total_steps(), &mut notes).unwrap();
        assert_eq!(notes.checkpoints, [30, 40, 42]);
        let mut again = Notes {
            every: Some(10),
            ..Notes::default()
        };
        trainer.run_until(trainer.total_steps(), &mut again).unwrap();
        assert_eq!((again.checkpoints, again.reports.len()), (vec![42], 0));
        assert!(trainer.run_until(5, &mut ()).is_err(), "below the steps done");
    }

    #[test]
    fn a_hooks_error_stops_the_run_after_its_step() {
        let mut trainer = Trainer::new(small()).unwrap();
        let mut notes = Notes {
            every: Some(10),
            stop_after: Some(20),
            ..Notes::default()
        };
        let stopped = trainer.run_until(trainer.total_steps(), &mut notes);
        assert!(matches!(
            stopped,
            Err(NeuralError::Agent(agent::AgentError::Interrupted))
        ));
        assert_eq!(trainer.steps_done(), 20);
        // The checkpoint due at the step the run stopped after was written.
        assert_eq!(notes.checkpoints, [10, 20]);
    }
}
