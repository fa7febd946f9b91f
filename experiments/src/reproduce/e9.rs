//! E9 (ours, issue 17): the classic Blocks World, seen from the side (docs/world.md section
//! 12), where planning and learning research measures itself: for 3 to 10 blocks and random
//! goals of one to three towers, the fewest block moves (A*), the near-optimal planner, and
//! how the planners' moves come out as gripper steps when the gripper carries them out
//! through the physics; reported by the number of stacking steps, as Duan et al. ("One-Shot
//! Imitation Learning", 2017) report their success; and how often the physics backend and
//! the grid model agreed.
//!
//! # How a problem is drawn
//!
//! Problem `j` of `N` blocks and `k` towers has the seed `episode_seed(episode_seed(test
//! seed, 1000 N + k), j)`: its goal is `Goal::random_towers(N, k)` drawn from that seed's
//! generator on a stream of its own, its start the side view's `reset(seed)` (random towers
//! in which the goal does not hold). So the quick run's problems are the first of the
//! default run's, and a cell's problems do not depend on how many the other cells have.
//!
//! # The grid
//!
//! The classic world's table is unbounded. Ours is as wide as the grid, so the grid has at
//! least as many columns as blocks (the table never runs out: the planners plan exactly as
//! on an unbounded table) and a row more than blocks (a tower of every block, and a row to
//! carry a block over it): the paper's 7 x 7 up to 6 blocks, `N x (N + 1)` beyond.
//!
//! # The stacking steps
//!
//! Duan et al. group their tasks by the number of stacking steps a task takes; ours are the
//! fewest block moves from the start (each move stacks one block on another or on the
//! table), the exact planner's count.

use agent::{EpisodeObserver, Policy, QAgent, RandomPolicy, TowersPolicy, TrainConfig, TrainOverrides};
use oracle::towers::{MovePlanner, plan_side};
use rayon::prelude::*;
use serde::Serialize;
use sim::seeding::{self, episode_seed};
use sim::{Action, Backend, Env, EnvConfig, Goal, GoalSpec, Grid, Observation, State, Step, View};

use super::Budget;
use super::Findings;
use super::shared::Shared;
use super::text::num;
use super::{Context, Drawing, Experiment, Figure, HORIZON, Result, Setting};
use plots::{CurvesChart, Series};

/// The numbers of blocks, as the issue lists them.
pub const BLOCKS: [usize; 6] = [3, 4, 5, 6, 8, 10];

/// Goals have one to this many towers.
pub const MAX_TOWERS: usize = 3;

/// The progress stage E9 reports under.
const STAGE: &str = "E9";

/// Problems per number of blocks and of towers.
fn problems_per_cell(budget: Budget) -> u64 {
    match budget {
        Budget::Quick => 2,
        Budget::Default => 200,
        Budget::Long => 1000,
    }
}

/// Random steps per number of blocks in the agreement table.
fn agreement_steps(budget: Budget) -> u64 {
    match budget {
        Budget::Quick => 1_000,
        Budget::Default => 50_000,
        Budget::Long => 1_000_000,
    }
}

/// The horizon of the agreement table's random episodes: short, so that it plays many starts.
const AGREEMENT_HORIZON: u32 = 200;

/// The grid of `blocks` blocks (module docs).
pub fn grid_for(blocks: usize) -> Grid {
    let (width, height) = (blocks.max(7), (blocks + 1).max(7));
    Grid::new(width, height).expect("at most 10 x 11 cells")
}

/// The learner plays the problems of this many blocks: it trains on every goal of them (the
/// role representation's table grows fast with the blocks: on 4 blocks its preset's 5,000
/// games take a minute here and reach few goals).
pub const LEARNER_BLOCKS: usize = 3;

/// The fewest gripper steps are searched for problems of up to this many blocks (the exact
/// solver of the side view is meant for up to 4).
pub const FEWEST_STEPS_BLOCKS: usize = 4;

/// Training games of the learner: its preset's, or few in a quick run (a check of the
/// pipeline).
fn learner_games(budget: Budget, preset: u64) -> u64 {
    match budget {
        Budget::Quick => preset.min(1000),
        Budget::Default | Budget::Long => preset,
    }
}

/// The agents that play the problems through the gripper, in the tables' order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Agent {
    /// The exact block-move planner's moves, carried out by the gripper.
    Exact,
    /// The near-optimal planner's moves, carried out by the gripper.
    NearOptimal,
    /// The tabular learner of the side view, greedy.
    Learner,
}

const AGENTS: [Agent; 3] = [Agent::Exact, Agent::NearOptimal, Agent::Learner];

