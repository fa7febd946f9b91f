//! A Gymnasium-style environment over either backend.

use std::borrow::Borrow;

use serde::{Deserialize, Serialize};

use crate::action::Action;
use crate::block_move::{self, BlockMove};
use crate::error::{Result, SimError};
use crate::goal::Goal;
use crate::grid::{Cell, Grid};
use crate::grid_world::GridWorld;
use crate::observation::Observation;
use crate::physics_world::PhysicsWorld;
use crate::protocol::{ActionMask, ActionProtocol};
use crate::reward::{RewardModel, Transition};
use crate::seeding::{self, SimRng};
use crate::start::StartRule;
use crate::state::{BlockId, State};
use crate::termination::Termination;
use crate::uniform;
use crate::view::{self, View};
use crate::world::{Effect, World};

/// The least share of the Blocks World states of its blocks a side-view grid must hold: the
/// uniform start draws states until one fits (docs/world.md, "The side view at any size").
pub const MIN_SIDE_FIT: f64 = 1e-3;

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

crate::names!(Backend { Physics = "physics", Grid = "grid" } unknown(name) -> SimError {
    SimError::Parse {
        what: "backend",
        text: name.to_string(),
        reason: "choose physics or grid".into(),
    }
});

/// What a step does with an action the world's rules refuse: one a restricting action
/// protocol forbids in the current state (the paper protocol's pick while holding), or a
/// block move that cannot be carried out (onto itself, from under another block).
///
/// The library's default is [`Refusal::Error`]: a planner, a replay or a learner that takes
/// such an action has a bug, and says so. Gymnasium's contract is [`Refusal::Step`]: `step`
/// accepts every element of the action space, so random agents, environment checkers and
/// learners without masks can act; the action changes nothing, still counts as a step towards
/// the horizon, gets the world's reward for a step that changes nothing (the reward model's
/// for the action from the state to itself: under the `original` profile the authors' code's
/// -0.1 for a step that leaves the state as it was), and says so in its effect,
/// [`Effect::Refused`] (Python's `info["illegal"]`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Refusal {
    /// An error, with nothing changed and no step counted.
    #[default]
    Error,
    /// A step that changes nothing ([`Effect::Refused`]).
    Step,
}

/// Where an episode's goal comes from.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GoalSpec {
    /// The same goal every episode.
    Fixed(Goal),
    /// A goal drawn uniformly at each reset, from the reset's seeded generator.
    #[default]
    Random,
}

/// Everything that defines an environment: the world's rules and size. What an agent outside
/// the library is shown of it (`sim::ObsKind`) is that agent's choice, not the world's: a
/// config written when it still held one (`"obs"`) reads back, the entry ignored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
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
    /// Which actions are legal in a state (default `free`: all of them).
    #[serde(default)]
    pub protocol: ActionProtocol,
    /// How a reset places the blocks (default `uniform`).
    #[serde(default)]
    pub start: StartRule,
    /// What ends an episode before the horizon (default: the goal holds).
    #[serde(default)]
    pub termination: Termination,
    /// Which world (default `top`, the paper's): seen from above, or from the side with
    /// gravity and towers (docs/world.md, "The side view"). A config written before the side
    /// view existed reads back as the top view.
    #[serde(default)]
    pub view: View,
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
            protocol: ActionProtocol::default(),
            start: StartRule::default(),
            termination: Termination::default(),
            view: View::default(),
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
        self.view.check_world(self.grid, self.blocks)?;
        if self.blocks >= self.grid.cell_count() {
            return Err(SimError::TooManyBlocks {
                blocks: self.blocks,
                width: self.grid.width(),
                height: self.grid.height(),
            });
        }
        match &self.goal {
            GoalSpec::Fixed(goal) => {
                if goal.block_count() != self.blocks {
                    return Err(SimError::BlockCountMismatch {
                        expected: self.blocks,
                        what: "the goal",
                        found: goal.block_count(),
                    });
                }
                goal.check_fits(self.grid)?;
                self.reward.check_goal(goal)?;
                // A side view of one block is the exception: its goal holds in every state,
                // and an episode is over at its reset (the empty plan; docs/world.md).
                if goal.holds_everywhere_in(self.view, self.grid) && !(self.view == View::Side && self.blocks == 1) {
                    // Every start would meet it: the uniform start rule would draw forever.
                    return Err(SimError::BadGoal {
                        goal: goal.to_string(),
                        count: self.blocks,
                        reason: format!("it holds in every state of the {} view", self.view),
                    });
                }
            }
            GoalSpec::Random if self.blocks > self.grid.height() => {
                return Err(SimError::StackTooTall {
                    blocks: self.blocks,
                    height: self.grid.height(),
                });
            }
            GoalSpec::Random => {}
        }
        if self.horizon == 0 {
            return Err(SimError::ZeroHorizon);
        }
        if self.view == View::Side && self.start != StartRule::Uniform {
            return Err(SimError::SideViewStart { rule: self.start });
        }
        if self.view == View::Side {
            // The uniform start draws states until one fits the grid (`view::uniform_state`).
            let fit = uniform::fit_probability(self.blocks, self.grid.width(), self.grid.height());
            if fit < MIN_SIDE_FIT {
                return Err(SimError::SideGridTooSmall {
                    blocks: self.blocks,
                    width: self.grid.width(),
                    height: self.grid.height(),
                    default: Grid::side_default(self.blocks).to_string(),
                });
            }
        }
        self.start.check_fits(self.grid, self.blocks)
    }
}

