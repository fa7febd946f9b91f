//! The participants a server holds, and those its recording folder remembers.
//!
//! A server may be restarted on the same `--record-dir` (after a crash, a kill, a new
//! day): participant numbers, the study's cap and the balance of conditions go on from the
//! recordings on disk, read at start-up from each recording's session line, so that no two
//! people share a number and a study capped at 40 takes 40 in all. Sessions live in memory
//! only while they are used: one with no page connected for [`Limits::session_idle`] is
//! let go (its recording stays on disk), so `--max-sessions` bounds the sessions held at
//! once, not the joins since start.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use agent::DemoWriter;
use agent::demos::{DemoRecord, ParticipantLine};
use files::OutputPath;
use serde::Serialize;

use crate::config::{Condition, Limits};
use crate::participant::{Participant, Recorder};
use crate::protocol::{Mode, Progress};

/// Locks `m`, going on after a panic elsewhere (the state stays consistent: every change
/// under a lock is one assignment or a whole message's work).
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Messages a session may still send now: refilled at the limit's rate up to one
/// second's worth.
pub(crate) struct Bucket {
    tokens: f64,
    last: Instant,
}

impl Bucket {
    /// A full bucket of `rate` messages.
    pub(crate) fn full(rate: u32) -> Self {
        Bucket {
            tokens: f64::from(rate),
            last: Instant::now(),
        }
    }

    /// Takes one message's token, if there is one.
    pub(crate) fn take(&mut self, rate: u32) -> bool {
        let now = Instant::now();
        let rate = f64::from(rate);
        self.tokens = (self.tokens + now.duration_since(self.last).as_secs_f64() * rate).min(rate);
        self.last = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

/// A participant's session while it is held: the state machine and its rate bucket.
pub(crate) struct Live {
    pub(crate) participant: Participant,
    pub(crate) bucket: Bucket,
}

/// One participant's place on the server.
pub(crate) struct Slot {
    pub(crate) number: u64,
    pub(crate) name: Option<String>,
    pub(crate) condition: String,
    pub(crate) recording: Option<String>,
    /// A page is connected (one at a time): the id of its connection, 0 for none.
    pub(crate) page: Mutex<u64>,
    /// Set when the session is let go.
    pub(crate) expired: AtomicBool,
    /// When a page last connected, sent a message or went away.
    pub(crate) last_active: Mutex<Instant>,
    /// The session, while it is held; its last totals once it is let go.
    pub(crate) state: Mutex<SlotState>,
}

/// A session held, or the totals it ended with.
pub(crate) enum SlotState {
    /// Held in memory.
    Live(Box<Live>),
    /// Let go after [`Limits::session_idle`] without a page: what the researcher's page
    /// still shows of it.
    Expired {
        /// The mode it was in.
        mode: Mode,
        /// Whether every episode asked for was done.
        done: bool,
        /// Its totals.
        progress: Progress,
    },
}

impl Slot {
    /// Marks the session as used now.
    pub(crate) fn touch(&self) {
        *lock(&self.last_active) = Instant::now();
    }

    /// Whether a page is connected.
    pub(crate) fn is_connected(&self) -> bool {
        *lock(&self.page) != 0
    }

    /// The researcher's page's row.
    pub(crate) fn row(&self) -> SessionRow {
        let (mode, done, progress) = match &*lock(&self.state) {
            SlotState::Live(live) => {
                let p = &live.participant;
                (p.mode(), p.is_done(), p.view(None).progress)
            }
            SlotState::Expired { mode, done, progress } => (*mode, *done, progress.clone()),
        };
        SessionRow {
            number: self.number,
            name: self.name.clone(),
            condition: self.condition.clone(),
            mode,
            connected: self.is_connected(),
            held: !self.expired.load(Ordering::SeqCst),
            done,
            recording: self.recording.clone(),
            progress,
        }
    }
}

/// One participant on the researcher's page.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct SessionRow {
    pub(crate) number: u64,
    pub(crate) name: Option<String>,
    pub(crate) condition: String,
    pub(crate) mode: Mode,
    pub(crate) connected: bool,
    /// Whether the session is still held in memory (else it was let go, idle).
    pub(crate) held: bool,
    pub(crate) done: bool,
    pub(crate) recording: Option<String>,
    pub(crate) progress: Progress,
}

/// Why a participant could not join.
#[derive(Debug)]
pub(crate) enum JoinRefused {
    /// A participant code that is not a name.
    BadName(String),
    /// The server holds `--max-sessions` sessions, or the study has all its participants.
    Full(String),
    /// The recording could not be opened (the folder is gone, the disk is full).
    Failed(String),
}

/// The participants: those held, those of this run, and the counts the folder remembers.
pub(crate) struct Registry {
    live: HashMap<String, Arc<Slot>>,
    /// Every session of this run, in order of arrival, for the researcher's page.
    all: Vec<Arc<Slot>>,
    /// The number the next participant gets: one past the highest on disk or given.
    next_number: u64,
    /// Participants per condition, on disk and of this run: the balance.
    assigned: Vec<u64>,
    /// Participants admitted in all, on disk and of this run: the study's cap counts them.
    admitted: u64,
}

impl Registry {
    /// The registry of a server whose recordings go to `record_dir`, with `conditions`:
    /// numbering, balance and the count admitted go on from the recordings there.
    pub(crate) fn new(record_dir: Option<&Path>, conditions: &[Arc<Condition>]) -> Registry {
        let mut registry = Registry {
            live: HashMap::new(),
            all: Vec::new(),
            next_number: 0,
            assigned: vec![0; conditions.len()],
            admitted: 0,
        };
        if let Some(dir) = record_dir {
            for found in recordings_in(dir) {
                registry.next_number = registry.next_number.max(found.number + 1);
                registry.admitted += 1;
                let condition = found
                    .participant
                    .as_ref()
                    .and_then(|p| conditions.iter().position(|c| c.name == p.condition));
                if let Some(i) = condition {
                    registry.assigned[i] += 1;
                }
            }
        }
        registry
    }

