//! Training the relational policy by imitation of the optimum, with DAgger.
//!
//! Every example is a problem (a state and a goal) and the set of its optimal moves: the
//! moves after which the optimum is one less, each optimum proven by the optimal solver
//! ([`oracle::towers::optimal_first_moves`]), so problems may be larger than the few blocks
//! whose whole state space fits in memory. The loss is the negative log of the probability
//! the policy's softmax over the legal moves gives the optimal set: any optimal move is
//! right, none is taught as a mistake.
//!
//! The examples come first from uniformly random problems, then from the states the policy
//! itself reaches (DAgger, Ross et al. 2011): each iteration plays the greedy policy on
//! fresh random problems and labels every state it meets with the optimal moves from
//! there, so it learns to recover from its own mistakes. The problems have 2 to
//! [`RelationalConfig::max_blocks`] blocks; goals name every block (as the literature's
//! do) or, for a share of them, some blocks in a few towers (as the side view's may).

use oracle::towers::{OptimalMoves, Table, TowerGoal, Towers, optimal_first_moves, random_goal, random_state};
use rand::RngExt;
use serde::{Deserialize, Serialize};
use sim::seeding::{episode_seed, rng};

use crate::error::{NeuralError, Result};
use crate::optim::{Optimizer, OptimizerKind};

use super::graph::Graph;
use super::move_policy::MovePolicy;
use super::net::{RelationalNet, Shape, Tape};

/// The most blocks a training problem may have: past it, labelling every move of every
/// state with proofs of the optimum costs more than a training run should.
pub const MAX_TRAINING_BLOCKS: usize = 64;

/// A training run of the relational policy.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RelationalConfig {
    /// The network.
    pub shape: Shape,
    /// Seed of the weights, the problems and every random choice.
    pub seed: u64,
    /// The most blocks of a training problem (the fewest is 2).
    pub max_blocks: usize,
    /// Share of goals that name only some blocks (the others name every block).
    pub partial_goals: f64,
    /// Random problems labelled before the first gradient step.
    pub problems: u64,
    /// DAgger iterations: each trains, then plays and labels what it reached.
    pub iterations: u64,
    /// Gradient steps per iteration.
    pub steps: u64,
    /// Games played per iteration to collect the states the policy reaches.
    pub rollouts: u64,
    /// Examples per gradient step.
    pub batch: usize,
    /// Adam's learning rate at the start.
    pub lr: f64,
    /// The learning rate at the end: it falls linearly over the run's gradient steps.
    pub lr_final: f64,
}

impl RelationalConfig {
    /// The `general` preset (`blockstack dqn --preset general`): problems of up to 20
    /// blocks and 6 rounds. Measured against the optimum on the planning competition's
    /// tasks (docs/dqn.md, "The general policy"), 20 blocks did better than 6 or 12 and as
    /// well as 40 at a seventh of its cost; 6 rounds better than 1 to 4 and than 8; a wider
    /// network and more gradient steps gained nothing.
    pub fn general() -> RelationalConfig {
        RelationalConfig {
            shape: Shape {
                width: 16,
                hidden: 16,
                score_hidden: 16,
                rounds: 6,
            },
            seed: 1,
            max_blocks: 20,
            partial_goals: 0.2,
            problems: 20_000,
            iterations: 10,
            steps: 3_000,
            rollouts: 1_000,
            batch: 64,
            lr: 3e-3,
            lr_final: 3e-4,
        }
    }

