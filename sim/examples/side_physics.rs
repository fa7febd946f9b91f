//! The side view's physics at scale (docs/world.md, "The side view at any size"): how tall a
//! tower of rapier2d bodies stands, and how the physics and the grid model agree on random
//! play of many blocks. Prints two tables.
//!
//! `cargo run --release -p sim --example side_physics [moves] [seed]` (default 200 block
//! moves per size, seed 1).
//!
//! - **Towers.** A tower built by the gripper: blocks standing side by side on the table are
//!   picked one after another, lifted over the tower, carried to its column and dropped on
//!   it, each gripper action through the physics and, in lockstep, through the grid model.
//!   The solver's settings are the world's (`SideSolver::for_blocks`: a tower of ten is a
//!   world of ten blocks, under the tall-tower settings, as every taller one).
//!   A height stands when every drop comes to rest on its cell (no `NotAtRest` error) and
//!   both backends show the same state after it. For each height: whether it stood, the
//!   rapier steps of the last drop, and the mean time of a drop and of a carry step.
//! - **Agreement.** Random legal block moves (uniform among the legal ones) from uniform
//!   random starts on the default grid, carried out by the gripper on the physics backend
//!   and on the grid backend: moves on which both gave the same step (state, reward, ends),
//!   physics errors, and the time per move on each.

use std::time::{Duration, Instant};

use rand::RngExt;
use sim::{
    Action, Backend, BlockId, BlockMove, Cell, Env, EnvConfig, Grid, GridWorld, PhysicsWorld, State, View, World,
};

/// The tower heights tried.
const HEIGHTS: [usize; 6] = [10, 25, 50, 75, 100, 150];

/// The block counts of the agreement table.
const AGREEMENT_BLOCKS: [usize; 3] = [20, 50, 100];

fn main() -> Result<(), sim::SimError> {
    let mut args = std::env::args().skip(1);
    let moves: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(200);
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);

    println!("Towers built by the gripper through rapier2d (one column, blocks dropped on top)");
    println!(
        "| height | stood | tallest that stood | rapier steps of the last drop | ms per drop | us per carry step |"
    );
    println!("|---:|---|---:|---:|---:|---:|");
    for height in HEIGHTS {
        let t = tower(height)?;
        let stood = match &t.failure {
            None => "yes".to_string(),
            Some(why) => format!("no: {why}"),
        };
        println!(
            "| {height} | {stood} | {} | {} | {:.2} | {:.2} |",
            t.tallest,
            t.last_settle_steps,
            ms(t.drop_time) / t.drops.max(1) as f64,
            ms(t.carry_time) * 1000.0 / t.carry_steps.max(1) as f64,
        );
    }

    println!();
    println!("Random legal block moves carried out by the gripper, physics against grid (seed {seed})");
    println!(
        "| blocks | grid | moves | gripper steps | same step | physics errors | ms per move, physics | ms per move, grid |"
    );
    println!("|---:|---|---:|---:|---:|---:|---:|---:|");
    for blocks in AGREEMENT_BLOCKS {
        let a = agreement(blocks, moves, seed)?;
        println!(
            "| {blocks} | {} | {} | {} | {} | {} | {:.3} | {:.3} |",
            a.grid,
            a.moves,
            a.gripper_steps,
            a.same,
            a.errors,
            ms(a.physics_time) / a.moves.max(1) as f64,
            ms(a.grid_time) / a.moves.max(1) as f64,
        );
        if let Some(first) = a.first_difference {
            println!("  first difference: {first}");
        }
    }
    Ok(())
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1000.0
}

/// How building one tower went.
struct Tower {
    failure: Option<String>,
    /// Blocks in the tower before the first drop that failed (the height if none did).
    tallest: usize,
    drops: usize,
    drop_time: Duration,
    carry_steps: u64,
    carry_time: Duration,
    last_settle_steps: u32,
}

