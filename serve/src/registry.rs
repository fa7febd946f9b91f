//! The participants a server holds, and those its recording folder remembers.
//!
//! A server may be restarted on the same `--record-dir` (after a crash, a kill, a new
//! day): participant numbers, the study's cap and the balance of conditions go on from the
//! recordings on disk, read at start-up from each recording's session line, so that no two
//! people share a number and a study capped at 40 takes 40 in all. Sessions live in memory
//! only while they are used: one with no page connected for [`Limits::session_idle`] is
//! let go (its recording stays on disk), so `--max-sessions` bounds the sessions held at
//! once, not the joins since start.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use agent::DemoWriter;
use agent::demos::{DemoRecord, ParticipantLine, WithdrawnLine, unix_ms};
use files::OutputPath;
use serde::Serialize;

use crate::config::{Condition, Limits, StudyPath, Withdrawal};
use crate::participant::{Participant, Recorder, Resumed};
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
    /// The platform's id of the participant (the study's first `participant_ids`).
    pub(crate) id: Option<String>,
    pub(crate) condition: String,
    /// The recording's file name in the record folder.
    pub(crate) recording: Option<String>,
    /// The session's token.
    pub(crate) token: String,
    /// A page is connected (one at a time): the id of its connection, 0 for none.
    pub(crate) page: Mutex<u64>,
    /// Set when the session is let go (idle) or withdrawn.
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
    /// Let go after [`Limits::session_idle`] without a page, or withdrawn: what the
    /// researcher's page still shows of it.
    Expired {
        /// The mode it was in.
        mode: Mode,
        /// Whether every episode asked for was done.
        done: bool,
        /// Its totals.
        progress: Progress,
        /// The participant withdrew.
        withdrawn: bool,
    },
}