/// Extra facts about a step, beside the observation and reward.
#[derive(Clone, Debug, PartialEq)]
pub struct Info {
    /// What the action did.
    pub effect: Effect,
    /// Whether a held block's move was stopped by a wall or a block.
    pub blocked: bool,
    /// How many of the goal's consecutive pairs stand in place.
    pub pairs_in_place: usize,
    /// Steps taken in this episode, this one included.
    pub steps: u32,
    /// The legal actions in the step's observation (the state after the step; with a
    /// [`VecEnv`](crate::VecEnv) that reset this environment, the next episode's first), as
    /// Gymnasium users read `info["action_mask"]`.
    pub action_mask: ActionMask,
    /// With a [`VecEnv`](crate::VecEnv) that reset this environment after this step: the
    /// last observation of the episode that ended (the step's `observation` is then the
    /// next episode's first). `None` otherwise.
    pub final_observation: Option<Box<Observation>>,
}

/// The result of one step, Gymnasium's five values.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    /// The observation after the action.
    pub observation: Observation,
    /// The reward of the action.
    pub reward: f64,
    /// The episode ended by its termination rule: by default, the goal holds after the
    /// action.
    pub terminated: bool,
    /// The horizon was reached without the episode terminating.
    pub truncated: bool,
    /// Extra facts.
    pub info: Info,
}

/// What one step did, without the observation it leaves: [`Env::advance`]'s result. The
/// observation and its legal actions are the environment's own after the step
/// ([`Env::current_observation`], [`Env::legal_actions`]); [`Outcome::into_step`] puts them
/// together as [`Env::step`] returns them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// The reward of the action.
    pub reward: f64,
    /// The episode ended by its termination rule.
    pub terminated: bool,
    /// The horizon was reached without the episode terminating.
    pub truncated: bool,
    /// What the action did.
    pub effect: Effect,
    /// How many of the goal's consecutive pairs stand in place after the action.
    pub pairs_in_place: usize,
    /// Steps taken in this episode, this one included.
    pub steps: u32,
}

impl Outcome {
    /// Whether a held block's move was stopped by a wall or a block (`info.blocked`).
    pub fn blocked(&self) -> bool {
        self.effect == Effect::Blocked
    }

    /// The [`Step`] of this outcome, whose observation is `observation` with legal actions
    /// `action_mask` (no final observation).
    pub fn into_step(self, observation: Observation, action_mask: ActionMask) -> Step {
        Step {
            observation,
            reward: self.reward,
            terminated: self.terminated,
            truncated: self.truncated,
            info: Info {
                effect: self.effect,
                blocked: self.blocked(),
                pairs_in_place: self.pairs_in_place,
                steps: self.steps,
                action_mask,
                final_observation: None,
            },
        }
    }
}

