//! Training checkpoints: a [`Trainer`] written to a file between two steps, and read back to
//! train on exactly as if it had never stopped.
//!
//! A run is fixed by its config and seed ([`crate::train`](mod@crate::train)), but unlike the tabular trainer's
//! a network's run carries a lot from one step to the next: both networks, the optimiser's
//! moments, the replay buffer (the demonstrations among it, and those added by corrections),
//! the generator the exploration and the batches draw from, the totals, and the game being
//! played. A checkpoint holds all of it, so a run resumed at step `k` and trained to step `n`
//! ends with the same network, bit for bit, as one trained from 0 to `n` without stopping
//! (on the same machine and number of threads, as any two runs).
//!
//! The game being played is kept as its actions: the environment is reset from the game's
//! seed and the actions replayed, which puts the world (physics included) back where it
//! was, and rebuilds the game's n-step window, its visited states and its hindsight record
//! as they were. What is only a cache (rendered screens, the passes' buffers) is not kept.
//!
//! The file is a `files` container (safetensors): format [`CHECKPOINT_FORMAT`], version
//! [`CHECKPOINT_VERSION`], with metadata `{"config": the run's config as network files store
//! it, "report": the totals, "recent": [reached the goal, ...] (the last games, oldest
//! first), "target_games": games at the last target refresh, "corrected": whether the current
//! game was corrected, "gradient_steps", "optimizer_steps", "agent_next": where the agent's
//! next transition goes in the ring, "contexts": [{"grid", "goal", "protocol", "view"}, ...]}`
//! and tensors:
//!
//! - `online/NAME` and `target/NAME` (F32): each network's tensors, named as in a network
//!   file;
//! - `optimizer/first` and, for Adam, `optimizer/second` (F32): the moments;
//!   `optimizer/lr` (F32, one value): the learning rate of the next step;
//! - `rng` (U8, 56 bytes): the generator's seed (32), stream (8, little-endian) and word
//!   position (16, little-endian);
//! - `last_loss` (F32: total, TD, n-step, margin): the last step's losses, for progress;
//! - for the agent's transitions (`agent/`, in ring order) and the demonstrations
//!   (`demos/`, in the order they came), one row per transition: `context` (U32, an index
//!   into `contexts`: the observations' grid, goal, protocol and view), `states` (U8,
//!   `[n, 3, 1 + 2 * blocks]`: the state before, after, and after the n-step window, each
//!   the held block (255 for none) then every block's x and y), `action` (U8, its index),
//!   `reward` and `n_step_rewards` (F32), `n_steps` (U32) and `flags` (U8: 1 the goal holds
//!   after the step, 2 it holds at the window's end, 4 a demonstrator chose the action);
//! - `game` (U8): the actions of the game being played, absent between games.
//!
//! A caller may keep a document of its own in the metadata's `"note"`
//! ([`Trainer::write_checkpoint_with`]): E8 keeps the tests an arm played along its training.
//!
//! It is written through the output helper (atomically for a regular file), so a kill while
//! it is written leaves the previous checkpoint whole.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use files::{Container, Expect, FilesError, OutputPath, Tensor};
use rand::SeedableRng;
use serde::{Deserialize, Serialize};
use sim::seeding::SimRng;
use sim::{Action, ActionProtocol, BlockId, Cell, Goal, Grid, Observation, State, View};

use crate::config::DqnConfig;
use crate::error::{NeuralError, Result};
use crate::learner::{Learner, Losses};
use crate::model::{StoredConfig, TrainReport};
use crate::net::QNet;
use crate::optim::Optimizer;
use crate::replay::{NStepReturn, ReplayBuffer, Transition};
use crate::train::Trainer;
use agent::run::{RECENT_GAMES, Recent};

/// The `format` of network training checkpoints.
pub const CHECKPOINT_FORMAT: &str = "blockstack-dqn-checkpoint";

/// The checkpoint version this build writes and reads.
pub const CHECKPOINT_VERSION: u32 = 1;

/// Steps (pre-training gradient steps and self-play steps) between two checkpoints unless
/// the caller says otherwise (`dqn --checkpoint-every`'s default): a few minutes of training
/// at most, and a checkpoint costs well under a second.
pub const DEFAULT_EVERY: u64 = 10_000;