impl Agent {
    fn name(self) -> &'static str {
        match self {
            Agent::Exact => "exact planner",
            Agent::NearOptimal => "near-optimal planner",
            Agent::Learner => "learner",
        }
    }

    /// Whether the agent plays problems of `blocks` blocks.
    fn plays(self, blocks: usize) -> bool {
        self != Agent::Learner || blocks == LEARNER_BLOCKS
    }

    /// The agent's policy; the learner's is `learner`'s, greedy.
    fn policy(self, learner: &QAgent) -> Result<Box<dyn Policy + '_>> {
        Ok(match self {
            Agent::Exact => Box::new(TowersPolicy::new(MovePlanner::Exact)),
            Agent::NearOptimal => Box::new(TowersPolicy::new(MovePlanner::NearOptimal)),
            Agent::Learner => Box::new(learner.policy(0.0)?),
        })
    }
}

/// The learner's training: the side view's preset (`blockstack train --view side`: the
/// role-towers representation, the step-cost reward, every goal of towers of
/// [`LEARNER_BLOCKS`] blocks), our learner's seed.
fn learner_config(ctx: &Context) -> Result<TrainConfig> {
    let preset = TrainConfig::resolve(&TrainOverrides {
        view: Some(View::Side),
        blocks: Some(LEARNER_BLOCKS),
        grid: Some(grid_for(LEARNER_BLOCKS)),
        seed: Some(ctx.seeds.ours),
        ..TrainOverrides::default()
    })?;
    Ok(TrainConfig {
        games: learner_games(ctx.budget, preset.games),
        ..preset
    })
}

/// How an agent's game of a problem went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Played {
    /// The goal was reached before the horizon.
    pub reached_goal: bool,
    /// Gripper steps taken.
    pub steps: u32,
    /// Block moves taken: the Drops.
    pub moves: u32,
    /// The game ended, failed, at a Drop the physics did not bring to rest on a cell
    /// ([`sim::SimError::NotAtRest`]).
    pub physics_error: bool,
}

/// One (start, goal) problem and how it was solved.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Blocks.
    pub blocks: usize,
    /// Towers of the goal.
    pub towers: usize,
    /// The problem's seed (module docs).
    pub seed: u64,
    /// The goal.
    pub goal: Goal,
    /// The start.
    pub start: State,
    /// The fewest block moves (the exact planner's plan): the problem's stacking steps.
    pub fewest_moves: u32,
    /// The near-optimal planner's plan from the start, in block moves.
    pub near_optimal_moves: u32,
    /// The fewest gripper steps, where computed.
    pub fewest_steps: Option<u32>,
    /// Each agent's game, in the agents' order (`None`: it does not play this many blocks).
    pub played: Vec<Option<Played>>,
}

/// An agent's figures over a group of problems.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AgentFigures {
    /// The agent.
    pub agent: String,
    /// Games played.
    pub games: usize,
    /// Share of the games that reached the goal.
    pub success: f64,
    /// Mean block moves over the successes.
    pub mean_moves: Option<f64>,
    /// Mean ratio of the block moves to the fewest, over the successes.
    pub moves_ratio: Option<f64>,
    /// Mean gripper steps over the successes.
    pub mean_steps: Option<f64>,
    /// Mean ratio of the gripper steps to the fewest, over the successes whose fewest is
    /// known.
    pub steps_ratio: Option<f64>,
    /// Games ended, failed, by a Drop the physics did not bring to rest on a cell.
    pub physics_errors: usize,
}

/// The figures of a group of problems: all those of a number of blocks, of a number of
/// goal towers, or of a number of stacking steps.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Group {
    /// The number of blocks, towers or stacking steps the group shares.
    pub key: usize,
    /// Problems in the group.
    pub problems: usize,
    /// Mean fewest block moves.
    pub fewest_moves: f64,
    /// Mean block moves of the near-optimal planner's plans.
    pub near_optimal_moves: f64,
    /// Mean ratio of the near-optimal plan to the fewest moves.
    pub near_optimal_ratio: f64,
    /// The largest such ratio.
    pub near_optimal_worst: f64,
    /// Mean fewest gripper steps, when known for every problem of the group.
    pub fewest_steps: Option<f64>,
    /// Each agent that played the group's problems.
    pub agents: Vec<AgentFigures>,
}

/// The physics backend against the grid model: the same random play on both.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Agreement {
    /// Blocks.
    pub blocks: usize,
    /// The grid, "W x H".
    pub grid: String,
    /// Episodes begun.
    pub episodes: u64,
    /// Starts that were the same on both.
    pub same_starts: u64,
    /// Random steps taken on both.
    pub steps: u64,
    /// Steps whose outcomes (state, reward, end, info) were the same on both.
    pub same_steps: u64,
    /// Drops among the steps.
    pub drops: u64,
    /// Drops whose block came to rest on the same cell on both.
    pub same_landings: u64,
    /// Steps the physics backend refused with an error (a Drop it did not bring to rest on a
    /// cell): each ends its episode, and counts as a step, and a drop, not the same.
    pub physics_errors: u64,
    /// The first such error: the episode's seed, the step and the message, to replay it.
    pub first_error: Option<String>,
}

