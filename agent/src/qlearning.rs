//! Tabular Q-learning (paper section III-B2): the agent, its hyper-parameters, and the
//! policy it plays with.
//!
//! The update is `Q(s,a) <- (1 - alpha) Q(s,a) + alpha (r + gamma max_a' Q(s',a'))`, with
//! `max_a' Q(s',a')` taken as 0 when `s'` ends the episode by reaching the goal (a
//! truncated episode's last state is not terminal: its value still counts). An agent of
//! the [`Schedule::PaperCode`] schedule updates as the authors' code did instead (the
//! [`schedule`](crate::schedule) module gives both rules).
//!
//! Actions are chosen epsilon-greedily *among the legal actions* of the observation
//! ([`Observation::legal_actions`]): with probability epsilon a uniformly random legal
//! action, otherwise a legal action of the highest value, ties broken uniformly at random
//! by the caller's seeded generator. Under the `free` protocol every action is legal and
//! the draws are the same as before protocols existed, so every seeded SPEC result is
//! unchanged.

use rand::RngExt;

use sim::seeding::SimRng;
use sim::{Action, Goal, Grid, Observation};

use crate::config::TrainConfig;
pub use crate::config::{QParams, check_epsilon, check_fits_table};
use crate::error::{AgentError, Result};
use crate::policy::Policy;
use crate::qtable::QTable;
use crate::repr::{Repr, ReprKind, Representation};
use crate::schedule::Schedule;

/// A tabular Q-learner: a representation, its table, and its hyper-parameters.
///
/// The table's columns are the representation's (for `role`, Pick columns name goal
/// places, not block ids); the methods taking an [`Observation`] and an [`Action`] speak
/// the world's terms and translate. They check that the observation belongs to the
/// agent's world (grid and block count) and return an error otherwise.
#[derive(Clone, Debug, PartialEq)]
pub struct QAgent {
    repr: Repr,
    grid: Grid,
    blocks: usize,
    params: QParams,
    table: QTable,
    training: Option<TrainConfig>,
    schedule: Schedule,
}

/// One step in table coordinates, as an update reads it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TableStep {
    /// The key of the state the action was taken in.
    pub key: u64,
    /// The action's column.
    pub column: usize,
    /// The reward.
    pub reward: f64,
    /// The next state's key; `None` when the step ended the episode by its termination rule.
    pub next: Option<u64>,
    /// The action was a Drop.
    pub drop: bool,
}

impl QAgent {
    /// An untrained agent of the `spec` schedule with representation `kind` for `blocks`
    /// blocks on `grid`, every Q-value at `params.initial_q`.
    pub fn new(kind: ReprKind, grid: Grid, blocks: usize, params: QParams) -> Result<QAgent> {
        QAgent::with_schedule(kind, grid, blocks, params, Schedule::Spec)
    }

    /// An untrained agent that updates by `schedule`'s rule (its table remembers which
    /// entries were written when the schedule reads them).
    pub fn with_schedule(
        kind: ReprKind,
        grid: Grid,
        blocks: usize,
        params: QParams,
        schedule: Schedule,
    ) -> Result<QAgent> {
        params.validate()?;
        let repr = Repr::new(kind, grid, blocks)?;
        let (keys, columns, initial) = (repr.key_count(), Action::count(blocks), params.initial_q as f32);
        let table = if schedule.tracks_seen() {
            QTable::tracking_seen(keys, columns, initial)
        } else {
            QTable::new(keys, columns, initial)
        };
        Ok(QAgent {
            repr,
            grid,
            blocks,
            params,
            table,
            training: None,
            schedule,
        })
    }

    /// Reassembles an agent from its parts (a model file's, whose table the reader has
    /// checked has the representation's shape and tracks seen entries as the schedule
    /// needs).
    pub(crate) fn from_parts(
        kind: ReprKind,
        grid: Grid,
        blocks: usize,
        params: QParams,
        table: QTable,
        training: Option<TrainConfig>,
        schedule: Schedule,
    ) -> Result<QAgent> {
        params.validate()?;
        let repr = Repr::new(kind, grid, blocks)?;
        debug_assert_eq!(
            (table.key_count(), table.columns(), table.tracks_seen()),
            (repr.key_count(), Action::count(blocks), schedule.tracks_seen())
        );
        Ok(QAgent {
            repr,
            grid,
            blocks,
            params,
            table,
            training,
            schedule,
        })
    }

    /// The schedule whose update rule the agent learns by.
    pub fn schedule(&self) -> Schedule {
        self.schedule
    }

