//! Model files (format version 2): a trained agent as a safetensors file, written
//! atomically, versioned, checksummed, and checked when read.
//!
//! The file is the `files` crate's container (a safetensors file whose `__metadata__`
//! holds `format` = `blockstack-q-agent`, `version` = `2`, a CRC-32 and this module's JSON
//! metadata); its extension is `.safetensors`. numpy, Python's `safetensors` package and
//! candle read it without blockstack (docs/formats.md shows how).
//!
//! # Tensors
//!
//! The table is stored in whichever of two layouts is smaller:
//!
//! - **rows**: `keys`, shape `[rows]`, U32 (U64 when some key does not fit 32 bits), the
//!   keys of the rows that differ from `initial`, increasing; and `values`, shape
//!   `[rows, columns]`, row `i` the values of key `keys[i]`. Every other row is `initial`.
//! - **dense**: `values` alone, shape `[keys, columns]`, row `k` the values of key `k`.
//!
//! `values` has the narrowest dtype that holds every value *exactly*, checked value by
//! value, bit for bit (so `-0.0` is not an integer): I8, then I16, then F16, else F32. A
//! step-cost learner's values are small integers, one byte each.
//!
//! A model of the `paper-code` schedule, whose table remembers which entries were ever
//! written ([`Schedule`]), also has `seen_keys`, shape `[n]`, U32 (U64 when some key does
//! not fit 32 bits), the keys with a seen entry, increasing; and `seen`, shape `[n]`, U32,
//! those keys' seen columns as bits (bit `c` for column `c`). A `spec` model has neither.
//!
//! # Metadata
//!
//! ```text
//! {"grid":{"width":7,"height":7},"blocks":3,"repr":"role",
//!  "params":{"alpha":1.0,"gamma":1.0,"epsilon":0.0,"initial_q":0.0},
//!  "training":{...the training run (`TrainingMeta`), or null...},
//!  "table":{"keys":470596,"columns":8,"initial":0.0}}
//! ```
//!
//! A `paper-code` model's metadata also has `"schedule":"paper-code"` (absent: `spec`).
//!
//! # Checks
//!
//! A reader refuses, each with a message that says which: a file that is not a model
//! (another format, not safetensors), a newer or older version, a corrupt file (a checksum
//! that does not match, metadata that does not parse), a truncated one, a file larger than
//! [`MAX_MODEL_BYTES`], a table whose shape does not fit its representation (checked
//! before anything is allocated), keys out of order or range, values that are not finite,
//! seen entries that a model of its schedule must not have or must have, or that do not fit
//! the table, and a training config that contradicts the model (another representation,
//! block count, grid or schedule; no goals; goals of another block count). A version-1 file (JSON, written by
//! blockstack before this format) is recognised and named as such.
//!
//! # Identity
//!
//! [`QAgent::identity`] names what an agent has learnt: the first 64 bits of a SHA-256 over
//! its representation, world, hyper-parameters, training config, schedule, every table row
//! that differs from the initial value and the seen entries, as 16 hex digits. A saved model loads with the same
//! identity (the file keeps every value exactly), and any change to the table changes it.
//! Demonstration recordings name the identity of the model a session started from, so
//! that a replay can refuse another model.
//!
//! Saving refuses a table holding a value that is not finite: nothing a file keeps could
//! be learnt from it. (Training and correction refuse up front the settings that lead
//! there: [`crate::qlearning::check_fits_table`].)

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use files::{Container, Dtype, Element, Expect, FilesError, OutputPath, Tensor};
use serde::{Deserialize, Serialize};
use sim::{Action, ActionProtocol, Backend, EnvConfig, Goal, GoalSpec, Grid, Profile, RewardModel, StartRule, View};

use crate::assist::{Assist, OracleKind, Oscillation};
use crate::config::TrainConfig;
use crate::error::{AgentError, Result};
use crate::qlearning::{QAgent, QParams};
use crate::qtable::{DENSE_LIMIT, QTable};
use crate::repr::{Repr, ReprKind, Representation};
use crate::schedule::Schedule;

/// The `format` of every model file.
pub const MODEL_FORMAT: &str = "blockstack-q-agent";

/// The model file version this build writes and reads.
pub const MODEL_VERSION: u32 = 2;

/// The extension of model files.
pub const MODEL_EXTENSION: &str = "safetensors";

