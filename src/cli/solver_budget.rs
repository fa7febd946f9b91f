//! `--solver-budget`: how many states the exact solver may store, on every command where it
//! runs (`solve`, `run --agent exact`, `eval`'s optimum); for a PDDL problem (`solve --pddl`,
//! `solve-all`), how many states the exact block-move search may generate. `--time-limit`:
//! how long the optimal block-move solver searches for its proof.
//!
//! The exact search's memory grows with the states it stores (about 125 bytes each here: the
//! default budget, 4,000,000, peaks under half a gigabyte). Past its budget a search gives
//! up rather than run the machine out of memory; on a large problem (many blocks on a
//! crowded grid) raise the budget, or plan with the oracle. The flag is bounded so that a
//! typo cannot ask for terabytes.

use std::time::Duration;

use anyhow::Error;
use clap::Args;
use oracle::{ExactSolver, PlanOptions};
use sim::Grid;

/// The largest budget the flag accepts: about 12 GB of search.
pub const MAX_SOLVER_BUDGET: u64 = 100_000_000;

/// `--solver-budget`.
#[derive(Debug, Clone, Copy, Args)]
pub struct SolverBudgetArg {
    /// The most states one exact search may store before it gives up (memory grows with
    /// it, about 125 bytes a state; at most 100000000) [default: 4000000; of block moves
    /// (--pddl, solve-all), 2000000 generated]
    #[arg(long, value_name = "STATES", value_parser = clap::value_parser!(u64).range(1..=MAX_SOLVER_BUDGET))]
    pub solver_budget: Option<u64>,
}

/// `--time-limit`.
#[derive(Debug, Clone, Copy, Args)]
pub struct TimeLimitArg {
    /// With --solver optimal: how long its search for the proof may take, in seconds; past
    /// it the best plan is given with its bound, not claimed optimal [default: 10]
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub time_limit: Option<Duration>,
}

/// A time limit in seconds: positive, at most a day.
fn parse_seconds(text: &str) -> Result<Duration, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s <= 86_400.0 => Ok(Duration::from_secs_f64(s)),
        _ => Err(format!("{text:?} is not a number of seconds above 0 and at most 86400")),
    }
}

impl SolverBudgetArg {
    /// The budget in states.
    pub fn budget(&self) -> usize {
        self.solver_budget.map_or(oracle::DEFAULT_NODE_BUDGET, |b| b as usize)
    }

    /// The options of a block-move planner: this budget and the time limit given.
    pub fn plan_options(&self, limit: TimeLimitArg) -> PlanOptions {
        PlanOptions {
            budget: self.solver_budget.map(|b| b as usize),
            time_limit: limit.time_limit,
        }
    }

    /// The planner of a block-move task (`neural::planning::block_planner`) named by
    /// `--solver` or given by `--model`, with this budget and `limit`; a refusal names the
    /// flag it is about.
    pub fn task_planner(
        &self,
        limit: TimeLimitArg,
        solver: Option<oracle::PlannerKind>,
        model: Option<&std::path::Path>,
    ) -> anyhow::Result<Box<dyn oracle::towers::BlockPlanner>> {
        neural::planning::block_planner(solver, model, &self.plan_options(limit)).map_err(|e| {
            let flag = match &e {
                neural::NeuralError::Oracle(oracle::OracleError::OptionNotApplicable { option, .. }) => {
                    if *option == "time limit" {
                        "--time-limit"
                    } else {
                        "--solver-budget"
                    }
                }
                _ if model.is_some() => "--model",
                _ => "--solver",
            };
            Error::new(e).context(flag)
        })
    }

    /// An exact solver on `grid` with this budget.
    pub fn solver(&self, grid: Grid) -> ExactSolver {
        ExactSolver::new(grid).with_node_budget(self.budget())
    }

    /// `e`, naming the flag if an exact search ran out of its budget.
    pub fn explain(&self, e: impl Into<Error>) -> Error {
        let e = e.into();
        let exhausted = e.chain().any(|c| {
            matches!(
                c.downcast_ref::<oracle::OracleError>(),
                Some(
                    oracle::OracleError::BudgetExceeded { .. }
                        | oracle::OracleError::Towers(oracle::towers::TowersError::BudgetExceeded { .. })
                )
            ) || matches!(
                c.downcast_ref::<neural::NeuralError>(),
                Some(neural::NeuralError::Agent(agent::AgentError::Oracle(
                    oracle::OracleError::BudgetExceeded { .. }
                )))
            ) || matches!(
                c.downcast_ref::<agent::AgentError>(),
                Some(agent::AgentError::Oracle(oracle::OracleError::BudgetExceeded { .. }))
            )
        });
        if exhausted {
            e.context(format!("--solver-budget {}", self.budget()))
        } else {
            e
        }
    }
}
