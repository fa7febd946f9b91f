//! Times side-view drops on the physics backend: a fall of six rows to the table, and a
//! random-play run among the legal actions. `cargo run -p sim --release --example
//! side_drop_timing`.
use std::time::Instant;

use rand::RngExt;
use sim::{Action, Backend, BlockId, Cell, Env, EnvConfig, Grid, PhysicsWorld, State, View, World};

fn main() {
    let grid = Grid::default();
    let state = State::new(&[Cell::new(0, 0), Cell::new(0, 1), Cell::new(4, 6)], Some(BlockId(2))).unwrap();
    let mut p = PhysicsWorld::new_in(View::Side, grid, state.clone()).unwrap();
    let n = 2000;
    let t = Instant::now();
    for _ in 0..n {
        p.place(&state).unwrap();
        p.act(Action::Drop).unwrap();
    }
    let per = t.elapsed().as_secs_f64() / f64::from(n);
    println!(
        "drop of 6 rows: {} steps, {:.1} us per drop",
        p.settle_steps(),
        per * 1e6
    );
    for backend in [Backend::Physics, Backend::Grid] {
        let mut env = Env::new(EnvConfig {
            blocks: 5,
            backend,
            view: View::Side,
            ..EnvConfig::default()
        })
        .unwrap();
        let mut rng = sim::seeding::rng(3);
        let mut legal = env.reset(1).legal_actions();
        let steps = if backend == Backend::Grid { 20_000_000 } else { 300_000 };
        let t = Instant::now();
        for _ in 0..steps {
            let a = legal.nth(rng.random_range(0..legal.count())).unwrap();
            let s = env.step(a).unwrap();
            legal = s.info.action_mask;
            if s.terminated || s.truncated {
                legal = env.reset(None).legal_actions();
            }
        }
        let rate = f64::from(steps) / t.elapsed().as_secs_f64();
        println!("random play, 5 blocks, {backend}: {rate:.0} steps/s");
    }
}
