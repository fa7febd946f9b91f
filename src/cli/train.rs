//! `blockstack train`: train a tabular Q-learner and save it as a model file.

use std::path::PathBuf;
use std::time::Instant;

use agent::{Assist, OracleKind, Oscillation, QParams, ReprKind, Schedule, TrainConfig};
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use sim::{Backend, Goal, Grid, Profile, RewardModel};

use super::profile::{PlayRulesArgs, ProfileArg};

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
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub play: PlayRulesArgs,
    /// State representation: raw, pairwise, chasing (the paper's prose), chasing-code (the
    /// paper's code) or role (ours) [default: the profile's: chasing under spec,
    /// chasing-code under original]
    #[arg(long)]
    pub repr: Option<ReprKind>,
    /// Reward model: sparse, dense, paper, step-cost or paper-code [default: the profile's:
    /// paper under spec, paper-code under original]
    #[arg(long)]
    pub reward: Option<String>,
    /// Training schedule: spec (goals in turn, constant alpha) or paper-code (the authors':
    /// a goal drawn per game, alpha decay after step 4000, bootstrap over seen actions,
    /// games ended by a reward above 70) [default: the profile's]
    #[arg(long)]
    pub schedule: Option<Schedule>,
    /// The oracle that assists: astar (ours) or paper (the authors' greedy walker)
    /// [default: the profile's: astar under spec, paper under original]
    #[arg(long)]
    pub oracle: Option<OracleKind>,
    /// How oscillation is spotted for --assist: actions (the same pair of actions three
    /// times in a row) or distances (the authors': the last six pair distances of period 2)
    /// [default: the profile's: actions under spec, distances under original]
    #[arg(long)]
    pub oscillation: Option<Oscillation>,
    /// Goals to train on, bottom to top, separated by ':', e.g. 0,1,2:1,0,2 (default: every
    /// goal).
    #[arg(long)]
    pub goals: Option<String>,
    /// Training games [default: 5000 under spec, 100 under original]
    #[arg(long)]
    pub games: Option<u64>,
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
    /// When the oracle chooses the action: none, oscillation (on oscillation, see
    /// --oscillation), or oscillation+P (also at each step with probability P).
    #[arg(long, default_value = "none")]
    pub assist: Assist,
    /// Steps before a training game is cut off [default: the schedule's: 1000 under spec,
    /// 5000 (1000 with 2 blocks) under paper-code]
    #[arg(long)]
    pub horizon: Option<u32>,
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
    /// The training config these arguments describe: the profile's learner
    /// ([`TrainConfig::for_profile`]), each part the command line names set as it says.
    pub fn config(&self) -> Result<TrainConfig> {
        let grid: Grid = self.grid.parse()?;
        let profile = self.profile.profile.unwrap_or(Profile::Spec);
        let goals = parse_goals(self.goals.as_deref(), self.blocks)?;
        let base = TrainConfig::for_profile(profile, goals);
        let schedule = self.schedule.unwrap_or(base.schedule);
        // Without --horizon, games are as long as the schedule's (the profile's unless
        // --schedule says otherwise).
        let horizon = self.horizon.unwrap_or_else(|| {
            if self.schedule.is_some() {
                schedule.game_steps(self.blocks)
            } else {
                base.horizon
            }
        });
        let config = TrainConfig {
            grid,
            blocks: self.blocks,
            repr: self.repr.unwrap_or(base.repr),
            reward: match &self.reward {
                Some(name) => RewardModel::from_name(name)?,
                None => base.reward,
            },
            params: QParams {
                alpha: self.alpha,
                gamma: self.gamma,
                epsilon: self.epsilon,
                initial_q: self.initial_q,
            },
            games: self.games.unwrap_or(base.games),
            seed: self.seed,
            horizon,
            backend: self.backend.parse::<Backend>()?,
            exploring_starts: self.exploring_starts,
            backward_replay: self.backward_replay,
            final_replay: self.final_replay,
            assist: self.assist,
            protocol: self.play.protocol.unwrap_or(base.protocol),
            start: self.play.start.start.unwrap_or(base.start),
            schedule,
            oracle: self.oracle.unwrap_or(base.oracle),
            oscillation: self.oscillation.unwrap_or(base.oscillation),
            ..base
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
        "profile {}: protocol {}, start {}, schedule {}, games of up to {} steps",
        config.profile, config.protocol, config.start, config.schedule, config.horizon
    ))?;
    line(format_args!(
        "{} games, {} reached the goal, {} steps; {} steps chosen by the {} oracle (assistance {}, oscillation by {}); {} final replay sweeps",
        r.games,
        r.successes,
        r.steps,
        r.assisted_steps,
        config.oracle,
        config.assist,
        config.oscillation,
        r.replay_sweeps
    ))?;
    line(format_args!("trained in {seconds:.1} s"))?;
    line(format_args!("saved {}", args.out.display()))
}
