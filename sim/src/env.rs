//! A Gymnasium-style environment over either backend.

use std::fmt;

use rand::RngExt;
use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::error::{Result, SimError};
use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::grid_world::GridWorld;
use crate::observation::Observation;
use crate::physics_world::PhysicsWorld;
use crate::reward::{RewardModel, Transition};
use crate::seeding::{self, SimRng};
use crate::state::{BlockId, MAX_BLOCKS, MIN_BLOCKS, State};
use crate::world::{Effect, World};

/// The default episode length limit.
pub const DEFAULT_HORIZON: u32 = 1000;

/// Which world model carries out the actions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Backend {
    /// rapier2d bodies and shape casts: the real world.
    #[default]
    Physics,
    /// The pure occupancy grid: the same rules, much faster.
    Grid,
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Backend::Physics => "physics",
            Backend::Grid => "grid",
        })
    }
}

impl std::str::FromStr for Backend {
    type Err = SimError;

    fn from_str(s: &str) -> Result<Backend> {
        match s {
            "physics" => Ok(Backend::Physics),
            "grid" => Ok(Backend::Grid),
            _ => Err(SimError::Parse {
                what: "backend",
                text: s.into(),
                reason: "choose physics or grid".into(),
            }),
        }
    }
}

/// Where an episode's goal comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GoalSpec {
    /// The same goal every episode.
    Fixed(Goal),
    /// A goal drawn uniformly at each reset, from the reset's seeded generator.
    #[default]
    Random,
}

/// Everything that defines an environment.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EnvConfig {
    /// The grid (default 7 x 7).
    pub grid: Grid,
    /// Number of blocks (default 3).
    pub blocks: usize,
    /// The goal, given or drawn (default drawn).
    pub goal: GoalSpec,
    /// Steps before an episode is truncated (default 1000).
    pub horizon: u32,
    /// The reward model (default `sparse`).
    pub reward: RewardModel,
    /// The backend (default physics).
    pub backend: Backend,
}

impl Default for EnvConfig {
    fn default() -> Self {
        Self {
            grid: Grid::default(),
            blocks: 3,
            goal: GoalSpec::Random,
            horizon: DEFAULT_HORIZON,
            reward: RewardModel::default(),
            backend: Backend::Physics,
        }
    }
}

impl EnvConfig {
    /// The default config with `blocks` blocks and a fixed `goal`.
    pub fn with_goal(goal: Goal) -> Self {
        Self {
            blocks: goal.block_count(),
            goal: GoalSpec::Fixed(goal),
            ..Self::default()
        }
    }

    /// An error naming the first thing in this config that cannot make a world.
    pub fn validate(&self) -> Result<()> {
        if !(MIN_BLOCKS..=MAX_BLOCKS).contains(&self.blocks) {
            return Err(SimError::BadBlockCount {
                count: self.blocks,
                min: MIN_BLOCKS,
                max: MAX_BLOCKS,
            });
        }
        if self.blocks >= self.grid.cell_count() {
            return Err(SimError::TooManyBlocks {
                blocks: self.blocks,
                width: self.grid.width(),
                height: self.grid.height(),
            });
        }
        if self.blocks > self.grid.height() {
            return Err(SimError::StackTooTall {
                blocks: self.blocks,
                height: self.grid.height(),
            });
        }
        if let GoalSpec::Fixed(goal) = self.goal {
            if goal.block_count() != self.blocks {
                return Err(SimError::BlockCountMismatch {
                    expected: self.blocks,
                    what: "the goal",
                    found: goal.block_count(),
                });
            }
        }
        if self.horizon == 0 {
            return Err(SimError::ZeroHorizon);
        }
        Ok(())
    }
}

/// Extra facts about a step, beside the observation and reward.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Info {
    /// What the action did.
    pub effect: Effect,
    /// Whether a held block's move was stopped by a wall or a block.
    pub blocked: bool,
    /// How many of the goal's consecutive pairs stand in place.
    pub pairs_in_place: usize,
    /// Steps taken in this episode, this one included.
    pub steps: u32,
    /// With a [`VecEnv`](crate::VecEnv) that reset this environment after this step: the
    /// last observation of the episode that ended (the step's `observation` is then the
    /// next episode's first). `None` otherwise.
    pub final_observation: Option<Observation>,
}

/// The result of one step, Gymnasium's five values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// The observation after the action.
    pub observation: Observation,
    /// The reward of the action.
    pub reward: f64,
    /// The goal holds after the action.
    pub terminated: bool,
    /// The horizon was reached without the goal.
    pub truncated: bool,
    /// Extra facts.
    pub info: Info,
}

/// Either backend, chosen at run time.
#[derive(Clone)]
enum AnyWorld {
    Grid(GridWorld),
    Physics(Box<PhysicsWorld>),
}

impl AnyWorld {
    fn world(&self) -> &dyn World {
        match self {
            AnyWorld::Grid(w) => w,
            AnyWorld::Physics(w) => w.as_ref(),
        }
    }