/// The result of a block move ([`Env::step_block_move`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MoveStep {
    /// The last gripper step the move took (its Drop, unless the episode ended first), with
    /// the reward of the whole move: the sum of its gripper steps' rewards, as a
    /// macro-action's reward is.
    pub step: Step,
    /// How many gripper steps the move took.
    pub gripper_steps: u32,
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
///
/// The config's [`ActionProtocol`] decides which actions are legal ([`Env::legal_actions`],
/// `info.action_mask`); under a restricting protocol an illegal action is an error that
/// changes nothing, or a step that changes nothing under [`Refusal::Step`]
/// ([`Env::with_refusal`]). Its [`StartRule`] places the blocks at each reset, and its
/// [`Termination`] decides which step ends an episode.
#[derive(Clone)]
pub struct Env {
    config: EnvConfig,
    world: AnyWorld,
    /// The current observation: the world's state as read back after its last change, and
    /// the episode's goal. Every change goes through `Env`, so a step reads the physics
    /// world's bodies once (after its action) instead of also before it and in
    /// [`Env::check_action`]; and a batched step writes its results from this one copy
    /// instead of an owned [`Step`] per environment, the top of its profile once
    /// (docs/performance.md).
    now: Observation,
    rng: SimRng,
    steps: u32,
    phase: Phase,
    previous_action: Option<Action>,
    /// The protocol's legal actions with nothing held (`[0]`) and with a block held
    /// (`[1]`): a protocol looks at nothing else, so a step looks its masks up.
    legal: [ActionMask; 2],
    /// What a step does with an action the world's rules refuse.
    refusal: Refusal,
}

impl Env {
    /// An environment for `config`; an error naming what is wrong with the config.
    /// Call [`Env::reset`] before the first step.
    pub fn new(config: EnvConfig) -> Result<Env> {
        config.validate()?;
        let grid = config.grid;
        let goal = match &config.goal {
            GoalSpec::Fixed(g) => g.clone(),
            GoalSpec::Random => Goal::identity(config.blocks)?,
        };
        // A placeholder start on the bottom rows (standing, for the side view); `reset`
        // replaces it.
        let cells: Vec<Cell> = (0..config.blocks).map(|i| grid.cell_at(i)).collect();
        let start = State::new(&cells, None)?;
        let view = config.view;
        let world = match config.backend {
            Backend::Grid => AnyWorld::Grid(GridWorld::new_in(view, grid, start)?),
            Backend::Physics => AnyWorld::Physics(Box::new(PhysicsWorld::new_in(view, grid, start)?)),
        };
        let legal = [
            config.protocol.legal_when(None, config.blocks),
            config.protocol.legal_when(Some(BlockId(0)), config.blocks),
        ];
        let now = Observation {
            grid,
            state: world.world().state(),
            goal,
            protocol: config.protocol,
            view,
        };
        Ok(Env {
            config,
            world,
            now,
            rng: seeding::rng(0),
            steps: 0,
            phase: Phase::NotReset,
            previous_action: None,
            legal,
            refusal: Refusal::Error,
        })
    }

    /// This environment, doing with an action the world's rules refuse what `refusal` says
    /// ([`Refusal`]; [`Refusal::Error`] unless set).
    pub fn with_refusal(mut self, refusal: Refusal) -> Env {
        self.refusal = refusal;
        self
    }

    /// What a step does with an action the world's rules refuse.
    pub fn refusal(&self) -> Refusal {
        self.refusal
    }

    /// Starts an episode: draws the goal (if the config says so), then a start by the
    /// config's [`StartRule`] (by default one in which the goal does not hold), both from the
    /// generator, re-seeded first when `seed` is given.
    pub fn reset(&mut self, seed: impl Into<Option<u64>>) -> Observation {
        if let Some(seed) = seed.into() {
            self.rng = seeding::rng(seed);
        }
        if let GoalSpec::Random = self.config.goal {
            self.now.goal = Goal::random(self.config.blocks, &mut self.rng).expect("the config was validated");
        }
        let start = self
            .config
            .start
            .draw_in(self.config.view, self.config.grid, &self.now.goal, &mut self.rng);
        // Drawn for this world's grid and block count: it fits without a check.
        self.world.world_mut().put(&start);
        self.begin(&start, self.config.start.keeps_goal_starts())
    }