impl Agreement {
    /// Whether the two agreed on everything.
    pub fn total(&self) -> bool {
        self.same_starts == self.episodes
            && self.same_steps == self.steps
            && self.same_landings == self.drops
            && self.physics_errors == 0
    }
}

/// E9's results beside its tables: what `results.json` holds of it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BlocksWorld {
    /// Problems per number of blocks and of towers.
    pub problems_per_cell: u64,
    /// The backend the agents played on.
    pub backend: Backend,
    /// By number of blocks.
    pub by_blocks: Vec<Group>,
    /// By number of goal towers.
    pub by_towers: Vec<Group>,
    /// By number of stacking steps (the fewest block moves).
    pub by_stacking_steps: Vec<Group>,
    /// Physics against the grid model, by number of blocks.
    pub agreement: Vec<Agreement>,
    /// Every problem (not written: the groups are its figures).
    #[serde(skip)]
    pub problems: Vec<Problem>,
}

/// Jobs reported: the learner's training, one per number of blocks and of towers, and one
/// agreement run per number of blocks.
pub(super) fn jobs(_: &Context) -> u64 {
    (1 + BLOCKS.len() * MAX_TOWERS + BLOCKS.len()) as u64
}

/// The backend the agents play on.
const BACKEND: Backend = Backend::Physics;

/// Runs E9.
pub(super) fn run(ctx: &Context, _: &Shared) -> Result<Experiment> {
    let per_cell = problems_per_cell(ctx.budget);
    let cells: Vec<(usize, usize)> = BLOCKS
        .iter()
        .flat_map(|&n| (1..=MAX_TOWERS).map(move |k| (n, k)))
        .collect();
    let config = learner_config(ctx)?;
    // The learner trains while the physics is checked against the grid; then every agent
    // plays.
    let (learner, agreement) = rayon::join(
        || -> Result<QAgent> {
            let trained = agent::train(&config, None)?;
            ctx.progress.advance(STAGE);
            Ok(trained.agent)
        },
        || -> Result<Vec<Agreement>> {
            BLOCKS
                .par_iter()
                .map(|&n| {
                    let a = agreement(
                        n,
                        agreement_steps(ctx.budget),
                        episode_seed(ctx.seeds.test, 9000 + n as u64),
                    )?;
                    ctx.progress.advance(STAGE);
                    Ok(a)
                })
                .collect()
        },
    );
    let (learner, agreement) = (learner?, agreement?);
    let per: Vec<Vec<Problem>> = cells
        .par_iter()
        .map(|&(n, k)| {
            let cell_seed = episode_seed(ctx.seeds.test, 1000 * n as u64 + k as u64);
            let problems = (0..per_cell)
                .into_par_iter()
                .map(|j| problem(n, k, episode_seed(cell_seed, j), &learner))
                .collect::<Result<Vec<_>>>()?;
            ctx.progress.advance(STAGE);
            Ok(problems)
        })
        .collect::<Result<_>>()?;
    let problems: Vec<Problem> = per.into_iter().flatten().collect();
    let world = BlocksWorld {
        problems_per_cell: per_cell,
        backend: BACKEND,
        by_blocks: groups(&problems, |p| p.blocks),
        by_towers: groups(&problems, |p| p.towers),
        by_stacking_steps: groups(&problems, |p| p.fewest_moves as usize),
        agreement,
        problems,
    };
    Ok(experiment(ctx, world, &config))
}

/// Counts the Drops of an episode that let a block go: its block moves.
#[derive(Default)]
struct Drops(u32);

impl EpisodeObserver for Drops {
    fn step(&mut self, _: u64, before: &Observation, action: Action, _: &Step) -> agent::Result<()> {
        self.0 += u32::from(action == Action::Drop && before.held_block().is_some());
        Ok(())
    }
}

/// The generator a problem's goal is drawn from: the problem seed's, on a stream the
/// start's draw does not use.
fn goal_rng(seed: u64) -> seeding::SimRng {
    let mut rng = seeding::rng(seed);
    rng.set_stream(2);
    rng
}

