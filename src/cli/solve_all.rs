//! `blockstack solve-all`: a block-move planner over every PDDL problem of a folder, each
//! plan checked by replaying its actions over the file's facts, with costs compared to the
//! best known ones of an `upper_bounds.json` (the 2023 planning competition's
//! `solutions/upper_bounds.json`) when given: a table and a summary per subfolder.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use oracle::pddl::Problem;
use serde::Serialize;

use super::solve::{PddlPlanReport, SolverKind, pddl_planner, plan_pddl};
use super::solver_budget::SolverBudgetArg;
use super::stdout::line;

/// The largest bounds file read.
const MAX_BOUNDS_BYTES: u64 = 16 << 20;

/// Arguments of `blockstack solve-all`.
#[derive(Debug, Args)]
pub struct SolveAllArgs {
    /// The folder of problems: every `*.pddl` in it and its subfolders (but `domain.pddl`),
    /// grouped by subfolder in the summary.
    #[arg(long, value_name = "DIR")]
    pub tasks: PathBuf,
    /// Best known costs, in actions, as a JSON object from a task's path to its cost
    /// (`{"blocksworld/testing/easy/p01.pddl": 10, ...}`); a task takes the entry its path
    /// ends with.
    #[arg(long, value_name = "upper_bounds.json")]
    pub bounds: Option<PathBuf>,
    /// The planner: near-optimal (at most twice the optimum, any size) or exact (the fewest
    /// moves; refuses what its budget cannot finish).
    #[arg(long, value_enum, default_value_t = SolverKind::NearOptimal)]
    pub solver: SolverKind,
    #[command(flatten)]
    pub budget: SolverBudgetArg,
    /// Print one JSON object: {"solver", "tasks": [...], "groups": [...], "overall"}.
    #[arg(long)]
    pub json: bool,
}

/// One task's row.
#[derive(Debug, Serialize)]
struct TaskRow {
    /// The path below `--tasks`.
    task: String,
    /// Its subfolder below `--tasks` (`.` for the folder itself).
    group: String,
    blocks: Option<usize>,
    moves: Option<usize>,
    /// The plan's cost: two actions per move.
    actions: Option<usize>,
    /// The best known cost, if `--bounds` gives one.
    bound: Option<u64>,
    /// `actions / bound`.
    ratio: Option<f64>,
    /// Why the task was not solved.
    error: Option<String>,
}

/// A group's (or all tasks') summary.
#[derive(Debug, Serialize)]
struct Summary {
    group: String,
    tasks: usize,
    solved: usize,
    /// Solved tasks with a best known cost.
    bounded: usize,
    /// The mean of `actions / bound` over them.
    mean_ratio: Option<f64>,
    /// The largest ratio.
    max_ratio: Option<f64>,
    /// Actions over all solved tasks.
    actions: usize,
}

impl Summary {
    fn of<'a>(group: &str, rows: impl Iterator<Item = &'a TaskRow>) -> Summary {
        let rows: Vec<&TaskRow> = rows.collect();
        let ratios: Vec<f64> = rows.iter().filter_map(|r| r.ratio).collect();
        Summary {
            group: group.to_string(),
            tasks: rows.len(),
            solved: rows.iter().filter(|r| r.actions.is_some()).count(),
            bounded: ratios.len(),
            mean_ratio: (!ratios.is_empty()).then(|| ratios.iter().sum::<f64>() / ratios.len() as f64),
            max_ratio: ratios.iter().copied().reduce(f64::max),
            actions: rows.iter().filter_map(|r| r.actions).sum(),
        }
    }
}

/// The whole report.
#[derive(Debug, Serialize)]
struct SolveAllReport {
    solver: &'static str,
    tasks: Vec<TaskRow>,
    groups: Vec<Summary>,
    overall: Summary,
}

