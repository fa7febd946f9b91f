//! Planning every task of a folder (`blockstack solve-all`, Python's `solve_all`): the
//! tasks found, each planned and its plan checked, its cost set against its lower bound and
//! against the best known cost where a file of them is given, and a summary per subfolder.
//!
//! - The folder is walked with [`files::files_below`]: links are followed, each folder and
//!   file once, so a link loop ends and no task is counted twice. Every `*.pddl` but
//!   `domain.pddl` is a task.
//! - Best known costs are a JSON object from a task's path to its cost, as the 2023
//!   competition's `solutions/upper_bounds.json` is (`{"blocksworld/testing/easy/p01.pddl":
//!   10, ...}`). A task takes the entry its path ends with; of several, the most specific
//!   (the one of most path components), so `sub/p01.pddl` is not given `p01.pddl`'s cost.
//! - Proven optima are read from a report of the optimal solver (`solve-all --solver optimal
//!   --json`): its tasks proven optimal, with their cost, matched to a task as best known
//!   costs are. Every plan is then set against its task's optimum too.
//! - A task that cannot be read or planned is a row with its error; the others go on.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::error::Result;
use crate::towers::BlockPlanner;

use super::error::PddlError;
use super::problem::Problem;

/// The largest file of best known costs read.
pub const MAX_BOUNDS_BYTES: u64 = 16 << 20;

/// Best known costs of tasks, by path (module docs).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BestKnown {
    costs: BTreeMap<String, u64>,
}

/// The text of the file at `path` (`what` it is, for messages), at most
/// [`MAX_BOUNDS_BYTES`], and its name as shown in messages.
fn read_bounded(path: &Path, what: &'static str) -> Result<(String, String)> {
    let shown = path.display().to_string();
    let mut text = String::new();
    files::open_bounded(path, MAX_BOUNDS_BYTES, what)
        .map_err(PddlError::from)?
        .read_to_string(&mut text)
        .map_err(|e| PddlError::Bounds {
            file: shown.clone(),
            reason: e.to_string(),
        })?;
    Ok((text, shown))
}

impl BestKnown {
    /// Reads a file of best known costs, at most [`MAX_BOUNDS_BYTES`].
    pub fn read(path: &Path) -> Result<BestKnown> {
        let (text, shown) = read_bounded(path, "a file of best known costs")?;
        BestKnown::parse(&text, &shown)
    }

    /// The proven optima of a report of the optimal solver (module docs), at most
    /// [`MAX_BOUNDS_BYTES`]: the cost of each task it proved optimal, by its path.
    pub fn read_optima(path: &Path) -> Result<BestKnown> {
        let (text, shown) = read_bounded(path, "a report of proven optima")?;
        let bad = |reason: String| PddlError::Bounds {
            file: shown.clone(),
            reason,
        };
        let report: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        let tasks = report["tasks"]
            .as_array()
            .ok_or_else(|| bad("no list of \"tasks\": not a report of `solve-all --json`".into()))?;
        let costs = tasks
            .iter()
            .filter(|t| t["optimal"].as_bool() == Some(true))
            .filter_map(|t| Some((t["task"].as_str()?.to_string(), t["actions"].as_u64()?)))
            .collect();
        Ok(BestKnown { costs })
    }

    /// The costs in `text` (named `file` in errors).
    pub fn parse(text: &str, file: &str) -> Result<BestKnown> {
        let costs = serde_json::from_str(text).map_err(|e| PddlError::Bounds {
            file: file.to_string(),
            reason: e.to_string(),
        })?;
        Ok(BestKnown { costs })
    }

    /// The best known cost of the task at `path`: the most specific entry its path ends
    /// with (module docs).
    pub fn of(&self, path: &Path) -> Option<u64> {
        self.costs
            .iter()
            .filter(|(key, _)| path.ends_with(Path::new(key.as_str())))
            .max_by_key(|(key, _)| Path::new(key.as_str()).components().count())
            .map(|(_, &cost)| cost)
    }
}

/// The tasks below `folder`: every `*.pddl` but `domain.pddl`, in the walk's sorted order;
/// an error if there is none.
pub fn find_tasks(folder: &Path) -> Result<Vec<PathBuf>> {
    let tasks = files::files_below(folder, |p| {
        p.extension().is_some_and(|e| e == "pddl") && p.file_name().is_some_and(|n| n != "domain.pddl")
    })
    .map_err(PddlError::from)?;
    if tasks.is_empty() {
        return Err(PddlError::NoTasks {
            folder: folder.display().to_string(),
        }
        .into());
    }
    Ok(tasks)
}

