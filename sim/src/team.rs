//! Keeping a pool's threads awake, the one home of it. One mechanism, a `Vigil`, serves
//! both callers: the vector env's `Team`, a caller outside every pool that hands out a
//! batch call after call, and the network trainer's loop run on a pool ([`on_pool_awake`]),
//! whose splits must find the other threads awake.
//!
//! # Why keep threads awake
//!
//! A rayon thread with nothing to do goes to sleep soon, and waking it costs tens of
//! microseconds on a virtual machine (docs/performance.md measures it). A vector env's
//! step at 1,024 environments takes a few hundred microseconds, and a training step is a
//! few splits apart from serial stretches of tens of microseconds: either would pay a
//! wake-up a hand-off, a large share of it.
//!
//! # One vigil, one policy
//!
//! While a `Vigil` is held, and for a while after its last hold ends (its one parameter), a
//! helper job on each of the pool's other threads looks for work ([`rayon::yield_now`]: a
//! spawned part, the other half of a `rayon::join`) and, when there is none, yields its core
//! to the scheduler before it looks again. OpenMP's default wait policy keeps its threads
//! the same way before they sleep. The core is offered, not spun on: given back at once when
//! nothing else wants it, and shared when something does (a pure spin made a training run on
//! a busy machine 1.8 times slower than no helper at all: docs/performance.md). The helpers
//! never carry work of their own, so whether they are awake changes how soon a part starts,
//! never what it computes: the same bits either way.
//!
//! - A `Team` holds its vigil for each call: the caller's thread runs the first part of
//!   a batch while the pool's threads take the others, and a call that follows within
//!   `WARM_FOR` (a Python caller's own work between two steps) finds them awake.
//! - [`on_pool_awake`] holds a vigil over the current pool while a loop runs on one of its
//!   threads: the splits happen inside the loop, on that thread, which a team could not do.
//!   Its helpers go as the loop ends, since no call follows: kept `WARM_FOR` longer, they
//!   made the neural bench's `train_step/small/2` slower in alternated runs
//!   (docs/performance.md).
//!
//! # The team's hand-off
//!
//! Why not `rayon::ThreadPool::install`: it hands the whole batch to the pool and puts the
//! caller to sleep until the pool finishes. A team's caller runs a part itself and waits for
//! the others by spinning (the helpers are at most a look behind). It hands the parts out
//! with `spawn` and counts them back itself, which needs the one `unsafe` of the module (a
//! part's borrowed lifetime erased for the pool, as `rayon::scope` does inside): at the end
//! of a `rayon::scope` the caller can still miss the last part's signal by a few
//! instructions and sleep until it is woken. The module's tests run under Miri
//! (docs/development.md, "Unsafe code under Miri"), which checks every access the parts make
//! against the lifetimes of what they borrow.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use crate::error::{Result, SimError};

/// How long a team's workers stay awake after a call: longer than a Python caller's own
/// work between two steps, short enough that a caller that has stopped gets the cores back
/// at once. A loop on an awake pool lets its helpers go when it ends: no call follows.
pub(crate) const WARM_FOR: Duration = Duration::from_micros(200);

/// Spins of a team caller's wait before it starts yielding its core.
const SPINS_BEFORE_YIELD: u32 = 1 << 12;

/// Keeps a pool's other threads looking for work while it is held and for `warm_for` after
/// the last hold ends, a helper job on each ([`Vigil::hold`]).
struct Vigil {
    /// How long the helpers stay after the last hold ends.
    warm_for: Duration,
    /// Holds in force.
    holds: AtomicUsize,
    /// When the last hold ended, in nanoseconds since `epoch`.
    released: AtomicU64,
    /// The zero of `released`.
    epoch: Instant,
    /// Helpers spawned that have not ended: a hold spawns the missing ones.
    helpers: AtomicUsize,
}

/// A hold on a [`Vigil`]: its helpers stay awake while this lives, and its `warm_for` after.
struct Hold<'a>(&'a Vigil);

impl Drop for Hold<'_> {
    fn drop(&mut self) {
        // The time first: a helper that sees no hold then sees this time.
        let now = self.0.since_epoch();
        self.0.released.store(now, Ordering::Release);
        self.0.holds.fetch_sub(1, Ordering::AcqRel);
    }
}

impl Vigil {
    /// A vigil whose helpers stay `warm_for` after its last hold ends.
    fn new(warm_for: Duration) -> Arc<Vigil> {
        Arc::new(Vigil {
            warm_for,
            holds: AtomicUsize::new(0),
            released: AtomicU64::new(0),
            epoch: Instant::now(),
            helpers: AtomicUsize::new(0),
        })
    }

