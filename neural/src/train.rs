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
    config: DqnConfig,
    learner: Learner,
    buffer: ReplayBuffer,
    envs: Vec<Env>,
    /// Exploration and batch draws.
    rng: SimRng,
    report: TrainReport,
    recent: VecDeque<bool>,
    /// The game being played: its environment and current observation.
    current: Option<(usize, Observation)>,
    n_step: NStep,
    last_loss: Losses,
    /// Games when the target network was last refreshed.
    target_games: u64,
    /// The states of the current game, to see it come back to one.
    visited: HashSet<State>,
    /// Whether a demonstrator has demonstrated from a loop of the current game.
    corrected: bool,
    /// Who corrects loops.
    corrector: Box<dyn Planner + Send + Sync>,
    /// The current game's steps, for hindsight relabelling (kept only with it).
    game: Vec<Step>,
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
        let envs = config
            .goals
            .iter()
            .map(|&g| Env::new(config.env_config(g)))
            .collect::<sim::Result<Vec<_>>>()?;
        let mut rng = seeding::rng(config.seed);
        rng.set_stream(3);
        let report = TrainReport {
            demo_episodes: episodes.len() as u64,
            demo_transitions: buffer.demo_len() as u64,
            ..TrainReport::default()
        };
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

    /// Runs the whole config: pre-training, then self-play, telling `progress` after every
    /// step.
    pub fn run(mut self, progress: &mut dyn FnMut(&Progress)) -> Result<Dqn> {
        self.pretrain(self.config.pretrain_steps, progress)?;
        self.play(self.config.steps, progress)?;
        self.finish()
    }

    /// `count` more gradient steps on the demonstrations alone.
    pub fn pretrain(&mut self, count: u64, progress: &mut dyn FnMut(&Progress)) -> Result<()> {
        let target = self.report.pretrain_steps + count;
        for _ in 0..count {
            let batch = self.buffer.sample_demos(self.config.batch, &mut self.rng);
            self.last_loss = self.learner.step(&batch, &self.config)?;
            self.report.pretrain_steps += 1;
            self.after_gradient_step()?;
            progress(&self.progress(Phase::Pretrain, self.report.pretrain_steps, target));
        }
        Ok(())
    }

    /// `count` more environment steps of self-play, learning as configured.
    pub fn play(&mut self, count: u64, progress: &mut dyn FnMut(&Progress)) -> Result<()> {
        let target = self.report.steps + count;
        for _ in 0..count {
            self.env_step()?;
            let learning = self.buffer.agent_len() as u64 >= self.config.learning_starts.max(1);
            if learning && self.report.steps.is_multiple_of(self.config.train_every) {
                let batch = self
                    .buffer
                    .sample(self.config.batch, self.config.demo_share, &mut self.rng);
                self.last_loss = self.learner.step(&batch, &self.config)?;
                self.after_gradient_step()?;
            }
            progress(&self.progress(Phase::SelfPlay, self.report.steps, target));
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
        let (env_index, obs) = match self.current {
            Some(c) => c,
            None => {
                let k = self.report.games;
                let i = (k % self.envs.len() as u64) as usize;
                let obs = self.envs[i].reset(episode_seed(self.config.seed, k));
                self.report.games += 1;
                self.visited.clear();
                self.corrected = false;
                self.game.clear();
                (i, obs)
            }
        };
        if self.config.correct_loops && !self.visited.insert(obs.state) && !self.corrected {
            self.correct(&obs)?;
            self.corrected = true;
        }
        let action = self.choose(&obs)?;
        let step = self.envs[env_index].step(action)?;
        self.report.steps += 1;
        let done = step.terminated || step.truncated;
        if self.config.hindsight > 0 {
            self.game.push(Step {
                obs,
                action,
                next: step.observation,
            });
        }
        if let Some(t) = self.n_step.push(
            obs,
            action,
            step.reward as f32,
            step.observation,
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
        let states = GridWorld::new(obs.grid, obs.state)?.replay(&plan.actions)?;
        let episode = DemoEpisode {
            goal: obs.goal,
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

/// Trains as `config` says; `progress` is told after every step.
pub fn train(config: DqnConfig, progress: &mut dyn FnMut(&Progress)) -> Result<Dqn> {
    Trainer::new(config)?.run(progress)
}
