//! The participants a server holds, and those its recording folder remembers.
//!
//! A server may be restarted on the same `--record-dir` (after a crash, a kill, a new
//! day): participant numbers, the study's cap and the balance of conditions go on from the
//! recordings on disk, read at start-up from each recording's session line, so that no two
//! people share a number and a study capped at 40 takes 40 in all.
//!
//! Only a participant who takes a step counts: their recording is made with that step
//! (until then it waits in memory), and the cap and the balance count them from then on.
//! A join that never acts (a script's) leaves nothing on disk, is let go after
//! [`Limits::session_idle`], and is the first let go when `--max-sessions` are held: joins
//! alone cannot close a study.
//!
//! A session is reached by its token only, never by a platform id (ids travel in URLs and
//! are shown to the researcher: they are not secrets). The browser keeps the token (a
//! cookie); the record folder's [`Ledger`] keeps which recording each token reaches, so
//! that a participant whose session was let go, or whose server restarted, comes back to
//! it. A platform id that took part cannot join again as someone new.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use agent::DemoWriter;
use agent::demos::{DemoRecord, ParticipantLine, WithdrawnLine, unix_ms};
use files::OutputPath;
use serde::Serialize;

use crate::config::{Condition, Limits, StudyPath, Withdrawal};
use crate::ledger::{Codes, Ledger};
use crate::participant::{Participant, Recorder, Resumed};
use crate::protocol::{Completion, Mode, Progress};

/// Locks `m`, going on after a panic elsewhere (the state stays consistent: every change
/// under a lock is one assignment or a whole message's work).
pub(crate) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a client may still do now (a session's messages, an address's joins): a bucket of
/// `capacity`, refilled at a steady rate.
pub(crate) struct Bucket {
    tokens: f64,
    last: Instant,
}

impl Bucket {
    /// A full bucket of `capacity`.
    pub(crate) fn full(capacity: u32) -> Self {
        Bucket {
            tokens: f64::from(capacity),
            last: Instant::now(),
        }
    }

    /// Whether the bucket is full again (it can be forgotten).
    pub(crate) fn is_full(&self, capacity: u32, per_second: f64) -> bool {
        self.tokens + self.last.elapsed().as_secs_f64() * per_second >= f64::from(capacity)
    }