/// The largest model file read: 1 GiB. A dense table is at most 2^24 values (64 MiB as
/// F32); only a hashed table of tens of millions of rows comes near the bound.
pub const MAX_MODEL_BYTES: u64 = 1 << 30;

const EXPECT: Expect<'static> = Expect {
    format: MODEL_FORMAT,
    version: MODEL_VERSION,
    max_bytes: MAX_MODEL_BYTES,
    what: "a model file",
};

/// The JSON metadata of a model file (module docs).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Metadata {
    grid: Grid,
    blocks: usize,
    repr: ReprKind,
    params: QParams,
    training: Option<TrainingMeta>,
    #[serde(default, skip_serializing_if = "is_spec")]
    schedule: Schedule,
    table: TableMeta,
}

/// A training run as model files (version 2) and checkpoints (version 1) store it: the
/// flat field layout those formats were written with, frozen here, converted explicitly
/// from and to [`TrainConfig`]. The identity of a model ([`QAgent::identity`]) hashes this
/// form, so a regrouping of `TrainConfig` changes neither the files nor the identities
/// that recordings name. Changing this struct is changing the format: bump its version.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainingMeta {
    grid: Grid,
    blocks: usize,
    repr: ReprKind,
    reward: RewardModel,
    params: QParams,
    goals: Vec<Goal>,
    games: u64,
    seed: u64,
    horizon: u32,
    backend: Backend,
    exploring_starts: bool,
    backward_replay: bool,
    final_replay: bool,
    assist: Assist,
    // Absent in files written before profiles existed.
    #[serde(default)]
    profile: Profile,
    #[serde(default)]
    protocol: ActionProtocol,
    #[serde(default)]
    start: StartRule,
    #[serde(default)]
    schedule: Schedule,
    #[serde(default)]
    oracle: OracleKind,
    #[serde(default)]
    oscillation: Oscillation,
    // Absent for the top view (and in files written before the side view existed), so
    // a top-view model's bytes are what they were.
    #[serde(default, skip_serializing_if = "is_top")]
    view: View,
}

impl TrainingMeta {
    /// The stored form of `config`.
    pub fn of(config: &TrainConfig) -> TrainingMeta {
        let w = &config.world;
        TrainingMeta {
            grid: w.grid,
            blocks: w.blocks,
            repr: config.repr,
            reward: w.reward,
            params: config.params,
            goals: config.goals.clone(),
            games: config.games,
            seed: config.seed,
            horizon: w.horizon,
            backend: w.backend,
            exploring_starts: config.exploring_starts,
            backward_replay: config.backward_replay,
            final_replay: config.final_replay,
            assist: config.assist,
            profile: config.profile,
            protocol: w.protocol,
            start: w.start,
            schedule: config.schedule,
            oracle: config.oracle,
            oscillation: config.oscillation,
            view: w.view,
        }
    }

    /// The config this stored form describes (the world's termination is the schedule's,
    /// as it always was).
    pub fn config(self) -> TrainConfig {
        TrainConfig {
            world: EnvConfig {
                grid: self.grid,
                blocks: self.blocks,
                goal: GoalSpec::Random,
                horizon: self.horizon,
                reward: self.reward,
                backend: self.backend,
                protocol: self.protocol,
                start: self.start,
                termination: self.schedule.training_termination(),
                view: self.view,
                ..EnvConfig::default()
            },
            goals: self.goals,
            repr: self.repr,
            params: self.params,
            games: self.games,
            seed: self.seed,
            exploring_starts: self.exploring_starts,
            backward_replay: self.backward_replay,
            final_replay: self.final_replay,
            assist: self.assist,
            profile: self.profile,
            schedule: self.schedule,
            oracle: self.oracle,
            oscillation: self.oscillation,
        }
    }
}

fn is_top(view: &View) -> bool {
    *view == View::Top
}

