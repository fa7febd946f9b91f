//! `blockstack generate`: seeded random Blocks World problems written as PDDL files, the
//! planning competitions' format (`oracle::pddl`), for any planner to read.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use files::OutputPath;
use oracle::pddl::Problem;
use oracle::towers::{TowerGoal, Towers, ipc_state, random_state};
use sim::View;
use sim::seeding::episode_seed;

use super::stdout::line;

/// How the start and the goal are drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Shape {
    /// Uniformly over the Blocks World states of N blocks (Slaney & Thiebaux's counts).
    Uniform,
    /// As the 2023 competition's generator draws them: the blocks shuffled and stacked in
    /// that order, each starting a new tower with probability 1/10 (few tall towers).
    Ipc,
}

/// The largest problem `generate` writes: ten times the competition's largest.
pub const MAX_GENERATED_BLOCKS: usize = 100_000;

/// The most blocks one `generate` writes in all its problems (about 60 bytes of PDDL a
/// block: some 600 MB): a typo such as `--count 100000` on large problems is refused before
/// anything is written, not found when the disk is full.
pub const MAX_GENERATED_TOTAL: u64 = 10_000_000;

/// Arguments of `blockstack generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// The world: side (the classic Blocks World, the only one PDDL describes).
    #[arg(long, default_value = "side")]
    pub view: View,
    /// Blocks per problem (1 to 100000).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=MAX_GENERATED_BLOCKS as u64))]
    pub blocks: u64,
    /// Problems to write (1 to 100000).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    pub count: u64,
    /// Base seed: problem k draws its start and its goal from episode_seed(seed, 2k) and
    /// episode_seed(seed, 2k + 1).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// How starts and goals are drawn; every goal places every block, as the competition's
    /// do.
    #[arg(long, value_enum, default_value_t = Shape::Uniform)]
    pub shape: Shape,
    /// The folder to write p01.pddl, p02.pddl, ... into (made if missing; regular files of the
    /// same names are replaced; a link of one of those names is refused, before anything is
    /// written).
    #[arg(long)]
    pub out: PathBuf,
}

/// Writes the problems and says where.
pub fn generate(args: GenerateArgs) -> Result<()> {
    anyhow::ensure!(
        args.view == View::Side,
        "--view top: PDDL describes the classic Blocks World, the side view; use --view side"
    );
    let total = args.blocks.saturating_mul(args.count);
    anyhow::ensure!(
        total <= MAX_GENERATED_TOTAL,
        "--blocks {} --count {} is {total} blocks in all, about {} GB of PDDL: generate writes at most \
         {MAX_GENERATED_TOTAL} blocks in one run; write fewer or smaller problems",
        args.blocks,
        args.count,
        total * 60 / 1_000_000_000
    );
    files::prepare_folder(&args.out)?;
    let blocks = args.blocks as usize;
    let draw = |seed| match args.shape {
        Shape::Uniform => random_state(blocks, seed),
        Shape::Ipc => ipc_state(blocks, seed),
    };
    let digits = args.count.to_string().len().max(2);
    let path_of = |k: u64| args.out.join(format!("p{:0digits$}.pddl", k + 1));
    // A link among the names would send a problem outside the folder: every name is looked
    // at before the first is written.
    for k in 0..args.count {
        let path = path_of(k);
        if std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink()) {
            anyhow::bail!(
                "--out {}: {} is a link, and generate replaces only regular files in its folder: \
                 remove the link or choose another folder",
                args.out.display(),
                path.display()
            );
        }
    }
    let shape = args.shape.to_possible_value().expect("no variant is skipped");
    let bar = super::progress::bar(args.count, "problems");
    for k in 0..args.count {
        let start: Towers = draw(episode_seed(args.seed, 2 * k));
        let goal = TowerGoal::new(&draw(episode_seed(args.seed, 2 * k + 1)).towers())?;
        let id = format!("{:0digits$}", k + 1);
        let problem = Problem::new(&format!("blockstack-{id}"), start, goal)?;
        let header = format!(
            ";; blockstack generate --blocks {blocks} --seed {} --shape {}: problem {id} of {}\n\n",
            args.seed,
            shape.get_name(),
            args.count
        );
        let out = OutputPath::check(path_of(k))?;
        out.write(format!("{header}{problem}").as_bytes())
            .with_context(|| format!("problem {id}"))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    line(format_args!(
        "wrote {} problems of {blocks} blocks ({} starts and goals, seed {}) to {}",
        args.count,
        shape.get_name(),
        args.seed,
        args.out.display()
    ))
}
