//! How far the exact solver scales: for each grid and block count, solves seeded starts
//! with the default budget and prints states expanded and stored, time per solve, and how
//! many starts ran out of the budget.
//!
//! Run: `cargo run --release -p oracle --example exact_scaling`

use std::time::Instant;

use oracle::gap::seeded_starts;
use oracle::{ExactSolver, OracleError};
use sim::{Goal, Grid};

const STARTS: u64 = 20;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!("exact solver, default budget, {STARTS} seeded starts each (seed 0), identity goal");
    println!("grid   blocks  solved  over budget  mean steps  median ms  max ms  max stored states");
    for (grid, blocks) in [
        (Grid::default(), 2),
        (Grid::default(), 3),
        (Grid::default(), 4),
        (Grid::default(), 5),
        (Grid::default(), 6),
        (Grid::default(), 7),
        (Grid::new(8, 8)?, 8),
        (Grid::new(10, 10)?, 3),
        (Grid::new(10, 10)?, 4),
        (Grid::new(16, 16)?, 3),
        (Grid::new(16, 16)?, 4),
        (Grid::new(16, 16)?, 6),
        (Grid::new(16, 16)?, 8),
    ] {
        let solver = ExactSolver::new(grid);
        let goal = Goal::identity(blocks)?;
        let (mut times, mut steps, mut stored, mut over) = (Vec::new(), Vec::new(), 0, 0);
        for start in seeded_starts(grid, &goal, STARTS, 0)? {
            let t = Instant::now();
            match solver.solve_with_stats(&start, &goal) {
                Ok((plan, stats)) => {
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                    steps.push(plan.len());
                    stored = stored.max(stats.generated);
                }
                Err(OracleError::BudgetExceeded { .. }) => over += 1,
                Err(e) => return Err(e.into()),
            }
        }
        times.sort_by(f64::total_cmp);
        let median = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
        let max = times.last().copied().unwrap_or(f64::NAN);
        let mean_steps = steps.iter().sum::<usize>() as f64 / steps.len().max(1) as f64;
        println!(
            "{:<6} {:>6} {:>7} {:>12} {:>11.2} {:>10.3} {:>7.1} {:>18}",
            grid.to_string(),
            blocks,
            steps.len(),
            over,
            mean_steps,
            median,
            max,
            stored
        );
    }
    Ok(())
}