/// One task's row. Costs are in the competitions' unit, actions (two per block move).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TaskRow {
    /// The path below the folder.
    pub task: String,
    /// Its subfolder below the folder (`.` for the folder itself).
    pub group: String,
    /// Blocks, if the task was read.
    pub blocks: Option<usize>,
    /// Block moves of the plan.
    pub moves: Option<usize>,
    /// The plan's cost.
    pub actions: Option<usize>,
    /// The lower bound on every plan's cost.
    pub lower_bound: Option<usize>,
    /// The cost above the bound (0: proven optimal).
    pub gap: Option<usize>,
    /// The bound's first part, in block moves (`towers::Certificate`): the blocks not in
    /// their final position.
    pub misplaced: Option<usize>,
    /// The bound's second part: the blocks forced to move twice.
    pub forced: Option<usize>,
    /// The bound's third part: the smallest set of the other blocks that breaks every
    /// deadlock (a bound on its size when the proof did not close).
    pub breakers: Option<usize>,
    /// Whether the plan is proven optimal.
    pub optimal: Option<bool>,
    /// The best known cost, if a file of them gives one.
    pub best_known: Option<u64>,
    /// `actions / best_known`.
    pub ratio: Option<f64>,
    /// The task's proven optimum, if a report of them gives one.
    pub optimum: Option<u64>,
    /// `actions / optimum`.
    pub over_optimum: Option<f64>,
    /// Seconds spent reading, planning and checking the task (the machine's, not a result).
    pub seconds: f64,
    /// CPU seconds the thread that read, planned and checked the task spent on it (one
    /// core's; at most `seconds` but for the clocks' granularity).
    pub cpu_seconds: f64,
    /// Why the task has no plan.
    pub error: Option<String>,
}

/// A group's (or all tasks') summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// The subfolder, or `all`.
    pub group: String,
    /// Tasks.
    pub tasks: usize,
    /// Tasks with a plan.
    pub solved: usize,
    /// Tasks whose plan is proven optimal.
    pub optimal: usize,
    /// Solved tasks with a best known cost.
    pub bounded: usize,
    /// The mean of `actions / best_known` over them.
    pub mean_ratio: Option<f64>,
    /// The largest such ratio.
    pub max_ratio: Option<f64>,
    /// The mean of `actions / lower_bound` over the solved tasks (1: all proven optimal).
    pub mean_over_bound: Option<f64>,
    /// The mean of `actions / optimum` over the solved tasks with a known optimum.
    pub mean_over_optimum: Option<f64>,
    /// The largest such ratio.
    pub max_over_optimum: Option<f64>,
    /// Actions over all solved tasks.
    pub actions: usize,
}

impl Summary {
    fn of<'a>(group: &str, rows: impl Iterator<Item = &'a TaskRow>) -> Summary {
        let rows: Vec<&TaskRow> = rows.collect();
        let ratios: Vec<f64> = rows.iter().filter_map(|r| r.ratio).collect();
        let over: Vec<f64> = rows
            .iter()
            .filter_map(|r| match (r.actions, r.lower_bound) {
                (Some(a), Some(b)) if b > 0 => Some(a as f64 / b as f64),
                (Some(_), Some(_)) => Some(1.0),
                _ => None,
            })
            .collect();
        let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
        let over_optimum: Vec<f64> = rows.iter().filter_map(|r| r.over_optimum).collect();
        Summary {
            group: group.to_string(),
            tasks: rows.len(),
            solved: rows.iter().filter(|r| r.actions.is_some()).count(),
            optimal: rows.iter().filter(|r| r.optimal == Some(true)).count(),
            bounded: ratios.len(),
            mean_ratio: mean(&ratios),
            max_ratio: ratios.iter().copied().reduce(f64::max),
            mean_over_bound: mean(&over),
            mean_over_optimum: mean(&over_optimum),
            max_over_optimum: over_optimum.iter().copied().reduce(f64::max),
            actions: rows.iter().filter_map(|r| r.actions).sum(),
        }
    }
}

