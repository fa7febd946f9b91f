//! `--solver-budget`: how many states the exact solver may store, on every command where it
//! runs (`solve`, `run --agent exact`, `eval`'s optimum); for a PDDL problem (`solve --pddl`,
//! `solve-all`), how many states the exact block-move search may generate.
//!
//! The exact search's memory grows with the states it stores (about 125 bytes each here: the
//! default budget, 4,000,000, peaks under half a gigabyte). Past its budget a search gives
//! up rather than run the machine out of memory; on a large problem (many blocks on a
//! crowded grid) raise the budget, or plan with the oracle. The flag is bounded so that a
//! typo cannot ask for terabytes.

use anyhow::Error;
use clap::Args;
use oracle::ExactSolver;
use sim::Grid;

/// The largest budget the flag accepts: about 12 GB of search.
pub const MAX_SOLVER_BUDGET: u64 = 100_000_000;

/// `--solver-budget`.
#[derive(Debug, Clone, Copy, Args)]
pub struct SolverBudgetArg {
    /// The most states one exact search may store before it gives up (memory grows with
    /// it, about 125 bytes a state; at most 100000000) [default: 4000000]
    #[arg(long, value_name = "STATES", value_parser = clap::value_parser!(u64).range(1..=MAX_SOLVER_BUDGET))]
    pub solver_budget: Option<u64>,
}

impl SolverBudgetArg {
    /// The budget in states.
    pub fn budget(&self) -> usize {
        self.solver_budget.map_or(oracle::DEFAULT_NODE_BUDGET, |b| b as usize)
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
