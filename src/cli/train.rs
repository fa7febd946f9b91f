//! `blockstack train`: train a tabular Q-learner and save it as a model file.

use std::path::PathBuf;
use std::time::Instant;

use agent::{Assist, QParams, ReprKind, TrainConfig};
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use sim::{Backend, Goal, Grid, RewardModel};

use super::stdout::line;

/// Arguments of `blockstack train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    /// Number of blocks.
    #[arg(long, default_value_t = 3)]
    pub blocks: usize,
    /// Grid size, WxH.
    #[arg(long, default_value = "7x7")]
    pub grid: String,
    /// State representation: raw, pairwise, chasing (the paper's) or role (ours).
    #[arg(long, default_value = "chasing")]
    pub repr: ReprKind,
    /// Reward model: sparse, dense, paper or step-cost.
    #[arg(long, default_value = "paper")]
    pub reward: String,
    /// Goals to train on, bottom to top, separated by ':', e.g. 0,1,2:1,0,2 (default: every
    /// goal).
    #[arg(long)]
    pub goals: Option<String>,
    /// Training games (played on the goals in turn).
    #[arg(long, default_value_t = 5000)]
    pub games: u64,
    /// Seed of the starts and of every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Learning rate alpha, in (0, 1].
    #[arg(long, default_value_t = QParams::default().alpha)]
    pub alpha: f64,
    /// Discount factor gamma, in [0, 1].
    #[arg(long, default_value_t = QParams::default().gamma)]
    pub gamma: f64,
    /// Probability of a random action while training.
    #[arg(long, default_value_t = QParams::default().epsilon)]
    pub epsilon: f64,
    /// Value every Q-table entry starts at.
    #[arg(long, default_value_t = QParams::default().initial_q, allow_hyphen_values = true)]
    pub initial_q: f64,
    /// Start every game holding a random block (or none), not only with nothing held.
    #[arg(long)]
    pub exploring_starts: bool,
    /// After each game, replay its updates once more, last step first.
    #[arg(long)]
    pub backward_replay: bool,
    /// Remember the last transition from every state-action and replay them all, sweep
    /// after sweep, after the last game.
    #[arg(long)]
    pub final_replay: bool,
    /// When the oracle chooses the action: none, oscillation (the same pair of actions three
    /// times in a row), or oscillation+P (also at each step with probability P).
    #[arg(long, default_value = "none")]
    pub assist: Assist,
    /// Steps before a training game is cut off.
    #[arg(long, default_value_t = sim::DEFAULT_HORIZON)]
    pub horizon: u32,
    /// World backend: physics (rapier2d) or grid (occupancy model).
    #[arg(long, default_value = "physics")]
    pub backend: String,
    /// Where to write the trained model (a .safetensors file; checked before training).
    #[arg(long)]
    pub out: PathBuf,
}

/// Reads goals separated by ':' (e.g. `0,1,2:1,0,2`), each with `blocks` blocks; every goal
/// of `blocks` blocks when `text` is `None`.
pub fn parse_goals(text: Option<&str>, blocks: usize) -> Result<Vec<Goal>> {
    match text {
        None => Goal::all(blocks).context("without --goals every goal is used"),
        Some(text) => Ok(Goal::parse_list(text, blocks)?),
    }
}

impl TrainArgs {
    /// The training config these arguments describe.
    pub fn config(&self) -> Result<TrainConfig> {
        let grid: Grid = self.grid.parse()?;
        let config = TrainConfig {
            grid,
            blocks: self.blocks,
            repr: self.repr,
            reward: RewardModel::from_name(&self.reward)?,
            params: QParams {
                alpha: self.alpha,
                gamma: self.gamma,
                epsilon: self.epsilon,
                initial_q: self.initial_q,
            },
            goals: parse_goals(self.goals.as_deref(), self.blocks)?,
            games: self.games,
            seed: self.seed,
            horizon: self.horizon,
            backend: self.backend.parse::<Backend>()?,
            exploring_starts: self.exploring_starts,
            backward_replay: self.backward_replay,
            final_replay: self.final_replay,
            assist: self.assist,
        };
        config.validate()?;
        Ok(config)
    }
}

/// Trains, showing a progress bar on a terminal, and saves the model.
pub fn train(args: TrainArgs) -> Result<()> {
    let out = files::OutputPath::check(&args.out)?;
    super::stdout::claim_for_data(&[Some(&out)])?;
    let config = args.config()?;
    // Hidden by indicatif itself when stderr is not a terminal.
    let bar = ProgressBar::new(config.games);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} games  {msg}  [{elapsed_precise}, eta {eta}]")
            .expect("a valid template"),
    );
    let mut show = |p: &agent::Progress| {
        if p.games_played % 64 == 0 || p.games_played == p.games_target {
            bar.set_position(p.games_played);
            let steps = p.recent_mean_steps.map_or("-".to_string(), |s| format!("{s:.1}"));
            bar.set_message(format!(
                "last {}: {:.0}% reached the goal, {steps} mean steps",
                p.recent_games,
                100.0 * p.recent_success_rate()
            ));
        }
    };
    let clock = Instant::now();
    let trained = agent::train(&config, Some(&mut show))?;
    let seconds = clock.elapsed().as_secs_f64();
    bar.finish_and_clear();
    trained
        .agent
        .save(&args.out)
        .with_context(|| "the agent was trained but not saved")?;
    let r = trained.report;
    let goals: Vec<String> = config.goals.iter().map(Goal::to_string).collect();
    line(format_args!(
        "trained {} with the {} reward on {} ({} blocks, {} grid, {} backend, seed {})",
        trained.agent.name(),
        config.reward,
        goals.join(":"),
        config.blocks,
        config.grid,
        config.backend,
        config.seed
    ))?;
    line(format_args!(
        "{} games, {} reached the goal, {} steps; {} steps chosen by the oracle (assistance {}); {} final replay sweeps",
        r.games, r.successes, r.steps, r.assisted_steps, config.assist, r.replay_sweeps
    ))?;
    line(format_args!("trained in {seconds:.1} s"))?;
    line(format_args!("saved {}", args.out.display()))
}