/// Plans every task and prints the table and the summary.
pub fn solve_all(args: SolveAllArgs) -> Result<()> {
    let planner = pddl_planner(Some(args.solver), &args.budget)?;
    let bounds = args.bounds.as_deref().map(read_bounds).transpose()?;
    let mut paths = Vec::new();
    find_problems(&args.tasks, &mut paths)?;
    anyhow::ensure!(
        !paths.is_empty(),
        "{} holds no .pddl problem (domain.pddl is not one)",
        args.tasks.display()
    );
    let bar = super::progress::bar(paths.len() as u64, "tasks");
    let mut rows = Vec::new();
    for path in &paths {
        let rel = path.strip_prefix(&args.tasks).unwrap_or(path);
        let group = rel.parent().map(|p| p.display().to_string()).filter(|g| !g.is_empty());
        let bound = bounds.as_ref().and_then(|b| {
            b.iter()
                .find(|(key, _)| path.ends_with(Path::new(key.as_str())))
                .map(|(_, &v)| v)
        });
        let mut row = TaskRow {
            task: rel.display().to_string(),
            group: group.unwrap_or_else(|| ".".into()),
            blocks: None,
            moves: None,
            actions: None,
            bound,
            ratio: None,
            error: None,
        };
        let solved = Problem::read(path).map_err(anyhow::Error::from).and_then(|problem| {
            row.blocks = Some(problem.block_names().len());
            let plan = plan_pddl(planner, &args.budget, &problem)?;
            Ok(PddlPlanReport::new(&problem, &plan)?.0)
        });
        match solved {
            Ok(report) => {
                row.moves = Some(report.moves);
                row.actions = Some(report.actions);
                row.ratio = bound.filter(|&b| b > 0).map(|b| report.actions as f64 / b as f64);
            }
            Err(e) => row.error = Some(format!("{e:#}")),
        }
        rows.push(row);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut names: Vec<&str> = rows.iter().map(|r| r.group.as_str()).collect();
    names.dedup();
    let groups: Vec<Summary> = names
        .iter()
        .map(|g| Summary::of(g, rows.iter().filter(|r| r.group == *g)))
        .collect();
    let report = SolveAllReport {
        solver: match planner {
            oracle::towers::MovePlanner::Exact => "exact",
            oracle::towers::MovePlanner::NearOptimal => "near-optimal",
        },
        overall: Summary::of("all", rows.iter()),
        groups,
        tasks: rows,
    };
    if args.json {
        line(serde_json::to_string(&report)?)
    } else {
        print_report(&report)
    }
}

/// The `.pddl` files under `dir`, but `domain.pddl`, sorted by path.
fn find_problems(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let entries = std::fs::read_dir(dir).with_context(|| format!("--tasks {}", dir.display()))?;
    let mut paths: Vec<PathBuf> = entries
        .map(|e| e.map(|e| e.path()))
        .collect::<std::io::Result<_>>()
        .with_context(|| format!("--tasks {}", dir.display()))?;
    paths.sort();
    for path in paths {
        if path.is_dir() {
            find_problems(&path, out)?;
        } else if path.extension().is_some_and(|e| e == "pddl") && path.file_name().is_some_and(|n| n != "domain.pddl")
        {
            out.push(path);
        }
    }
    Ok(())
}

/// The bounds file: a JSON object from task paths to costs.
fn read_bounds(path: &Path) -> Result<BTreeMap<String, u64>> {
    let mut text = String::new();
    files::open_bounded(path, MAX_BOUNDS_BYTES, "a bounds file")?
        .read_to_string(&mut text)
        .with_context(|| format!("--bounds {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| {
        format!(
            "--bounds {}: expected a JSON object from task paths to costs, e.g. {{\"easy/p01.pddl\": 10}}",
            path.display()
        )
    })
}

fn print_report(r: &SolveAllReport) -> Result<()> {
    let width = r.tasks.iter().map(|t| t.task.len()).max().unwrap_or(4).max(4);
    let opt = |v: Option<usize>| v.map_or("-".to_string(), |v| v.to_string());
    line(format_args!(
        "{:width$}  {:>6}  {:>6}  {:>7}  {:>6}  {:>6}",
        "task", "blocks", "moves", "actions", "bound", "ratio"
    ))?;
    for t in &r.tasks {
        line(format_args!(
            "{:width$}  {:>6}  {:>6}  {:>7}  {:>6}  {:>6}{}",
            t.task,
            opt(t.blocks),
            opt(t.moves),
            opt(t.actions),
            t.bound.map_or("-".to_string(), |b| b.to_string()),
            t.ratio.map_or("-".to_string(), |x| format!("{x:.3}")),
            t.error.as_deref().map_or(String::new(), |e| format!("  {e}"))
        ))?;
    }
    line("")?;
    line(format_args!(
        "{} plans, each replayed over its file's facts; ratio = actions / best known",
        r.solver
    ))?;
    line(format_args!(
        "{:8}  {:>5}  {:>6}  {:>7}  {:>10}  {:>9}",
        "group", "tasks", "solved", "bounded", "mean ratio", "max ratio"
    ))?;
    for s in r.groups.iter().chain(std::iter::once(&r.overall)) {
        let f = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4}"));
        line(format_args!(
            "{:8}  {:>5}  {:>6}  {:>7}  {:>10}  {:>9}",
            s.group,
            s.tasks,
            s.solved,
            s.bounded,
            f(s.mean_ratio),
            f(s.max_ratio)
        ))?;
    }
    Ok(())
}
