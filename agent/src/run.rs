//! The one skeleton of a training run, for both learners: the tabular [`Trainer`](crate::Trainer)
//! here and the network's `neural::Trainer`.
//!
//! Why one: a run is the same loop whatever learns in it. It goes one unit at a time (a game
//! for the tabular learner, a step for the network) up to a total; after each unit the
//! caller sees the run's progress and may stop it (Ctrl-C: its hook returns an error); and,
//! when the run has a checkpoint file, it is written every so many units counted from the
//! run's first, after the last, and once when nothing was left to do. A learner says only
//! how to do one unit and how to write its checkpoint ([`Runnable`]); the loop ([`run_until`]),
//! the checkpoint's schedule ([`Checkpoints`]) and the recent games the progress reports
//! ([`RecentGames`]) live here once.

use std::collections::VecDeque;

use files::OutputPath;

/// Games the progress figures look back over.
pub const RECENT_GAMES: usize = 100;

/// A learner the run loop ([`run_until`]) drives.
pub trait Runnable {
    /// What it tells after each unit.
    type Progress;
    /// Its error: a hook's error (a stop) ends the run as one.
    type Error;

    /// Units done so far, counted from the run's first.
    fn units_done(&self) -> u64;

    /// Makes `total` units the run's end, an error if it cannot be (below the units done);
    /// the total it will run to.
    fn plan_to(&mut self, total: u64) -> Result<u64, Self::Error>;

    /// Does the next unit of a run to `total`; the progress after it.
    fn next_unit(&mut self, total: u64) -> Result<Self::Progress, Self::Error>;

    /// Writes the run as it stands to its checkpoint file.
    fn write_checkpoint(&self, out: &OutputPath) -> Result<(), Self::Error>;
}

/// Where a run writes its checkpoint, and how often.
#[derive(Clone, Copy, Debug)]
pub struct Checkpoints<'a> {
    /// The checkpoint file.
    pub out: &'a OutputPath,
    /// Units between two checkpoints, counted from the run's first (0 counts as 1).
    pub every: u64,
}

impl<'a> Checkpoints<'a> {
    /// A checkpoint every `every` units to `out`, when `out` is given.
    pub fn to(out: Option<&'a OutputPath>, every: u64) -> Option<Checkpoints<'a>> {
        out.map(|out| Checkpoints { out, every })
    }

    /// Whether the checkpoint is due after `units` of a run to `total`: after a multiple of
    /// `every`, and after the last.
    pub fn due(&self, units: u64, total: u64) -> bool {
        units.is_multiple_of(self.every.max(1)) || units == total
    }
}

/// What a run does beside learning: `after` sees the progress after every unit (its error,
/// say Ctrl-C seen, stops the run before the next unit), and the checkpoints, if any.
pub struct RunHooks<'a, F> {
    /// Told the progress after every unit; an error stops the run.
    pub after: F,
    /// Where and how often the checkpoint is written, if the run has one.
    pub checkpoints: Option<Checkpoints<'a>>,
}

impl<'a, P, E> RunHooks<'a, fn(&P) -> Result<(), E>> {
    /// Hooks that only write `checkpoints` (none: a run that only learns).
    pub fn quiet(checkpoints: Option<Checkpoints<'a>>) -> Self {
        RunHooks {
            after: |_| Ok(()),
            checkpoints,
        }
    }
}

/// Runs `learner` until `total` units are done in all, the one loop of a whole run for the
/// command line and Python: after each unit, the checkpoint when it is due (first, so that
/// a run the hook stops keeps the checkpoint it was due), then `hooks.after`. A run with
/// nothing left to do still writes its checkpoint. An error if `total` is below the units
/// done.
pub fn run_until<L, F>(learner: &mut L, total: u64, hooks: &mut RunHooks<'_, F>) -> Result<(), L::Error>
where
    L: Runnable + ?Sized,
    F: FnMut(&L::Progress) -> Result<(), L::Error>,
{
    let done = learner.units_done();
    let total = learner.plan_to(total)?;
    while learner.units_done() < total {
        let progress = learner.next_unit(total)?;
        if let Some(c) = hooks.checkpoints
            && c.due(learner.units_done(), total)
        {
            learner.write_checkpoint(c.out)?;
        }
        (hooks.after)(&progress)?;
    }
    if let Some(c) = hooks.checkpoints
        && done == total
    {
        // Nothing was left to do: the checkpoint still records the run as it stands.
        learner.write_checkpoint(c.out)?;
    }
    Ok(())
}

/// The outcomes of the last (at most [`RECENT_GAMES`]) games of a run, oldest first: `T` is
/// what a game's outcome records (whether it reached the goal, or in how many steps).
#[derive(Clone, Debug, PartialEq)]
pub struct Recent<T> {
    games: VecDeque<T>,
}

impl<T> Default for Recent<T> {
    fn default() -> Self {
        Recent {
            games: VecDeque::with_capacity(RECENT_GAMES),
        }
    }
}

impl<T: Clone> Recent<T> {
    /// The window holding `games` (the last [`RECENT_GAMES`] of them).
    pub fn of(games: impl IntoIterator<Item = T>) -> Recent<T> {
        let mut recent = Recent::default();
        for g in games {
            recent.push(g);
        }
        recent
    }

    /// Adds a finished game's outcome, forgetting the oldest past [`RECENT_GAMES`].
    pub fn push(&mut self, outcome: T) {
        if self.games.len() == RECENT_GAMES {
            self.games.pop_front();
        }
        self.games.push_back(outcome);
    }

    /// The outcomes, oldest first.
    pub fn iter(&self) -> impl Iterator<Item = &T> {
        self.games.iter()
    }

    /// How many games it holds.
    pub fn len(&self) -> usize {
        self.games.len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.games.is_empty()
    }

    /// How many of them and how many reached the goal (`reached` says of one).
    pub fn count(&self, reached: impl Fn(&T) -> bool) -> RecentGames {
        RecentGames {
            games: self.games.len(),
            successes: self.games.iter().filter(|g| reached(g)).count(),
        }
    }
}

/// Of the last (at most [`RECENT_GAMES`]) games of a run, how many, and how many reached the
/// goal: what both learners' progress reports.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RecentGames {
    /// Games.
    pub games: usize,
    /// Of those, games that reached the goal.
    pub successes: usize,
}

