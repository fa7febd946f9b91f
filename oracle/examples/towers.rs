//! Block-move plans in the side-view Blocks World: a plan from each planner, and how far
//! the near-optimal planner is from the optimum.
//!
//! Run: `cargo run --release -p oracle --example towers` prints the plans for a random
//! problem (`-- plan BLOCKS SEED`, default 8 blocks, seed 1); `-- ratios` measures the
//! near-optimal / exact ratio on every start of 5 blocks against every goal naming all 5
//! in one to three towers, and on 200 random problems of each size from 6 to 10 blocks.

use std::time::Instant;

use oracle::towers::{ExactMoves, NearOptimal, TowerGoal, Towers, random_goal, random_state};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("ratios") => ratios(),
        None | Some("plan") => {
            let blocks = args.get(1).map_or(Ok(8), |s| s.parse())?;
            let seed = args.get(2).map_or(Ok(1), |s| s.parse())?;
            plan(blocks, seed)
        }
        Some(other) => Err(format!("unknown command {other:?}: use `plan [BLOCKS] [SEED]` or `ratios`").into()),
    }
}

/// Prints both planners' plans for a random problem of `blocks` blocks.
fn plan(blocks: usize, seed: u64) -> Result<(), Box<dyn std::error::Error>> {
    let start = random_state(blocks, seed);
    let goal = random_goal(blocks, 2.min(blocks), blocks, seed)?;
    println!("start {start}");
    println!("goal  {goal}");
    let t = Instant::now();
    let near = NearOptimal::new().plan(&start, &goal)?;
    println!("near-optimal ({} moves, {:?}): {near}", near.len(), t.elapsed());
    let t = Instant::now();
    let exact = ExactMoves::new().solve(&start, &goal)?;
    println!("exact        ({} moves, {:?}): {exact}", exact.len(), t.elapsed());
    Ok(())
}

/// Running summary of ratios.
#[derive(Default)]
struct Summary {
    count: usize,
    sum: f64,
    max: f64,
    optimal: usize,
    slowest: f64,
}

impl Summary {
    fn add(&mut self, near: usize, exact: usize, seconds: f64) {
        let r = if exact == 0 { 1.0 } else { near as f64 / exact as f64 };
        self.count += 1;
        self.sum += r;
        self.max = self.max.max(r);
        self.optimal += usize::from(near == exact);
        self.slowest = self.slowest.max(seconds);
    }

    fn print(&self, what: &str) {
        println!(
            "{what}: {} problems, ratio mean {:.4} max {:.3}, optimal in {:.1} %, slowest exact solve {:.3} s",
            self.count,
            self.sum / self.count as f64,
            self.max,
            100.0 * self.optimal as f64 / self.count as f64,
            self.slowest
        );
    }
}

/// Solves one problem with both planners and adds it to `summary`.
fn compare(start: &Towers, goal: &TowerGoal, summary: &mut Summary) -> Result<(), Box<dyn std::error::Error>> {
    let t = Instant::now();
    let exact = ExactMoves::new().solve(start, goal)?.len();
    let seconds = t.elapsed().as_secs_f64();
    let near = NearOptimal::new().plan(start, goal)?.len();
    summary.add(near, exact, seconds);
    Ok(())
}

/// The ratio measurements described in the module docs.
fn ratios() -> Result<(), Box<dyn std::error::Error>> {
    // Every state of 5 blocks, and every goal naming all 5 in 1-3 towers: the states with
    // 1-3 towers, read as goals.
    let mut states = vec![Towers::new(&[(0..5).collect()])?];
    let mut i = 0;
    while i < states.len() {
        for mv in states[i].moves(Default::default()) {
            let mut next = states[i].clone();
            next.apply(mv, Default::default())?;
            if !states.contains(&next) {
                states.push(next);
            }
        }
        i += 1;
    }
    let goals: Vec<TowerGoal> = states
        .iter()
        .filter(|s| s.tower_count() <= 3)
        .map(|s| TowerGoal::new(&s.towers()))
        .collect::<Result<_, _>>()?;
    let mut all = Summary::default();
    for goal in &goals {
        for start in &states {
            compare(start, goal, &mut all)?;
        }
    }
    all.print(&format!(
        "5 blocks, every start ({}) x every goal of 1-3 towers ({})",
        states.len(),
        goals.len()
    ));
    for n in 6..=10 {
        let mut summary = Summary::default();
        for seed in 0..200u64 {
            let start = random_state(n, seed);
            let goal = random_goal(n, 1 + seed as usize % 3, n, seed ^ 0xfeed)?;
            compare(&start, &goal, &mut summary)?;
        }
        summary.print(&format!("{n} blocks, 200 random starts and goals of 1-3 towers"));
    }
    Ok(())
}