    /// The representation.
    pub fn repr(&self) -> &Repr {
        &self.repr
    }

    /// Which representation.
    pub fn kind(&self) -> ReprKind {
        self.repr.kind()
    }

    /// The grid the agent plays on.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The number of blocks the agent plays with.
    pub fn blocks(&self) -> usize {
        self.blocks
    }

    /// The hyper-parameters.
    pub fn params(&self) -> &QParams {
        &self.params
    }

    /// Changes the hyper-parameters used by later updates (the table is kept).
    pub fn set_params(&mut self, params: QParams) -> Result<()> {
        params.validate()?;
        self.params = params;
        Ok(())
    }

    /// The table.
    pub fn table(&self) -> &QTable {
        &self.table
    }

    /// The table, to write to directly (rules beyond the Q-update, such as a large-margin
    /// correction).
    pub fn table_mut(&mut self) -> &mut QTable {
        &mut self.table
    }

    /// How the agent was trained, if it was.
    pub fn training(&self) -> Option<&TrainConfig> {
        self.training.as_ref()
    }

    /// Records how the agent was trained.
    pub fn set_training(&mut self, training: Option<TrainConfig>) {
        self.training = training;
    }

    /// A short name for reports: `q-<representation>`.
    pub fn name(&self) -> String {
        format!("q-{}", self.kind())
    }