/// Draws problem `seed` of `blocks` blocks and `towers` towers, plans it and plays it with
/// every agent (`learner`: the learner's agent).
fn problem(blocks: usize, towers: usize, seed: u64, learner: &QAgent) -> Result<Problem> {
    let grid = grid_for(blocks);
    let goal = Goal::random_towers(blocks, towers, &mut goal_rng(seed))?;
    let mut env = Env::new(EnvConfig {
        grid,
        blocks,
        goal: GoalSpec::Fixed(goal.clone()),
        horizon: HORIZON,
        backend: BACKEND,
        view: View::Side,
        ..EnvConfig::default()
    })?;
    let start = env.reset(seed).state;
    let fewest_moves = plan_side(MovePlanner::Exact, grid, &start, &goal)?.len() as u32;
    let near_optimal_moves = plan_side(MovePlanner::NearOptimal, grid, &start, &goal)?.len() as u32;
    let fewest_steps = (blocks <= FEWEST_STEPS_BLOCKS)
        .then(|| oracle::ExactSolver::for_world(env.config()).distance(&start, &goal))
        .transpose()?;
    let played = AGENTS
        .iter()
        .map(|&a| {
            if !a.plays(blocks) {
                return Ok(None);
            }
            let mut drops = Drops::default();
            Ok(Some(
                match agent::play_episode(&mut env, a.policy(learner)?.as_mut(), 0, seed, &mut drops) {
                    Ok(r) => Played {
                        reached_goal: r.reached_goal,
                        steps: r.steps,
                        moves: drops.0,
                        physics_error: false,
                    },
                    // A failure of the physics, measured (the agreement table counts them too),
                    // rather than the end of the run.
                    Err(agent::AgentError::Sim(sim::SimError::NotAtRest { .. })) => Played {
                        reached_goal: false,
                        steps: env.steps(),
                        moves: drops.0,
                        physics_error: true,
                    },
                    Err(e) => return Err(e.into()),
                },
            ))
        })
        .collect::<Result<_>>()?;
    Ok(Problem {
        blocks,
        towers,
        seed,
        goal,
        start,
        fewest_moves,
        near_optimal_moves,
        fewest_steps,
        played,
    })
}

/// The mean of `values`, `None` for none.
fn mean(values: impl IntoIterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.into_iter().fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    (n > 0).then(|| sum / n as f64)
}

/// The problems grouped by `key`, in increasing order of it.
fn groups(problems: &[Problem], key: impl Fn(&Problem) -> usize) -> Vec<Group> {
    let mut keys: Vec<usize> = problems.iter().map(&key).collect();
    keys.sort_unstable();
    keys.dedup();
    keys.into_iter()
        .map(|k| {
            let members: Vec<&Problem> = problems.iter().filter(|p| key(p) == k).collect();
            group(k, &members)
        })
        .collect()
}

fn group(key: usize, members: &[&Problem]) -> Group {
    let ratio = |p: &Problem| f64::from(p.near_optimal_moves) / f64::from(p.fewest_moves);
    let agents = AGENTS
        .iter()
        .enumerate()
        .filter_map(|(i, a)| {
            let games: Vec<(&Problem, Played)> = members.iter().filter_map(|p| p.played[i].map(|g| (*p, g))).collect();
            if games.is_empty() {
                return None;
            }
            let wins: Vec<&(&Problem, Played)> = games.iter().filter(|(_, g)| g.reached_goal).collect();
            Some(AgentFigures {
                agent: a.name().into(),
                games: games.len(),
                success: wins.len() as f64 / games.len() as f64,
                mean_moves: mean(wins.iter().map(|(_, g)| f64::from(g.moves))),
                moves_ratio: mean(wins.iter().map(|(p, g)| f64::from(g.moves) / f64::from(p.fewest_moves))),
                mean_steps: mean(wins.iter().map(|(_, g)| f64::from(g.steps))),
                steps_ratio: mean(
                    wins.iter()
                        .filter_map(|(p, g)| p.fewest_steps.map(|f| f64::from(g.steps) / f64::from(f))),
                ),
                physics_errors: games.iter().filter(|(_, g)| g.physics_error).count(),
            })
        })
        .collect();
    Group {
        key,
        problems: members.len(),
        fewest_moves: mean(members.iter().map(|p| f64::from(p.fewest_moves))).unwrap_or(0.0),
        near_optimal_moves: mean(members.iter().map(|p| f64::from(p.near_optimal_moves))).unwrap_or(0.0),
        near_optimal_ratio: mean(members.iter().map(|p| ratio(p))).unwrap_or(0.0),
        near_optimal_worst: members.iter().map(|p| ratio(p)).fold(0.0, f64::max),
        fewest_steps: members
            .iter()
            .map(|p| p.fewest_steps.map(f64::from))
            .collect::<Option<Vec<f64>>>()
            .and_then(mean),
        agents,
    }
}