    /// Holds the vigil, and has `spawn` start helpers until `threads` are awake. `runner` is
    /// the pool thread (by index) that holds it, if any: a helper that lands there leaves at
    /// once, since that thread has its own work and would otherwise never return to it.
    fn hold(
        self: &Arc<Self>,
        threads: usize,
        runner: Option<usize>,
        spawn: impl Fn(Box<dyn FnOnce() + Send>),
    ) -> Hold<'_> {
        self.holds.fetch_add(1, Ordering::AcqRel);
        while self.helpers.load(Ordering::Acquire) < threads {
            self.helpers.fetch_add(1, Ordering::AcqRel);
            let vigil = Arc::clone(self);
            spawn(Box::new(move || {
                if rayon::current_thread_index() != runner {
                    vigil.look_for_work();
                }
                vigil.helpers.fetch_sub(1, Ordering::AcqRel);
            }));
        }
        Hold(self)
    }

    /// The helpers' loop: runs the pool's pending jobs, and yields the core when there are
    /// none, while the vigil is awake.
    fn look_for_work(&self) {
        loop {
            if rayon::yield_now() == Some(rayon::Yield::Executed) {
                continue;
            }
            if !self.awake() {
                return;
            }
            std::thread::yield_now();
        }
    }

    /// Whether the helpers stay awake now: the clock is read only once no hold is in force.
    fn awake(&self) -> bool {
        self.holds.load(Ordering::Acquire) > 0 || self.awake_at(self.since_epoch())
    }

    /// Whether the helpers stay awake at `now` (nanoseconds since the epoch): while held,
    /// and for `warm_for` after the last hold ended.
    fn awake_at(&self, now: u64) -> bool {
        self.holds.load(Ordering::Acquire) > 0
            || now.saturating_sub(self.released.load(Ordering::Acquire)) < self.warm_for.as_nanos() as u64
    }

    fn since_epoch(&self) -> u64 {
        u64::try_from(self.epoch.elapsed().as_nanos()).unwrap_or(u64::MAX)
    }
}

/// The caller's thread and `threads - 1` pool workers, sharing each batch of parts.
pub(crate) struct Team {
    /// The workers: one fewer than the team, since the caller's thread takes a part.
    pool: rayon::ThreadPool,
    /// Keeps the workers awake during a call and for [`WARM_FOR`] after.
    vigil: Arc<Vigil>,
}

impl Team {
    /// A team of `threads` (at least 2): the caller's thread and `threads - 1` workers.
    pub(crate) fn new(threads: usize) -> Result<Team> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.saturating_sub(1).max(1))
            .build()
            .map_err(|e| SimError::ThreadPool {
                threads,
                reason: e.to_string(),
            })?;
        Ok(Team {
            pool,
            vigil: Vigil::new(WARM_FOR),
        })
    }

    /// Threads that share a batch, the caller's among them.
    pub(crate) fn threads(&self) -> usize {
        self.pool.current_num_threads() + 1
    }

    /// `f` of every part, in order: the first on the caller's thread, the others on the
    /// workers. A panic in any part reaches the caller once every part has ended.
    pub(crate) fn run<T: Send, R: Send>(&self, parts: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
        let mut parts = parts.into_iter();
        let Some(first) = parts.next() else {
            return Vec::new();
        };
        let mut others: Vec<Option<std::thread::Result<R>>> =
            std::iter::repeat_with(|| None).take(parts.len()).collect();
        let ended = AtomicUsize::new(0);
        let (f, ended_ref) = (&f, &ended);
        for (part, slot) in parts.zip(others.iter_mut()) {
            let job: Box<dyn FnOnce() + Send + '_> = Box::new(move || {
                *slot = Some(catch_unwind(AssertUnwindSafe(|| f(part))));
                // The job's last use of anything it borrows.
                ended_ref.fetch_add(1, Ordering::Release);
            });
            // SAFETY: the job borrows `f`, `ended`, its part and its slot, all of which
            // outlive it: this call returns only after `ended` counts every job (the wait
            // below), each job counts itself after its last use of them, and nothing
            // between here and the wait can unwind (the caller's part runs inside
            // `catch_unwind`, and the hold only spawns 'static helpers). Erasing the lifetime
            // is what `rayon::scope` does inside; its own end, though, can put the caller to
            // sleep for a wake-up.
            let job: Box<dyn FnOnce() + Send + 'static> = unsafe { std::mem::transmute(job) };
            self.pool.spawn(job);
        }
        // After the parts: a worker woken for a part takes it before any helper.
        let hold = self
            .vigil
            .hold(self.pool.current_num_threads(), None, |helper| self.pool.spawn(helper));
        let head = catch_unwind(AssertUnwindSafe(|| f(first)));
        wait_for(&ended, others.len());
        drop(hold);
        std::iter::once(head)
            .chain(others.into_iter().map(|r| r.expect("every job counted itself")))
            .map(|r| r.unwrap_or_else(|panic| resume_unwind(panic)))
            .collect()
    }

    /// `check` of every part, then, only if every part passed, `step` of every part: as
    /// [`Team::run`], in one hand-off. Each part waits for every part's check before it
    /// steps, so there are at most as many parts as threads. The first refusal in part
    /// order is the error.
    pub(crate) fn run_checked<T: Send, R: Send, E: Send>(
        &self,
        parts: Vec<T>,
        check: impl Fn(&T) -> Result<(), E> + Sync,
        step: impl Fn(T) -> R + Sync,
    ) -> Result<Vec<R>, E> {
        let count = parts.len();
        assert!(
            count <= self.threads(),
            "one part per thread: each waits for the others' checks"
        );
        let (checked, refused) = (AtomicUsize::new(0), AtomicBool::new(false));
        let outcomes = self.run(parts, |part| {
            let verdict = catch_unwind(AssertUnwindSafe(|| check(&part)));
            if !matches!(verdict, Ok(Ok(()))) {
                refused.store(true, Ordering::Release);
            }
            checked.fetch_add(1, Ordering::AcqRel);
            wait_for(&checked, count);
            let passed = verdict.unwrap_or_else(|panic| resume_unwind(panic));
            passed.map(|()| (!refused.load(Ordering::Acquire)).then(|| step(part)))
        });
        let stepped = outcomes.into_iter().collect::<Result<Vec<_>, E>>()?;
        Ok(stepped.into_iter().map(|r| r.expect("no part refused")).collect())
    }
}

