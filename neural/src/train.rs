//! Training: DQfD pre-training on the demonstrations, then self-play with experience
//! replay, a target network and an epsilon schedule; fixed by the config's seed.
//!
//! Self-play game `k` plays goal `goals[k % len]` from the start
//! `reset(episode_seed(seed, k))`, as the tabular trainer's games do. The weights, the
//! exploration and the batches come from the seed's own streams. Same seed, same network,
//! on the same machine and number of threads (a matrix product's sums may be split
//! differently on another thread count).

use std::collections::HashSet;

use agent::run::{self, Recent, RecentGames, RunHooks, Runnable};

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
use crate::replay::{NStep, ReplayBuffer, Transition};

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
    /// The last (at most [`RECENT_GAMES`](agent::run::RECENT_GAMES)) finished games, and how many reached the goal.
    pub recent: RecentGames,
    /// The last gradient step's loss.
    pub loss: Losses,
    /// Gradient steps in all.
    pub gradient_steps: u64,
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
    pub(crate) recent: Recent<bool>,
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
            recent: Recent::default(),
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

    /// Trains until `total` steps of the run are done (at most [`Trainer::total_steps`]):
    /// the one run loop ([`agent::run::run_until`]), a step a unit, with `hooks`' progress,
    /// stop and checkpoints. An error if `total` is below the steps done already.
    pub fn run_until<F>(&mut self, total: u64, hooks: &mut RunHooks<'_, F>) -> Result<()>
    where
        F: FnMut(&Progress) -> Result<()>,
    {
        run::run_until(self, total, hooks)
    }

    /// [`Trainer::run_until`] on a thread of rayon's global pool while the pool's other
    /// threads stay awake to take the second halves of its splits
    /// ([`sim::team::on_pool_awake`]), for a caller outside every pool (the command
    /// line's main thread, Python's trainer); the same steps, so the same bits.
    ///
    /// Why: a network's passes are split in two halves ([`crate::kernels::join`]). Called
    /// from outside a pool, each split hands both halves to the pool and puts the caller to
    /// sleep until they end: two thread wake-ups a split, several splits a step. On a pool
    /// thread the caller runs one half while the other thread takes the second, and that
    /// thread, kept awake, takes it at once (docs/performance.md measures both). The
    /// hooks run on that thread, so they must be `Send`, and cannot look for Ctrl-C, which
    /// only the main thread sees: Python's trainer looks for it on its own thread meanwhile.
    pub fn run_until_on_pool<F>(&mut self, total: u64, hooks: &mut RunHooks<'_, F>) -> Result<()>
    where
        F: FnMut(&Progress) -> Result<()> + Send,
    {
        sim::team::on_pool_awake(|| self.run_until(total, hooks))
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
            recent: self.recent.count(|&reached| reached),
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
                self.report.games += 1;
                self.begin_game(k)
            }
        };
        if self.revisits(&obs) && !self.corrected {
            self.correct(&obs)?;
            self.corrected = true;
        }
        let action = self.choose(&obs)?;
        let (step, finished) = self.take_step(env_index, obs, action)?;
        if let Some(t) = finished {
            self.buffer.push(t);
        }
        self.report.steps += 1;
        if step.terminated || step.truncated {
            for t in self.n_step.finish() {
                self.buffer.push(t);
            }
            for t in hindsight::relabel(&self.game, self.config.hindsight, &self.config, &mut self.rng) {
                self.buffer.push(t);
                self.report.relabelled += 1;
            }
            self.recent.push(step.terminated);
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

    /// Begins game `k` of the run: its environment (goal `k` modulo the goals) reset from
    /// the game's seed and the game's bookkeeping emptied; the environment's index and the
    /// first observation. A trainer's new game and a checkpoint's game in progress
    /// ([`crate::checkpoint`]) both begin here.
    pub(crate) fn begin_game(&mut self, k: u64) -> (usize, Observation) {
        let i = (k % self.envs.len() as u64) as usize;
        let obs = self.envs[i].reset(episode_seed(self.config.seed, k));
        self.visited.clear();
        self.corrected = false;
        self.game.clear();
        self.actions.clear();
        (i, obs)
    }

    /// Whether the current game comes back to `obs`'s state, which it notes among the
    /// game's states; always false without loop correction (nothing is noted).
    pub(crate) fn revisits(&mut self, obs: &Observation) -> bool {
        self.config.correct_loops && !self.visited.insert(obs.state.clone())
    }

    /// Plays `action` from `obs` in environment `env_index` and keeps the game's
    /// bookkeeping (its actions, its hindsight record, its n-step window): the step, and the
    /// transition the window completes, if any. A trainer's step and a checkpoint's replay
    /// of its game in progress both step here, so they keep the same books.
    pub(crate) fn take_step(
        &mut self,
        env_index: usize,
        obs: Observation,
        action: Action,
    ) -> Result<(sim::Step, Option<Transition>)> {
        let step = self.envs[env_index].step(action)?;
        self.actions.push(action);
        if self.config.hindsight > 0 {
            self.game.push(Step {
                obs: obs.clone(),
                action,
                next: step.observation.clone(),
            });
        }
        let finished = self.n_step.push(
            obs,
            action,
            step.reward as f32,
            step.observation.clone(),
            step.terminated,
            false,
        );
        Ok((step, finished))
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

/// A step a unit (pre-training gradient steps, then self-play environment steps): the
/// network's learner in the one run loop ([`agent::run::run_until`]). Each phase's progress
/// counts towards the phase's part of the total.
impl Runnable for Trainer {
    type Progress = Progress;
    type Error = NeuralError;

    fn units_done(&self) -> u64 {
        self.steps_done()
    }

    fn plan_to(&mut self, total: u64) -> Result<u64> {
        let total = total.min(self.total_steps());
        let done = self.steps_done();
        if total < done {
            return Err(NeuralError::Config(format!(
                "{total} steps in all: the run has done {done} already"
            )));
        }
        Ok(total)
    }

    fn next_unit(&mut self, total: u64) -> Result<Progress> {
        let pretrain_target = total.min(self.config.pretrain_steps);
        if self.report.pretrain_steps < pretrain_target {
            self.pretrain_step()?;
            Ok(self.progress(Phase::Pretrain, self.report.pretrain_steps, pretrain_target))
        } else {
            self.play_step()?;
            Ok(self.progress(Phase::SelfPlay, self.report.steps, total - pretrain_target))
        }
    }

    fn write_checkpoint(&self, out: &files::OutputPath) -> Result<()> {
        Trainer::write_checkpoint(self, out)
    }
}

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

    /// Hooks that note each progress report, and stop the run after `stop_after` steps.
    fn notes(
        reports: &mut Vec<(Phase, u64, u64)>,
        stop_after: Option<u64>,
    ) -> RunHooks<'static, impl FnMut(&Progress) -> Result<()>> {
        RunHooks {
            after: move |p: &Progress| {
                reports.push((p.phase, p.done, p.target));
                match stop_after {
                    Some(n) if reports.len() as u64 == n => Err(agent::AgentError::Interrupted.into()),
                    _ => Ok(()),
                }
            },
            checkpoints: None,
        }
    }

    fn weights(trainer: &Trainer) -> Vec<Vec<f32>> {
        trainer.net().tensors().map(|t| t.values.to_vec()).collect()
    }

    #[test]
    fn run_until_takes_the_steps_run_takes_and_reports_each_phase() {
        let mut trainer = Trainer::new(small()).unwrap();
        let mut reports = Vec::new();
        trainer
            .run_until(trainer.total_steps(), &mut notes(&mut reports, None))
            .unwrap();
        // Each phase's progress counts towards the phase's own end.
        assert_eq!(reports.len(), 42);
        assert_eq!(reports[0], (Phase::Pretrain, 1, 12));
        assert_eq!(reports[11], (Phase::Pretrain, 12, 12));
        assert_eq!(reports[12], (Phase::SelfPlay, 1, 30));
        assert_eq!(reports[41], (Phase::SelfPlay, 30, 30));
        // The steps are the ones `run` takes.
        let mut whole = Trainer::new(small()).unwrap();
        whole.train_until(whole.total_steps(), &mut |_| {}).unwrap();
        assert_eq!(weights(&trainer), weights(&whole));
        assert_eq!(trainer.report(), whole.report());
        assert!(
            trainer.run_until(5, &mut RunHooks::quiet(None)).is_err(),
            "below the steps done"
        );
    }

    #[test]
    fn a_run_stopped_by_its_hook_keeps_the_checkpoint_due_at_its_step() {
        let dir = tempfile::tempdir().unwrap();
        let out = files::OutputPath::check(dir.path().join("ck")).unwrap();
        let mut trainer = Trainer::new(small()).unwrap();
        let mut reports = Vec::new();
        let mut hooks = RunHooks {
            checkpoints: agent::Checkpoints::to(Some(&out), 10),
            ..notes(&mut reports, Some(20))
        };
        let stopped = trainer.run_until(trainer.total_steps(), &mut hooks);
        assert!(matches!(
            stopped,
            Err(NeuralError::Agent(agent::AgentError::Interrupted))
        ));
        assert_eq!(trainer.steps_done(), 20);
        assert_eq!(Trainer::resume(out.path()).unwrap().steps_done(), 20);
    }
}