    /// Takes one token, if there is one, the bucket (of `capacity`) refilled at
    /// `per_second` since the last take.
    pub(crate) fn take(&mut self, capacity: u32, per_second: f64) -> bool {
        let now = Instant::now();
        let capacity = f64::from(capacity);
        self.tokens = (self.tokens + now.duration_since(self.last).as_secs_f64() * per_second).min(capacity);
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
    /// The condition's place in the study's list.
    index: usize,
    /// The recording's file name in the record folder.
    pub(crate) recording: Option<String>,
    /// The session's token.
    pub(crate) token: String,
    /// A page is connected (one at a time): the id of its connection, 0 for none.
    pub(crate) page: Mutex<u64>,
    /// Set when the session is let go (idle) or withdrawn.
    pub(crate) expired: AtomicBool,
    /// The participant has taken a step: they count towards the cap and the balance, and
    /// their recording is on disk.
    pub(crate) acted: AtomicBool,
    /// When the session was begun (or taken up again).
    began: Instant,
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

    /// Whether the participant has taken a step.
    pub(crate) fn has_acted(&self) -> bool {
        self.acted.load(Ordering::SeqCst)
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

    fn new(known: &Known, index: usize, token: String, participant: Participant, limits: &Limits) -> Arc<Slot> {
        Arc::new(Slot {
            number: known.number,
            name: known.name.clone(),
            id: known.id.clone(),
            condition: known.condition.clone(),
            index,
            recording: known.file.clone(),
            token,
            page: Mutex::new(0),
            expired: AtomicBool::new(false),
            acted: AtomicBool::new(false),
            began: Instant::now(),
            last_active: Mutex::new(Instant::now()),
            state: Mutex::new(SlotState::Live(Box::new(Live {
                participant,
                bucket: Bucket::full(limits.actions_per_second),
            }))),
        })
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
    /// Someone with this platform id took part already, in another browser: the answer a
    /// join gets instead of their session (ids are not secrets).
    Exists,
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
    /// A study's server keeps its ledger in the record folder ([`crate::ledger`]).
    pub(crate) keeps_ledger: bool,
}

/// Who asks to join: the code typed, the platform's ids from the URL, whether consent was
/// given, and the session token the browser keeps (its cookie), if any.
#[derive(Clone, Debug, Default)]
pub(crate) struct Arrival {
    pub(crate) name: Option<String>,
    pub(crate) ids: BTreeMap<String, String>,
    pub(crate) consent: bool,
    pub(crate) token: Option<String>,
}

/// A participant as their recording's session line names them.
#[derive(Clone, Debug)]
struct Known {
    number: u64,
    condition: String,
    /// The recording's file name.
    file: Option<String>,
    ids: BTreeMap<String, String>,
    /// Their platform id (the study's first `participant_ids`).
    id: Option<String>,
    name: Option<String>,
    withdrawn: bool,
}

/// The participants: those held, those of this run, and the counts the folder remembers.
pub(crate) struct Registry {
    live: HashMap<String, Arc<Slot>>,
    /// This run's sessions that are held or took a step, in order of arrival, for the
    /// researcher's page.
    all: Vec<Arc<Slot>>,
    /// Participants who took part (a step, or a withdrawal), by their platform id.
    by_id: HashMap<String, Known>,
    /// Tokens whose recording is being taken up again (by a join or a page not yet done).
    resuming: HashSet<String>,
    /// The number the next participant gets: one past the highest on disk or given.
    next_number: u64,
    /// Participants per condition who took a step, on disk and of this run, withdrawn ones
    /// left out: the balance.
    assigned: Vec<u64>,
    /// Participants who took a step in all, on disk and of this run, withdrawn ones left
    /// out: the study's cap counts them.
    admitted: u64,
    /// Tokens to recordings, withdrawn ids, the key.
    ledger: Ledger,
}

impl Registry {
    /// The registry of a server seating by `seating`: numbering, balance, the count
    /// admitted and the participants known by id go on from the recordings in its folder
    /// (a recording without a step counts for nothing: a join that never acted).
    pub(crate) fn new(seating: &Seating) -> Result<Registry, String> {
        let ledger_dir = seating.record_dir.as_deref().filter(|_| seating.keeps_ledger);
        let mut registry = Registry {
            live: HashMap::new(),
            all: Vec::new(),
            by_id: HashMap::new(),
            resuming: HashSet::new(),
            next_number: 0,
            assigned: vec![0; seating.conditions.len()],
            admitted: 0,
            ledger: Ledger::open(ledger_dir)?,
        };
        let Some(dir) = &seating.record_dir else {
            return Ok(registry);
        };
        for found in recordings_in(dir) {
            registry.next_number = registry.next_number.max(found.number + 1);
            if !found.acted && !found.withdrawn {
                continue;
            }
            let counted = found.acted && !found.withdrawn;
            registry.admitted += u64::from(counted);
            let Some(known) = known_of(seating, &found) else {
                continue;
            };
            if counted && let Some(i) = seating.conditions.iter().position(|c| c.name == known.condition) {
                registry.assigned[i] += 1;
            }
            if let Some(id) = known.id.clone() {
                registry.by_id.insert(id, known);
            }
        }
        Ok(registry)
    }

    /// Participants who took a step in all (on disk and of this run).
    pub(crate) fn admitted(&self) -> u64 {
        self.admitted
    }

    /// The session of `token`, while it is held.
    pub(crate) fn find(&self, token: &str) -> Option<Arc<Slot>> {
        self.live.get(token).cloned()
    }

    /// This run's sessions that are held or took a step, in order of arrival.
    pub(crate) fn all(&self) -> Vec<Arc<Slot>> {
        self.all.clone()
    }

    /// The study's completion codes (the researcher's CSV lists them).
    pub(crate) fn codes(&self, study: &StudyPath) -> Codes {
        self.ledger
            .codes(study.completion_code.as_deref(), study.code_per_participant)
    }

    /// The completion code and link participant `number` is given at the end.
    fn completion(&self, study: &StudyPath, number: u64) -> Completion {
        let code = self.codes(study).of(number);
        let url = study
            .completion_url
            .as_ref()
            .map(|u| u.replace("{code}", code.as_deref().unwrap_or_default()));
        Completion { code, url }
    }

    /// The session `token` reaches: the one held, else the recording the ledger says the
    /// token reaches, taken up again. With `id`, only a session of that participant (a
    /// token kept by a browser another participant now uses reaches nothing). `None` for
    /// a token that reaches nothing; an error when the session cannot be taken up.
    pub(crate) fn session(
        registry: &Mutex<Registry>,
        seating: &Seating,
        token: &str,
        id: Option<&str>,
    ) -> Result<Option<Arc<Slot>>, JoinRefused> {
        let theirs = |slot: &Slot| id.is_none_or(|id| slot.id.as_deref() == Some(id));
        let (known, index, path) = {
            let mut r = lock(registry);
            if let Some(slot) = r.live.get(token) {
                return Ok(Some(slot.clone()).filter(|s| theirs(s)));
            }
            let Some(file) = r.ledger.recording_of(token).map(str::to_string) else {
                return Ok(None);
            };
            // A resume link the researcher issued reaches the session already held.
            if let Some(slot) = r.live.values().find(|s| s.recording.as_deref() == Some(file.as_str())) {
                return Ok(Some(slot.clone()).filter(|s| theirs(s)));
            }
            let Some(dir) = &seating.record_dir else {
                return Ok(None);
            };
            let Some(found) = recordings_in(dir).into_iter().find(|f| f.file() == file) else {
                return Ok(None);
            };
            let Some(known) = known_of(seating, &found) else {
                return Ok(None);
            };
            if id.is_some_and(|id| known.id.as_deref() != Some(id)) {
                return Ok(None);
            }
            if known.withdrawn {
                return Err(JoinRefused::Withdrawn);
            }
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
            r.make_room(&seating.limits)?;
            if !r.resuming.insert(token.to_string()) {
                return Err(JoinRefused::Full(
                    "this session is being begun in another window: reload this page".into(),
                ));
            }
            (known, index, found.path)
        };
        let resumed = resume(
            seating,
            &known,
            index,
            &path,
            &lock(registry).completion(&seating.study, known.number),
        );
        let mut r = lock(registry);
        r.resuming.remove(token);
        let slot = Slot::new(&known, index, token.to_string(), resumed?, &seating.limits);
        // Its recording has steps: the participant was counted when it was read.
        slot.acted.store(true, Ordering::SeqCst);
        r.live.insert(slot.token.clone(), slot.clone());
        r.all.push(slot.clone());
        Ok(Some(slot))
    }

    /// A participant who arrives: their own session when their browser keeps its token
    /// ([`Registry::session`]), else a new one in the condition with the fewest participants
    /// so far (the first of those on a tie), recording into the record folder from its
    /// first step: its token. A platform id that took part already is refused
    /// ([`JoinRefused::Exists`]): a session is reached by its token only. The session (its
    /// agent, its first episode, the shortest plan of its start) is made here, so this runs
    /// off the async workers.
    pub(crate) fn join(registry: &Mutex<Registry>, seating: &Seating, arrival: Arrival) -> Result<String, JoinRefused> {
        check_arrival(seating, &arrival)?;
        let id = primary_id(seating, &arrival);
        if let Some(token) = &arrival.token
            && let Some(slot) = Registry::session(registry, seating, token, id.as_deref())?
        {
            return Ok(slot.token.clone());
        }
        let name = arrival.name.clone();
        // The number, condition and recording are taken under the lock; the session, which
        // may take long to begin, is made outside it.
        let (known, index, recorder, completion) = {
            let mut r = lock(registry);
            if let Some(id) = &id {
                if r.ledger.withdrew(id) {
                    return Err(JoinRefused::Withdrawn);
                }
                match r.by_id.get(id) {
                    Some(k) if k.withdrawn => return Err(JoinRefused::Withdrawn),
                    Some(_) => return Err(JoinRefused::Exists),
                    None => {}
                }
                // A session begun with this id that never acted (a window left on the
                // instructions, or a script that named the id) holds nothing: let go.
                let stale: Vec<String> = r
                    .live
                    .values()
                    .filter(|s| !s.has_acted() && s.id.as_deref() == Some(id.as_str()))
                    .map(|s| s.token.clone())
                    .collect();
                for token in stale {
                    r.let_go(&token, false);
                }
            }
            r.make_room(&seating.limits)?;
            if let Some(max) = seating.max_participants.filter(|&max| r.admitted >= max) {
                return Err(JoinRefused::Full(format!(
                    "this study takes {max} participants, and has them all: thank you for your interest"
                )));
            }
            let waiting = |i: usize| r.live.values().filter(|s| s.index == i && !s.has_acted()).count();
            let index = (0..seating.conditions.len())
                .min_by_key(|&i| (r.assigned[i], waiting(i), i))
                .expect("a server has a condition");
            let condition = &seating.conditions[index];
            let (number, recorder, file) = match &seating.record_dir {
                None => (r.next_number, Recorder::new(None), None),
                Some(dir) => {
                    let (number, path, file) = recording_path(dir, r.next_number, &condition.name, name.as_deref());
                    let out = OutputPath::check(&path).map_err(|e| JoinRefused::Failed(e.to_string()))?;
                    (number, Recorder::at_first_step(out), Some(file))
                }
            };
            r.next_number = number + 1;
            let known = Known {
                number,
                condition: condition.name.clone(),
                file,
                ids: arrival.ids.clone(),
                id: id.clone(),
                name: name.clone(),
                withdrawn: false,
            };
            let completion = r.completion(&seating.study, number);
            (known, index, recorder, completion)
        };
        let condition = seating.conditions[index].clone();
        let who = ParticipantLine {
            number: known.number,
            condition: condition.name.clone(),
            code: name,
            ids: arrival.ids.clone(),
        };
        let participant = Participant::new(condition, seating.study.clone(), recorder, Some(who), None, completion)
            .map_err(|e| JoinRefused::Failed(e.to_string()))?;
        let slot = Slot::new(&known, index, new_token(), participant, &seating.limits);
        let token = slot.token.clone();
        let mut r = lock(registry);
        r.live.insert(token.clone(), slot.clone());
        r.all.push(slot);
        Ok(token)
    }

    /// Counts the participant of `slot` as one who acted, before their first step is
    /// carried out: towards the cap (an error line when the study has all its
    /// participants) and the balance; their platform id is now taken.
    pub(crate) fn first_step(registry: &Mutex<Registry>, seating: &Seating, slot: &Slot) -> Result<(), String> {
        let mut r = lock(registry);
        if slot.has_acted() {
            return Ok(());
        }
        if let Some(max) = seating.max_participants.filter(|&max| r.admitted >= max) {
            return Err(format!(
                "this study takes {max} participants, and others have taken every place since you began: \
                 thank you for your interest"
            ));
        }
        if let Some(id) = &slot.id
            && r.by_id.contains_key(id)
        {
            return Err("someone with your participant id took part already, in another window or browser".into());
        }
        r.admitted += 1;
        r.assigned[slot.index] += 1;
        slot.acted.store(true, Ordering::SeqCst);
        r.take_id(slot, false);
        Ok(())
    }

    /// The platform id of `slot`'s participant is taken: they acted, or `withdrawn`.
    fn take_id(&mut self, slot: &Slot, withdrawn: bool) {
        if let Some(id) = &slot.id {
            let known = Known {
                number: slot.number,
                condition: slot.condition.clone(),
                file: slot.recording.clone(),
                ids: BTreeMap::new(),
                id: Some(id.clone()),
                name: slot.name.clone(),
                withdrawn,
            };
            self.by_id.insert(id.clone(), known);
        }
    }

    /// `slot`'s participant counts no more towards the cap and the balance; whether they
    /// did.
    fn uncount(&mut self, slot: &Slot) -> bool {
        let counted = slot.acted.swap(false, Ordering::SeqCst);
        if counted {
            self.admitted = self.admitted.saturating_sub(1);
            self.assigned[slot.index] = self.assigned[slot.index].saturating_sub(1);
        }
        counted
    }

    /// [`Registry::first_step`] taken back: the message took no step after all.
    pub(crate) fn no_first_step(registry: &Mutex<Registry>, slot: &Slot) {
        let mut r = lock(registry);
        if r.uncount(slot)
            && let Some(id) = &slot.id
        {
            r.by_id.remove(id);
        }
    }

    /// The participant's first step is on disk: the ledger notes which recording their
    /// token reaches, so that they can come back to it after their session is let go or
    /// the server restarted.
    pub(crate) fn recorded(registry: &Mutex<Registry>, slot: &Slot) -> Result<(), String> {
        match &slot.recording {
            Some(file) => lock(registry).ledger.remember(&slot.token, file),
            None => Ok(()),
        }
    }

    /// A resume link for participant `number` (the researcher's page): a fresh token that
    /// reaches their recording, for another browser. `None` when no recording of theirs
    /// is on disk.
    pub(crate) fn resume_link(
        registry: &Mutex<Registry>,
        seating: &Seating,
        number: u64,
    ) -> Result<Option<String>, String> {
        let Some(dir) = &seating.record_dir else {
            return Ok(None);
        };
        let Some(found) = recordings_in(dir).into_iter().find(|f| f.number == number && f.acted) else {
            return Ok(None);
        };
        if found.withdrawn {
            return Err(format!("participant {number} withdrew"));
        }
        let token = new_token();
        lock(registry).ledger.remember(&token, &found.file())?;
        Ok(Some(token))
    }

    /// The participant of `token` withdraws: their recording is deleted or marked
    /// withdrawn, as the study says; their session ends, and they count no more towards
    /// the cap and the balance. With `withdrawal = "delete"` nothing of them is kept but
    /// the keyed hash of their platform id, which stops it from joining again. The
    /// completion code and link when the study gives them on withdrawal; an error line when
    /// the study offers no withdrawal or the token reaches no session.
    pub(crate) fn withdraw(
        registry: &Mutex<Registry>,
        seating: &Seating,
        token: &str,
    ) -> Result<(Withdrawal, Option<Completion>), String> {
        let how = seating
            .study
            .withdrawal
            .ok_or_else(|| "this study offers no withdrawal here: write to the researcher".to_string())?;
        let slot = match Registry::session(registry, seating, token, None) {
            Ok(Some(slot)) => slot,
            Ok(None) => return Err("this session is not known here (any more)".into()),
            Err(JoinRefused::Withdrawn) => return Err("you withdrew from this study already".into()),
            Err(e) => return Err(format!("{e:?}")),
        };
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
                    match std::fs::remove_file(dir.join(file)) {
                        Ok(()) => {}
                        // Never made: the participant took no step.
                        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                        Err(e) => return Err(format!("the recording cannot be deleted: {e}")),
                    }
                    lock(registry).ledger.withdraw_deleted(file, slot.id.as_deref())?;
                }
            }
        }
        let completion = seating
            .study
            .completion_on_withdrawal
            .then(|| live.participant.completion().clone());
        *state = SlotState::ended(&live.participant, true);
        drop(state);
        slot.expired.store(true, Ordering::SeqCst);
        let mut r = lock(registry);
        r.live.remove(&slot.token);
        r.uncount(&slot);
        r.take_id(&slot, true);
        Ok((how, completion))
    }