fn is_spec(schedule: &Schedule) -> bool {
    *schedule == Schedule::Spec
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TableMeta {
    keys: u64,
    columns: usize,
    /// The value of rows not stored, as the f64 equal to the table's f32 (exact, so a load
    /// gives back the same bits).
    initial: f64,
}

/// The dtypes `values` may have, narrowest first.
const VALUE_DTYPES: [Dtype; 4] = [Dtype::I8, Dtype::I16, Dtype::F16, Dtype::F32];

/// Whether the dtype holds `v` exactly, bit for bit.
fn holds(dtype: Dtype, v: f32) -> bool {
    let bits = v.to_bits();
    match dtype {
        Dtype::I8 => f32::from(v as i8).to_bits() == bits,
        Dtype::I16 => f32::from(v as i16).to_bits() == bits,
        Dtype::F16 => half::f16::from_f32(v).to_f32().to_bits() == bits,
        _ => true,
    }
}

/// Bytes per value of the value dtypes.
fn size_of(dtype: Dtype) -> u64 {
    match dtype {
        Dtype::I8 => 1,
        Dtype::I16 | Dtype::F16 => 2,
        _ => 4,
    }
}

/// `values` as a `[rows, columns]` tensor of `dtype` (which holds each exactly).
fn values_tensor(dtype: Dtype, rows: usize, columns: usize, values: &[f32]) -> Tensor<'static> {
    let shape = [rows, columns];
    let tensor = match dtype {
        Dtype::I8 => Tensor::from_values(&shape, &values.iter().map(|&v| v as i8).collect::<Vec<_>>()),
        Dtype::I16 => Tensor::from_values(&shape, &values.iter().map(|&v| v as i16).collect::<Vec<_>>()),
        Dtype::F16 => Tensor::from_values(
            &shape,
            &values.iter().map(|&v| half::f16::from_f32(v)).collect::<Vec<_>>(),
        ),
        _ => Tensor::from_values(&shape, values),
    };
    tensor.expect("rows x columns values")
}

/// A tensor's values as `f32`s, if its dtype is one `values` may have.
fn to_f32(t: &Tensor<'_>) -> Option<Vec<f32>> {
    fn widen<T: Element>(t: &Tensor<'_>, f: impl Fn(T) -> f32) -> Option<Vec<f32>> {
        Some(t.bytes().chunks_exact(T::SIZE).map(|b| f(T::get(b))).collect())
    }
    match t.dtype() {
        Dtype::I8 => widen(t, |v: i8| f32::from(v)),
        Dtype::I16 => widen(t, |v: i16| f32::from(v)),
        Dtype::F16 => widen(t, half::f16::to_f32),
        Dtype::F32 => widen(t, |v: f32| v),
        _ => None,
    }
}

/// The table's tensors (module docs), or the first value that is not finite.
fn table_tensors(table: &QTable) -> std::result::Result<Vec<(&'static str, Tensor<'static>)>, String> {
    let columns = table.columns();
    let written = table.written_rows();
    for &(key, row) in &written {
        if let Some((c, v)) = row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(format!(
                "its table holds {v} (key {key}, column {c}), which is not a finite number: the learning diverged"
            ));
        }
    }
    let initial = table.initial();
    let dtype = *VALUE_DTYPES
        .iter()
        .find(|&&d| holds(d, initial) && written.iter().all(|(_, row)| row.iter().all(|&v| holds(d, v))))
        .expect("F32 holds every value");
    let wide_keys = table.key_count() > 1 << 32;
    let key_bytes = if wide_keys { 8 } else { 4 };
    let rows_bytes = written.len() as u64 * (key_bytes + columns as u64 * size_of(dtype));
    let dense_bytes = table
        .key_count()
        .checked_mul(columns as u64 * size_of(dtype))
        .filter(|&b| b <= rows_bytes);
    if dense_bytes.is_some() {
        let keys = table.key_count() as usize;
        let mut values = Vec::with_capacity(keys * columns);
        for key in 0..keys as u64 {
            values.extend_from_slice(table.row(key));
        }
        return Ok(vec![("values", values_tensor(dtype, keys, columns, &values))]);
    }
    let values: Vec<f32> = written.iter().flat_map(|(_, row)| row.iter().copied()).collect();
    let keys = if wide_keys {
        Tensor::from_values(&[written.len()], &written.iter().map(|&(k, _)| k).collect::<Vec<u64>>())
    } else {
        Tensor::from_values(
            &[written.len()],
            &written.iter().map(|&(k, _)| k as u32).collect::<Vec<u32>>(),
        )
    };
    Ok(vec![
        ("keys", keys.expect("one key per row")),
        ("values", values_tensor(dtype, written.len(), columns, &values)),
    ])
}