/// Seeded random play on the physics backend and the same actions on the grid model,
/// `steps` steps of `blocks` blocks on their grid: how often the two agreed. An episode
/// whose outcomes part stops there (the next starts both afresh).
fn agreement(blocks: usize, steps: u64, seed: u64) -> Result<Agreement> {
    let grid = grid_for(blocks);
    let config = |backend| EnvConfig {
        grid,
        blocks,
        horizon: AGREEMENT_HORIZON,
        backend,
        view: View::Side,
        ..EnvConfig::default()
    };
    let (mut physics, mut model) = (Env::new(config(Backend::Physics))?, Env::new(config(Backend::Grid))?);
    let mut a = Agreement {
        blocks,
        grid: format!("{} x {}", grid.width(), grid.height()),
        episodes: 0,
        same_starts: 0,
        steps: 0,
        same_steps: 0,
        drops: 0,
        same_landings: 0,
        physics_errors: 0,
        first_error: None,
    };
    let mut random = RandomPolicy;
    // Starts drawn alike by both (the same code draws them); the bound on episodes only
    // guards against a loop that never steps.
    while a.steps < steps && a.episodes < steps {
        let episode = episode_seed(seed, a.episodes);
        a.episodes += 1;
        let mut obs = physics.reset(episode);
        if obs != model.reset(episode) {
            continue;
        }
        a.same_starts += 1;
        let mut rng = agent::rollout::policy_rng(episode);
        let mut step = 0u32;
        while !physics.is_over() && a.steps < steps {
            step += 1;
            let action = random.act(&obs, &mut rng)?;
            let held = obs.held_block();
            let g = model.step(action)?;
            a.steps += 1;
            let dropped = matches!((action, held), (Action::Drop, Some(_)));
            a.drops += u64::from(dropped);
            let p = match physics.step(action) {
                Ok(p) => p,
                // Measured, not the end of the run: the table is there to find these.
                Err(e @ sim::SimError::NotAtRest { .. }) => {
                    a.physics_errors += 1;
                    a.first_error.get_or_insert_with(|| {
                        format!("{blocks} blocks, episode reset with {episode}, step {step}: {e}")
                    });
                    break;
                }
                Err(e) => return Err(e.into()),
            };
            if let (true, Some(block)) = (dropped, held) {
                a.same_landings += u64::from(p.observation.state.cell(block) == g.observation.state.cell(block));
            }
            if p != g {
                break;
            }
            a.same_steps += 1;
            obs = p.observation;
        }
    }
    Ok(a)
}

/// The report's section from the results; `learner` is how the learner was trained.
fn experiment(ctx: &Context, world: BlocksWorld, learner: &TrainConfig) -> Experiment {
    Experiment {
        id: "E9".into(),
        title: "The classic Blocks World, seen from the side (ours)".into(),
        setup: setup(ctx, &world, learner),
        tables: Vec::new(),
        paper_notes: Vec::new(),
        reading: reading(&world),
        figures: figures(&world),
        findings: Findings::BlocksWorld(world),
    }
}

/// An agent's figures in a group, if it played the group's problems.
fn figures_of(group: &Group, agent: Agent) -> Option<&AgentFigures> {
    group.agents.iter().find(|f| f.agent == agent.name())
}

/// The run's reading: one paragraph computed from the figures.
fn reading(world: &BlocksWorld) -> String {
    let all = &world.problems;
    let everything = group(0, &all.iter().collect::<Vec<_>>());
    let (exact, near, learned) = (
        figures_of(&everything, Agent::Exact),
        figures_of(&everything, Agent::NearOptimal),
        figures_of(&everything, Agent::Learner),
    );
    let success = |f: Option<&AgentFigures>| num(f.map(|f| 100.0 * f.success), 1);
    let sum = |field: fn(&Agreement) -> u64| world.agreement.iter().map(field).sum::<u64>();
    let (agreed_drops, drops) = (sum(|a| a.same_landings), sum(|a| a.drops));
    let (agreed_steps, steps) = (sum(|a| a.same_steps), sum(|a| a.steps));
    let errors = physics_errors_reading(world, &everything);
    let deepest = world.by_stacking_steps.last().map_or(0, |g| g.key);
    let per_move = |f: Option<&AgentFigures>| num(f.and_then(|f| Some(f.mean_steps? / f.mean_moves?)), 1);
    let steps_reading = gripper_steps_reading(all);
    let learner_reading = learned.map_or(String::new(), |f| {
        format!(
            " The learner, greedy, reached the goal in {}% of its {} problems of {LEARNER_BLOCKS} blocks, with {}x the \
             fewest block moves{}.",
            num(Some(100.0 * f.success), 1),
            f.games,
            num(f.moves_ratio, 3),
            f.steps_ratio.map_or(String::new(), |r| format!(
                " and {}x the fewest gripper steps",
                num(Some(r), 3)
            ))
        )
    });
    format!(
        "Over {} problems of 3 to 10 blocks (up to {deepest} stacking steps), the near-optimal planner's plans were \
         {}x the fewest block moves on average (worst {}x); carried out by the gripper through the physics, the \
         exact planner reached the goal in {}% of the problems and the near-optimal planner in {}%, with {} and {} \
         gripper steps per block move.{steps_reading}{learner_reading} Physics and grid agreed on {agreed_steps} of {steps} random \
         steps and {agreed_drops} of {drops} drops.{errors}",
        all.len(),
        num(Some(everything.near_optimal_ratio), 3),
        num(Some(everything.near_optimal_worst), 2),
        success(exact),
        success(near),
        per_move(exact),
        per_move(near),
    )
}