/// A folder's report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuiteReport {
    /// The planner's name.
    pub solver: String,
    /// One row per task, in the walk's order.
    pub tasks: Vec<TaskRow>,
    /// One summary per subfolder, in the order they first appear.
    pub groups: Vec<Summary>,
    /// The summary of all tasks.
    pub overall: Summary,
}

/// What each plan is set against besides its own bound: best known costs and proven optima
/// (module docs), where given.
#[derive(Debug, Clone, Copy, Default)]
pub struct Yardsticks<'a> {
    /// Best known costs.
    pub best_known: Option<&'a BestKnown>,
    /// Proven optima.
    pub optima: Option<&'a BestKnown>,
}

/// Plans every task below `folder` with `planner` (module docs), calling `progress` after
/// each; an error only if the folder cannot be walked or holds no task.
pub fn run(
    folder: &Path,
    planner: &dyn BlockPlanner,
    against: Yardsticks,
    progress: &mut dyn FnMut(&TaskRow, usize),
) -> Result<SuiteReport> {
    let paths = find_tasks(folder)?;
    let mut rows = Vec::with_capacity(paths.len());
    for path in &paths {
        let row = plan_task(folder, path, planner, against);
        progress(&row, paths.len());
        rows.push(row);
    }
    let mut names: Vec<&str> = rows.iter().map(|r| r.group.as_str()).collect();
    names.dedup();
    let groups = names
        .iter()
        .map(|g| Summary::of(g, rows.iter().filter(|r| r.group == *g)))
        .collect();
    Ok(SuiteReport {
        solver: planner.name().to_string(),
        overall: Summary::of("all", rows.iter()),
        groups,
        tasks: rows,
    })
}

/// The row of the task at `path` below `folder`.
fn plan_task(folder: &Path, path: &Path, planner: &dyn BlockPlanner, against: Yardsticks) -> TaskRow {
    let started = Instant::now();
    let cpu_started = thread_cpu_seconds();
    let rel = path.strip_prefix(folder).unwrap_or(path);
    let group = rel.parent().map(|p| p.display().to_string()).filter(|g| !g.is_empty());
    let best = against.best_known.and_then(|b| b.of(path));
    let optimum = against.optima.and_then(|o| o.of(path));
    let mut row = TaskRow {
        task: rel.display().to_string(),
        group: group.unwrap_or_else(|| ".".into()),
        blocks: None,
        moves: None,
        actions: None,
        lower_bound: None,
        gap: None,
        misplaced: None,
        forced: None,
        breakers: None,
        optimal: None,
        best_known: best,
        ratio: None,
        optimum,
        over_optimum: None,
        seconds: 0.0,
        cpu_seconds: 0.0,
        error: None,
    };
    let solved = Problem::read(path).and_then(|problem| {
        row.blocks = Some(problem.block_names().len());
        problem.solve(planner)
    });
    match solved {
        Ok(plan) => {
            row.moves = Some(plan.moves.len());
            row.actions = Some(plan.cost());
            row.lower_bound = Some(plan.lower_bound_cost());
            row.gap = Some(plan.cost() - plan.lower_bound_cost());
            row.misplaced = Some(plan.certificate.misplaced);
            row.forced = Some(plan.certificate.forced);
            row.breakers = Some(plan.certificate.breakers);
            row.optimal = Some(plan.is_optimal());
            row.ratio = best.filter(|&b| b > 0).map(|b| plan.cost() as f64 / b as f64);
            row.over_optimum = optimum.filter(|&o| o > 0).map(|o| plan.cost() as f64 / o as f64);
        }
        Err(e) => row.error = Some(e.to_string()),
    }
    row.seconds = started.elapsed().as_secs_f64();
    row.cpu_seconds = thread_cpu_seconds() - cpu_started;
    row
}