/// The seen entries' tensors (module docs), for a table that tracks them.
fn seen_tensors(table: &QTable) -> Vec<(&'static str, Tensor<'static>)> {
    if !table.tracks_seen() {
        return Vec::new();
    }
    let seen = table.seen_entries();
    let n = [seen.len()];
    let keys = if table.key_count() > 1 << 32 {
        Tensor::from_values(&n, &seen.iter().map(|&(k, _)| k).collect::<Vec<u64>>())
    } else {
        Tensor::from_values(&n, &seen.iter().map(|&(k, _)| k as u32).collect::<Vec<u32>>())
    };
    let bits = Tensor::from_values(&n, &seen.iter().map(|&(_, b)| b).collect::<Vec<u32>>());
    vec![
        ("seen_keys", keys.expect("one key per entry")),
        ("seen", bits.expect("one set of bits per key")),
    ]
}

impl QAgent {
    /// Writes the agent to `path` as a model file (module docs), through the output
    /// helper: atomically for a regular file.
    pub fn save(&self, path: &Path) -> Result<()> {
        let out = OutputPath::check(path)?;
        let bytes = self.to_bytes().map_err(|reason| AgentError::ModelSave {
            path: path.display().to_string(),
            reason,
        })?;
        Ok(out.write(&bytes)?)
    }

    /// The bytes of the agent's model file (module docs); an error saying why for a table
    /// no file can keep.
    pub fn to_bytes(&self) -> std::result::Result<Vec<u8>, String> {
        let table = self.table();
        let mut tensors = table_tensors(table)?;
        tensors.extend(seen_tensors(table));
        let metadata = Metadata {
            grid: self.grid(),
            blocks: self.blocks(),
            repr: self.kind(),
            params: *self.params(),
            training: self.training().map(TrainingMeta::of),
            schedule: self.schedule(),
            table: TableMeta {
                keys: table.key_count(),
                columns: table.columns(),
                initial: f64::from(table.initial()),
            },
        };
        files::container::to_bytes(MODEL_FORMAT, MODEL_VERSION, &metadata, &tensors)
    }

    /// The agent's identity (module docs): 16 hex digits.
    pub fn identity(&self) -> String {
        use sha2::{Digest, Sha256};
        let mut hash = Sha256::new();
        let table = self.table();
        let settings = serde_json::to_vec(&(
            self.kind(),
            self.grid(),
            self.blocks(),
            self.params(),
            self.training().map(TrainingMeta::of),
            self.schedule(),
            (table.key_count(), table.columns(), table.initial().to_bits()),
        ))
        .expect("the settings serialise");
        hash.update((settings.len() as u64).to_le_bytes());
        hash.update(&settings);
        let mut bytes = Vec::with_capacity(8 + 4 * table.columns());
        for (key, row) in table.written_rows() {
            bytes.clear();
            bytes.extend_from_slice(&key.to_le_bytes());
            bytes.extend(row.iter().flat_map(|v| v.to_bits().to_le_bytes()));
            hash.update(&bytes);
        }
        // What the paper-code schedule has seen changes what it learns next.
        for (key, bits) in table.seen_entries() {
            hash.update(key.to_le_bytes());
            hash.update(bits.to_le_bytes());
        }
        hash.finalize()[..8].iter().map(|b| format!("{b:02x}")).collect()
    }

    /// Reads an agent from the model file at `path`; an error saying what is wrong if the
    /// file is missing, too large, truncated, corrupt, of another format or version, or
    /// holds a table that does not fit its representation (module docs).
    pub fn load(path: &Path) -> Result<QAgent> {
        let name = path.display().to_string();
        let input = files::open_bounded(path, MAX_MODEL_BYTES, EXPECT.what).map_err(|e| AgentError::Model {
            path: name.clone(),
            reason: read_problem(e),
        })?;
        QAgent::read_from(input, &name)
    }

    /// Reads an agent from the bytes of a model file, named `name` in errors, with the
    /// checks of [`QAgent::load`] (the fuzz target `model_file` feeds it).
    pub fn read_from(input: impl Read, name: &str) -> Result<QAgent> {
        let fail = |reason: String| AgentError::Model {
            path: name.to_string(),
            reason,
        };
        let mut input = BufReader::new(input);
        let starts_json = input
            .fill_buf()
            .map_err(|e| fail(e.to_string()))?
            .first()
            .is_some_and(|&b| b == b'{');
        let container = if starts_json {
            // Perhaps a version-1 model, which was JSON.
            let mut bytes = Vec::new();
            input.read_to_end(&mut bytes).map_err(|e| fail(e.to_string()))?;
            if let Some(version) = json_model_version(&bytes) {
                return Err(fail(format!(
                    "it is a version-{version} model file (JSON), and this blockstack reads version {MODEL_VERSION} \
                     (safetensors) only: train the model again with `blockstack train ... --out MODEL.{MODEL_EXTENSION}` \
                     (the old file's \"training\" field lists the settings it was trained with)"
                )));
            }
            Container::read_from(&bytes[..], name, &EXPECT)
        } else {
            Container::read_from(input, name, &EXPECT)
        };
        QAgent::from_container(&container.map_err(|e| fail(read_problem(e)))?).map_err(|e| match e {
            AgentError::Model { reason, .. } => fail(reason),
            other => fail(other.to_string()),
        })
    }