    /// Starts an episode from a given state and goal (for planners, tests, and experiments
    /// that replay recorded starts); the state may hold a block. An error if either does not
    /// fit the world. Under [`Termination::Goal`] a state in which the goal holds starts an
    /// episode that is already over.
    /// The state and goal are taken by value or by reference.
    pub fn reset_to(&mut self, state: impl Borrow<State>, goal: impl Borrow<Goal>) -> Result<Observation> {
        let (state, goal) = (state.borrow(), goal.borrow());
        if goal.block_count() != self.config.blocks {
            return Err(SimError::BlockCountMismatch {
                expected: self.config.blocks,
                what: "the goal",
                found: goal.block_count(),
            });
        }
        goal.check_fits(self.config.grid)?;
        self.config.reward.check_goal(goal)?;
        self.world.world_mut().place(state)?;
        self.now.goal = goal.clone();
        Ok(self.begin(state, false))
    }

    /// Starts the episode whose start the world already shows. Under
    /// [`Termination::Goal`], a start meeting the goal is over at once unless
    /// `keeps_goal_start` (then its first step ends it).
    fn begin(&mut self, start: &State, keeps_goal_start: bool) -> Observation {
        self.now.state = self.world.world().state();
        self.steps = 0;
        self.previous_action = None;
        let over = matches!(self.config.termination, Termination::Goal)
            && !keeps_goal_start
            && self.now.goal.holds_in(self.config.view, start);
        self.phase = if over { Phase::Over } else { Phase::Running };
        self.observation()
    }

    /// Takes one action. An error, with nothing changed (no step counted), if the episode
    /// has not started or has ended, if the action names a block that does not exist, or if
    /// the config's action protocol forbids it in the current state
    /// ([`SimError::IllegalAction`]; under [`Refusal::Step`] that is a step that changes
    /// nothing instead).
    pub fn step(&mut self, action: Action) -> Result<Step> {
        let outcome = self.advance(action)?;
        Ok(outcome.into_step(self.observation(), self.legal_actions()))
    }

    /// Takes one action as [`Env::step`] does (the same errors, the same episode), but
    /// returns only what the step did: its observation is [`Env::current_observation`] and
    /// its legal actions [`Env::legal_actions`], read in place. A caller that copies them
    /// into its own buffers ([`VecEnv::step_chunks`](crate::VecEnv::step_chunks)) builds no
    /// owned [`Step`].
    pub fn advance(&mut self, action: Action) -> Result<Outcome> {
        self.check_running()?;
        // Under `free` every action that exists is legal, and `act` refuses one that does
        // not before changing anything: the SPEC world's step pays for no check. In the side
        // view too the world's rules make an action outside the mask a no-op.
        if !matches!(self.config.protocol, ActionProtocol::Free)
            && let Err(e) = self.check_legal(&self.now.state, action)
        {
            return match self.refusal {
                Refusal::Step if e.is_refusal() => Ok(self.refuse(action)),
                _ => Err(e),
            };
        }
        self.advance_checked(action)
    }

    /// The step that changes nothing ([`Refusal::Step`]): counted, with the reward of
    /// `action` from the current state to itself and the episode's end rules.
    fn refuse(&mut self, action: Action) -> Outcome {
        self.steps += 1;
        let (now, config) = (&self.now, &self.config);
        let transition = Transition {
            grid: config.grid,
            view: config.view,
            goal: &now.goal,
            before: &now.state,
            action,
            previous_action: self.previous_action,
            after: &now.state,
        };
        let reward = config.reward.reward(&transition);
        let pairs_in_place = now.goal.pairs_in_place(&now.state);
        // A running episode's goal does not hold, and nothing changed: only a termination
        // by reward can end it here.
        let terminated = config.termination.ends(reward, false);
        let truncated = !terminated && self.steps >= config.horizon;
        self.previous_action = Some(action);
        if terminated || truncated {
            self.phase = Phase::Over;
        }
        Outcome {
            reward,
            terminated,
            truncated,
            effect: Effect::Refused,
            pairs_in_place,
            steps: self.steps,
        }
    }