impl SlotState {
    fn ended(participant: &Participant, withdrawn: bool) -> SlotState {
        SlotState::Expired {
            mode: participant.mode(),
            done: participant.is_done(),
            progress: participant.view(None).progress,
            withdrawn,
        }
    }
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
        let (mode, done, progress, withdrawn) = match &*lock(&self.state) {
            SlotState::Live(live) => {
                let p = &live.participant;
                (p.mode(), p.is_done(), p.view(None).progress, false)
            }
            SlotState::Expired {
                mode,
                done,
                progress,
                withdrawn,
            } => (*mode, *done, progress.clone(), *withdrawn),
        };
        SessionRow {
            number: self.number,
            name: self.name.clone(),
            id: self.id.clone(),
            condition: self.condition.clone(),
            mode,
            connected: self.is_connected(),
            held: !self.expired.load(Ordering::SeqCst),
            done,
            withdrawn,
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
    /// The platform's id.
    pub(crate) id: Option<String>,
    pub(crate) condition: String,
    pub(crate) mode: Mode,
    pub(crate) connected: bool,
    /// Whether the session is still held in memory (else it was let go, idle).
    pub(crate) held: bool,
    pub(crate) done: bool,
    pub(crate) withdrawn: bool,
    pub(crate) recording: Option<String>,
    pub(crate) progress: Progress,
}

/// Why a participant could not join.
#[derive(Debug)]
pub(crate) enum JoinRefused {
    /// A participant code, an id or a consent that is not what the study takes.
    BadRequest(String),
    /// The server holds `--max-sessions` sessions, or the study has all its participants.
    Full(String),
    /// The participant withdrew from this study.
    Withdrawn,
    /// The recording could not be opened or read (the folder is gone, the disk is full).
    Failed(String),
}

/// What a server seats participants with: its conditions, recording folder, bounds and
/// study path.
pub(crate) struct Seating {
    pub(crate) conditions: Vec<Arc<Condition>>,
    pub(crate) record_dir: Option<PathBuf>,
    pub(crate) limits: Limits,
    pub(crate) max_participants: Option<u64>,
    pub(crate) study: Arc<StudyPath>,
}

/// Who asks to join: the code typed, the platform's ids from the URL, and whether consent
/// was given.
#[derive(Clone, Debug, Default)]
pub(crate) struct Arrival {
    pub(crate) name: Option<String>,
    pub(crate) ids: BTreeMap<String, String>,
    pub(crate) consent: bool,
}

/// A participant the record folder or this run knows by their platform id.
#[derive(Clone)]
struct Known {
    number: u64,
    condition: String,
    path: PathBuf,
    ids: BTreeMap<String, String>,
    name: Option<String>,
    withdrawn: bool,
    /// Their session is being begun (by a join not yet done).
    pending: bool,
    /// Their session, when this run has made one.
    slot: Option<Arc<Slot>>,
}

/// The participants: those held, those of this run, and the counts the folder remembers.
pub(crate) struct Registry {
    live: HashMap<String, Arc<Slot>>,
    /// Every session of this run, in order of arrival, for the researcher's page.
    all: Vec<Arc<Slot>>,
    /// Participants by their platform id (the study's first `participant_ids`).
    by_id: HashMap<String, Known>,
    /// The number the next participant gets: one past the highest on disk or given.
    next_number: u64,
    /// Participants per condition, on disk and of this run, withdrawn ones left out: the
    /// balance.
    assigned: Vec<u64>,
    /// Participants admitted in all, on disk and of this run, withdrawn ones left out: the
    /// study's cap counts them.
    admitted: u64,
}

impl Registry {
    /// The registry of a server seating by `seating`: numbering, balance, the count
    /// admitted and the participants known by id go on from the recordings in its folder.
    pub(crate) fn new(seating: &Seating) -> Registry {
        let mut registry = Registry {
            live: HashMap::new(),
            all: Vec::new(),
            by_id: HashMap::new(),
            next_number: 0,
            assigned: vec![0; seating.conditions.len()],
            admitted: 0,
        };
        let Some(dir) = &seating.record_dir else {
            return registry;
        };
        let primary = seating.study.participant_ids.first();
        for found in recordings_in(dir) {
            registry.next_number = registry.next_number.max(found.number + 1);
            let Some(p) = &found.participant else {
                registry.admitted += u64::from(!found.withdrawn);
                continue;
            };
            if !found.withdrawn {
                registry.admitted += 1;
                if let Some(i) = seating.conditions.iter().position(|c| c.name == p.condition) {
                    registry.assigned[i] += 1;
                }
            }
            if let Some(id) = primary.and_then(|key| p.ids.get(key)) {
                registry.by_id.insert(
                    id.clone(),
                    Known {
                        number: found.number,
                        condition: p.condition.clone(),
                        path: found.path.clone(),
                        ids: p.ids.clone(),
                        name: p.code.clone(),
                        withdrawn: found.withdrawn,
                        pending: false,
                        slot: None,
                    },
                );
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

    /// The token of the session of a participant who returns with the platform id of
    /// `arrival`, resumed from their recording when this run holds it no more; `None` for
    /// a participant not known.
    pub(crate) fn returning(
        registry: &Mutex<Registry>,
        seating: &Seating,
        arrival: &Arrival,
    ) -> Result<Option<String>, JoinRefused> {
        let Some(id) = primary_id(seating, arrival) else {
            return Ok(None);
        };
        let known = lock(registry).by_id.get(&id).cloned();
        let Some(known) = known else {
            return Ok(None);
        };
        if known.withdrawn {
            return Err(JoinRefused::Withdrawn);
        }
        if known.pending {
            return Err(JoinRefused::Full(
                "this participant's session is being begun in another window: reload this page".into(),
            ));
        }
        if let Some(slot) = known.slot.as_ref().filter(|s| !s.expired.load(Ordering::SeqCst)) {
            return Ok(Some(slot.token.clone()));
        }
        // Let go or from an earlier run: the recording is taken up again.
        let index = seating
            .conditions
            .iter()
            .position(|c| c.name == known.condition)
            .ok_or_else(|| {
                JoinRefused::Failed(format!(
                    "the recording of this participant is of the condition {}, which this study no longer has",
                    known.condition
                ))
            })?;
        {
            let mut r = lock(registry);
            if r.live.len() >= seating.limits.max_sessions {
                return Err(full_now(&seating.limits));
            }
            match r.by_id.get_mut(&id) {
                Some(k) if !k.pending => k.pending = true,
                _ => {
                    return Err(JoinRefused::Full(
                        "this participant's session is being begun in another window: reload this page".into(),
                    ));
                }
            }
        }
        let resumed = Self::resume(seating, &known, index, &id);
        let mut r = lock(registry);
        let k = r.by_id.get_mut(&id).expect("known above");
        k.pending = false;
        let slot = resumed?;
        k.slot = Some(slot.clone());
        r.live.insert(slot.token.clone(), slot.clone());
        r.all.push(slot.clone());
        Ok(Some(slot.token.clone()))
    }

    /// The session of `known` (in condition `index`, platform id `id`) taken up again
    /// from its recording.
    fn resume(seating: &Seating, known: &Known, index: usize, id: &str) -> Result<Arc<Slot>, JoinRefused> {
        let condition = seating.conditions[index].clone();
        let resumed = resume_from(&condition, &known.path).map_err(JoinRefused::Failed)?;
        let writer =
            DemoWriter::append(&OutputPath::check(&known.path).map_err(|e| JoinRefused::Failed(e.to_string()))?)
                .map_err(|e| JoinRefused::Failed(e.to_string()))?;
        let who = ParticipantLine {
            number: known.number,
            condition: condition.name.clone(),
            code: known.name.clone(),
            ids: known.ids.clone(),
        };
        let participant = Participant::new(
            condition.clone(),
            seating.study.clone(),
            Recorder::new(Some(writer)),
            Some(who),
            Some(resumed),
        )
        .map_err(|e| JoinRefused::Failed(e.to_string()))?;
        let file = known.path.file_name().map(|f| f.to_string_lossy().into_owned());
        Ok(Slot::new(known, id.to_string(), file, participant, &seating.limits))
    }

    /// A participant who arrives: the session of one who returns with their platform id
    /// ([`Registry::returning`]), else a new one in the condition with the fewest
    /// participants so far (the first of those on a tie), recording into the record
    /// folder: its token. The session (its agent, its first episode, the shortest plan of
    /// its start) is made here, so this runs off the async workers.
    pub(crate) fn join(registry: &Mutex<Registry>, seating: &Seating, arrival: Arrival) -> Result<String, JoinRefused> {
        check_arrival(seating, &arrival)?;
        if let Some(token) = Registry::returning(registry, seating, &arrival)? {
            return Ok(token);
        }
        let id = primary_id(seating, &arrival);
        let name = arrival.name.clone();
        // The number, condition and recording are taken under the lock; the session, which
        // may take long to begin, is made outside it.
        let (number, index, writer, recording, path) = {
            let mut r = lock(registry);
            if r.live.len() >= seating.limits.max_sessions {
                return Err(full_now(&seating.limits));
            }
            if let Some(max) = seating.max_participants.filter(|&max| r.admitted >= max) {
                return Err(JoinRefused::Full(format!(
                    "this study takes {max} participants, and has them all: thank you for your interest"
                )));
            }
            if id.as_ref().is_some_and(|id| r.by_id.contains_key(id)) {
                return Err(JoinRefused::Full(
                    "this participant's session is being begun in another window: reload this page".into(),
                ));
            }
            let index = (0..seating.conditions.len())
                .min_by_key(|&i| (r.assigned[i], i))
                .expect("a server has a condition");
            let condition = &seating.conditions[index];
            let (number, writer, recording, path) = match &seating.record_dir {
                None => (r.next_number, None, None, None),
                Some(dir) => {
                    let (number, path, file) = recording_path(dir, r.next_number, &condition.name, name.as_deref());
                    let out = OutputPath::check(&path).map_err(|e| JoinRefused::Failed(e.to_string()))?;
                    let writer = DemoWriter::append(&out).map_err(|e| JoinRefused::Failed(e.to_string()))?;
                    (number, Some(writer), Some(file), Some(path))
                }
            };
            r.next_number = number + 1;
            r.assigned[index] += 1;
            r.admitted += 1;
            if let (Some(id), Some(path)) = (&id, &path) {
                // Known at once, so that a second window with the same id waits for this one.
                r.by_id.insert(
                    id.clone(),
                    Known {
                        number,
                        condition: condition.name.clone(),
                        path: path.clone(),
                        ids: arrival.ids.clone(),
                        name: name.clone(),
                        withdrawn: false,
                        pending: true,
                        slot: None,
                    },
                );
            }
            (number, index, writer, recording, path)
        };
        let condition = seating.conditions[index].clone();
        let who = ParticipantLine {
            number,
            condition: condition.name.clone(),
            code: name.clone(),
            ids: arrival.ids.clone(),
        };
        let made = Participant::new(
            condition.clone(),
            seating.study.clone(),
            Recorder::new(writer),
            Some(who),
            None,
        );
        let participant = match made {
            Ok(p) => p,
            Err(e) => {
                let mut r = lock(registry);
                r.assigned[index] -= 1;
                r.admitted -= 1;
                if let Some(id) = &id {
                    r.by_id.remove(id);
                }
                return Err(JoinRefused::Failed(e.to_string()));
            }
        };
        let known = Known {
            number,
            condition: condition.name.clone(),
            path: path.unwrap_or_default(),
            ids: arrival.ids.clone(),
            name,
            withdrawn: false,
            pending: false,
            slot: None,
        };
        let slot = Slot::new(
            &known,
            id.clone().unwrap_or_default(),
            recording,
            participant,
            &seating.limits,
        );
        let token = slot.token.clone();
        let mut r = lock(registry);
        r.live.insert(token.clone(), slot.clone());
        r.all.push(slot.clone());
        if let Some(k) = id.and_then(|id| r.by_id.get_mut(&id)) {
            k.slot = Some(slot);
            k.pending = false;
        }
        Ok(token)
    }

    /// The participant of `token` withdraws: their recording is deleted or marked
    /// withdrawn, as the study says; their session ends, and they count no more towards
    /// the cap and the balance. An error line when the study offers no withdrawal or the
    /// session is not held.
    pub(crate) fn withdraw(registry: &Mutex<Registry>, seating: &Seating, token: &str) -> Result<Withdrawal, String> {
        let how = seating
            .study
            .withdrawal
            .ok_or_else(|| "this study offers no withdrawal here: write to the researcher".to_string())?;
        let slot = lock(registry)
            .live
            .get(token)
            .cloned()
            .ok_or_else(|| "this session is not known here (any more)".to_string())?;
        let mut state = lock(&slot.state);
        let SlotState::Live(live) = &mut *state else {
            return Err("this session has ended".into());
        };
        match how {
            Withdrawal::Mark => live
                .participant
                .record(&DemoRecord::Withdrawn(WithdrawnLine { at_ms: unix_ms() }))
                .map_err(|e| e.to_string())?,
            Withdrawal::Delete => {
                if let (Some(dir), Some(file)) = (&seating.record_dir, &slot.recording) {
                    std::fs::remove_file(dir.join(file))
                        .map_err(|e| format!("the recording cannot be deleted: {e}"))?;
                }
            }
        }
        *state = SlotState::ended(&live.participant, true);
        drop(state);
        slot.expired.store(true, Ordering::SeqCst);
        let mut r = lock(registry);
        r.live.remove(token);
        r.admitted = r.admitted.saturating_sub(1);
        if let Some(i) = seating.conditions.iter().position(|c| c.name == slot.condition) {
            r.assigned[i] = r.assigned[i].saturating_sub(1);
        }
        if let Some(k) = slot.id.as_ref().and_then(|id| r.by_id.get_mut(id)) {
            k.withdrawn = true;
        }
        Ok(how)
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
                let ended = SlotState::ended(&live.participant, false);
                *state = ended;
            }
        }
        idle.len()
    }
}

impl Slot {
    fn new(
        known: &Known,
        id: String,
        recording: Option<String>,
        participant: Participant,
        limits: &Limits,
    ) -> Arc<Slot> {
        Arc::new(Slot {
            number: known.number,
            name: known.name.clone(),
            id: Some(id).filter(|id| !id.is_empty()),
            condition: known.condition.clone(),
            recording,
            token: new_token(),
            page: Mutex::new(0),
            expired: AtomicBool::new(false),
            last_active: Mutex::new(Instant::now()),
            state: Mutex::new(SlotState::Live(Box::new(Live {
                participant,
                bucket: Bucket::full(limits.actions_per_second),
            }))),
        })
    }
}

fn full_now(limits: &Limits) -> JoinRefused {
    JoinRefused::Full(format!(
        "this server holds at most {} sessions at once, and has them all: try again later",
        limits.max_sessions
    ))
}

/// The participant's platform id: the value of the study's first `participant_ids`.
fn primary_id(seating: &Seating, arrival: &Arrival) -> Option<String> {
    seating
        .study
        .participant_ids
        .first()
        .and_then(|key| arrival.ids.get(key))
        .cloned()
}

/// An error unless `arrival` is one the study takes: a code that is a name, ids the study
/// names with values that are plain (1-64 of letters, digits, `-`, `_`, `.`), and consent
/// when the study asks for it.
fn check_arrival(seating: &Seating, arrival: &Arrival) -> Result<(), JoinRefused> {
    if let Some(n) = &arrival.name {
        crate::config::check_name(n).map_err(|e| JoinRefused::BadRequest(format!("participant name: {e}")))?;
    }
    for (key, value) in &arrival.ids {
        if !seating.study.participant_ids.contains(key) {
            return Err(JoinRefused::BadRequest(format!("{key} is not an id this study reads")));
        }
        let plain = (1..=64).contains(&value.len())
            && value
                .bytes()
                .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'-' | b'_' | b'.'));
        if !plain {
            return Err(JoinRefused::BadRequest(format!(
                "{key}={value:?} is not an id: 1 to 64 letters, digits, -, _ and ."
            )));
        }
    }
    if seating.study.consent.is_some() && !arrival.consent {
        return Err(JoinRefused::BadRequest(
            "this study asks for consent first: open its first page".into(),
        ));
    }
    Ok(())
}