/// Builds a tower of `height` blocks in column 0 (module docs).
fn tower(height: usize) -> Result<Tower, sim::SimError> {
    // Block i stands on the table at column i; block 0 is the tower's bottom.
    let grid = Grid::new(height.max(2), height + 1)?;
    let cells: Vec<Cell> = (0..height).map(|i| Cell::new(i as u16, 0)).collect();
    let start = State::new(&cells, None)?;
    let mut physics = PhysicsWorld::new_in(View::Side, grid, start.clone())?;
    let mut model = GridWorld::new_in(View::Side, grid, start)?;
    let mut t = Tower {
        failure: None,
        tallest: height,
        drops: 0,
        drop_time: Duration::ZERO,
        carry_steps: 0,
        carry_time: Duration::ZERO,
        last_settle_steps: 0,
    };
    for i in 1..height {
        let block = BlockId::of(i);
        // Over the tower (i blocks high), then left to column 0.
        let mut carry = vec![Action::Pick(block)];
        carry.extend(std::iter::repeat_n(Action::Up, i));
        carry.extend(std::iter::repeat_n(Action::Left, i));
        let clock = Instant::now();
        for &a in &carry {
            physics.act(a)?;
            model.act(a)?;
        }
        t.carry_time += clock.elapsed();
        t.carry_steps += carry.len() as u64;
        let clock = Instant::now();
        let dropped = physics.act(Action::Drop);
        t.drop_time += clock.elapsed();
        t.drops += 1;
        model.act(Action::Drop)?;
        t.last_settle_steps = physics.settle_steps();
        match dropped {
            Err(e) => {
                t.failure = Some(format!("drop {i}: {e}"));
                t.tallest = i;
                break;
            }
            Ok(_) if physics.state() != model.state() => {
                t.failure = Some(format!("drop {i}: the physics and the grid model differ"));
                t.tallest = i;
                break;
            }
            Ok(_) => {}
        }
    }
    Ok(t)
}

/// How random play went on both backends.
struct Agreement {
    grid: String,
    moves: u64,
    gripper_steps: u64,
    same: u64,
    errors: u64,
    physics_time: Duration,
    grid_time: Duration,
    first_difference: Option<String>,
}

/// `moves` random legal block moves of `blocks` blocks on both backends (module docs).
fn agreement(blocks: usize, moves: u64, seed: u64) -> Result<Agreement, sim::SimError> {
    let grid = Grid::side_default(blocks);
    let config = |backend| EnvConfig {
        grid,
        blocks,
        backend,
        view: View::Side,
        horizon: u32::MAX,
        ..EnvConfig::default()
    };
    let (mut physics, mut model) = (Env::new(config(Backend::Physics))?, Env::new(config(Backend::Grid))?);
    let mut a = Agreement {
        grid: grid.to_string(),
        moves: 0,
        gripper_steps: 0,
        same: 0,
        errors: 0,
        physics_time: Duration::ZERO,
        grid_time: Duration::ZERO,
        first_difference: None,
    };
    let mut rng = sim::seeding::rng(seed);
    let mut episode = 0;
    let mut fresh = true;
    while a.moves < moves {
        if fresh || physics.is_over() || model.is_over() {
            episode += 1;
            physics.reset(sim::seeding::episode_seed(seed, episode));
            model.reset(sim::seeding::episode_seed(seed, episode));
            fresh = false;
            continue;
        }
        let legal: Vec<usize> = model
            .legal_moves()
            .iter()
            .enumerate()
            .filter(|(_, l)| **l)
            .map(|(i, _)| i)
            .collect();
        let mv = BlockMove::from_index(legal[rng.random_range(0..legal.len())], blocks, grid)?;
        a.moves += 1;
        let clock = Instant::now();
        let g = model.step_block_move(mv)?;
        a.grid_time += clock.elapsed();
        a.gripper_steps += u64::from(g.gripper_steps);
        let clock = Instant::now();
        let p = physics.step_block_move(mv);
        a.physics_time += clock.elapsed();
        match p {
            Ok(p) if p == g => a.same += 1,
            Ok(_) => {
                a.first_difference
                    .get_or_insert_with(|| format!("episode {episode}, {mv}: the steps differ"));
                fresh = true;
            }
            Err(e) => {
                a.errors += 1;
                a.first_difference
                    .get_or_insert_with(|| format!("episode {episode}, {mv}: {e}"));
                fresh = true;
            }
        }
    }
    Ok(a)
}