    /// An error naming the first setting that cannot work.
    pub fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(NeuralError::Config(what));
        self.shape.validate()?;
        if !(2..=MAX_TRAINING_BLOCKS).contains(&self.max_blocks) {
            return bad(format!(
                "training problems of at most {} blocks: choose 2 to {MAX_TRAINING_BLOCKS}",
                self.max_blocks
            ));
        }
        if !(0.0..=1.0).contains(&self.partial_goals) {
            return bad(format!(
                "the share of partial goals {} is not in [0, 1]",
                self.partial_goals
            ));
        }
        if self.batch == 0 || self.batch > 1 << 16 {
            return bad(format!("a batch of {} examples: choose 1 to 65536", self.batch));
        }
        for lr in [self.lr, self.lr_final] {
            if !(lr > 0.0 && lr.is_finite()) {
                return bad(format!("the learning rate {lr} is not a positive number"));
            }
        }
        if self.problems == 0 {
            return bad("no problems to start from: label at least 1".into());
        }
        if self.problems > 10_000_000 || self.rollouts > 10_000_000 {
            return bad("at most 10,000,000 problems and games per iteration are kept in memory".into());
        }
        Ok(())
    }

    /// Gradient steps of the whole run.
    pub fn total_steps(&self) -> u64 {
        self.iterations * self.steps
    }
}

/// A labelled example: a problem and its optimal moves, as a mask over its legal moves in
/// [`Towers::moves`] order.
#[derive(Clone, Debug)]
struct Example {
    state: Towers,
    goal: TowerGoal,
    optimal: Vec<bool>,
}

/// The exact labels of problems at any size: the optimal solver's proven optimal moves
/// ([`optimal_first_moves`]).
struct Labeller {
    solver: OptimalMoves,
}

impl Labeller {
    fn new() -> Labeller {
        Labeller {
            solver: OptimalMoves::new(),
        }
    }

    /// The optimum of `state` and `goal` and its example; `None` where the goal holds or a
    /// proof did not close (then the state teaches nothing).
    fn label(&self, state: &Towers, goal: &TowerGoal) -> Result<Option<(usize, Example)>> {
        let Some((fewest, optimal)) = optimal_first_moves(&self.solver, state, goal)? else {
            return Ok(None);
        };
        if optimal.is_empty() {
            return Ok(None);
        }
        let optimal = state
            .moves(Table::Unbounded)
            .iter()
            .map(|m| optimal.contains(m))
            .collect();
        Ok(Some((
            fewest,
            Example {
                state: state.clone(),
                goal: goal.clone(),
                optimal,
            },
        )))
    }
}

/// A random training problem from `seed`: 2 to `max_blocks` blocks (weighted towards the
/// most, where the problems are hardest), a uniformly random state, and a goal naming every
/// block (a uniformly random state's towers) or, with probability `partial`, some.
pub fn random_problem(max_blocks: usize, partial: f64, seed: u64) -> (Towers, TowerGoal) {
    let mut r = rng(seed);
    // Sizes weighted by themselves: 20 blocks are drawn ten times as often as 2.
    let total: usize = (2..=max_blocks).sum();
    let mut pick = r.random_range(0..total);
    let mut n = 2;
    while pick >= n {
        pick -= n;
        n += 1;
    }
    let state = random_state(n, r.random());
    let goal = if r.random_bool(partial) {
        let named = r.random_range(1..=n);
        let stacks = r.random_range(1..=named.min(3));
        random_goal(n, stacks, named, r.random()).expect("a shape that can be drawn")
    } else {
        TowerGoal::new(&random_state(n, r.random()).towers()).expect("a state's towers")
    };
    (state, goal)
}

/// What training reports as it goes.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IterationReport {
    /// The iteration, from 1.
    pub iteration: u64,
    /// Examples in the data set after it.
    pub examples: u64,
    /// Mean loss over its gradient steps.
    pub loss: f64,
    /// Share of its games (from starts where the goal does not hold) that reached the goal
    /// within the move limit.
    pub success: f64,
    /// Mean ratio of moves to the fewest over the games that succeeded.
    pub moves_ratio: f64,
}

