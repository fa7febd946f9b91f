//! Training checkpoints: a [`Trainer`] written to a file between two games, and read back
//! to play on exactly as if it had never stopped.
//!
//! A run is fixed by its config and its seed ([`crate::train`](mod@crate::train)): game `k` draws everything
//! from `episode_seed(seed, k)`, and each game's environment is reset from its seed. So
//! what a trainer carries from one game to the next is all a checkpoint needs: the agent
//! (its table, and for `paper-code` the entries it has seen), the totals, the recent
//! games the progress figures look back over, and the replay memory of a run that ends
//! with a final replay. Resumed at game `k` and played to game `n`, a run ends with the
//! same table, bit for bit, as one played from 0 to `n` without stopping.
//!
//! The file is a `files` container (safetensors): format `blockstack-train-checkpoint`,
//! version 1, metadata `{"config":TrainingMeta (the model file's stored run),"report":TrainReport,"recent":[steps or
//! null, ...]}`, and tensors:
//!
//! - `model`, U8: the agent as a model file, byte for byte (write the tensor's bytes out and
//!   any model reader takes them: blockstack's, numpy's, the `safetensors` package's);
//! - for a run with a final replay, the memory's transitions in key order: `memory_keys`
//!   (U64), `memory_columns` (U32), `memory_rewards` (F32) and `memory_next` (U64, the next
//!   key, or `u64::MAX` for a transition that reached the goal).
//!
//! The file is written through the output helper (atomically for a regular file), so a
//! kill while it is written leaves the previous checkpoint whole.

use std::io::Read;
use std::path::Path;

use files::{Container, Expect, FilesError, OutputPath, Tensor};
use serde::{Deserialize, Serialize};

use crate::config::TrainConfig;
use crate::error::{AgentError, Result};
use crate::model::MAX_MODEL_BYTES;
use crate::model::TrainingMeta;
use crate::qlearning::QAgent;
use crate::run::{RECENT_GAMES, Recent};
use crate::train::{TrainReport, Trainer};

/// The `format` of checkpoint files.
pub const CHECKPOINT_FORMAT: &str = "blockstack-train-checkpoint";

/// The checkpoint version this build writes and reads.
pub const CHECKPOINT_VERSION: u32 = 1;

/// Games between two checkpoints unless the caller says otherwise (`train
/// --checkpoint-every`'s default).
pub const DEFAULT_EVERY: u64 = 1000;

/// The largest checkpoint read: a model file at its bound and a replay memory as large.
pub const MAX_CHECKPOINT_BYTES: u64 = 2 * MAX_MODEL_BYTES;

const EXPECT: Expect<'static> = Expect {
    format: CHECKPOINT_FORMAT,
    version: CHECKPOINT_VERSION,
    max_bytes: MAX_CHECKPOINT_BYTES,
    what: "a training checkpoint",
};

/// Marks a remembered transition that reached the goal in `memory_next`.
const GOAL: u64 = u64::MAX;

/// The JSON metadata of a checkpoint (module docs).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Metadata {
    config: TrainingMeta,
    report: TrainReport,
    recent: Vec<Option<u32>>,
}

impl Trainer {
    /// Writes the run as it stands, between two games, to `out` (module docs).
    pub fn write_checkpoint(&self, out: &OutputPath) -> Result<()> {
        let fail = |reason: String| AgentError::Checkpoint {
            path: out.path().display().to_string(),
            reason,
        };
        let model = self.agent.to_bytes().map_err(fail)?;
        let mut tensors = vec![(
            "model",
            Tensor::from_values(&[model.len()], &model).expect("one byte each"),
        )];
        if let Some(memory) = &self.memory {
            let (mut keys, mut columns, mut rewards, mut next) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            memory.for_each(|k, c, r, n| {
                keys.push(k);
                columns.push(c as u32);
                rewards.push(r);
                next.push(n.unwrap_or(GOAL));
            });
            let n = [keys.len()];
            tensors.extend([
                ("memory_keys", Tensor::from_values(&n, &keys).expect("one each")),
                ("memory_columns", Tensor::from_values(&n, &columns).expect("one each")),
                ("memory_rewards", Tensor::from_values(&n, &rewards).expect("one each")),
                ("memory_next", Tensor::from_values(&n, &next).expect("one each")),
            ]);
        }
        let metadata = Metadata {
            config: TrainingMeta::of(&self.config),
            report: self.report,
            recent: self.recent.iter().copied().collect(),
        };
        files::container::write(out, CHECKPOINT_FORMAT, CHECKPOINT_VERSION, &metadata, &tensors)?;
        Ok(())
    }

    /// The run a checkpoint file holds, ready to play its next game; an error saying what
    /// is wrong with a file that is not a checkpoint or does not hold a run.
    pub fn resume(path: &Path) -> Result<Trainer> {
        let name = path.display().to_string();
        let input =
            files::open_bounded(path, MAX_CHECKPOINT_BYTES, EXPECT.what).map_err(|e| AgentError::Checkpoint {
                path: name.clone(),
                reason: read_problem(e),
            })?;
        Trainer::read_checkpoint(input, &name)
    }

