//! Model files: a trained agent saved as JSON, written atomically, versioned, and checked
//! when read.
//!
//! ```text
//! {"format":"blockstack-q-agent","version":1,
//!  "grid":{"width":7,"height":7},"blocks":3,"repr":"role",
//!  "params":{"alpha":1.0,"gamma":1.0,"epsilon":0.0,"initial_q":0.0},
//!  "training":{...the TrainConfig, or null...},
//!  "table":{"keys":470596,"columns":8,"initial":0.0,
//!           "rows":[[key,[q0,...,q7]],...],"checksum":1234567890}}
//! ```
//!
//! A model of the `paper-code` schedule also has `"schedule":"paper-code"` and, in its
//! table, `"seen":[[key,bits],...]`: the keys with entries ever written and those entries
//! as bits (bit `c` for column `c`), by increasing key. Both are absent for the `spec`
//! schedule, so a SPEC model file is written as before.
//!
//! `rows` holds only the rows that differ from `initial`, by increasing key; values are
//! written as the exact decimal of each `f32`, so a load gives back the same bits.
//! `checksum` is the CRC-32 of every row's key (8 bytes, little-endian) followed by its
//! values (4 bytes each, little-endian), in file order, then (when the table keeps them)
//! every seen entry's key (8 bytes) and bits (4 bytes): a flipped digit anywhere in the
//! table is caught. A reader refuses a file of another format or version, a truncated or
//! corrupt file, and a table that does not fit its representation, each with a message
//! that says which.

use std::path::Path;

use serde::ser::{SerializeTuple, Serializer};
use serde::{Deserialize, Serialize};
use sim::files::{AtomicWriter, write_error};
use sim::{Action, Grid};

use crate::error::{AgentError, Result};
use crate::qlearning::{QAgent, QParams};
use crate::qtable::QTable;
use crate::repr::{Repr, ReprKind, Representation};
use crate::schedule::Schedule;
use crate::train::TrainConfig;

/// The `format` field of every model file.
pub const MODEL_FORMAT: &str = "blockstack-q-agent";

/// The model file version this build writes and reads.
pub const MODEL_VERSION: u32 = 1;

/// Just enough to tell what a file is before reading the rest.
#[derive(Deserialize)]
struct Header {
    format: Option<String>,
    version: Option<u32>,
}

#[derive(Serialize)]
struct ModelOut<'a> {
    format: &'static str,
    version: u32,
    grid: Grid,
    blocks: usize,
    repr: ReprKind,
    params: &'a QParams,
    training: Option<&'a TrainConfig>,
    #[serde(skip_serializing_if = "is_spec")]
    schedule: Schedule,
    table: TableOut<'a>,
}

fn is_spec(schedule: &Schedule) -> bool {
    *schedule == Schedule::Spec
}

#[derive(Serialize)]
struct TableOut<'a> {
    keys: u64,
    columns: usize,
    initial: f64,
    rows: Vec<RowOut<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    seen: Option<Vec<(u64, u32)>>,
    checksum: u32,
}

/// One row, written `[key, [values...]]`, values as the f64 equal to each f32 (exact, and
/// read back to the same f32 whatever the decimal parser's last-digit rounding).
struct RowOut<'a>(u64, &'a [f32]);

impl Serialize for RowOut<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(2)?;
        t.serialize_element(&self.0)?;
        t.serialize_element(&Values(self.1))?;
        t.end()
    }
}

struct Values<'a>(&'a [f32]);

impl Serialize for Values<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.collect_seq(self.0.iter().map(|&v| f64::from(v)))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelIn {
    #[allow(dead_code, reason = "checked by the header pass")]
    format: String,
    #[allow(dead_code, reason = "checked by the header pass")]
    version: u32,
    grid: Grid,
    blocks: usize,
    repr: ReprKind,
    params: QParams,
    training: Option<TrainConfig>,
    #[serde(default)]
    schedule: Schedule,
    table: TableIn,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TableIn {
    keys: u64,
    columns: usize,
    initial: f32,
    rows: Vec<(u64, Vec<f32>)>,
    #[serde(default)]
    seen: Option<Vec<(u64, u32)>>,
    checksum: u32,
}

/// The CRC-32 of the rows, as the module documentation defines it.
fn checksum<'a>(rows: impl Iterator<Item = (u64, &'a [f32])>, seen: Option<&[(u64, u32)]>) -> u32 {
    let mut h = crc32fast::Hasher::new();
    for (key, values) in rows {
        h.update(&key.to_le_bytes());
        for v in values {
            h.update(&v.to_le_bytes());
        }
    }
    // Then each seen entry's key and bits, when the table keeps them.
    for &(key, bits) in seen.into_iter().flatten() {
        h.update(&key.to_le_bytes());
        h.update(&bits.to_le_bytes());
    }
    h.finalize()
}