/// The sentence on Drops the physics did not bring to rest, empty when there were none.
fn physics_errors_reading(world: &BlocksWorld, everything: &Group) -> String {
    let physics_errors: u64 = world.agreement.iter().map(|a| a.physics_errors).sum();
    let game_errors: usize = everything.agents.iter().map(|f| f.physics_errors).sum();
    if physics_errors + game_errors as u64 == 0 {
        return String::new();
    }
    let times = |n: u64| {
        if n == 1 {
            "once".to_string()
        } else {
            format!("{n} times")
        }
    };
    format!(
        " The physics did not bring a dropped block to rest on a cell {} in random play and {} in the \
         agents' games (first: {}).",
        times(physics_errors),
        times(game_errors as u64),
        world
            .agreement
            .iter()
            .find_map(|a| a.first_error.as_deref())
            .unwrap_or("in an agent's game")
    )
}

/// The sentence on the planners' gripper steps against the fewest, where they were searched
/// (empty when none was).
fn gripper_steps_reading(all: &[Problem]) -> String {
    let small: Vec<&Problem> = all.iter().filter(|p| p.fewest_steps.is_some()).collect();
    let small = group(0, &small);
    if small.problems == 0 {
        return String::new();
    }
    let steps_of = |agent: Agent| num(figures_of(&small, agent).and_then(|f| f.steps_ratio), 3);
    format!(
        " On the {} problems of up to {FEWEST_STEPS_BLOCKS} blocks, the exact planner's gripper steps were {}x the \
         fewest gripper steps, the near-optimal planner's {}x.",
        small.problems,
        steps_of(Agent::Exact),
        steps_of(Agent::NearOptimal)
    )
}

/// The two charts, by stacking steps: the goal reached, and the block moves beyond the fewest.
fn figures(world: &BlocksWorld) -> Vec<Figure> {
    let all = &world.problems;
    // The ratios lie within a few per cent of 1: drawn as the per cent above it.
    let extra = |ratio: f64| 100.0 * (ratio - 1.0);
    let mut series = vec![Series {
        name: "near-optimal plan".into(),
        points: world
            .by_stacking_steps
            .iter()
            .map(|g| (g.key as f64, extra(g.near_optimal_ratio)))
            .collect(),
    }];
    // The planners only: the learner's extra moves would flatten theirs (the success chart
    // and the tables have it).
    for agent in [Agent::Exact, Agent::NearOptimal] {
        series.push(Series {
            name: format!("{}, played", agent.name()),
            points: world
                .by_stacking_steps
                .iter()
                .filter_map(|g| Some((g.key as f64, extra(figures_of(g, agent)?.moves_ratio?))))
                .collect(),
        });
    }
    series.retain(|s| !s.points.is_empty());
    let moves = CurvesChart {
        title: "E9: block moves beyond the fewest, by stacking steps".into(),
        x_label: "stacking steps (the fewest block moves)".into(),
        y_label: "block moves beyond the fewest (%, mean)".into(),
        y_range: None,
        series,
        note: format!(
            "{} problems, 3-10 blocks, goals of 1-{MAX_TOWERS} towers; a game that failed has no ratio.",
            all.len()
        ),
    };
    let reached = CurvesChart {
        title: "E9: reached the goal, by stacking steps".into(),
        x_label: "stacking steps (the fewest block moves)".into(),
        y_label: "reached the goal (%)".into(),
        y_range: Some((0.0, 100.0)),
        series: AGENTS
            .iter()
            .map(|&agent| Series {
                name: agent.name().into(),
                points: world
                    .by_stacking_steps
                    .iter()
                    .filter_map(|g| Some((g.key as f64, 100.0 * figures_of(g, agent)?.success)))
                    .collect(),
            })
            .filter(|s| !s.points.is_empty())
            .collect(),
        note: format!(
            "{} problems, 3-10 blocks, goals of 1-{MAX_TOWERS} towers; the learner plays those of {LEARNER_BLOCKS} \
             blocks. Duan et al. (\"One-Shot Imitation Learning\", 2017) report success by stacking steps alike.",
            all.len()
        ),
    };
    vec![
        Figure::new(
            "e9-reached",
            "Games that reached the goal, by stacking steps: every agent through the gripper".into(),
            Drawing::Curves(reached),
        ),
        Figure::new(
            "e9-moves",
            "Block moves beyond the fewest, in per cent, by stacking steps: the near-optimal planner's plans, \
             and each planner carried out by the gripper"
                .into(),
            Drawing::Curves(moves),
        ),
    ]
}

