//! Soak: a long run of random legal actions in the physics world, every step checked against
//! the occupancy-grid model (docs/world.md section 4, invariant 2), and the steps per second.
//!
//! `cargo run --release -p sim --example soak [steps] [seed]` (default 10^8 steps, seed 1)
//!
//! Episodes take turns over a set of worlds chosen so that every way an episode ends
//! happens often: goals reached (two blocks on small grids, where random play gets there),
//! reward-above termination (the authors' world: paper protocol, start rule and reward),
//! the horizon (many blocks), and a grid one cell wide. Each world is a pair of
//! environments, physics and grid, reset with the same seed; every step's observation,
//! reward, end flags and info must be equal. A disagreement is counted, the first few are
//! printed, and the pair is reset afresh. The exit status is 1 if there was any.

use std::time::Instant;

use rand::RngExt;
use sim::{
    ActionProtocol, Backend, Env, EnvConfig, GoalSpec, Grid, Observation, RewardModel, StartRule, Step, Termination,
};

/// Disagreements printed in full; the rest are only counted.
const SHOWN: u64 = 5;

/// One world of the soak and what happened in it.
struct World {
    name: &'static str,
    physics: Env,
    grid: Env,
    steps: u64,
    /// Episodes ended by the goal (under goal termination), by a reward above the
    /// threshold, and by the horizon.
    goal_ends: u64,
    reward_ends: u64,
    horizon_ends: u64,
}

impl World {
    #[allow(clippy::too_many_arguments, reason = "one line per world in the table below")]
    fn new(
        name: &'static str,
        (width, height): (usize, usize),
        blocks: usize,
        reward: &str,
        horizon: u32,
        protocol: ActionProtocol,
        start: StartRule,
        termination: Termination,
    ) -> Result<World, sim::SimError> {
        let config = |backend| EnvConfig {
            grid: Grid::new(width, height).expect("a grid"),
            blocks,
            goal: GoalSpec::Random,
            horizon,
            reward: RewardModel::from_name(reward).expect("a reward model"),
            backend,
            protocol,
            start,
            termination,
            ..EnvConfig::default()
        };
        Ok(World {
            name,
            physics: Env::new(config(Backend::Physics))?,
            grid: Env::new(config(Backend::Grid))?,
            steps: 0,
            goal_ends: 0,
            reward_ends: 0,
            horizon_ends: 0,
        })
    }

    /// Resets both with `seed`: the first observation, or the two that differ.
    fn reset(&mut self, seed: u64) -> Result<Observation, Box<(Observation, Observation)>> {
        let (p, g) = (self.physics.reset(seed), self.grid.reset(seed));
        if p == g { Ok(p) } else { Err(Box::new((p, g))) }
    }

    /// Counts how `step` ended its episode.
    fn count_end(&mut self, step: &Step) {
        if step.terminated {
            match self.physics.config().termination {
                Termination::Goal => self.goal_ends += 1,
                Termination::RewardAbove(_) => self.reward_ends += 1,
            }
        } else if step.truncated {
            self.horizon_ends += 1;
        }
    }
}

fn main() -> Result<(), sim::SimError> {
    let mut args = std::env::args().skip(1);
    let total: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(100_000_000);
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    use ActionProtocol::{Free, Paper as PaperProtocol};
    use StartRule::{Paper as PaperStart, Uniform};
    let goal = Termination::Goal;
    let mut worlds = vec![
        World::new("2 blocks, 3x3, sparse", (3, 3), 2, "sparse", 60, Free, Uniform, goal)?,
        World::new("2 blocks, 7x7, dense", (7, 7), 2, "dense", 400, Free, Uniform, goal)?,
        World::new("3 blocks, 7x7, paper", (7, 7), 3, "paper", 1000, Free, Uniform, goal)?,
        World::new(
            "3 blocks, 7x7, original (paper-code, reward above 70)",
            (7, 7),
            3,
            "paper-code",
            1000,
            PaperProtocol,
            PaperStart,
            Termination::paper_training(),
        )?,
        World::new(
            "5 blocks, 7x7, step-cost",
            (7, 7),
            5,
            "step-cost",
            1000,
            Free,
            Uniform,
            goal,
        )?,
        World::new("2 blocks, 1x4, sparse", (1, 4), 2, "sparse", 40, Free, Uniform, goal)?,
        World::new(
            "16 blocks, 16x16, sparse",
            (16, 16),
            16,
            "sparse",
            300,
            PaperProtocol,
            Uniform,
            goal,
        )?,
    ];
    let mut rng = sim::seeding::rng(seed);
    let mut disagreements = 0u64;
    let mut episodes = 0u64;
    let mut done = 0u64;
    let clock = Instant::now();
    'run: while done < total {
        let k = (episodes % worlds.len() as u64) as usize;
        let world = &mut worlds[k];
        let episode_seed = sim::seeding::episode_seed(seed, episodes);
        episodes += 1;
        let mut legal = match world.reset(episode_seed) {
            Ok(obs) => obs.legal_actions(),
            Err(pair) => {
                let (p, g) = *pair;
                disagreements += 1;
                if disagreements <= SHOWN {
                    eprintln!(
                        "disagreement at the reset of {} (seed {episode_seed}):\n{p:?}\n{g:?}",
                        world.name
                    );
                }
                continue;
            }
        };
        loop {
            let action = legal.nth(rng.random_range(0..legal.count())).expect("a legal action");
            let p = world.physics.step(action)?;
            let g = world.grid.step(action)?;
            world.steps += 1;
            done += 1;
            if p != g {
                disagreements += 1;
                if disagreements <= SHOWN {
                    eprintln!(
                        "disagreement in {} after {action} (episode seed {episode_seed}):\n{p:?}\n{g:?}",
                        world.name
                    );
                }
                continue 'run;
            }
            if done.is_multiple_of(10_000_000) {
                eprintln!(
                    "{done} steps, {disagreements} disagreements, {:.0} steps/s",
                    done as f64 / clock.elapsed().as_secs_f64()
                );
            }
            if p.terminated || p.truncated {
                world.count_end(&p);
                break;
            }
            if done >= total {
                break 'run;
            }
            legal = p.info.action_mask;
        }
    }
    let seconds = clock.elapsed().as_secs_f64();
    println!("soak: {done} physics steps, each checked against the grid model, in {episodes} episodes, seed {seed}");
    println!(
        "{:<54} {:>12} {:>10} {:>10} {:>10}",
        "world", "steps", "goal", "reward>70", "horizon"
    );
    for w in &worlds {
        println!(
            "{:<54} {:>12} {:>10} {:>10} {:>10}",
            w.name, w.steps, w.goal_ends, w.reward_ends, w.horizon_ends
        );
    }
    println!("disagreements: {disagreements}");
    println!(
        "{:.0} steps per second (one physics step and one grid step each), {seconds:.1} s",
        done as f64 / seconds
    );
    if disagreements > 0 {
        std::process::exit(1);
    }
    Ok(())
}