impl RecentGames {
    /// The share that reached the goal, in `[0, 1]` (0 before any game ended).
    pub fn success_rate(&self) -> f64 {
        if self.games == 0 {
            0.0
        } else {
            self.successes as f64 / self.games as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A learner that counts its units; its checkpoint fails, naming the unit it was at.
    struct Counter {
        done: u64,
        planned: u64,
    }

    impl Runnable for Counter {
        type Progress = u64;
        type Error = String;

        fn units_done(&self) -> u64 {
            self.done
        }

        fn plan_to(&mut self, total: u64) -> Result<u64, String> {
            if total < self.done {
                return Err(format!("{total} < {}", self.done));
            }
            Ok(total.min(self.planned))
        }

        fn next_unit(&mut self, _total: u64) -> Result<u64, String> {
            self.done += 1;
            Ok(self.done)
        }

        fn write_checkpoint(&self, _out: &OutputPath) -> Result<(), String> {
            Err(format!("checkpoint at {}", self.done))
        }
    }

    #[test]
    fn a_run_checkpoints_on_multiples_and_at_its_end_and_stops_on_its_hooks_word() {
        let dir = tempfile::tempdir().unwrap();
        let out = OutputPath::check(dir.path().join("ck")).unwrap();
        let mut c = Counter { done: 0, planned: 10 };
        // Without checkpoints it runs to the plan's end, telling every unit.
        let mut seen = Vec::new();
        run_until(
            &mut c,
            7,
            &mut RunHooks {
                after: |p: &u64| {
                    seen.push(*p);
                    Ok(())
                },
                checkpoints: None,
            },
        )
        .unwrap();
        assert_eq!(seen, (1..=7).collect::<Vec<_>>());
        // A checkpoint due is written before the hook is told (here it fails, ending the run).
        let err = run_until(&mut c, 20, &mut RunHooks::quiet(Checkpoints::to(Some(&out), 4))).unwrap_err();
        assert_eq!(err, "checkpoint at 8");
        // A run with nothing left to do still writes its checkpoint.
        c.done = 10;
        let err = run_until(&mut c, 10, &mut RunHooks::quiet(Checkpoints::to(Some(&out), 4))).unwrap_err();
        assert_eq!(err, "checkpoint at 10");
        assert_eq!(run_until(&mut c, 3, &mut RunHooks::quiet(None)).unwrap_err(), "3 < 10");
        // The hook's error stops the run after the unit it saw.
        c.done = 0;
        let stop = run_until(
            &mut c,
            10,
            &mut RunHooks {
                after: |p: &u64| if *p == 2 { Err("stop".to_string()) } else { Ok(()) },
                checkpoints: None,
            },
        );
        assert_eq!((stop, c.done), (Err("stop".to_string()), 2));
        let due = Checkpoints::to(Some(&out), 4).unwrap();
        assert!(due.due(8, 10) && due.due(10, 10) && !due.due(9, 10));
    }

    #[test]
    fn the_recent_window_keeps_the_last_hundred_games() {
        let mut recent = Recent::default();
        assert_eq!(recent.count(|&r| r).success_rate(), 0.0);
        for k in 0..250u32 {
            recent.push(k % 4 == 0);
        }
        assert_eq!(recent.len(), RECENT_GAMES);
        let counted = recent.count(|&r| r);
        assert_eq!((counted.games, counted.successes), (100, 25));
        assert_eq!(counted.success_rate(), 0.25);
        assert_eq!(Recent::of(recent.iter().copied()), recent);
    }
}