/// Waits until `ended` counts `parts`: the workers are at most a look behind, so the caller
/// spins, and yields its core only if they are later than that.
fn wait_for(ended: &AtomicUsize, parts: usize) {
    let mut spins = 0;
    while ended.load(Ordering::Acquire) < parts {
        if spins < SPINS_BEFORE_YIELD {
            spins += 1;
            std::hint::spin_loop();
        } else {
            std::thread::yield_now();
        }
    }
}

/// Runs `f` on a thread of the current rayon pool (the global one outside every pool)
/// while a `Vigil` keeps the pool's other threads awake, so the halves a `rayon::join`
/// offers (the network kernels' splits, `neural::kernels::join`) are taken at once. Nothing
/// changes which half runs what, so results are the same bits.
///
/// Why: a training step is a few splits apart from serial stretches (the gradients' norm,
/// the losses) of tens of microseconds, long enough for an idle rayon thread to go to
/// sleep, and then each split pays a wake-up in the kernel (docs/performance.md measures
/// it). The price is the other threads' cores for as long as `f` runs, offered to the
/// scheduler between looks.
pub fn on_pool_awake<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    // A scope without spawns: the way onto a pool thread from outside every pool.
    rayon::scope(|_| {
        // No call follows the loop: the helpers go when it ends.
        let vigil = Vigil::new(Duration::ZERO);
        let _hold = vigil.hold(
            rayon::current_num_threads().saturating_sub(1),
            rayon::current_thread_index(),
            rayon::spawn,
        );
        f()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rounds of the tests that repeat: fewer under Miri, which interprets every step.
    const ROUNDS: u64 = if cfg!(miri) { 4 } else { 50 };

    /// Waits until every helper of `vigil` has ended.
    fn until_asleep(vigil: &Vigil) {
        while vigil.helpers.load(Ordering::Acquire) > 0 {
            std::thread::yield_now();
        }
    }

    #[test]
    fn every_part_runs_once_and_results_keep_their_order() {
        let team = Team::new(2).unwrap();
        assert_eq!(team.threads(), 2);
        for round in 0..ROUNDS {
            let parts: Vec<u64> = (0..5).map(|i| i + round).collect();
            let threads = std::sync::Mutex::new(std::collections::HashSet::new());
            let out = team.run(parts.clone(), |p| {
                threads.lock().unwrap().insert(std::thread::current().id());
                p * 3
            });
            assert_eq!(out, parts.iter().map(|p| p * 3).collect::<Vec<_>>());
            assert!(
                threads.lock().unwrap().contains(&std::thread::current().id()),
                "the caller takes a part"
            );
            if round % 2 == 1 {
                // The next call finds the workers asleep: it wakes them.
                until_asleep(&team.vigil);
            }
        }
        assert!(team.run(Vec::<u8>::new(), |p| p).is_empty());
    }

    #[test]
    fn a_panic_in_any_part_reaches_the_caller_after_every_part_ended() {
        let team = Team::new(2).unwrap();
        for panicking in [0, 1] {
            let ended = AtomicUsize::new(0);
            let caught = catch_unwind(AssertUnwindSafe(|| {
                team.run(vec![0, 1], |p| {
                    if p == panicking {
                        panic!("part {p}");
                    }
                    // The other part outlasts the panic: the caller must still wait for it.
                    std::thread::sleep(Duration::from_millis(20));
                    ended.fetch_add(1, Ordering::SeqCst);
                })
            }));
            assert!(caught.is_err(), "the panic of part {panicking} is the caller's");
            assert_eq!(ended.load(Ordering::SeqCst), 1, "the other part ended first");
        }
        assert_eq!(team.run(vec![4, 5], |p| p + 1), vec![5, 6], "the team still works");
    }

    #[test]
    fn a_checked_run_steps_every_part_or_none_and_names_the_first_refusal() {
        let team = Team::new(2).unwrap();
        let stepped = AtomicUsize::new(0);
        let step = |p: u32| {
            stepped.fetch_add(1, Ordering::SeqCst);
            p * 2
        };
        assert_eq!(
            team.run_checked(vec![1, 2], |_| Ok::<(), u32>(()), step),
            Ok(vec![2, 4])
        );
        for refusing in [vec![1], vec![2], vec![1, 2]] {
            let before = stepped.load(Ordering::SeqCst);
            let refuse = |p: &u32| if refusing.contains(p) { Err(*p) } else { Ok(()) };
            assert_eq!(team.run_checked(vec![1, 2], refuse, step), Err(refusing[0]));
            assert_eq!(
                stepped.load(Ordering::SeqCst),
                before,
                "nothing stepped after a refusal"
            );
        }
    }

    #[test]
    fn a_vigil_is_awake_while_held_and_for_warm_for_after_its_last_hold() {
        let vigil = Vigil::new(WARM_FOR);
        let warm = WARM_FOR.as_nanos() as u64;
        let (first, second) = (vigil.hold(0, None, |_| {}), vigil.hold(0, None, |_| {}));
        drop(first);
        assert!(vigil.awake_at(u64::MAX), "one hold is still in force");
        drop(second);
        let released = vigil.released.load(Ordering::Acquire);
        assert!(vigil.awake_at(released));
        assert!(vigil.awake_at(released + warm - 1));
        assert!(!vigil.awake_at(released + warm));
    }

    #[test]
    fn a_hold_spawns_only_the_missing_helpers_and_they_end_after_it() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let vigil = Vigil::new(WARM_FOR);
        let spawned = AtomicUsize::new(0);
        let spawn = |helper: Box<dyn FnOnce() + Send>| {
            spawned.fetch_add(1, Ordering::SeqCst);
            pool.spawn(helper);
        };
        let hold = vigil.hold(2, None, spawn);
        assert_eq!(spawned.load(Ordering::SeqCst), 2);
        // While held, the helpers take the pool's work and stay.
        let (tx, rx) = std::sync::mpsc::channel();
        pool.spawn(move || tx.send(7).unwrap());
        assert_eq!(rx.recv().unwrap(), 7);
        let again = vigil.hold(2, None, spawn);
        assert_eq!(spawned.load(Ordering::SeqCst), 2, "both helpers are still awake");
        drop((hold, again));
        until_asleep(&vigil);
        drop(vigil.hold(2, None, spawn));
        assert_eq!(
            spawned.load(Ordering::SeqCst),
            4,
            "a hold after they ended wakes two more"
        );
        until_asleep(&vigil);
    }

    #[test]
    fn a_run_on_the_awake_pool_gives_its_result_and_its_splits_end() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let sums = pool.install(|| {
            on_pool_awake(|| {
                (0..4 * ROUNDS)
                    .map(|k: u64| {
                        let (a, b) = rayon::join(|| (0..k).sum::<u64>(), || (k..2 * k).sum::<u64>());
                        a + b
                    })
                    .sum::<u64>()
            })
        });
        assert_eq!(sums, (0..4 * ROUNDS).map(|k| (0..2 * k).sum::<u64>()).sum::<u64>());
        // Outside every pool and on a pool of one thread, the same.
        assert_eq!(on_pool_awake(|| rayon::join(|| 1, || 2)), (1, 2));
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        assert_eq!(one.install(|| on_pool_awake(|| rayon::join(|| 3, || 4))), (3, 4));
    }

    #[test]
    fn a_panic_on_the_awake_pool_reaches_the_caller_and_frees_the_pool() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let caught = pool.install(|| {
            std::panic::catch_unwind(|| on_pool_awake(|| rayon::join(|| 1, || -> i32 { panic!("a half failed") })))
        });
        assert!(caught.is_err());
        // The hold ended with the panic: the pool still runs work on both threads.
        assert_eq!(pool.install(|| on_pool_awake(|| rayon::join(|| 5, || 6))), (5, 6));
    }
}