impl QAgent {
    /// Writes the agent to `path` as a model file, atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        let table = self.table();
        let written = table.written_rows();
        let seen = table.tracks_seen().then(|| table.seen_entries());
        let model = ModelOut {
            format: MODEL_FORMAT,
            version: MODEL_VERSION,
            grid: self.grid(),
            blocks: self.blocks(),
            repr: self.kind(),
            params: self.params(),
            training: self.training(),
            schedule: self.schedule(),
            table: TableOut {
                keys: table.key_count(),
                columns: table.columns(),
                initial: f64::from(table.initial()),
                checksum: checksum(written.iter().copied(), seen.as_deref()),
                rows: written.into_iter().map(|(k, r)| RowOut(k, r)).collect(),
                seen,
            },
        };
        let mut out = AtomicWriter::create(path)?;
        serde_json::to_writer(&mut out, &model).map_err(|e| write_error(path, &e))?;
        out.commit()?;
        Ok(())
    }

    /// Reads an agent from the model file at `path`; an error saying what is wrong if the
    /// file is missing, truncated, corrupt, of another format or version, or holds a table
    /// that does not fit its representation.
    pub fn load(path: &Path) -> Result<QAgent> {
        let fail = |reason: String| AgentError::Model {
            path: path.display().to_string(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| fail(e.to_string()))?;
        QAgent::from_model_text(&text).map_err(|e| match e {
            AgentError::Model { reason, .. } => fail(reason),
            other => fail(other.to_string()),
        })
    }

    /// Reads an agent from the text of a model file (errors name no path).
    fn from_model_text(text: &str) -> Result<QAgent> {
        let fail = |reason: String| AgentError::Model {
            path: String::new(),
            reason,
        };
        let json_error = |e: serde_json::Error| {
            fail(match e.classify() {
                serde_json::error::Category::Eof => format!("the file is truncated ({e})"),
                serde_json::error::Category::Io | serde_json::error::Category::Syntax => {
                    format!("the file is corrupt, not valid JSON ({e})")
                }
                serde_json::error::Category::Data => format!("the file is corrupt ({e})"),
            })
        };
        let header: Header = serde_json::from_str(text).map_err(json_error)?;
        match (header.format.as_deref(), header.version) {
            (Some(MODEL_FORMAT), Some(MODEL_VERSION)) => {}
            (Some(MODEL_FORMAT), Some(v)) => {
                return Err(fail(format!(
                    "it is model format version {v}, and this blockstack reads version {MODEL_VERSION}"
                )));
            }
            (Some(MODEL_FORMAT), None) => return Err(fail("the file is corrupt (it has no version)".into())),
            _ => {
                return Err(fail(format!(
                    "it is not a blockstack model file (no \"format\": \"{MODEL_FORMAT}\")"
                )));
            }
        }
        let model: ModelIn = serde_json::from_str(text).map_err(json_error)?;
        let t = model.table;
        if checksum(t.rows.iter().map(|(k, r)| (*k, &r[..])), t.seen.as_deref()) != t.checksum {
            return Err(fail(
                "the table does not match its checksum: the file is corrupt".into(),
            ));
        }
        // The shape comes from the representation, not from the file, before anything is
        // allocated.
        let repr = Repr::new(model.repr, model.grid, model.blocks).map_err(|e| fail(e.to_string()))?;
        if t.keys != repr.key_count() || t.columns != Action::count(model.blocks) {
            return Err(fail(format!(
                "the table has {} keys and {} columns, but a {} table for {} blocks on {} has {} and {}",
                t.keys,
                t.columns,
                model.repr,
                model.blocks,
                model.grid,
                repr.key_count(),
                Action::count(model.blocks)
            )));
        }
        if t.seen.is_some() != model.schedule.tracks_seen() {
            return Err(fail(format!(
                "the file is inconsistent: a model of the {} schedule {} its seen entries",
                model.schedule,
                if t.seen.is_some() { "does not keep" } else { "must keep" }
            )));
        }
        let mut table = if model.schedule.tracks_seen() {
            QTable::tracking_seen(t.keys, t.columns, t.initial)
        } else {
            QTable::new(t.keys, t.columns, t.initial)
        };
        let mut previous = None;
        for (key, values) in &t.rows {
            if *key >= t.keys || values.len() != t.columns || previous.is_some_and(|p| p >= *key) {
                return Err(fail(format!(
                    "the table is corrupt: row {key} does not fit a table of {} keys and {} columns in key order",
                    t.keys, t.columns
                )));
            }
            table.row_mut(*key).copy_from_slice(values);
            previous = Some(*key);
        }
        let mut previous = None;
        for &(key, bits) in t.seen.iter().flatten() {
            if key >= t.keys || bits >> t.columns != 0 || previous.is_some_and(|p| p >= key) {
                return Err(fail(format!(
                    "the table is corrupt: seen entries {bits:#b} of key {key} do not fit a table of {} keys and {} columns in key order",
                    t.keys, t.columns
                )));
            }
            for c in 0..t.columns {
                if bits & (1 << c) != 0 {
                    table.mark_seen(key, c);
                }
            }
            previous = Some(key);
        }
        if let Some(training) = &model.training {
            if training.schedule != model.schedule {
                return Err(fail(format!(
                    "the file is inconsistent: the agent learns by the {} schedule, its training config says {}",
                    model.schedule, training.schedule
                )));
            }
            if training.repr != model.repr || training.blocks != model.blocks || training.grid != model.grid {
                return Err(fail(format!(
                    "the file is inconsistent: the agent is {} for {} blocks on {}, its training config says {} for {} blocks on {}",
                    model.repr, model.blocks, model.grid, training.repr, training.blocks, training.grid
                )));
            }
        }
        QAgent::from_parts(
            model.repr,
            model.grid,
            model.blocks,
            model.params,
            table,
            model.training,
            model.schedule,
        )
    }
}