    /// Lets go of the sessions `limits.session_idle` has passed for: one whose participant
    /// never took a step, that long after it began (nothing of it is on disk, and it leaves
    /// no trace); one that did, that long with no page connected (its recording stays, and
    /// its token takes it up again). How many.
    pub(crate) fn expire_idle(registry: &Mutex<Registry>, limits: &Limits) -> usize {
        let mut r = lock(registry);
        let idle: Vec<(String, bool)> = r
            .live
            .values()
            .filter_map(|slot| {
                let acted = slot.has_acted();
                let over = if acted {
                    !slot.is_connected() && lock(&slot.last_active).elapsed() >= limits.session_idle
                } else {
                    slot.began.elapsed() >= limits.session_idle
                };
                over.then(|| (slot.token.clone(), acted))
            })
            .collect();
        for (token, acted) in &idle {
            r.let_go(token, *acted);
        }
        idle.len()
    }

    /// Lets the session of `token` go: one that `acted` stays on the researcher's page
    /// with its totals; one that did not is forgotten.
    fn let_go(&mut self, token: &str, acted: bool) {
        let Some(slot) = self.live.remove(token) else {
            return;
        };
        slot.expired.store(true, Ordering::SeqCst);
        // The participant's state is dropped here: only its totals stay.
        let mut state = lock(&slot.state);
        if let SlotState::Live(live) = &*state {
            let ended = SlotState::ended(&live.participant, false);
            *state = ended;
        }
        drop(state);
        if !acted {
            self.all.retain(|s| !Arc::ptr_eq(s, &slot));
        }
    }