    /// The agent in a checked container (errors name no path).
    fn from_container(c: &Container) -> Result<QAgent> {
        let fail = |reason: String| AgentError::Model {
            path: String::new(),
            reason,
        };
        let meta: Metadata = c
            .metadata()
            .map_err(|e| fail(format!("the file is corrupt: its metadata does not parse ({e})")))?;
        let t = &meta.table;
        // The shape comes from the representation, not from the file, before anything is
        // allocated.
        let repr = Repr::new(meta.repr, meta.grid, meta.blocks).map_err(|e| fail(e.to_string()))?;
        if t.keys != repr.key_count() || t.columns != Action::count(meta.blocks) {
            return Err(fail(format!(
                "the table has {} keys and {} columns, but a {} table for {} blocks on {} has {} and {}",
                t.keys,
                t.columns,
                meta.repr,
                meta.blocks,
                meta.grid,
                repr.key_count(),
                Action::count(meta.blocks)
            )));
        }
        if let Some(training) = &meta.training {
            check_training(training, &meta).map_err(fail)?;
        }
        let initial = t.initial as f32;
        if f64::from(initial) != t.initial {
            return Err(fail(format!(
                "the file is corrupt: the initial value {} is not a 32-bit float",
                t.initial
            )));
        }
        let corrupt = |what: String| fail(format!("the file is corrupt: {what}"));
        let values = c
            .tensor("values")
            .ok_or_else(|| corrupt("it has no \"values\" tensor".into()))?;
        let [rows, columns] = values.shape() else {
            return Err(corrupt(format!(
                "\"values\" has shape {:?}, not [rows, columns]",
                values.shape()
            )));
        };
        if *columns != t.columns {
            return Err(corrupt(format!("\"values\" has {columns} columns, not {}", t.columns)));
        }
        let keys: Option<Vec<u64>> = match c.tensor("keys") {
            None => None,
            Some(k) if k.shape() != [*rows] => {
                return Err(corrupt(format!(
                    "\"keys\" has shape {:?} and \"values\" {rows} rows",
                    k.shape()
                )));
            }
            Some(k) => Some(
                k.values::<u32>()
                    .map(|v| v.into_iter().map(u64::from).collect())
                    .or_else(|| k.values::<u64>())
                    .ok_or_else(|| corrupt(format!("\"keys\" are {}, not U32 or U64", k.dtype())))?,
            ),
        };
        if keys.is_none() && *rows as u64 != t.keys {
            return Err(corrupt(format!(
                "a dense \"values\" has {rows} rows, and the table {} keys",
                t.keys
            )));
        }
        if let Some(keys) = &keys
            && let Some(i) = (0..keys.len()).find(|&i| keys[i] >= t.keys || (i > 0 && keys[i - 1] >= keys[i]))
        {
            return Err(corrupt(format!(
                "row {i}'s key {} does not fit a table of {} keys in key order",
                keys[i], t.keys
            )));
        }
        let values = to_f32(&values).ok_or_else(|| {
            corrupt(format!(
                "\"values\" are {}, not one of I8, I16, F16, F32",
                values.dtype()
            ))
        })?;
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(corrupt(format!("value {i} is {}, not a finite number", values[i])));
        }
        let dense = t.keys.checked_mul(t.columns as u64).is_some_and(|n| n <= DENSE_LIMIT);
        let table = if keys.is_none() && dense {
            // The file's array is the table's.
            QTable::from_dense(t.keys, t.columns, initial, values)
        } else {
            let mut table = QTable::new(t.keys, t.columns, initial);
            let unwritten = |row: &[f32]| row.iter().all(|v| v.to_bits() == initial.to_bits());
            for (i, row) in values.chunks_exact(t.columns).enumerate() {
                let key = keys.as_ref().map_or(i as u64, |k| k[i]);
                // A hashed table keeps only the rows that differ from the initial one.
                if table.is_dense() || !unwritten(row) {
                    table.row_mut(key).copy_from_slice(row);
                }
            }
            table
        };
        let mut table = table;
        read_seen(c, &meta, &mut table).map_err(corrupt)?;
        QAgent::from_parts(
            meta.repr,
            meta.grid,
            meta.blocks,
            meta.params,
            table,
            meta.training.map(TrainingMeta::config),
            meta.schedule,
        )
    }
}