    fn world_mut(&mut self) -> &mut dyn World {
        match self {
            AnyWorld::Grid(w) => w,
            AnyWorld::Physics(w) => w.as_mut(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    NotReset,
    Running,
    Over,
}

/// A Gymnasium-style environment: `reset` then `step` until terminated or truncated.
///
/// Seeding follows Gymnasium: `reset(seed)` re-seeds the environment's generator, and
/// `reset(None)` continues from where it was (from seed 0 if it was never seeded), so a
/// sequence of episodes is fixed by the first seed.
#[derive(Clone)]
pub struct Env {
    config: EnvConfig,
    world: AnyWorld,
    rng: SimRng,
    goal: Goal,
    steps: u32,
    phase: Phase,
    previous_action: Option<Action>,
}

impl Env {
    /// An environment for `config`; an error naming what is wrong with the config.
    /// Call [`Env::reset`] before the first step.
    pub fn new(config: EnvConfig) -> Result<Env> {
        config.validate()?;
        let grid = config.grid;
        let goal = match config.goal {
            GoalSpec::Fixed(g) => g,
            GoalSpec::Random => Goal::identity(config.blocks)?,
        };
        // A placeholder start on the bottom rows; `reset` replaces it.
        let cells: Vec<Cell> = (0..config.blocks).map(|i| grid.cell_at(i)).collect();
        let start = State::new(&cells, None)?;
        let world = match config.backend {
            Backend::Grid => AnyWorld::Grid(GridWorld::new(grid, start)?),
            Backend::Physics => AnyWorld::Physics(Box::new(PhysicsWorld::new(grid, start)?)),
        };
        Ok(Env {
            config,
            world,
            rng: seeding::rng(0),
            goal,
            steps: 0,
            phase: Phase::NotReset,
            previous_action: None,
        })
    }

    /// Starts an episode: draws the goal (if the config says so) and a start state in which
    /// the goal does not hold, both from the generator, re-seeded first when `seed` is given.
    pub fn reset(&mut self, seed: impl Into<Option<u64>>) -> Observation {
        if let Some(seed) = seed.into() {
            self.rng = seeding::rng(seed);
        }
        if let GoalSpec::Random = self.config.goal {
            self.goal = Goal::random(self.config.blocks, &mut self.rng).expect("the config was validated");
        }
        let start = random_start(self.config.grid, &self.goal, &mut self.rng);
        // Drawn for this world's grid and block count: it fits without a check.
        self.world.world_mut().put(&start);
        self.begin(start)
    }

    /// Starts an episode from a given state and goal (for planners, tests, and experiments
    /// that replay recorded starts); the state may hold a block. An error if either does not
    /// fit the world.
    pub fn reset_to(&mut self, state: State, goal: Goal) -> Result<Observation> {
        if goal.block_count() != self.config.blocks {
            return Err(SimError::BlockCountMismatch {
                expected: self.config.blocks,
                what: "the goal",
                found: goal.block_count(),
            });
        }
        self.world.world_mut().place(&state)?;
        self.goal = goal;
        Ok(self.begin(state))
    }

    /// Starts the episode whose start the world already shows.
    fn begin(&mut self, start: State) -> Observation {
        self.steps = 0;
        self.previous_action = None;
        self.phase = if self.goal.holds(&start) {
            Phase::Over
        } else {
            Phase::Running
        };
        self.observation()
    }

    /// Takes one action. An error if the episode has not started or has ended, or if the
    /// action names a block that does not exist.
    pub fn step(&mut self, action: Action) -> Result<Step> {
        match self.phase {
            Phase::NotReset => return Err(SimError::NotReset),
            Phase::Over => return Err(SimError::EpisodeOver),
            Phase::Running => {}
        }
        let before = self.world.world().state();
        let effect = self.world.world_mut().act(action)?;
        let after = self.world.world().state();
        self.steps += 1;
        let transition = Transition {
            grid: self.config.grid,
            goal: &self.goal,
            before: &before,
            action,
            previous_action: self.previous_action,
            after: &after,
        };
        let reward = self.config.reward.reward(&transition);
        let terminated = self.goal.holds(&after);
        let truncated = !terminated && self.steps >= self.config.horizon;
        self.previous_action = Some(action);
        if terminated || truncated {
            self.phase = Phase::Over;
        }
        Ok(Step {
            observation: Observation {
                grid: self.config.grid,
                state: after,
                goal: self.goal,
            },
            reward,
            terminated,
            truncated,
            info: Info {
                effect,
                blocked: effect == Effect::Blocked,
                pairs_in_place: self.goal.pairs_in_place(&after),
                steps: self.steps,
                final_observation: None,
            },
        })
    }

    /// Takes the action with index `index` (SPEC section 2's table); an error for an index
    /// out of range.
    pub fn step_index(&mut self, index: usize) -> Result<Step> {
        self.step(Action::from_index(index, self.config.blocks)?)
    }

    /// The current observation.
    pub fn observation(&self) -> Observation {
        Observation {
            grid: self.config.grid,
            state: self.state(),
            goal: self.goal,
        }
    }

    /// The current state, read back from the backend.
    pub fn state(&self) -> State {
        self.world.world().state()
    }

    /// The current goal.
    pub fn goal(&self) -> Goal {
        self.goal
    }

    /// The configuration.
    pub fn config(&self) -> &EnvConfig {
        &self.config
    }

    /// Steps taken in the current episode.
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// Whether the current episode has ended (or none has started).
    pub fn is_over(&self) -> bool {
        self.phase != Phase::Running
    }

    /// Number of actions, `5 + N`.
    pub fn action_count(&self) -> usize {
        Action::count(self.config.blocks)
    }

    /// The block held now, if any.
    pub fn held_block(&self) -> Option<BlockId> {
        self.world.world().held_block()
    }
}

/// Blocks on distinct cells drawn uniformly, nothing held, the goal not holding.
fn random_start(grid: Grid, goal: &Goal, rng: &mut SimRng) -> State {
    let n = goal.block_count();
    let mut cells = [Cell::default(); MAX_BLOCKS];
    loop {
        let mut k = 0;
        while k < n {
            let c = grid.cell_at(rng.random_range(0..grid.cell_count()));
            if !cells[..k].contains(&c) {
                cells[k] = c;
                k += 1;
            }
        }
        let state = State::new(&cells[..n], None).expect("distinct cells");
        if !goal.holds(&state) {
            return state;
        }
    }
}