/// The largest checkpoint read: a buffer at its bound ([`crate::config::MAX_BUFFER_BYTES`])
/// stored as rows is smaller than it.
pub const MAX_CHECKPOINT_BYTES: u64 = crate::config::MAX_BUFFER_BYTES;

const EXPECT: Expect<'static> = Expect {
    format: CHECKPOINT_FORMAT,
    version: CHECKPOINT_VERSION,
    max_bytes: MAX_CHECKPOINT_BYTES,
    what: "a training checkpoint",
};

/// The held block of a state with none, in `states`.
const NONE_HELD: u8 = u8::MAX;

/// `flags` bits.
const TERMINAL: u8 = 1;
const N_STEP_TERMINAL: u8 = 2;
const EXPERT: u8 = 4;

/// What the observations of a transition share: everything but the state.
#[derive(Clone, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Context {
    grid: Grid,
    goal: Goal,
    protocol: ActionProtocol,
    view: View,
}

impl Context {
    fn of(obs: &Observation) -> Context {
        Context {
            grid: obs.grid,
            goal: obs.goal.clone(),
            protocol: obs.protocol,
            view: obs.view,
        }
    }

    fn observation(&self, state: State) -> Observation {
        Observation {
            grid: self.grid,
            state,
            goal: self.goal.clone(),
            protocol: self.protocol,
            view: self.view,
        }
    }
}

/// The JSON metadata of a checkpoint (module docs).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Metadata {
    config: StoredConfig,
    report: TrainReport,
    recent: Vec<bool>,
    target_games: u64,
    corrected: bool,
    gradient_steps: u64,
    optimizer_steps: u64,
    agent_next: usize,
    contexts: Vec<Context>,
    /// The caller's own document, kept with the run ([`Trainer::write_checkpoint_with`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    note: Option<serde_json::Value>,
}

/// Transitions as columns, the tensors of one table (module docs).
#[derive(Default)]
struct Columns {
    context: Vec<u32>,
    states: Vec<u8>,
    action: Vec<u8>,
    reward: Vec<f32>,
    n_step_rewards: Vec<f32>,
    n_steps: Vec<u32>,
    flags: Vec<u8>,
}

/// The bytes of one state in `states`.
fn state_width(blocks: usize) -> usize {
    1 + 2 * blocks
}

fn put_state(state: &State, out: &mut Vec<u8>) {
    // A network's world has at most 256 cells and 16 blocks (`ObsKind::check`), so every
    // block id and coordinate fits a byte.
    out.push(state.held_block().map_or(NONE_HELD, |b| b.0 as u8));
    for c in state.cells() {
        out.extend([c.x as u8, c.y as u8]);
    }
}

impl Columns {
    fn of(transitions: &[Transition], contexts: &mut Vec<Context>, index: &mut HashMap<Context, u32>) -> Columns {
        let mut c = Columns::default();
        for t in transitions {
            let context = Context::of(&t.obs);
            let i = *index.entry(context.clone()).or_insert_with(|| {
                contexts.push(context);
                (contexts.len() - 1) as u32
            });
            c.context.push(i);
            for obs in [&t.obs, &t.next, &t.n_step.last] {
                put_state(&obs.state, &mut c.states);
            }
            c.action.push(t.action.index() as u8);
            c.reward.push(t.reward);
            c.n_step_rewards.push(t.n_step.rewards);
            c.n_steps.push(t.n_step.steps);
            c.flags.push(
                [
                    (t.terminal, TERMINAL),
                    (t.n_step.terminal, N_STEP_TERMINAL),
                    (t.expert, EXPERT),
                ]
                .iter()
                .filter(|(set, _)| *set)
                .fold(0, |flags, (_, bit)| flags | bit),
            );
        }
        c
    }

    fn tensors(&self, prefix: &str, blocks: usize) -> Vec<(String, Tensor<'static>)> {
        let n = self.context.len();
        let one = "one value a transition";
        vec![
            (
                format!("{prefix}/context"),
                Tensor::from_values(&[n], &self.context).expect(one),
            ),
            (
                format!("{prefix}/states"),
                Tensor::from_values(&[n, 3, state_width(blocks)], &self.states).expect("three states a transition"),
            ),
            (
                format!("{prefix}/action"),
                Tensor::from_values(&[n], &self.action).expect(one),
            ),
            (
                format!("{prefix}/reward"),
                Tensor::from_values(&[n], &self.reward).expect(one),
            ),
            (
                format!("{prefix}/n_step_rewards"),
                Tensor::from_values(&[n], &self.n_step_rewards).expect(one),
            ),
            (
                format!("{prefix}/n_steps"),
                Tensor::from_values(&[n], &self.n_steps).expect(one),
            ),
            (
                format!("{prefix}/flags"),
                Tensor::from_values(&[n], &self.flags).expect(one),
            ),
        ]
    }
}

