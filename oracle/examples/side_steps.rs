//! How far the exact solver reaches in the side view (fewest gripper steps): for each block
//! count on 7 x 7, solves seeded random starts towards seeded random goals of one to three
//! towers naming every block, with the default budget, and prints time per solve, states
//! stored and how many starts ran out of the budget.
//!
//! Run: `cargo run --release -p oracle --example side_steps`

use std::time::Instant;

use oracle::towers::random_goal;
use oracle::{ExactSolver, OracleError};
use sim::{Env, EnvConfig, Goal, Grid, View};

const STARTS: u64 = 30;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let grid = Grid::default();
    println!("side view, exact gripper steps on {grid}, default budget, {STARTS} seeded starts each (seed 0..)");
    println!("blocks  solved  over budget  mean steps  median ms  max ms  max stored states");
    for blocks in [2, 3, 4, 5] {
        let solver = ExactSolver::new(grid).with_view(View::Side);
        let (mut times, mut steps, mut stored, mut over) = (Vec::new(), Vec::new(), 0, 0);
        for seed in 0..STARTS {
            let stacks = 1 + (seed as usize) % 3.min(blocks);
            let goal = Goal::of_towers(random_goal(blocks, stacks, blocks, seed)?.towers(), blocks)?;
            let mut env = Env::new(EnvConfig {
                view: View::Side,
                blocks,
                ..EnvConfig::with_goal(goal.clone())
            })?;
            let start = env.reset(seed).state;
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
        let mean = steps.iter().sum::<usize>() as f64 / steps.len().max(1) as f64;
        let median = times.get(times.len() / 2).copied().unwrap_or(f64::NAN);
        let max = times.last().copied().unwrap_or(f64::NAN);
        println!(
            "{blocks:>6}  {:>6}  {over:>11}  {mean:>10.1}  {median:>9.3}  {max:>6.1}  {stored:>17}",
            times.len()
        );
    }
    Ok(())
}