    /// [`Env::advance`] for an action [`Env::check_action`] has accepted in the current
    /// state: a [`VecEnv`](crate::VecEnv) checks a whole batch before it steps any of it,
    /// and does not pay for the check twice.
    pub(crate) fn advance_checked(&mut self, action: Action) -> Result<Outcome> {
        let effect = self.world.world_mut().act(action)?;
        let before = self.now.state.clone();
        self.world.world().read_back(&mut self.now.state, effect);
        self.steps += 1;
        let (now, config) = (&self.now, &self.config);
        let after = &now.state;
        let transition = Transition {
            grid: config.grid,
            view: config.view,
            goal: &now.goal,
            before: &before,
            action,
            previous_action: self.previous_action,
            after,
        };
        let reward = config.reward.reward(&transition);
        let pairs_in_place = now.goal.pairs_in_place(after);
        let goal_holds = match config.view {
            View::Top => pairs_in_place == now.goal.pair_count(),
            View::Side => now.goal.holds_in(View::Side, after),
        };
        let terminated = config.termination.ends(reward, goal_holds);
        let truncated = !terminated && self.steps >= config.horizon;
        self.previous_action = Some(action);
        if terminated || truncated {
            self.phase = Phase::Over;
        }
        Ok(Outcome {
            reward,
            terminated,
            truncated,
            effect,
            pairs_in_place,
            steps: self.steps,
        })
    }

    /// Carries out the block move `mv` (side view only) as the gripper actions
    /// [`block_move::expand`] gives, each one a step of the episode. An error, with nothing
    /// changed, if the episode is not running or the move cannot be carried out now. The
    /// episode may end before the move's last action (at the horizon); the result says how
    /// many gripper steps were taken and holds the last one, rewarded with the sum of their
    /// rewards.
    ///
    /// The physics backend carries out every gripper action through rapier. The grid
    /// backend, when the episode ends only at the goal, the move ends before the horizon and
    /// the reward model pays the steps before the Drop a known amount (`sparse`: nothing;
    /// `step-cost`: its cost each), carries the block straight to the cell the Drop releases
    /// it from and takes the Drop as an ordinary step: the same world, step count, last step
    /// and reward as every action one by one (none of the actions before the Drop can end the
    /// episode: the goal cannot hold while a block it names is held, nor start to hold while
    /// a block it leaves free moves), at O(N + W) for the whole move instead of O(N) for each
    /// of its gripper steps.
    pub fn step_block_move(&mut self, mv: BlockMove) -> Result<MoveStep> {
        if self.config.view != View::Side {
            return Err(SimError::MovesNeedSideView);
        }
        self.check_running()?;
        if self.refusal == Refusal::Step && block_move::route(&self.now.state, self.config.grid, mv).is_err() {
            // One step that changes nothing, rewarded as a drop with nothing held (between
            // moves nothing is held).
            let outcome = self.refuse(Action::Drop);
            return Ok(MoveStep {
                step: outcome.into_step(self.observation(), self.legal_actions()),
                gripper_steps: 1,
            });
        }
        let (termination, horizon, steps) = (self.config.termination, self.config.horizon, self.steps);
        // What the reward model pays each step before the Drop, when it is known without
        // taking them: the goal cannot hold while a block is carried.
        let carried = match self.config.reward {
            RewardModel::Sparse(_) => Some(0.0),
            RewardModel::StepCost(c) => Some(c.cost),
            _ => None,
        };
        if let (AnyWorld::Grid(world), Some(carried)) = (&mut self.world, carried) {
            let carry = block_move::route_in(world, mv)?;
            let len = carry.len() as u32;
            if matches!(termination, Termination::Goal) && steps + len <= horizon {
                world.act(Action::Pick(carry.block))?;
                world.carry_held(carry.release_cell());
                self.now.state = world.state();
                self.steps += len - 1;
                self.previous_action = Some(carry.across());
                let mut step = self.step(Action::Drop)?;
                step.reward += carried * f64::from(len - 1);
                return Ok(MoveStep {
                    step,
                    gripper_steps: len,
                });
            }
        }
        let actions = block_move::expand(&self.now.state, self.config.grid, mv)?;
        let mut last = None;
        let mut reward = 0.0;
        for (k, &action) in actions.iter().enumerate() {
            let step = self.step(action)?;
            reward += step.reward;
            let over = step.terminated || step.truncated;
            last = Some((step, k + 1));
            if over {
                break;
            }
        }
        let (mut step, taken) = last.expect("a move has at least a pick and a drop");
        step.reward = reward;
        Ok(MoveStep {
            step,
            gripper_steps: taken as u32,
        })
    }