/// The CPU time the calling thread has used, in seconds: a task is planned on one thread,
/// so the difference of two readings is its CPU time on one core, whatever else the machine
/// runs.
fn thread_cpu_seconds() -> f64 {
    let mut now = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `now` is a valid, writable timespec for the call's duration, and the clock
    // exists on every Unix the workspace builds for; on failure `now` stays zero.
    let failed = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut now) } != 0;
    if failed {
        return 0.0;
    }
    now.tv_sec as f64 + now.tv_nsec as f64 * 1e-9
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::towers::{NearOptimal, OptimalMoves};

    const TASK: &str = "(define (problem p) (:domain blocksworld) (:objects b1 b2 b3)
      (:init (arm-empty) (clear b3) (on b3 b1) (on-table b1) (clear b2) (on-table b2))
      (:goal (and (on b1 b2) (on-table b2))))";

    #[test]
    fn the_most_specific_best_known_cost_wins() {
        let known = BestKnown::parse(r#"{"sub/p01.pddl": 3, "p01.pddl": 1, "x/sub/p01.pddl": 7}"#, "b.json").unwrap();
        assert_eq!(known.of(Path::new("tasks/sub/p01.pddl")), Some(3));
        assert_eq!(known.of(Path::new("tasks/x/sub/p01.pddl")), Some(7));
        assert_eq!(known.of(Path::new("tasks/p01.pddl")), Some(1));
        assert_eq!(known.of(Path::new("tasks/p02.pddl")), None);
        let err = BestKnown::parse("[1, 2]", "b.json").unwrap_err().to_string();
        assert!(err.starts_with("b.json: ") && err.contains("JSON object"), "{err}");
    }

    #[test]
    fn a_folder_with_link_loops_is_planned_once_per_task() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        std::fs::create_dir_all(dir.join("easy")).unwrap();
        std::fs::write(dir.join("easy/p01.pddl"), TASK).unwrap();
        std::fs::write(dir.join("easy/domain.pddl"), "(define (domain blocksworld))").unwrap();
        std::fs::write(dir.join("bad.pddl"), "(define").unwrap();
        std::os::unix::fs::symlink("..", dir.join("easy/up")).unwrap();
        std::os::unix::fs::symlink(dir, dir.join("easy/self")).unwrap();
        let known = BestKnown::parse(r#"{"easy/p01.pddl": 8}"#, "b.json").unwrap();
        let mut seen = 0;
        let against = Yardsticks {
            best_known: Some(&known),
            optima: None,
        };
        let report = run(dir, &OptimalMoves::new(), against, &mut |_, _| seen += 1).unwrap();
        assert_eq!(seen, 2);
        let names: Vec<&str> = report.tasks.iter().map(|t| t.task.as_str()).collect();
        assert_eq!(names, ["bad.pddl", "easy/p01.pddl"]);
        let row = &report.tasks[1];
        assert_eq!(
            (row.actions, row.lower_bound, row.gap, row.optimal),
            (Some(4), Some(4), Some(0), Some(true))
        );
        assert_eq!(row.ratio, Some(0.5));
        // The task ran on this thread: its CPU time is measured, and no more than its wall
        // time (the clocks' granularity aside).
        assert!(
            row.cpu_seconds > 0.0 && row.cpu_seconds <= row.seconds + 1e-3,
            "{row:?}"
        );
        assert!(report.tasks[0].error.is_some());
        assert_eq!(
            (report.overall.tasks, report.overall.solved, report.overall.optimal),
            (2, 1, 1)
        );
        assert_eq!(report.groups.len(), 2);
        // The near-optimal planner is measured against the bound that takes no search, and
        // against the optima the optimal solver's report proved.
        let path = dir.join("optima.json");
        std::fs::write(&path, serde_json::to_string(&report).unwrap()).unwrap();
        let optima = BestKnown::read_optima(&path).unwrap();
        assert_eq!(optima.of(&dir.join("easy/p01.pddl")), Some(4));
        let against = Yardsticks {
            best_known: None,
            optima: Some(&optima),
        };
        let near = run(dir, &NearOptimal::new(), against, &mut |_, _| {}).unwrap();
        assert_eq!(near.solver, "near-optimal");
        let row = &near.tasks[1];
        assert!(row.lower_bound.unwrap() <= row.actions.unwrap());
        assert_eq!(row.optimum, Some(4));
        assert_eq!(row.over_optimum, Some(row.actions.unwrap() as f64 / 4.0));
        assert_eq!(near.overall.mean_over_optimum, row.over_optimum);
        std::fs::write(&path, "{}").unwrap();
        let err = BestKnown::read_optima(&path).unwrap_err().to_string();
        assert!(err.contains("solve-all --json"), "{err}");
    }

    #[test]
    fn an_empty_folder_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let err = run(tmp.path(), &NearOptimal::new(), Yardsticks::default(), &mut |_, _| {})
            .unwrap_err()
            .to_string();
        assert!(err.contains("holds no .pddl problem"), "{err}");
    }
}