/// What was run: the world, the problems, the planners, the learner and the checks.
fn setup(ctx: &Context, world: &BlocksWorld, learner: &TrainConfig) -> Vec<Setting> {
    let grids = BLOCKS
        .iter()
        .map(|&n| {
            let g = grid_for(n);
            format!("{n}: {} x {}", g.width(), g.height())
        })
        .collect::<Vec<_>>()
        .join(", ");
    let setting = |name: &str, value: String| Setting {
        name: name.into(),
        value,
    };
    vec![
        setting(
            "world",
            "the side view (docs/world.md section 12): towers under gravity, only a clear block picked, a released \
             block falls to the top of the column below; the classic Blocks World of Gupta & Nau (\"On the \
             complexity of blocks-world planning\", 1992) and Slaney & Thiebaux (\"Blocks World revisited\", 2001)"
                .into(),
        ),
        setting(
            "problems",
            format!(
                "{per} per number of blocks ({}) and of goal towers (1 to {MAX_TOWERS}), {} in all: the goal drawn \
                 uniformly among those of that many towers naming every block, the start random towers in which it \
                 does not hold; problem j of N blocks and k towers from seed episode_seed(episode_seed({}, 1000 N + \
                 k), j)",
                BLOCKS.map(|n| n.to_string()).join(", "),
                world.problems.len(),
                ctx.seeds.test,
                per = world.problems_per_cell,
            ),
        ),
        setting(
            "grids",
            format!(
                "by blocks, {grids}: as many columns as blocks at least, so the table never runs out (the classic \
                 world's table is unbounded), and a row more than blocks, for a tower of every block and a block \
                 carried over it"
            ),
        ),
        setting(
            "planners",
            "the fewest block moves by A* (`oracle::towers::ExactMoves`), the near-optimal planner (`NearOptimal`, \
             at most twice the fewest); each also played by the gripper (`agent::TowersPolicy`: at each block-move \
             boundary it plans from the state it sees and carries the first move out as gripper actions, a move to \
             the table going to the leftmost empty column), its Drops counted as block moves"
                .into(),
        ),
        setting(
            "fewest gripper steps",
            format!(
                "for problems of up to {FEWEST_STEPS_BLOCKS} blocks, by the exact solver of the side view \
                 (`oracle::ExactSolver::for_world`: A* over Pick, moves and Drop); every agent's gripper steps are \
                 set against it"
            ),
        ),
        setting("learner", learner_setting(learner)),
        setting(
            "backend",
            format!(
                "the games on the {} backend (rapier2d dynamics to rest at every Drop), horizon {HORIZON}",
                world.backend
            ),
        ),
        setting(
            "stacking steps",
            "a problem's fewest block moves, as Duan et al. (\"One-Shot Imitation Learning\", 2017) group their \
             tasks by stacking steps"
                .into(),
        ),
        setting(
            "agreement",
            format!(
                "per number of blocks, {} uniformly random legal steps on the physics backend and the same actions \
                 on the grid model, in episodes of up to {AGREEMENT_HORIZON} steps (a goal drawn per episode) reset \
                 with episode_seed(episode_seed({}, 9000 + N), e); an episode whose outcomes part ends there",
                agreement_steps(ctx.budget),
                ctx.seeds.test
            ),
        ),
    ]
}

/// How the learner was trained, in words.
fn learner_setting(learner: &TrainConfig) -> String {
    format!(
        "the tabular learner of the side view (`blockstack train --view side`'s preset: {} representation, {} \
         reward, alpha {}, gamma {}, epsilon {}), {} training games on the goals {} of {LEARNER_BLOCKS} blocks on {} \
         x {}, seed {}; it plays the problems of {LEARNER_BLOCKS} blocks greedily (epsilon 0)",
        learner.repr,
        learner.world.reward.name(),
        learner.params.alpha,
        learner.params.gamma,
        learner.params.epsilon,
        learner.games,
        learner.goals.iter().map(Goal::to_string).collect::<Vec<_>>().join(", "),
        learner.world.grid.width(),
        learner.world.grid.height(),
        learner.seed
    )
}

#[cfg(test)]
mod tests {
    use super::super::{Options, Report, reproduce};
    use super::*;

    /// E9 alone, at the quick budget.
    fn quick() -> Experiment {
        let options = Options {
            report: Report::BlocksWorld,
            seed: 3,
            quick: true,
            long: false,
            only: vec!["E9".into()],
        };
        reproduce(&options, &()).unwrap().experiments.swap_remove(0)
    }

