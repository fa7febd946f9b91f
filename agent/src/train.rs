//! Training a Q-learner headless: games against the world (physics by default), on a set
//! of goals, fixed by a seed.
//!
//! Game `k` is reset with `episode_seed(seed, k)` and draws its exploration from
//! [`policy_rng`]`(episode_seed(seed, k))`: the same config gives the same table, bit for
//! bit. Under the `spec` schedule it plays goal `goals[k % goals.len()]`; under
//! `paper-code` its generator first draws the goal uniformly from `goals` (the
//! [`schedule`](crate::schedule) module gives the rest of each schedule). Nothing is
//! printed: progress goes to an optional callback after every game.
//!
//! A config names its world: the action protocol, the start rule and the reward, and the
//! schedule's termination rule (a training game ends at the goal under `spec`, at a step
//! reward above 70 under `paper-code`). [`TrainConfig::for_profile`] gives each profile's
//! learner: the paper's learner in our world, or the paper's learner as its authors coded
//! it.

use files::OutputPath;
use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::seeding::episode_seed;
use sim::{BlockId, Env};

use crate::assist::{Assist, OracleKind, OscillationWatch};
use crate::config::{QParams, TrainConfig};
use crate::error::{AgentError, Result};
use crate::memory::ReplayMemory;
use crate::qlearning::{QAgent, TableStep};
use crate::rollout::policy_rng;
use crate::run::{self, Recent, RecentGames, RunHooks, Runnable};

/// The most sweeps of the final experience replay.
pub const MAX_REPLAY_SWEEPS: u32 = 1000;

/// How training is going, after a game.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Games played so far.
    pub games_played: u64,
    /// Games this call was asked to play, counting from the start of the run.
    pub games_target: u64,
    /// The last (at most [`RECENT_GAMES`](crate::run::RECENT_GAMES)) games, and how many reached the goal.
    pub recent: RecentGames,
    /// Mean steps of the recent games that reached the goal (`None` if none did).
    pub recent_mean_steps: Option<f64>,
}

/// Totals of a training run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TrainReport {
    /// Games played.
    pub games: u64,
    /// Games that reached the goal.
    pub successes: u64,
    /// Actions taken, in all games.
    pub steps: u64,
    /// Of those, actions the oracle chose.
    pub assisted_steps: u64,
    /// Sweeps of the final experience replay (0 without it).
    pub replay_sweeps: u32,
}

/// The outcome of [`train`].
#[derive(Clone, Debug)]
pub struct Trained {
    /// The trained agent; its [`QAgent::training`] is the config, with the games played.
    pub agent: QAgent,
    /// Totals.
    pub report: TrainReport,
}

/// A training run in progress: play some games, look at (or evaluate) the agent, play
/// more. `Send`, so runs go on separate threads.
pub struct Trainer {
    pub(crate) config: TrainConfig,
    pub(crate) agent: QAgent,
    /// One environment per goal, in the order of `config.goals`.
    envs: Vec<Env>,
    pub(crate) report: TrainReport,
    /// Steps of the recent games, `None` for a game cut off.
    pub(crate) recent: Recent<Option<u32>>,
    /// The current game's transitions, for backward replay.
    path: Vec<TableStep>,
    /// The oracle, when it assists.
    oracle: Option<AssistingOracle>,
    /// Oscillation seen in the current game.
    watch: OscillationWatch,
    /// The last transition from every state-action, when the run ends with a replay.
    pub(crate) memory: Option<ReplayMemory>,
}

/// The oracle that assists, as [`TrainConfig::oracle`] names it.
#[derive(Clone, Copy, Debug)]
enum AssistingOracle {
    /// Ours, planning under the training protocol.
    Astar(oracle::Oracle),
    /// The authors' walker.
    Paper(oracle::CentroidWalker),
}

impl Trainer {
    /// A fresh agent about to be trained as `config` says; an error for a config that
    /// cannot train.
    pub fn new(config: TrainConfig) -> Result<Trainer> {
        config.validate()?;
        let agent = QAgent::with_schedule(
            config.repr,
            config.world.grid,
            config.world.blocks,
            config.params,
            config.schedule,
        )?;
        let memory = config
            .final_replay
            .then(|| ReplayMemory::new(agent.table().key_count(), agent.table().columns()));
        let envs = config
            .goals
            .iter()
            .map(|g| Env::new(config.env_config(g.clone())))
            .collect::<sim::Result<Vec<_>>>()?;
        Ok(Trainer {
            agent,
            envs,
            report: TrainReport::default(),
            recent: Recent::default(),
            path: Vec::new(),
            oracle: (config.assist != Assist::None).then(|| match config.oracle {
                OracleKind::Astar => {
                    AssistingOracle::Astar(oracle::Oracle::new(config.world.grid).with_protocol(config.world.protocol))
                }
                OracleKind::Paper => AssistingOracle::Paper(oracle::CentroidWalker::new(config.world.grid)),
            }),
            watch: OscillationWatch::new(config.oscillation),
            memory,
            config,
        })
    }