    /// An error unless a world of `blocks` blocks on `grid` is the agent's.
    pub fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        if grid != self.grid || blocks != self.blocks {
            return Err(AgentError::ModelMismatch(format!(
                "the agent plays {} blocks on a {} grid, the world has {blocks} blocks on a {grid} grid",
                self.blocks, self.grid
            )));
        }
        Ok(())
    }

    /// An error unless `obs` belongs to the agent's world.
    fn check(&self, obs: &Observation) -> Result<()> {
        self.check_world(obs.grid, obs.state.block_count())?;
        if obs.goal.block_count() != self.blocks {
            return Err(AgentError::ModelMismatch(format!(
                "the goal {} has {} blocks, the agent plays {}",
                obs.goal,
                obs.goal.block_count(),
                self.blocks
            )));
        }
        obs.state.check_fits(self.grid)?;
        // The other representations name blocks by their place in one tower of every block.
        if !self.kind().takes_towers() {
            obs.goal.one_tower(
                "the tabular learner's representation (train with --repr role-towers for goals of towers)",
            )?;
        }
        Ok(())
    }

    /// The table key of `obs`.
    pub fn key(&self, obs: &Observation) -> Result<u64> {
        self.check(obs)?;
        Ok(self.key_unchecked(obs))
    }

    #[inline]
    pub(crate) fn key_unchecked(&self, obs: &Observation) -> u64 {
        self.repr.key(&obs.state, &obs.goal)
    }

    /// The table column of `action` under `goal`; an error for a block that does not exist.
    pub fn column(&self, goal: &Goal, action: Action) -> Result<usize> {
        if action.index() >= Action::count(self.blocks) {
            return Err(sim::SimError::ActionOutOfRange {
                index: action.index(),
                blocks: self.blocks,
            }
            .into());
        }
        Ok(self.repr.column(goal, action))
    }

    /// The world action of table column `column` under `goal`.
    #[inline]
    pub fn action_of_column(&self, goal: &Goal, column: usize) -> Action {
        self.repr.action(goal, column)
    }

    /// Q(obs, a) for every action `a`, in the world's action-index order.
    pub fn q_values(&self, obs: &Observation) -> Result<Vec<f32>> {
        let row = self.table.row(self.key(obs)?);
        Ok(Action::all(self.blocks)
            .map(|a| row[self.repr.column(&obs.goal, a)])
            .collect())
    }

    /// Q(obs, action).
    pub fn q(&self, obs: &Observation, action: Action) -> Result<f32> {
        let column = self.column(&obs.goal, action)?;
        Ok(self.table.row(self.key(obs)?)[column])
    }

    /// Sets Q(obs, action) to `value` (and marks the entry seen, for a table that tracks
    /// seen entries).
    pub fn set_q(&mut self, obs: &Observation, action: Action, value: f32) -> Result<()> {
        let column = self.column(&obs.goal, action)?;
        let key = self.key(obs)?;
        self.table.row_mut(key)[column] = value;
        self.table.mark_seen(key, column);
        Ok(())
    }

    /// The table columns of the actions legal in `obs`, as bits (bit `c`: column `c`): what
    /// the agent plays among.
    #[inline]
    pub(crate) fn legal_columns(&self, obs: &Observation) -> u32 {
        self.repr.column_mask(&obs.goal, obs.legal_actions())
    }

    /// The table columns the learner tries while training in `obs`: under the free protocol
    /// every action (in the side view the rules make one outside its mask change nothing),
    /// since its bootstrap, the best value in the next state's row, is right only over
    /// actions it tries (one never tried keeps its optimistic initial value); the legal ones
    /// otherwise. In the top view under `free` every action is legal, so the two agree.
    #[inline]
    pub(crate) fn training_columns(&self, obs: &Observation) -> u32 {
        match obs.protocol {
            sim::ActionProtocol::Free => all_columns(self.table.columns()),
            _ => self.legal_columns(obs),
        }
    }

    /// The legal action with the highest Q-value in `obs`, ties broken uniformly at random.
    pub fn greedy_action(&self, obs: &Observation, rng: &mut SimRng) -> Result<Action> {
        let key = self.key(obs)?;
        let column = self.greedy_column(key, self.legal_columns(obs), rng);
        Ok(self.repr.action(&obs.goal, column))
    }

    /// With probability `epsilon` a uniformly random legal action, otherwise the greedy
    /// legal one: the agent's proposal for `obs`.
    pub fn choose_action(&self, obs: &Observation, epsilon: f64, rng: &mut SimRng) -> Result<Action> {
        check_epsilon(epsilon)?;
        let key = self.key(obs)?;
        let column = self.choose_column(key, self.legal_columns(obs), epsilon, rng);
        Ok(self.repr.action(&obs.goal, column))
    }

    /// The Q-learning update, by the agent's schedule's rule (module docs), for `action`
    /// taken in `obs`, which gave `reward` and led to `next` (`terminated`: the step ended
    /// the episode by its termination rule: the goal, or under `paper-code` training a
    /// reward above 70). `action` may be any action, the agent's or a demonstrator's; the
    /// learning rate is the agent's alpha. Returns the new Q(obs, action).
    pub fn update(
        &mut self,
        obs: &Observation,
        action: Action,
        reward: f64,
        next: &Observation,
        terminated: bool,
    ) -> Result<f32> {
        let column = self.column(&obs.goal, action)?;
        let key = self.key(obs)?;
        let next_key = self.key(next)?;
        let step = TableStep {
            key,
            column,
            reward,
            next: (!terminated).then_some(next_key),
            drop: action == Action::Drop,
        };
        Ok(self.learn(&step, self.params.alpha))
    }

    /// The greedy column of row `key` among the columns in `legal` (bits), ties broken at
    /// random. With every column legal this is the draw the agent made before protocols
    /// existed.
    #[inline]
    pub(crate) fn greedy_column(&self, key: u64, legal: u32, rng: &mut SimRng) -> usize {
        let row = self.table.row(key);
        if legal == all_columns(row.len()) {
            return greedy_in(row, rng);
        }
        let columns = || Columns(legal).filter(|&c| c < row.len());
        let max = columns().map(|c| row[c]).fold(f32::NEG_INFINITY, f32::max);
        let ties = columns().filter(|&c| row[c] == max).count();
        match ties {
            1 => columns().find(|&c| row[c] == max).expect("the maximum is in the row"),
            // Only NaNs: nothing to prefer.
            0 => {
                let k = rng.random_range(0..columns().count());
                columns().nth(k).expect("k < the legal columns")
            }
            _ => {
                let k = rng.random_range(0..ties);
                columns().filter(|&c| row[c] == max).nth(k).expect("k < ties")
            }
        }
    }

    /// Epsilon-greedy column of row `key` among the columns in `legal` (bits).
    #[inline]
    pub(crate) fn choose_column(&self, key: u64, legal: u32, epsilon: f64, rng: &mut SimRng) -> usize {
        if epsilon > 0.0 && rng.random_bool(epsilon) {
            let n = self.table.columns();
            if legal == all_columns(n) {
                return rng.random_range(0..n);
            }
            let columns = Columns(legal).filter(|&c| c < n);
            let k = rng.random_range(0..columns.clone().count());
            columns.clone().nth(k).expect("k < the legal columns")
        } else {
            self.greedy_column(key, legal, rng)
        }
    }

    /// The update of one step by the agent's schedule, at learning rate `alpha`.
    #[inline]
    pub(crate) fn learn(&mut self, step: &TableStep, alpha: f64) -> f32 {
        match self.schedule {
            Schedule::Spec => self.update_key_at(step.key, step.column, step.reward, step.next, alpha),
            Schedule::PaperCode => self.update_as_coded(step, alpha),
        }
    }

    /// The authors' update ([`Schedule::PaperCode`]): the entry is marked seen, then moved
    /// towards `r + gamma M`, `M` the best seen value of the next state (0 if none, or after
    /// a Drop), or set to `(1 - alpha) Q + alpha r` at the step that ended the game.
    fn update_as_coded(&mut self, step: &TableStep, alpha: f64) -> f32 {
        let gamma = self.params.gamma;
        self.table.mark_seen(step.key, step.column);
        let q = f64::from(self.table.row(step.key)[step.column]);
        let value = match step.next {
            None => (1.0 - alpha) * q + alpha * step.reward,
            Some(next) => {
                let best = if step.drop {
                    0.0
                } else {
                    self.table.seen_max(next).map_or(0.0, f64::from)
                };
                q + alpha * (step.reward + gamma * best - q)
            }
        };
        let cell = &mut self.table.row_mut(step.key)[step.column];
        *cell = value as f32;
        *cell
    }

    /// The `spec` update on table coordinates at the agent's alpha; `next_key` is `None`
    /// when the next state is terminal.
    #[inline]
    pub(crate) fn update_key(&mut self, key: u64, column: usize, reward: f64, next_key: Option<u64>) -> f32 {
        self.update_key_at(key, column, reward, next_key, self.params.alpha)
    }

    /// The `spec` update at learning rate `alpha`.
    #[inline]
    fn update_key_at(&mut self, key: u64, column: usize, reward: f64, next_key: Option<u64>, alpha: f64) -> f32 {
        let gamma = self.params.gamma;
        let future = next_key.map_or(0.0, |k| {
            f64::from(self.table.row(k).iter().copied().fold(f32::NEG_INFINITY, f32::max))
        });
        let target = reward + gamma * future;
        let cell = &mut self.table.row_mut(key)[column];
        let value = if alpha == 1.0 {
            target
        } else {
            (1.0 - alpha) * f64::from(*cell) + alpha * target
        };
        *cell = value as f32;
        *cell
    }

    /// The agent as a [`Policy`] that plays epsilon-greedily with `epsilon` (the paper's
    /// test policy: 0.1) and does not learn.
    pub fn policy(&self, epsilon: f64) -> Result<QPolicy<'_>> {
        check_epsilon(epsilon)?;
        Ok(QPolicy { agent: self, epsilon })
    }
}