/// What the recording at `path` left of a participant's sessions in `condition`: the agent
/// replayed from the condition's, the totals, and the next episode's number. An episode a
/// crash cut short stays in the recording unfinished; the participant goes on with the
/// next.
fn resume_from(condition: &Condition, path: &Path) -> Result<Resumed, String> {
    let read = agent::demos::read_demonstrations(path, None).map_err(|e| e.to_string())?;
    let mut agent = condition.agent.clone();
    let steps: usize = read.episodes.iter().map(|e| e.steps.len()).sum();
    if steps > 0 {
        agent::demos::learn_from_file(&mut agent, path, agent::BadLines::Skip).map_err(|e| e.to_string())?;
    }
    let ended = |e: &agent::demos::DemoEpisode| e.steps.last().is_some_and(|s| s.terminated || s.truncated);
    Ok(Resumed {
        agent,
        next_episode: read.episodes.last().map_or(0, |e| e.episode + 1),
        progress: Progress {
            episodes_done: read.episodes.iter().filter(|e| ended(e)).count() as u64,
            steps: steps as u64,
            corrections: read
                .episodes
                .iter()
                .flat_map(|e| &e.steps)
                .filter(|s| s.demonstrated)
                .count() as u64,
            ..Progress::default()
        },
    })
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
    /// Its path.
    pub(crate) path: PathBuf,
    /// The participant its first session line names (none in a recording made before
    /// participants were named, or one whose first line cannot be read).
    pub(crate) participant: Option<ParticipantLine>,
    /// Its last line says the participant withdrew.
    pub(crate) withdrawn: bool,
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
            let path = e.path();
            let participant = first_session(&path).and_then(|s| s.participant);
            let withdrawn = ends_withdrawn(&path);
            Some(FoundRecording {
                number,
                path,
                participant,
                withdrawn,
            })
        })
        .collect();
    found.sort_by_key(|f| f.number);
    found
}

/// Whether the last line of the recording at `path` is a `withdrawn` line (the line a
/// withdrawal appends; nothing is recorded after it).
pub(crate) fn ends_withdrawn(path: &Path) -> bool {
    use std::io::{Read, Seek, SeekFrom};
    let Ok(mut file) = std::fs::File::open(path) else {
        return false;
    };
    let len = file.metadata().map_or(0, |m| m.len());
    let mut tail = Vec::new();
    let _ = file.seek(SeekFrom::Start(len.saturating_sub(256)));
    let _ = file.take(256).read_to_end(&mut tail);
    let text = String::from_utf8_lossy(&tail);
    text.trim_end()
        .rsplit('\n')
        .next()
        .and_then(|last| serde_json::from_str::<DemoRecord>(last).ok())
        .is_some_and(|r| matches!(r, DemoRecord::Withdrawn(_)))
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