    /// The agent as trained so far.
    pub fn agent(&self) -> &QAgent {
        &self.agent
    }

    /// The config.
    pub fn config(&self) -> &TrainConfig {
        &self.config
    }

    /// Totals so far.
    pub fn report(&self) -> &TrainReport {
        &self.report
    }

    /// Sets the games the run is to play in all (what a checkpoint remembers as its
    /// config's `games`); playing is still [`Trainer::play_games`]'s.
    pub fn set_games(&mut self, games: u64) {
        self.config.games = games;
    }

    /// Plays `count` more games, calling `progress` after each.
    pub fn play_games(&mut self, count: u64, mut progress: Option<&mut dyn FnMut(&Progress)>) -> Result<()> {
        let target = self.report.games + count;
        for _ in 0..count {
            self.play_counted()?;
            if let Some(report) = progress.as_deref_mut() {
                report(&self.progress(target));
            }
        }
        Ok(())
    }

    /// Plays games until `total` have been played in all (the config's games become
    /// `total`): the one run loop ([`run::run_until`]), a game a unit, with `hooks`' progress,
    /// stop and checkpoints. An error if `total` is below the games played already.
    pub fn run_until<F>(&mut self, total: u64, hooks: &mut RunHooks<'_, F>) -> Result<()>
    where
        F: FnMut(&Progress) -> Result<()>,
    {
        run::run_until(self, total, hooks)
    }

    /// Plays the next game and counts it among the recent ones.
    fn play_counted(&mut self) -> Result<()> {
        let outcome = self.play_game()?;
        self.recent.push(outcome);
        Ok(())
    }

    fn progress(&self, target: u64) -> Progress {
        let successes: Vec<u32> = self.recent.iter().flatten().copied().collect();
        Progress {
            games_played: self.report.games,
            games_target: target,
            recent: self.recent.count(Option::is_some),
            recent_mean_steps: (!successes.is_empty())
                .then(|| successes.iter().map(|&s| f64::from(s)).sum::<f64>() / successes.len() as f64),
        }
    }

    /// Plays the next game and learns from every step; the step at which the goal first
    /// held, if it did.
    fn play_game(&mut self) -> Result<Option<u32>> {
        let k = self.report.games;
        let seed = episode_seed(self.config.seed, k);
        let mut rng = policy_rng(seed);
        let schedule = self.config.schedule;
        let goals = self.config.goals.len();
        let index = if schedule.draws_goal_per_game() {
            rng.random_range(0..goals)
        } else {
            (k % goals as u64) as usize
        };
        let env = &mut self.envs[index];
        let agent = &mut self.agent;
        let mut obs = env.reset(seed);
        if self.config.exploring_starts {
            let slot = rng.random_range(0..=self.config.world.blocks);
            if slot > 0 {
                let held = obs.state.with_held(Some(BlockId::of(slot - 1)))?;
                obs = env.reset_to(held, &obs.goal)?;
            }
        }
        let QParams { alpha, epsilon, .. } = *agent.params();
        let mut key = agent.key_unchecked(&obs);
        let mut reached = None;
        let replay = self.config.backward_replay;
        let memory = &mut self.memory;
        let path = &mut self.path;
        path.clear();
        let watch = &mut self.watch;
        watch.clear();
        if let Some(AssistingOracle::Paper(walker)) = &mut self.oracle {
            walker.begin_episode();
        }
        let mut assisted = 0;
        while !env.is_over() {
            let by_oracle = match self.config.assist {
                Assist::None => false,
                Assist::Oscillation => {
                    watch.see_state(&obs);
                    watch.oscillating()
                }
                Assist::OscillationOrChance { p } => {
                    watch.see_state(&obs);
                    watch.oscillating() || rng.random_bool(p)
                }
            };
            let (action, column) = match &mut self.oracle {
                Some(oracle) if by_oracle => {
                    assisted += 1;
                    let action = match oracle {
                        AssistingOracle::Astar(o) => o.next_action(&obs.state, &obs.goal)?,
                        AssistingOracle::Paper(w) => w.next_action(&obs.state, &obs.goal, &mut rng)?,
                    };
                    (action, agent.column(&obs.goal, action)?)
                }
                _ => {
                    let column = agent.choose_column(key, agent.training_columns(&obs), epsilon, &mut rng);
                    (agent.action_of_column(&obs.goal, column), column)
                }
            };
            if self.config.assist != Assist::None {
                watch.see_action(action);
            }
            let step_number = env.steps() + 1;
            let step = env.step(action)?;
            let next_key = agent.key_unchecked(&step.observation);
            let next = (!step.terminated).then_some(next_key);
            let t = TableStep {
                key,
                column,
                reward: step.reward,
                next,
                drop: action == sim::Action::Drop,
            };
            agent.learn(&t, schedule.alpha_at(alpha, epsilon, step_number));
            if let Some(m) = memory.as_mut() {
                m.remember(key, column, step.reward, next);
            }
            if replay {
                path.push(t);
            }
            key = next_key;
            obs = step.observation.clone();
            if reached.is_none()
                && step
                    .observation
                    .goal
                    .holds_in(self.config.world.view, &step.observation.state)
            {
                reached = Some(step_number);
            }
        }
        for t in path.iter().rev() {
            agent.update_key(t.key, t.column, t.reward, t.next);
        }
        let steps = env.steps();
        self.report.games += 1;
        self.report.steps += u64::from(steps);
        self.report.successes += u64::from(reached.is_some());
        self.report.assisted_steps += assisted;
        Ok(reached)
    }

    /// Ends the run: the final replay if the config asks for it, then the agent, with the
    /// config (and the games actually played) recorded in it, and the totals.
    pub fn finish(self) -> Trained {
        let Trainer {
            mut agent,
            config,
            mut report,
            memory,
            ..
        } = self;
        if let Some(memory) = &memory {
            report.replay_sweeps = replay(&mut agent, memory);
        }
        agent.set_training(Some(TrainConfig {
            games: report.games,
            ..config
        }));
        Trained { agent, report }
    }

    /// What [`Trainer::finish`] would give now, leaving the run as it is (to evaluate the
    /// agent along a learning curve and train on).
    pub fn snapshot(&self) -> Trained {
        let mut agent = self.agent.clone();
        let mut report = self.report;
        if let Some(memory) = &self.memory {
            report.replay_sweeps = replay(&mut agent, memory);
        }
        agent.set_training(Some(TrainConfig {
            games: report.games,
            ..self.config.clone()
        }));
        Trained { agent, report }
    }
}

/// Replays `memory` into `agent` until a sweep changes no value (relative to its size, by
/// more than a millionth); the number of sweeps.
fn replay(agent: &mut QAgent, memory: &ReplayMemory) -> u32 {
    for sweep in 1..=MAX_REPLAY_SWEEPS {
        let mut changed = false;
        memory.for_each(|key, column, reward, next| {
            let old = agent.table().row(key)[column];
            let new = agent.update_key(key, column, f64::from(reward), next);
            changed |= (new - old).abs() > 1e-6 * old.abs().max(1.0);
        });
        if !changed {
            return sweep;
        }
    }
    MAX_REPLAY_SWEEPS
}

/// A game a unit: the tabular learner in the one run loop ([`run::run_until`]).
impl Runnable for Trainer {
    type Progress = Progress;
    type Error = AgentError;