    /// Room for one more session: when `--max-sessions` are held, the one that never took
    /// a step and was used longest ago is let go (it holds nothing), so that sessions
    /// begun by scripts cannot keep people out; an error when every session held acted.
    fn make_room(&mut self, limits: &Limits) -> Result<(), JoinRefused> {
        if self.live.len() < limits.max_sessions {
            return Ok(());
        }
        let oldest = self
            .live
            .values()
            .filter(|s| !s.has_acted())
            .min_by_key(|s| *lock(&s.last_active))
            .map(|s| s.token.clone());
        match oldest {
            Some(token) => {
                self.let_go(&token, false);
                Ok(())
            }
            None => Err(full_now(limits)),
        }
    }
}

/// The session of `known` (in condition `index`) taken up again from its recording at
/// `path`.
fn resume(
    seating: &Seating,
    known: &Known,
    index: usize,
    path: &Path,
    completion: &Completion,
) -> Result<Participant, JoinRefused> {
    let condition = seating.conditions[index].clone();
    let resumed = resume_from(&condition, path).map_err(JoinRefused::Failed)?;
    let writer = DemoWriter::append(&OutputPath::check(path).map_err(|e| JoinRefused::Failed(e.to_string()))?)
        .map_err(|e| JoinRefused::Failed(e.to_string()))?;
    let who = ParticipantLine {
        number: known.number,
        condition: condition.name.clone(),
        code: known.name.clone(),
        ids: known.ids.clone(),
    };
    Participant::new(
        condition,
        seating.study.clone(),
        Recorder::new(Some(writer)),
        Some(who),
        Some(resumed),
        completion.clone(),
    )
    .map_err(|e| JoinRefused::Failed(e.to_string()))
}

