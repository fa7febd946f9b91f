//! The oracle's optimality gap: for every goal of 2, 3 and 4 blocks on 7 x 7, the
//! oracle's plan against a shortest plan on 500 seeded starts (`Env::reset` with the
//! episode seeds of base seed 0); then over every 3-block state (every placement, nothing
//! or any block held) for the goal 1,0,2, with the largest excess found.
//!
//! Run: `cargo run --release -p oracle --example optimality_gap`

use oracle::gap::{self, GapReport};
use oracle::{ExactSolver, Oracle};
use sim::{BlockId, Cell, Goal, Grid, State};

const STARTS: u64 = 500;
const SEED: u64 = 0;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let grid = Grid::default();
    let (oracle, exact) = (Oracle::new(grid), ExactSolver::new(grid));
    println!("oracle steps / exact steps, {STARTS} seeded starts per goal (seed {SEED}), grid {grid}");
    println!("goal    mean oracle  mean exact  mean ratio  max ratio  longer");
    let mut reports: Vec<GapReport> = Vec::new();
    for blocks in [2, 3, 4] {
        for goal in Goal::all(blocks)? {
            let starts = gap::seeded_starts(grid, &goal, STARTS, SEED)?;
            let r = gap::measure(&oracle, &exact, &goal, &starts)?;
            println!(
                "{:<7} {:>11.3} {:>11.3} {:>11.4} {:>10.3} {:>7}",
                r.goal.to_string(),
                r.mean_oracle_steps,
                r.mean_exact_steps,
                r.mean_ratio,
                r.max_ratio,
                r.longer
            );
            reports.push(r);
        }
    }
    let goal: Goal = "1,0,2".parse()?;
    let cells: Vec<Cell> = grid.cells().collect();
    for held in [false, true] {
        let mut every = Vec::new();
        for &a in &cells {
            for &b in &cells {
                for &c in &cells {
                    let holds = if held {
                        vec![Some(0), Some(1), Some(2)]
                    } else {
                        vec![None]
                    };
                    for h in holds {
                        if let Ok(s) = State::new(&[a, b, c], h.map(BlockId))
                            && !goal.holds(&s)
                        {
                            every.push(s);
                        }
                    }
                }
            }
        }
        let r = gap::measure(&oracle, &exact, &goal, &every)?;
        println!(
            "every 3-block state for goal {goal} with {}: {} states, mean ratio {:.5}, max ratio {:.3}, oracle longer on {}",
            if held { "a block held" } else { "nothing held" },
            r.starts,
            r.mean_ratio,
            r.max_ratio,
            r.longer
        );
        if let Some(case) = &r.worst {
            println!("  worst: start {:?}", case.start);
            println!("    oracle ({} steps): {}", case.oracle.len(), case.oracle);
            println!("    exact  ({} steps): {}", case.exact.len(), case.exact);
        }
    }
    if let Some((r, case)) = reports
        .iter()
        .filter_map(|r| r.worst.as_ref().map(|c| (r, c)))
        .max_by_key(|(_, c)| c.oracle.len() - c.exact.len())
    {
        println!(
            "largest excess on the seeded starts: goal {}, start {:?}",
            r.goal, case.start
        );
        println!("  oracle ({} steps): {}", case.oracle.len(), case.oracle);
        println!("  exact  ({} steps): {}", case.exact.len(), case.exact);
    }
    Ok(())
}