/// The mask of every one of `n` columns (`n` <= 32).
#[inline]
fn all_columns(n: usize) -> u32 {
    u32::MAX.checked_shr(32 - n as u32).unwrap_or(0)
}

/// The greedy column of `row`, every column legal, ties broken at random: a column of the
/// highest value, the `k`-th of `ties` equal ones for a uniform `k`.
#[inline]
fn greedy_in(row: &[f32], rng: &mut SimRng) -> usize {
    let max = row.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let ties = row.iter().filter(|&&v| v == max).count();
    match ties {
        1 => row.iter().position(|&v| v == max).expect("the maximum is in the row"),
        // Only NaNs: nothing to prefer.
        0 => rng.random_range(0..row.len()),
        _ => {
            let k = rng.random_range(0..ties);
            row.iter()
                .enumerate()
                .filter(|&(_, &v)| v == max)
                .nth(k)
                .expect("k < ties")
                .0
        }
    }
}

/// The indices of the set bits of a column mask, in increasing order.
#[derive(Clone, Copy)]
struct Columns(u32);

impl Iterator for Columns {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        (self.0 != 0).then(|| {
            let c = self.0.trailing_zeros() as usize;
            self.0 &= self.0 - 1;
            c
        })
    }
}

/// A trained agent playing without learning: epsilon-greedy over its table. Borrows the
/// agent, so many can play one agent at once (e.g. on several threads).
#[derive(Clone, Copy, Debug)]
pub struct QPolicy<'a> {
    agent: &'a QAgent,
    epsilon: f64,
}

impl QPolicy<'_> {
    /// The probability of a random action.
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }
}

impl Policy for QPolicy<'_> {
    fn name(&self) -> String {
        self.agent.name()
    }

    fn act(&mut self, obs: &Observation, rng: &mut SimRng) -> Result<Action> {
        self.agent.choose_action(obs, self.epsilon, rng)
    }
}