/// The participant a recording found on disk names (none when its first line names none).
fn known_of(seating: &Seating, found: &FoundRecording) -> Option<Known> {
    let p = found.participant.as_ref()?;
    let id = seating
        .study
        .participant_ids
        .first()
        .and_then(|key| p.ids.get(key))
        .cloned();
    Some(Known {
        number: found.number,
        condition: p.condition.clone(),
        file: Some(found.file()),
        ids: p.ids.clone(),
        id,
        name: p.code.clone(),
        withdrawn: found.withdrawn,
    })
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
/// names with values that are plain (1-64 of letters, digits, `-`, `_`, `.`), every id
/// when the study requires them, and consent when the study asks for it.
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
    if seating.study.require_ids
        && let Some(missing) = seating
            .study
            .participant_ids
            .iter()
            .find(|key| !arrival.ids.contains_key(*key))
    {
        return Err(JoinRefused::BadRequest(format!(
            "this study takes part through its platform's link, which names {missing}: open that link"
        )));
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
    let mut agent = (*condition.agent).clone();
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
    /// It holds a step: the participant acted (a recording without one is a join that
    /// never did, written before recordings waited for the first step).
    pub(crate) acted: bool,
}

impl FoundRecording {
    /// Its file name.
    pub(crate) fn file(&self) -> String {
        self.path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned())
    }
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
            let acted = has_step(&path);
            Some(FoundRecording {
                number,
                path,
                participant,
                withdrawn,
                acted,
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

/// Whether the recording at `path` holds a step line (read up to the first one).
fn has_step(path: &Path) -> bool {
    let Ok(file) = files::open_bounded(path, agent::demos::MAX_RECORDING_BYTES, "a recording") else {
        return false;
    };
    let mut input = std::io::BufReader::new(file);
    let mut line = Vec::new();
    while sim::trajectory::read_bounded_line(&mut input, &mut line).is_ok_and(|n| n > 0) {
        if let Ok(DemoRecord::Step(_)) = serde_json::from_slice::<DemoRecord>(line.trim_ascii()) {
            return true;
        }
    }
    false
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
    fn the_bucket_allows_its_capacity_then_refills() {
        let mut b = Bucket::full(5);
        assert_eq!((0..10).filter(|_| b.take(5, 5.0)).count(), 5);
        b.last -= std::time::Duration::from_millis(400);
        assert_eq!((0..10).filter(|_| b.take(5, 5.0)).count(), 2);
        // A bucket of 20 joins refilled at 20 a minute: 3 s give one more.
        let mut joins = Bucket::full(20);
        assert_eq!((0..30).filter(|_| joins.take(20, 20.0 / 60.0)).count(), 20);
        joins.last -= std::time::Duration::from_secs(3);
        assert_eq!((0..30).filter(|_| joins.take(20, 20.0 / 60.0)).count(), 1);
        assert!(!joins.is_full(20, 20.0 / 60.0));
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