    /// Participants admitted in all (on disk and of this run).
    pub(crate) fn admitted(&self) -> u64 {
        self.admitted
    }

    /// The session of `token`, while it is held.
    pub(crate) fn find(&self, token: &str) -> Option<Arc<Slot>> {
        self.live.get(token).cloned()
    }

    /// Every session of this run, in order of arrival.
    pub(crate) fn all(&self) -> Vec<Arc<Slot>> {
        self.all.clone()
    }

    /// A new participant in the condition with the fewest participants so far (the first
    /// of those on a tie), recording into `record_dir`: its token. The session (its agent,
    /// its first episode, the shortest plan of its start) is made here, so this runs off
    /// the async workers.
    pub(crate) fn join(
        registry: &Mutex<Registry>,
        conditions: &[Arc<Condition>],
        record_dir: Option<&Path>,
        limits: &Limits,
        max_participants: Option<u64>,
        name: Option<String>,
    ) -> Result<String, JoinRefused> {
        if let Some(n) = &name {
            crate::config::check_name(n).map_err(|e| JoinRefused::BadName(format!("participant name: {e}")))?;
        }
        // The number, condition and recording are taken under the lock; the session, which
        // may take long to begin, is made outside it.
        let (number, index, writer, recording) = {
            let mut r = lock(registry);
            if r.live.len() >= limits.max_sessions {
                return Err(JoinRefused::Full(format!(
                    "this server holds at most {} sessions at once, and has them all: try again later",
                    limits.max_sessions
                )));
            }
            if let Some(max) = max_participants.filter(|&max| r.admitted >= max) {
                return Err(JoinRefused::Full(format!(
                    "this study takes {max} participants, and has them all: thank you for your interest"
                )));
            }
            let index = (0..conditions.len())
                .min_by_key(|&i| (r.assigned[i], i))
                .expect("a server has a condition");
            let condition = &conditions[index];
            let (number, writer, recording) = match record_dir {
                None => (r.next_number, None, None),
                Some(dir) => {
                    let (number, path, file) = recording_path(dir, r.next_number, &condition.name, name.as_deref());
                    let out = OutputPath::check(&path).map_err(|e| JoinRefused::Failed(e.to_string()))?;
                    let writer = DemoWriter::append(&out).map_err(|e| JoinRefused::Failed(e.to_string()))?;
                    (number, Some(writer), Some(file))
                }
            };
            r.next_number = number + 1;
            r.assigned[index] += 1;
            r.admitted += 1;
            (number, index, writer, recording)
        };
        let condition = conditions[index].clone();
        let who = ParticipantLine {
            number,
            condition: condition.name.clone(),
            code: name.clone(),
        };
        let participant = Participant::new(condition.clone(), Recorder::new(writer), Some(who))
            .map_err(|e| JoinRefused::Failed(e.to_string()))?;
        let token = new_token();
        let slot = Arc::new(Slot {
            number,
            name,
            condition: condition.name.clone(),
            recording,
            page: Mutex::new(0),
            expired: AtomicBool::new(false),
            last_active: Mutex::new(Instant::now()),
            state: Mutex::new(SlotState::Live(Box::new(Live {
                participant,
                bucket: Bucket::full(limits.actions_per_second),
            }))),
        });
        let mut r = lock(registry);
        r.live.insert(token.clone(), slot.clone());
        r.all.push(slot);
        Ok(token)
    }