/// The 56 bytes of `rng`'s state (module docs).
fn rng_bytes(rng: &SimRng) -> Vec<u8> {
    let mut out = rng.get_seed().to_vec();
    out.extend(rng.get_stream().to_le_bytes());
    out.extend(rng.get_word_pos().to_le_bytes());
    out
}

fn rng_from(bytes: &[u8]) -> Option<SimRng> {
    let seed: [u8; 32] = bytes.get(..32)?.try_into().ok()?;
    let stream = u64::from_le_bytes(bytes.get(32..40)?.try_into().ok()?);
    let word_pos = u128::from_le_bytes(bytes.get(40..56)?.try_into().ok()?);
    if bytes.len() != 56 {
        return None;
    }
    let mut rng = SimRng::from_seed(seed);
    rng.set_stream(stream);
    rng.set_word_pos(word_pos);
    Some(rng)
}

impl Trainer {
    /// Writes the run as it stands, between two steps, to `out` (module docs).
    pub fn write_checkpoint(&self, out: &OutputPath) -> Result<()> {
        self.write_checkpoint_with(out, None)
    }

    /// [`Trainer::write_checkpoint`] with a document of the caller's kept beside the run, in
    /// the same file (so written with it, atomically): what the caller has made of the run so
    /// far, such as the tests it played along the way. [`Trainer::resume_with_note`] gives it
    /// back.
    pub fn write_checkpoint_with(&self, out: &OutputPath, note: Option<&serde_json::Value>) -> Result<()> {
        let blocks = self.config.blocks();
        let learner = &self.learner;
        let mut tensors: Vec<(String, Tensor<'static>)> = Vec::new();
        for (prefix, net) in [("online", learner.online()), ("target", learner.target())] {
            for t in net.tensors() {
                let tensor = Tensor::from_values(t.shape, t.values).expect("a tensor's shape fits its values");
                tensors.push((format!("{prefix}/{}", t.name), tensor));
            }
        }
        let optimizer = learner.optimizer();
        let (first, second) = optimizer.moments();
        tensors.push((
            "optimizer/first".into(),
            Tensor::from_values(&[first.len()], first).expect("a moment a parameter"),
        ));
        if !second.is_empty() {
            tensors.push((
                "optimizer/second".into(),
                Tensor::from_values(&[second.len()], second).expect("a moment a parameter"),
            ));
        }
        tensors.push((
            "optimizer/lr".into(),
            Tensor::from_values(&[1], &[optimizer.lr()]).expect("one value"),
        ));
        tensors.push((
            "rng".into(),
            Tensor::from_values(&[56], &rng_bytes(&self.rng)).expect("56 bytes"),
        ));
        let l = self.last_loss;
        tensors.push((
            "last_loss".into(),
            Tensor::from_values(&[4], &[l.total, l.td, l.n_step, l.margin]).expect("four losses"),
        ));
        let (mut contexts, mut index) = (Vec::new(), HashMap::new());
        let (agent, agent_next) = self.buffer.agent_ring();
        tensors.extend(Columns::of(agent, &mut contexts, &mut index).tensors("agent", blocks));
        tensors.extend(Columns::of(self.buffer.demos(), &mut contexts, &mut index).tensors("demos", blocks));
        if !self.actions.is_empty() {
            let actions: Vec<u8> = self.actions.iter().map(|a| a.index() as u8).collect();
            tensors.push((
                "game".into(),
                Tensor::from_values(&[actions.len()], &actions).expect("one byte an action"),
            ));
        }
        let metadata = Metadata {
            config: StoredConfig::of(&self.config),
            report: self.report(),
            recent: self.recent.iter().copied().collect(),
            target_games: self.target_games,
            corrected: self.corrected,
            gradient_steps: learner.gradient_steps(),
            optimizer_steps: optimizer.steps(),
            agent_next,
            contexts,
            note: note.cloned(),
        };
        let named: Vec<(&str, Tensor<'_>)> = tensors.iter().map(|(n, t)| (n.as_str(), t.clone())).collect();
        files::container::write(out, CHECKPOINT_FORMAT, CHECKPOINT_VERSION, &metadata, &named)?;
        Ok(())
    }

    /// The run a checkpoint file holds, ready to take its next step; an error saying what
    /// is wrong with a file that is not a checkpoint or does not hold a run.
    pub fn resume(path: &Path) -> Result<Trainer> {
        Ok(Trainer::resume_with_note(path)?.0)
    }

    /// The run of `config` a checkpoint file holds; an error if the file holds a run of
    /// other settings.
    pub fn resume_run(path: &Path, config: &DqnConfig) -> Result<Trainer> {
        let trainer = Trainer::resume(path)?;
        if trainer.config() != config {
            return Err(NeuralError::Checkpoint {
                path: path.display().to_string(),
                reason: "it holds a run of other settings".into(),
            });
        }
        Ok(trainer)
    }

    /// [`Trainer::resume`], with the caller's document written with the run, if any
    /// ([`Trainer::write_checkpoint_with`]).
    pub fn resume_with_note(path: &Path) -> Result<(Trainer, Option<serde_json::Value>)> {
        let name = path.display().to_string();
        let input =
            files::open_bounded(path, MAX_CHECKPOINT_BYTES, EXPECT.what).map_err(|e| NeuralError::Checkpoint {
                path: name.clone(),
                reason: read_problem(e),
            })?;
        Trainer::read_noted(input, &name)
    }

    /// [`Trainer::resume`] from the bytes of a checkpoint, named `name` in errors.
    pub fn read_checkpoint(input: impl Read, name: &str) -> Result<Trainer> {
        Ok(Trainer::read_noted(input, name)?.0)
    }

    /// The run and the caller's note a checkpoint's bytes hold.
    fn read_noted(input: impl Read, name: &str) -> Result<(Trainer, Option<serde_json::Value>)> {
        let fail = |reason: String| NeuralError::Checkpoint {
            path: name.to_string(),
            reason,
        };
        let corrupt = |reason: String| fail(format!("the file is corrupt: {reason}"));
        let c = Container::read_from(input, name, &EXPECT).map_err(|e| fail(read_problem(e)))?;
        let meta: Metadata = c
            .metadata()
            .map_err(|e| corrupt(format!("its metadata does not parse ({e})")))?;
        let config = meta.config.config();
        config.validate().map_err(|e| fail(format!("its config: {e}")))?;
        let blocks = config.blocks();

        let learner = read_learner(&c, &config, (meta.optimizer_steps, meta.gradient_steps), &corrupt)?;
        let f32s = |name: &str| -> Result<Vec<f32>> {
            c.tensor(name)
                .ok_or_else(|| corrupt(format!("it has no tensor {name}")))?
                .values::<f32>()
                .ok_or_else(|| corrupt(format!("{name} is not F32")))
        };
        let bytes = |name: &str| -> Result<Vec<u8>> {
            c.tensor(name)
                .ok_or_else(|| corrupt(format!("it has no tensor {name}")))?
                .values::<u8>()
                .ok_or_else(|| corrupt(format!("{name} is not U8")))
        };
        let rng = rng_from(&bytes("rng")?).ok_or_else(|| corrupt("rng is not 56 bytes".into()))?;
        let loss = match f32s("last_loss")?[..] {
            [total, td, n_step, margin] => Losses {
                total,
                td,
                n_step,
                margin,
            },
            _ => return Err(corrupt("last_loss is not four values".into())),
        };
        let contexts = &meta.contexts;
        for context in contexts {
            if context.grid != config.grid() || context.goal.block_count() != blocks {
                return Err(corrupt(format!(
                    "a transition's goal {} on a {} grid is not of the run's world",
                    context.goal, context.grid
                )));
            }
        }
        let read_table = |prefix: &str| -> Result<Vec<Transition>> {
            read_transitions(&c, prefix, contexts, &config).map_err(|e| corrupt(format!("{prefix}: {e}")))
        };
        let buffer = ReplayBuffer::restore(
            config.buffer,
            read_table("agent")?,
            meta.agent_next,
            read_table("demos")?,
        )
        .map_err(corrupt)?;
        if meta.report.demo_transitions != buffer.demo_len() as u64 {
            return Err(corrupt(format!(
                "its totals count {} demonstrated transitions and it holds {}",
                meta.report.demo_transitions,
                buffer.demo_len()
            )));
        }
        if meta.recent.len() > RECENT_GAMES || meta.recent.len() as u64 > meta.report.games {
            return Err(corrupt(format!(
                "it remembers {} recent games of {} played",
                meta.recent.len(),
                meta.report.games
            )));
        }
        if meta.report.gradient_steps != meta.gradient_steps
            || meta.report.pretrain_steps > config.pretrain_steps
            || meta.report.steps > config.steps
        {
            return Err(corrupt("its totals do not fit its run".into()));
        }
        let game = match c.tensor("game") {
            None => Vec::new(),
            Some(_) => bytes("game")?
                .into_iter()
                .map(|a| Action::from_index(a.into(), blocks))
                .collect::<sim::Result<Vec<_>>>()
                .map_err(|e| corrupt(format!("game: {e}")))?,
        };

        let mut trainer = Trainer::assemble(config, learner, buffer, rng, meta.report)?;
        trainer.recent = Recent::of(meta.recent);
        trainer.last_loss = loss;
        trainer.target_games = meta.target_games;
        if !game.is_empty() {
            trainer.replay_game(&game).map_err(|e| corrupt(e.to_string()))?;
        }
        trainer.corrected = meta.corrected;
        Ok((trainer, meta.note))
    }

    /// Puts the game being played back where it was: it begins again and `actions` are
    /// replayed through the steps a trainer takes ([`Trainer::begin_game`],
    /// [`Trainer::take_step`]), which rebuild its environment, n-step window, visited states
    /// and hindsight record as they were.
    fn replay_game(&mut self, actions: &[Action]) -> Result<()> {
        let k = self
            .report
            .games
            .checked_sub(1)
            .ok_or_else(|| NeuralError::Config("a game is being played, and no game has begun".into()))?;
        let (i, mut obs) = self.begin_game(k);
        for (played, &action) in actions.iter().enumerate() {
            self.revisits(&obs);
            // Its finished transitions are in the buffer already.
            let (step, _) = self.take_step(i, obs, action)?;
            if step.terminated || step.truncated {
                return Err(NeuralError::Config(format!(
                    "its game in progress ends at its action {}, before its last",
                    played + 1
                )));
            }
            obs = step.observation;
        }
        self.current = Some((i, obs));
        Ok(())
    }
}

/// The learner a checkpoint holds: its online and target networks and its optimiser, which
/// have taken `steps` (the optimiser's, the learner's gradient steps); `corrupt` makes the
/// error of a file that does not hold them.
fn read_learner(
    c: &Container,
    config: &DqnConfig,
    steps: (u64, u64),
    corrupt: &dyn Fn(String) -> NeuralError,
) -> Result<Learner> {
    let input = config.net.input(config.grid(), config.blocks())?;
    let mut nets = Vec::new();
    for prefix in ["online", "target"] {
        let mut net = QNet::new(config.net, input, &mut sim::seeding::rng(0))?;
        let names: Vec<String> = net.tensors().map(|t| t.name.to_string()).collect();
        for tensor_name in names {
            let full = format!("{prefix}/{tensor_name}");
            let t = c
                .tensor(&full)
                .ok_or_else(|| corrupt(format!("it has no tensor {full}")))?;
            let values = t.values::<f32>().ok_or_else(|| corrupt(format!("{full} is not F32")))?;
            net.set_tensor(&tensor_name, t.shape(), &values)
                .map_err(|e| corrupt(e.to_string()))?;
        }
        nets.push(net);
    }
    let target = nets.pop().expect("two networks");
    let online = nets.pop().expect("two networks");
    let f32s = |name: &str| -> Result<Vec<f32>> {
        c.tensor(name)
            .ok_or_else(|| corrupt(format!("it has no tensor {name}")))?
            .values::<f32>()
            .ok_or_else(|| corrupt(format!("{name} is not F32")))
    };
    let lr = match f32s("optimizer/lr")?[..] {
        [lr] => lr,
        _ => return Err(corrupt("optimizer/lr is not one value".into())),
    };
    let second = match c.tensor("optimizer/second") {
        Some(_) => f32s("optimizer/second")?,
        None => Vec::new(),
    };
    let optimizer = Optimizer::restore(
        config.optimizer,
        online.parameter_count(),
        lr,
        steps.0,
        f32s("optimizer/first")?,
        second,
    )
    .map_err(corrupt)?;
    Ok(Learner::from_parts(online, target, optimizer, steps.1))
}

/// The transitions of table `prefix` (module docs), checked against the run's world.
fn read_transitions(
    c: &Container,
    prefix: &str,
    contexts: &[Context],
    config: &DqnConfig,
) -> std::result::Result<Vec<Transition>, String> {
    let tensor = |name: &str| {
        let full = format!("{prefix}/{name}");
        c.tensor(&full).ok_or_else(|| format!("it has no tensor {full}"))
    };
    let wrong = |name: &str, dtype: &str| format!("{prefix}/{name} is not {dtype}");
    let context = tensor("context")?
        .values::<u32>()
        .ok_or_else(|| wrong("context", "U32"))?;
    let states = tensor("states")?.values::<u8>().ok_or_else(|| wrong("states", "U8"))?;
    let action = tensor("action")?.values::<u8>().ok_or_else(|| wrong("action", "U8"))?;
    let reward = tensor("reward")?
        .values::<f32>()
        .ok_or_else(|| wrong("reward", "F32"))?;
    let n_step_rewards = tensor("n_step_rewards")?
        .values::<f32>()
        .ok_or_else(|| wrong("n_step_rewards", "F32"))?;
    let n_steps = tensor("n_steps")?
        .values::<u32>()
        .ok_or_else(|| wrong("n_steps", "U32"))?;
    let flags = tensor("flags")?.values::<u8>().ok_or_else(|| wrong("flags", "U8"))?;
    let n = context.len();
    let blocks = config.blocks();
    let width = state_width(blocks);
    if [
        action.len(),
        reward.len(),
        n_step_rewards.len(),
        n_steps.len(),
        flags.len(),
    ]
    .iter()
    .any(|&len| len != n)
        || states.len() != n * 3 * width
    {
        return Err("its tensors differ in length".into());
    }
    let state = |bytes: &[u8], grid: Grid| -> std::result::Result<State, String> {
        let held = match bytes[0] {
            NONE_HELD => None,
            b => Some(BlockId(u16::from(b))),
        };
        let cells: Vec<Cell> = bytes[1..]
            .chunks_exact(2)
            .map(|c| Cell::new(u16::from(c[0]), u16::from(c[1])))
            .collect();
        let s = State::new(&cells, held).map_err(|e| e.to_string())?;
        s.check_fits(grid).map_err(|e| e.to_string())?;
        Ok(s)
    };
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let bad = |what: &str| format!("transition {i}: {what}");
        let ctx = contexts
            .get(context[i] as usize)
            .ok_or_else(|| bad("its context is not in the list"))?;
        let rows = &states[i * 3 * width..(i + 1) * 3 * width];
        let mut observations = rows
            .chunks_exact(width)
            .map(|row| state(row, ctx.grid).map(|s| ctx.observation(s)).map_err(|e| bad(&e)));
        let mut take = || observations.next().expect("three states a row");
        let (obs, next, last) = (take()?, take()?, take()?);
        let action = Action::from_index(action[i].into(), blocks).map_err(|e| bad(&e.to_string()))?;
        if flags[i] & !(TERMINAL | N_STEP_TERMINAL | EXPERT) != 0 {
            return Err(bad("its flags are not 1, 2 and 4"));
        }
        if n_steps[i] == 0 || n_steps[i] as usize > config.n_step.max(1) {
            return Err(bad("its n-step window is not 1 to n steps"));
        }
        out.push(Transition {
            obs,
            action,
            reward: reward[i],
            next,
            terminal: flags[i] & TERMINAL != 0,
            n_step: NStepReturn {
                rewards: n_step_rewards[i],
                last,
                steps: n_steps[i],
                terminal: flags[i] & N_STEP_TERMINAL != 0,
            },
            expert: flags[i] & EXPERT != 0,
        });
    }
    Ok(out)
}

fn read_problem(e: FilesError) -> String {
    match e {
        FilesError::Read { problem, .. } => problem.to_string(),
        other => other.to_string(),
    }
}