    /// The run of `config` a checkpoint file holds, to be played to `config.games` games in
    /// all; an error if the file holds another run (other settings), or has played more
    /// games than that.
    pub fn resume_run(path: &Path, config: &TrainConfig) -> Result<Trainer> {
        let mut trainer = Trainer::resume(path)?;
        let fail = |reason: String| AgentError::Checkpoint {
            path: path.display().to_string(),
            reason,
        };
        let held = TrainConfig {
            games: config.games,
            ..trainer.config().clone()
        };
        if TrainingMeta::of(&held) != TrainingMeta::of(config) {
            return Err(fail("it holds a run of other settings".into()));
        }
        let played = trainer.report().games;
        if played > config.games {
            return Err(fail(format!(
                "its run has played {played} games, more than the {} asked for",
                config.games
            )));
        }
        trainer.set_games(config.games);
        Ok(trainer)
    }

    /// [`Trainer::resume`] from the bytes of a checkpoint, named `name` in errors.
    pub fn read_checkpoint(input: impl Read, name: &str) -> Result<Trainer> {
        let fail = |reason: String| AgentError::Checkpoint {
            path: name.to_string(),
            reason,
        };
        let c = Container::read_from(input, name, &EXPECT).map_err(|e| fail(read_problem(e)))?;
        let meta: Metadata = c
            .metadata()
            .map_err(|e| fail(format!("the file is corrupt: its metadata does not parse ({e})")))?;
        let model = c
            .tensor("model")
            .and_then(|t| t.values::<u8>())
            .ok_or_else(|| fail("the file is corrupt: it has no U8 \"model\" tensor".into()))?;
        let agent = QAgent::read_from(&model[..], name).map_err(|e| match e {
            AgentError::Model { reason, .. } => fail(format!("its model: {reason}")),
            other => fail(other.to_string()),
        })?;
        let mut trainer = Trainer::new(meta.config.config()).map_err(|e| fail(format!("its config: {e}")))?;
        let fresh = &trainer.agent;
        if (
            agent.kind(),
            agent.grid(),
            agent.blocks(),
            agent.params(),
            agent.schedule(),
        ) != (
            fresh.kind(),
            fresh.grid(),
            fresh.blocks(),
            fresh.params(),
            fresh.schedule(),
        ) {
            return Err(fail(
                "the file is corrupt: its model is not the one its config trains".into(),
            ));
        }
        if meta.recent.len() > RECENT_GAMES || meta.recent.len() as u64 > meta.report.games {
            return Err(fail(format!(
                "the file is corrupt: it remembers {} recent games of {} played",
                meta.recent.len(),
                meta.report.games
            )));
        }
        trainer.memory = match (trainer.memory.take(), read_memory(&c, &agent)) {
            (Some(mut memory), Ok(Some(transitions))) => {
                for (k, col, r, n) in transitions {
                    memory.remember(k, col, f64::from(r), n);
                }
                Some(memory)
            }
            (None, Ok(None)) => None,
            (Some(_), Ok(None)) => {
                return Err(fail(
                    "the file is corrupt: its run ends with a final replay, but it has no memory".into(),
                ));
            }
            (None, Ok(Some(_))) => {
                return Err(fail(
                    "the file is corrupt: it has a replay memory its run does not use".into(),
                ));
            }
            (_, Err(reason)) => return Err(fail(format!("the file is corrupt: {reason}"))),
        };
        trainer.agent = agent;
        trainer.report = meta.report;
        trainer.recent = Recent::of(meta.recent);
        Ok(trainer)
    }
}

/// A remembered transition: key, column, reward, next key (`None`: the goal).
type Transition = (u64, usize, f32, Option<u64>);

/// The replay memory's transitions, checked against `agent`'s table; `None` if the file
/// has none.
fn read_memory(c: &Container, agent: &QAgent) -> std::result::Result<Option<Vec<Transition>>, String> {
    let names = ["memory_keys", "memory_columns", "memory_rewards", "memory_next"];
    let tensors: Vec<_> = names.iter().map(|n| c.tensor(n)).collect();
    if tensors.iter().all(Option::is_none) {
        return Ok(None);
    }
    let [Some(keys), Some(columns), Some(rewards), Some(next)] = &tensors[..] else {
        return Err(format!("it has some of the tensors {names:?} but not all"));
    };
    let (Some(keys), Some(columns), Some(rewards), Some(next)) = (
        keys.values::<u64>(),
        columns.values::<u32>(),
        rewards.values::<f32>(),
        next.values::<u64>(),
    ) else {
        return Err("its memory tensors are not U64, U32, F32 and U64".into());
    };
    if [columns.len(), rewards.len(), next.len()]
        .iter()
        .any(|&n| n != keys.len())
    {
        return Err("its memory tensors differ in length".into());
    }
    let (key_count, column_count) = (agent.table().key_count(), agent.table().columns());
    let mut out = Vec::with_capacity(keys.len());
    for i in 0..keys.len() {
        let (k, col, r, n) = (keys[i], columns[i] as usize, rewards[i], next[i]);
        if k >= key_count || col >= column_count || (n != GOAL && n >= key_count) || !r.is_finite() {
            return Err(format!("remembered transition {i} does not fit the table"));
        }
        out.push((k, col, r, (n != GOAL).then_some(n)));
    }
    Ok(Some(out))
}

fn read_problem(e: FilesError) -> String {
    match e {
        FilesError::Read { problem, .. } => problem.to_string(),
        other => other.to_string(),
    }
}