/// Trains a relational network as `config` says; `progress` after every iteration.
pub fn train(
    config: &RelationalConfig,
    progress: &mut dyn FnMut(&IterationReport),
) -> Result<(RelationalNet, Vec<IterationReport>)> {
    config.validate()?;
    let mut net = RelationalNet::new(config.shape, &mut rng(episode_seed(config.seed, 0)))?;
    let labeller = Labeller::new();
    let mut data = Vec::new();
    for k in 0..config.problems {
        let (state, goal) = random_problem(
            config.max_blocks,
            config.partial_goals,
            episode_seed(config.seed, 1_000 + k),
        );
        data.extend(labeller.label(&state, &goal)?.map(|(_, e)| e));
    }
    let mut opt = Optimizer::new(OptimizerKind::Adam, config.lr, net.params().len());
    let mut grads = vec![0.0f32; net.params().len()];
    let mut tape = Tape::new();
    let mut draw = rng(episode_seed(config.seed, 2));
    let mut reports = Vec::new();
    let total = config.total_steps().max(1) as f64;
    let mut step = 0u64;
    for iteration in 1..=config.iterations {
        let mut loss_sum = 0.0;
        for _ in 0..config.steps {
            let lr = config.lr + (config.lr_final - config.lr) * step as f64 / total;
            opt.set_lr(lr);
            let batch: Vec<&Example> = (0..config.batch)
                .map(|_| &data[draw.random_range(0..data.len())])
                .collect();
            grads.fill(0.0);
            loss_sum += gradient(&net, &batch, &mut tape, &mut grads);
            opt.step(net.params_mut(), &mut grads, 0.0, None);
            step += 1;
        }
        // DAgger: play the policy and label what it reached.
        let mut policy = MovePolicy::new(&net);
        let (mut played, mut won, mut ratio_sum) = (0u64, 0u64, 0.0);
        for k in 0..config.rollouts {
            let seed = episode_seed(episode_seed(config.seed, 3), iteration * 10_000_000 + k);
            let (start, goal) = random_problem(config.max_blocks, config.partial_goals, seed);
            let Some((fewest, first)) = labeller.label(&start, &goal)? else {
                continue;
            };
            played += 1;
            let mut state = start.clone();
            // The start's example is the one just labelled: its proofs are not made twice.
            let mut known = Some(first);
            let mut moves = 0;
            let limit = super::move_limit(start.blocks());
            while moves < limit {
                if goal.holds(&state) {
                    break;
                }
                let example = match known.take() {
                    Some(example) => Some(example),
                    None => labeller.label(&state, &goal)?.map(|(_, e)| e),
                };
                data.extend(example);
                let mv = policy
                    .choose(&state, &goal, Table::Unbounded)
                    .expect("a legal move where the goal does not hold");
                state.apply(mv, Table::Unbounded)?;
                moves += 1;
            }
            if goal.holds(&state) {
                won += 1;
                ratio_sum += moves as f64 / fewest.max(1) as f64;
            }
        }
        let report = IterationReport {
            iteration,
            examples: data.len() as u64,
            loss: loss_sum / config.steps.max(1) as f64,
            success: won as f64 / played.max(1) as f64,
            moves_ratio: if won > 0 { ratio_sum / won as f64 } else { 0.0 },
        };
        progress(&report);
        reports.push(report);
    }
    Ok((net, reports))
}

/// The mean loss of `batch` (module docs) and its gradient, added into `grads`.
fn gradient(net: &RelationalNet, batch: &[&Example], tape: &mut Tape, grads: &mut [f32]) -> f64 {
    let graph = Graph::with_moves(batch.iter().map(|e| (&e.state, &e.goal)));
    net.forward(&graph, tape);
    let scores = tape.scores();
    let mut dscores = vec![0.0f32; scores.len()];
    let mut loss = 0.0;
    let scale = 1.0 / batch.len() as f64;
    for (e, span) in batch.iter().zip(&graph.spans) {
        let s = &scores[span.first_move..span.first_move + span.moves];
        let max = s.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v));
        let exp: Vec<f64> = s.iter().map(|&v| f64::from(v - max).exp()).collect();
        let all: f64 = exp.iter().sum();
        let good: f64 = exp.iter().zip(&e.optimal).filter(|(_, o)| **o).map(|(x, _)| x).sum();
        loss += (all.ln() - good.ln()) * scale;
        for (k, (&x, &o)) in exp.iter().zip(&e.optimal).enumerate() {
            let target = if o { x / good } else { 0.0 };
            dscores[span.first_move + k] = ((x / all - target) * scale) as f32;
        }
    }
    net.backward(&graph, tape, &dscores, grads);
    loss
}