/// What is wrong with a file that could not be read, without its path (the model error
/// names it).
fn read_problem(e: FilesError) -> String {
    match e {
        FilesError::Read { problem, .. } => problem.to_string(),
        other => other.to_string(),
    }
}

/// Reads the seen entries of a `paper-code` model into `table` (a `spec` model has none);
/// what is wrong with them otherwise.
fn read_seen(c: &Container, meta: &Metadata, table: &mut QTable) -> std::result::Result<(), String> {
    let (keys, bits) = (c.tensor("seen_keys"), c.tensor("seen"));
    let tracks = meta.schedule.tracks_seen();
    let (keys, bits) = match (keys, bits) {
        (None, None) if !tracks => return Ok(()),
        (Some(k), Some(b)) if tracks => (k, b),
        _ if tracks => {
            return Err(format!(
                "a model of the {} schedule lacks its seen entries",
                meta.schedule
            ));
        }
        _ => return Err(format!("a model of the {} schedule has seen entries", meta.schedule)),
    };
    let keys: Vec<u64> = keys
        .values::<u32>()
        .map(|v| v.into_iter().map(u64::from).collect())
        .or_else(|| keys.values::<u64>())
        .ok_or_else(|| format!("\"seen_keys\" are {}, not U32 or U64", keys.dtype()))?;
    let bits: Vec<u32> = bits
        .values::<u32>()
        .ok_or_else(|| format!("\"seen\" are {}, not U32", bits.dtype()))?;
    if keys.len() != bits.len() {
        return Err(format!(
            "\"seen_keys\" has {} entries and \"seen\" {}",
            keys.len(),
            bits.len()
        ));
    }
    table.track_seen();
    let columns = meta.table.columns;
    for (i, (&key, &b)) in keys.iter().zip(&bits).enumerate() {
        if key >= meta.table.keys || (i > 0 && keys[i - 1] >= key) || u64::from(b) >> columns != 0 {
            return Err(format!(
                "seen entry {i} (key {key}, bits {b:#b}) does not fit a table of {} keys and {columns} columns in key order",
                meta.table.keys
            ));
        }
        for column in (0..columns).filter(|c| b & (1 << c) != 0) {
            table.mark_seen(key, column);
        }
    }
    Ok(())
}

/// The training config must describe the model it trained: same representation, block
/// count and grid, and at least one goal, each of the model's block count.
fn check_training(training: &TrainingMeta, meta: &Metadata) -> std::result::Result<(), String> {
    if training.schedule != meta.schedule {
        return Err(format!(
            "the file is inconsistent: the agent learns by the {} schedule, its training config says {}",
            meta.schedule, training.schedule
        ));
    }
    if training.repr != meta.repr || training.blocks != meta.blocks || training.grid != meta.grid {
        return Err(format!(
            "the file is inconsistent: the agent is {} for {} blocks on {}, its training config says {} for {} blocks on {}",
            meta.repr, meta.blocks, meta.grid, training.repr, training.blocks, training.grid
        ));
    }
    if training.goals.is_empty() {
        return Err("the file is inconsistent: its training config lists no goals".into());
    }
    if let Some(goal) = training.goals.iter().find(|g| g.block_count() != meta.blocks) {
        return Err(format!(
            "the file is inconsistent: its training goal {goal} has {} blocks, and the agent {}",
            goal.block_count(),
            meta.blocks
        ));
    }
    Ok(())
}

/// The version of a JSON blockstack model (format 1 was JSON), if `bytes` is one.
fn json_model_version(bytes: &[u8]) -> Option<u64> {
    #[derive(Deserialize)]
    struct Header {
        format: String,
        version: u64,
    }
    serde_json::from_slice::<Header>(bytes)
        .ok()
        .filter(|h| h.format == MODEL_FORMAT)
        .map(|h| h.version)
}