    /// The block moves legal now, by index ([`block_move::legal_moves`]); all `false` in
    /// the top view.
    pub fn legal_moves(&self) -> Vec<bool> {
        let n = self.config.blocks;
        match self.config.view {
            View::Top => vec![false; BlockMove::count(n, self.config.grid)],
            View::Side => block_move::legal_moves(&self.now.state, self.config.grid),
        }
    }

    /// `Ok` if [`Env::step`] would take `action` now; otherwise the error it would return
    /// (episode not started or over, no such block, illegal under the action protocol;
    /// under [`Refusal::Step`] an illegal action is taken, as a step that changes nothing).
    pub fn check_action(&self, action: Action) -> Result<()> {
        self.check_running()?;
        match self.check_legal(&self.now.state, action) {
            Err(e) if self.refusal == Refusal::Step && e.is_refusal() => Ok(()),
            checked => checked,
        }
    }

    /// An error unless an episode is running.
    #[inline]
    fn check_running(&self) -> Result<()> {
        match self.phase {
            Phase::NotReset => Err(SimError::NotReset),
            Phase::Over => Err(SimError::EpisodeOver),
            Phase::Running => Ok(()),
        }
    }

    /// An error unless `action` exists and the protocol allows it in `state`: under `free`
    /// every action that exists, in either view; under a restricting protocol in the side
    /// view, the side view's mask.
    #[inline]
    fn check_legal(&self, state: &State, action: Action) -> Result<()> {
        let free = matches!(self.config.protocol, ActionProtocol::Free);
        let legal = if free {
            self.legal[usize::from(state.held_block().is_some())].contains(action)
        } else {
            self.legal_in(state).contains(action)
        };
        if legal {
            Ok(())
        } else if free {
            // Only a pick of a block that does not exist.
            self.config.protocol.check(state, action)
        } else {
            // The rules name what is wrong: no such block, or an illegal action.
            self.config.view.check(self.config.protocol, state, action)
        }
    }

    /// The legal actions in `state`: in the top view the protocol's, which look only at
    /// whether a block is held; in the side view the side view's rules.
    #[inline]
    fn legal_in(&self, state: &State) -> ActionMask {
        match self.config.view {
            View::Top => self.legal[usize::from(state.held_block().is_some())].clone(),
            View::Side => match &self.world {
                // The column heights answer which blocks are clear in O(N).
                AnyWorld::Grid(world) => world.side_mask(),
                AnyWorld::Physics(_) => view::side_mask(state),
            },
        }
    }

    /// Takes the action with index `index` (docs/world.md section 2's table); an error for an index
    /// out of range.
    pub fn step_index(&mut self, index: usize) -> Result<Step> {
        self.step(Action::from_index(index, self.config.blocks)?)
    }

    /// The current observation.
    pub fn observation(&self) -> Observation {
        self.now.clone()
    }

    /// The current observation, borrowed: what [`Env::observation`] copies.
    pub fn current_observation(&self) -> &Observation {
        &self.now
    }

    /// The legal actions in the current state, by the config's action protocol (in the side
    /// view, by its rules).
    pub fn legal_actions(&self) -> ActionMask {
        self.legal_in(&self.now.state)
    }

    /// The current state, as read back from the backend after its last change.
    pub fn state(&self) -> State {
        self.now.state.clone()
    }

    /// The current goal.
    pub fn goal(&self) -> &Goal {
        &self.now.goal
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