    fn units_done(&self) -> u64 {
        self.report.games
    }

    fn plan_to(&mut self, total: u64) -> Result<u64> {
        let played = self.report.games;
        if total < played {
            return Err(AgentError::Config(format!(
                "{total} games in all: the run has played {played} already"
            )));
        }
        self.set_games(total);
        Ok(total)
    }

    fn next_unit(&mut self, total: u64) -> Result<Progress> {
        self.play_counted()?;
        Ok(self.progress(total))
    }

    fn write_checkpoint(&self, out: &OutputPath) -> Result<()> {
        Trainer::write_checkpoint(self, out)
    }
}

/// Trains an agent as `config` says, calling `progress` after every game.
pub fn train(config: &TrainConfig, progress: Option<&mut dyn FnMut(&Progress)>) -> Result<Trained> {
    let mut trainer = Trainer::new(config.clone())?;
    trainer.play_games(config.games, progress)?;
    Ok(trainer.finish())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_final_replay_leaves_every_remembered_value_consistent() {
        // After the replay, with alpha 1 every remembered transition satisfies the update's
        // fixed point: Q(s, a) = r + gamma max Q(s'), exactly.
        let config = TrainConfig {
            games: 300,
            ..TrainConfig::role_step_cost(vec!["1,2,0".parse().unwrap()])
        }
        .with_backend(sim::Backend::Grid);
        let mut trainer = Trainer::new(config).unwrap();
        trainer.play_games(300, None).unwrap();
        let memory = trainer.memory.clone().unwrap();
        let trained = trainer.finish();
        assert!(trained.report.replay_sweeps > 1);
        let table = trained.agent.table();
        let mut checked = 0;
        memory.for_each(|key, column, reward, next| {
            let future = next.map_or(0.0, |k| table.row(k).iter().copied().fold(f32::NEG_INFINITY, f32::max));
            assert_eq!(table.row(key)[column], reward + future);
            checked += 1;
        });
        assert!(checked > 10_000, "{checked}");
    }
}
