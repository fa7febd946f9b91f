//! Keeping a pool's threads awake, the one home of it: for a caller outside every pool that
//! hands out batches call after call (`Team`, the vector env's), and for a loop run on a
//! pool whose splits must find the other threads awake ([`on_pool_awake`], the network
//! trainer's).
//!
//! # A team: the caller's thread and a pool's workers sharing one batch, call after call
//!
//! Why not `rayon::ThreadPool::install`: a vector env's step at 1,024 environments takes a
//! few hundred microseconds, and `install` hands the whole batch to pool threads that have
//! gone to sleep since the last call, then puts the caller to sleep until they finish. On
//! a virtual machine each wake-up costs tens of microseconds, a large share of such a call
//! (docs/performance.md measures it). A `Team` runs the first part of a batch on the
//! caller's thread while its workers take the others, waits for them by spinning (they are
//! at most a wake-up behind), and keeps its workers spinning for `WARM_FOR` after each
//! call, so a call that follows soon finds them awake; OpenMP's default wait policy spins
//! the same way before it sleeps. It hands the parts out with `spawn` and counts them back
//! itself: at the end of a `rayon::scope` the caller can still miss the last part's signal
//! by a few instructions and sleep until it is woken.
//!
//! # A loop on an awake pool
//!
//! A network's training step forks and joins a few times, between serial stretches long
//! enough for an idle rayon thread to go to sleep; [`on_pool_awake`] runs the loop on a pool
//! thread and keeps the others looking for work (yielding their cores between looks) until it
//! ends. A team would not do here: the splits happen inside the loop, on its thread.
//!
//! The team's `unsafe` lifetime erasure is checked under Miri (docs/development.md, "Unsafe
//! code under Miri"): its tests run there.

use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use crate::error::{Result, SimError};

/// How long the workers spin after a call, waiting for the next one: longer than a
/// Python caller's own work between two steps, short enough that a caller that has
/// stopped stepping gets its cores back at once.
pub(crate) const WARM_FOR: Duration = Duration::from_micros(200);

/// Spins of the caller's wait before it starts yielding its core.
const SPINS_BEFORE_YIELD: u32 = 1 << 12;

/// The caller's thread and `threads - 1` pool workers, sharing each batch of parts.
pub(crate) struct Team {
    /// The workers: one fewer than the team, since the caller's thread takes a part.
    pool: rayon::ThreadPool,
    /// Counts the calls; a worker spinning after one stops when the next begins.
    calls: Arc<AtomicU64>,
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
            calls: Arc::new(AtomicU64::new(0)),
        })
    }

    /// Threads that share a batch, the caller's among them.
    pub(crate) fn threads(&self) -> usize {
        self.pool.current_num_threads() + 1
    }

    /// `f` of every part, in order: the first on the caller's thread, the others on the
    /// workers. A panic in any part reaches the caller once every part has ended.
    pub(crate) fn run<T: Send, R: Send>(&self, parts: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
        let call = self.calls.fetch_add(1, Ordering::AcqRel) + 1;
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
            // `catch_unwind`). Erasing the lifetime is what `rayon::scope` does inside;
            // its own end, though, can put the caller to sleep for a wake-up.
            let job: Box<dyn FnOnce() + Send + 'static> = unsafe { std::mem::transmute(job) };
            self.pool.spawn(job);
        }
        let head = catch_unwind(AssertUnwindSafe(|| f(first)));
        wait_for(&ended, others.len());
        self.keep_warm(call);
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

    /// Has every worker spin until the next call begins or [`WARM_FOR`] has passed.
    fn keep_warm(&self, call: u64) {
        for _ in 0..self.pool.current_num_threads() {
            let calls = Arc::clone(&self.calls);
            self.pool.spawn(move || {
                let start = Instant::now();
                while calls.load(Ordering::Acquire) == call && start.elapsed() < WARM_FOR {
                    std::hint::spin_loop();
                }
            });
        }
    }
}

/// Waits until `ended` counts `parts`: the workers are at most a wake-up behind, so the
/// caller spins, and yields its core only if they are later than that.
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
/// while the pool's other threads stay awake until it returns, each looking for work
/// ([`rayon::yield_now`]) and yielding its core between looks, so the halves a `rayon::join`
/// offers (the network kernels' splits, `neural::kernels::join`) are taken at once. Nothing changes which half runs what, so results are the
/// same bits.
///
/// Why: a training step is a few splits apart from serial stretches (the gradients' norm,
/// the losses) of tens of microseconds, long enough for an idle rayon thread to go to
/// sleep, and then each split pays a wake-up in the kernel (docs/performance.md
/// measures it). The price is the other threads' cores for as long as `f` runs, when
/// nothing else wants them.
pub fn on_pool_awake<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    /// Ends the helpers when `f` returns or unwinds: the scope waits for them.
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }
    let done = AtomicBool::new(false);
    rayon::scope(|s| {
        let runner = rayon::current_thread_index();
        for _ in 1..rayon::current_num_threads() {
            let done = &done;
            s.spawn(move |_| {
                // The thread running `f` can take this job while it waits for a half; it
                // must not stay here.
                if rayon::current_thread_index() == runner {
                    return;
                }
                while !done.load(Ordering::Acquire) {
                    // Between looks the core is offered to the scheduler: given back at
                    // once when nothing else wants it, and shared when something does (a
                    // pure spin made a run on a busy machine 1.8 times slower than no
                    // helper at all: docs/performance.md).
                    if rayon::yield_now() != Some(rayon::Yield::Executed) {
                        std::thread::yield_now();
                    }
                }
            });
        }
        let _done = Done(&done);
        f()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_part_runs_once_and_results_keep_their_order() {
        let team = Team::new(2).unwrap();
        assert_eq!(team.threads(), 2);
        for round in 0..50u64 {
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
    fn a_run_on_the_awake_pool_gives_its_result_and_its_splits_end() {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let sums = pool.install(|| {
            on_pool_awake(|| {
                (0..200)
                    .map(|k: u64| {
                        let (a, b) = rayon::join(|| (0..k).sum::<u64>(), || (k..2 * k).sum::<u64>());
                        a + b
                    })
                    .sum::<u64>()
            })
        });
        assert_eq!(sums, (0..200u64).map(|k| (0..2 * k).sum::<u64>()).sum::<u64>());
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
        // The helpers ended: the pool still runs work on both threads.
        assert_eq!(pool.install(|| on_pool_awake(|| rayon::join(|| 5, || 6))), (5, 6));
    }
}
