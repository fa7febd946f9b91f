//! Random actions on both backends, checked against each other, with a rough speed figure.
//!
//! `cargo run --release -p sim --example random_walk [steps]`

use std::time::Instant;

use rand::RngExt;
use sim::{Action, Grid, GridWorld, PhysicsWorld, World};

fn main() -> Result<(), sim::SimError> {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let grid = Grid::default();
    let mut env = sim::Env::new(sim::EnvConfig::default())?;
    let start = env.reset(1).state;
    let mut rng = sim::seeding::rng(7);
    let actions: Vec<Action> = (0..steps)
        .map(|_| Action::from_index(rng.random_range(0..Action::count(3)), 3))
        .collect::<Result<_, _>>()?;

    let mut occupancy = GridWorld::new(grid, start.clone())?;
    let t = Instant::now();
    for &a in &actions {
        occupancy.act(a)?;
    }
    let grid_time = t.elapsed();

    let mut physics = PhysicsWorld::new(grid, start)?;
    let t = Instant::now();
    for &a in &actions {
        physics.act(a)?;
    }
    let physics_time = t.elapsed();

    assert_eq!(occupancy.state(), physics.state(), "the backends disagree");
    println!("{steps} random actions, 3 blocks on 7x7; both backends end in the same state:");
    println!(
        "{}",
        sim::render::ascii(
            &sim::Observation {
                grid,
                state: physics.state(),
                goal: env.goal().clone(),
                protocol: sim::ActionProtocol::Free,
                view: sim::View::Top,
            },
            sim::render::Colour::Never
        )
    );
    println!("grid    {:>8.1} ns/step", grid_time.as_nanos() as f64 / steps as f64);
    println!("physics {:>8.1} ns/step", physics_time.as_nanos() as f64 / steps as f64);
    Ok(())
}