    #[test]
    fn every_grid_holds_a_tower_of_every_block_and_a_column_per_block() {
        for n in BLOCKS {
            let g = grid_for(n);
            assert!(g.width() >= n && g.height() > n, "{n}");
        }
        assert_eq!(
            grid_for(6),
            Grid::default(),
            "the paper's 7 x 7 while it is wide enough"
        );
    }

    #[test]
    fn e9_alone_draws_its_problems_plans_them_and_the_planners_reach_every_goal() {
        let e = quick();
        assert_eq!(e.id, "E9");
        let Findings::BlocksWorld(world) = &e.findings else {
            panic!("E9 reports its problems")
        };
        let per = problems_per_cell(Budget::Quick) as usize;
        assert_eq!(world.problems.len(), BLOCKS.len() * MAX_TOWERS * per);
        for p in &world.problems {
            assert_eq!(p.goal.tower_lists().len(), p.towers, "{}", p.goal);
            assert_eq!((p.goal.block_count(), p.start.block_count()), (p.blocks, p.blocks));
            assert!(!p.goal.holds_in(View::Side, &p.start), "a start that needs no move");
            // The exact planner's count is the fewest; the near-optimal planner's at most twice.
            assert!(p.fewest_moves >= 1);
            assert!(p.fewest_moves <= p.near_optimal_moves && p.near_optimal_moves <= 2 * p.fewest_moves);
            let [exact, near] = [p.played[0].unwrap(), p.played[1].unwrap()];
            assert!(exact.reached_goal && near.reached_goal, "{}", p.goal);
            assert_eq!(exact.moves, p.fewest_moves, "played as planned");
            assert!(near.moves >= p.fewest_moves);
            // A block move takes a Pick, a Drop and at least one move between.
            assert!(exact.steps >= 3 * exact.moves);
            // The learner plays the problems of its blocks only.
            assert_eq!(p.played[2].is_some(), p.blocks == LEARNER_BLOCKS);
            // No game that reaches the goal takes fewer gripper steps than the fewest.
            assert_eq!(p.fewest_steps.is_some(), p.blocks <= FEWEST_STEPS_BLOCKS);
            if let Some(fewest) = p.fewest_steps {
                for g in p.played.iter().flatten().filter(|g| g.reached_goal) {
                    assert!(g.steps >= fewest, "{g:?} against {fewest}");
                }
            }
        }
        // Each grouping splits the same problems.
        for groups in [&world.by_blocks, &world.by_towers, &world.by_stacking_steps] {
            assert_eq!(groups.iter().map(|g| g.problems).sum::<usize>(), world.problems.len());
            for g in groups.iter() {
                assert!(g.near_optimal_ratio >= 1.0 && g.near_optimal_worst <= 2.0);
                let planners: Vec<&AgentFigures> =
                    g.agents.iter().filter(|a| a.agent != Agent::Learner.name()).collect();
                assert!(
                    planners.len() == 2 && planners.iter().all(|a| a.success == 1.0),
                    "{g:?}"
                );
            }
        }
        assert_eq!(world.by_blocks.iter().map(|g| g.key).collect::<Vec<_>>(), BLOCKS);
        assert_eq!(world.by_towers.iter().map(|g| g.key).collect::<Vec<_>>(), [1, 2, 3]);
        for g in &world.by_stacking_steps {
            assert_eq!(g.fewest_moves, g.key as f64, "a group of stacking steps is one count");
        }
        // Physics and grid agree, on drops too.
        for a in &world.agreement {
            assert!(a.total(), "{a:?}");
            assert_eq!(a.steps, agreement_steps(Budget::Quick));
            assert!(a.drops > 0 && a.episodes > 1, "{a:?}");
        }
        assert_eq!(e.figures.len(), 2);
        assert!(
            e.reading.contains("reached the goal in 100.0% of the problems"),
            "{}",
            e.reading
        );
        // Seeded: the same run again gives the same problems and figures.
        assert_eq!(quick(), e);
    }

    #[test]
    fn a_disagreement_is_counted_where_it_happens() {
        let mut a = Agreement {
            blocks: 3,
            grid: "7 x 7".into(),
            episodes: 2,
            same_starts: 2,
            steps: 10,
            same_steps: 10,
            drops: 2,
            same_landings: 2,
            physics_errors: 0,
            first_error: None,
        };
        assert!(a.total());
        a.same_landings = 1;
        assert!(!a.total());
        a.same_landings = 2;
        a.same_steps = 9;
        assert!(!a.total());
        a.same_steps = 10;
        a.physics_errors = 1;
        assert!(!a.total());
    }
}