    /// Lets go of every session with no page connected that was last used more than
    /// `limits.session_idle` ago; how many.
    pub(crate) fn expire_idle(registry: &Mutex<Registry>, limits: &Limits) -> usize {
        let idle: Vec<(String, Arc<Slot>)> = lock(registry)
            .live
            .iter()
            .filter(|(_, slot)| !slot.is_connected() && lock(&slot.last_active).elapsed() >= limits.session_idle)
            .map(|(t, s)| (t.clone(), s.clone()))
            .collect();
        for (token, slot) in &idle {
            lock(registry).live.remove(token);
            slot.expired.store(true, Ordering::SeqCst);
            let mut state = lock(&slot.state);
            if let SlotState::Live(live) = &*state {
                let p = &live.participant;
                let expired = SlotState::Expired {
                    mode: p.mode(),
                    done: p.is_done(),
                    progress: p.view(None).progress,
                };
                *state = expired;
            }
        }
        idle.len()
    }
}

/// A fresh token: 128 bits from the operating system's generator, as 32 hex digits
/// (`server`'s module docs say why this is not seeded).
pub(crate) fn new_token() -> String {
    use rand::RngExt;
    format!("{:032x}", rand::rng().random::<u128>())
}

/// The recording of participant `number` (or the first number after it whose file name is
/// free) under `dir`: `pNNNN-CONDITION[-NAME].jsonl`; its number, path and file name. An
/// earlier run's recordings are never appended to. Every part is checked to be a plain
/// name, so the path stays in `dir`.
pub(crate) fn recording_path(dir: &Path, number: u64, condition: &str, name: Option<&str>) -> (u64, PathBuf, String) {
    let mut n = number;
    loop {
        let file = match name {
            Some(name) => format!("p{n:04}-{condition}-{name}.jsonl"),
            None => format!("p{n:04}-{condition}.jsonl"),
        };
        let path = dir.join(&file);
        if std::fs::symlink_metadata(&path).is_err() {
            return (n, path, file);
        }
        n += 1;
    }
}

/// A recording found in a record folder.
pub(crate) struct FoundRecording {
    /// The participant number of its file name.
    pub(crate) number: u64,
    /// The participant its first session line names (none in a recording made before
    /// participants were named, or one whose first line cannot be read).
    pub(crate) participant: Option<ParticipantLine>,
}

/// The participants' recordings in `dir`: the regular files named `pNNNN-*.jsonl`, each
/// with the participant its session line names. Other files are left alone.
pub(crate) fn recordings_in(dir: &Path) -> Vec<FoundRecording> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut found: Vec<FoundRecording> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let rest = name.strip_prefix('p')?.strip_suffix(".jsonl")?;
            let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
            if digits.is_empty() || !rest[digits.len()..].starts_with('-') {
                return None;
            }
            let number = digits.parse().ok()?;
            let participant = first_session(&e.path()).and_then(|s| s.participant);
            Some(FoundRecording { number, participant })
        })
        .collect();
    found.sort_by_key(|f| f.number);
    found
}

/// The session line that opens the recording at `path`, if its first line is one.
fn first_session(path: &Path) -> Option<agent::demos::SessionLine> {
    let file = files::open_bounded(path, agent::demos::MAX_RECORDING_BYTES, "a recording").ok()?;
    let mut line = Vec::new();
    sim::trajectory::read_bounded_line(&mut std::io::BufReader::new(file), &mut line).ok()?;
    match serde_json::from_slice::<DemoRecord>(line.trim_ascii()).ok()? {
        DemoRecord::Session(s) => Some(s),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bucket_allows_a_seconds_worth_then_refills() {
        let mut b = Bucket::full(5);
        assert_eq!((0..10).filter(|_| b.take(5)).count(), 5);
        b.last -= std::time::Duration::from_millis(400);
        assert_eq!((0..10).filter(|_| b.take(5)).count(), 2);
    }

    #[test]
    fn tokens_are_fresh_128_bit_hex() {
        let (a, b) = (new_token(), new_token());
        assert_eq!(a.len(), 32);
        assert!(a.bytes().all(|c| c.is_ascii_hexdigit()));
        assert_ne!(a, b);
    }

    #[test]
    fn a_recording_never_reuses_a_name_and_stays_in_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        let (_, path, file) = recording_path(dir.path(), 3, "c", Some("P1"));
        assert_eq!(file, "p0003-c-P1.jsonl");
        assert_eq!(path.parent().unwrap(), dir.path());
        std::fs::write(&path, "").unwrap();
        assert_eq!(recording_path(dir.path(), 3, "c", Some("P1")).2, "p0004-c-P1.jsonl");
    }
}
