//! `blockstack train`: train a tabular Q-learner and save it as a model file.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use agent::{Assist, OracleKind, Oscillation, Preset, ReprKind, Schedule, TrainConfig, TrainOverrides, Trainer};
use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use sim::Goal;

use super::profile::{PlayRulesArgs, ProfileArg};
use super::world::WorldArgs;

use super::checkpoint::{CheckpointArgs, CheckpointKind};
use super::stdout::line;

/// The flags that set up a run, which `--resume` takes from its checkpoint instead.
const RUN_FLAGS: [&str; 24] = [
    "preset",
    "blocks",
    "grid",
    "profile",
    "protocol",
    "start",
    "repr",
    "reward",
    "schedule",
    "oracle",
    "oscillation",
    "goals",
    "seed",
    "alpha",
    "gamma",
    "epsilon",
    "initial_q",
    "exploring_starts",
    "backward_replay",
    "final_replay",
    "assist",
    "horizon",
    "backend",
    "view",
];

/// Arguments of `blockstack train`.
#[derive(Debug, Args)]
#[command(mut_arg("blocks", |a| a.help("Number of blocks [default: 3]")))]
#[command(mut_arg("checkpoint_every", |a| a.help("Games between two checkpoints [default: 1000]")))]
#[command(mut_arg("resume", |a| a.conflicts_with_all(RUN_FLAGS).help(
    "Continue the run in this checkpoint file, with its settings, to --games games in all (default: the total it \
     was started with); it goes on writing checkpoints to the same file unless --checkpoint names another. The flags \
     that set up a run are refused with it: the checkpoint fixes them, so the run ends as if it had never stopped."
)))]
#[command(mut_arg("grid", |a| a.help("Grid size, WxH [default: 7x7]")))]
#[command(mut_arg("reward", |a| a.help("Reward model: sparse, dense, paper, step-cost or paper-code [default: the preset's: paper under spec, paper-code under original, step-cost under --preset optimal]")))]
#[command(mut_arg("horizon", |a| a.help("Steps before a training game is cut off [default: the schedule's: 1000 under spec, 5000 (1000 with 2 blocks) under paper-code]")))]
#[command(mut_arg("view", |a| a.help("The world: top (the paper's) or side (the classic Blocks World: goals default to one goal of each shape of towers, e.g. 0,1,2 and 0,1/2 and 0/1/2 for 3 blocks, which the role-towers learner plays on every goal of that shape; --goals 0,1/2:... names others) [default: top]")))]
pub struct TrainArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    #[command(flatten)]
    pub profile: ProfileArg,
    #[command(flatten)]
    pub play: PlayRulesArgs,
    /// The learner's recipe: paper (the profile's
    /// learner) or optimal (the role recipe: role, step-cost, alpha 1, gamma 1, epsilon 0,
    /// backward and final replay; role-towers in the side view) [default: optimal for --repr
    /// role or role-towers under the spec profile and in the side view, paper otherwise]. A profile sets the world and the learner as coded; a preset
    /// then sets the representation, reward, alpha, gamma, epsilon, initial value and
    /// replays; an explicit flag beats both.
    #[arg(long)]
    pub preset: Option<Preset>,
    /// State representation: raw, pairwise, chasing (the paper's prose), chasing-code (the
    /// paper's code), role (ours) or role-towers (ours, for goals of towers) [default: the
    /// preset's: chasing under spec, chasing-code under original, role under --preset
    /// optimal, role-towers in the side view]
    #[arg(long)]
    pub repr: Option<ReprKind>,
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
    /// goal; in the side view one goal of each shape, 0,1,2:0,1/2:0/1/2 for 3 blocks).
    #[arg(long)]
    pub goals: Option<String>,
    /// Training games [default: 5000 under spec, 100 under original, 100000 in the side view]
    #[arg(long)]
    pub games: Option<u64>,
    /// Seed of the starts and of every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Learning rate alpha, in (0, 1] [default: the preset's: 1]
    #[arg(long)]
    pub alpha: Option<f64>,
    /// Discount factor gamma, in [0, 1] [default: the preset's: 0.1 paper, 1 optimal]
    #[arg(long)]
    pub gamma: Option<f64>,
    /// Probability of a random action while training [default: the preset's: 0.1 paper,
    /// 0 optimal]
    #[arg(long)]
    pub epsilon: Option<f64>,
    /// Value every Q-table entry starts at [default: the preset's: 0]
    #[arg(long, allow_hyphen_values = true)]
    pub initial_q: Option<f64>,
    /// Start every game holding a random block (or none), not only with nothing held.
    #[arg(long)]
    pub exploring_starts: bool,
    /// After each game, replay its updates once more, last step first (`--backward-replay`
    /// or `--backward-replay=false`) [default: the preset's: off paper, on optimal]
    #[arg(long, num_args = 0..=1, require_equals = true, default_missing_value = "true", value_name = "BOOL")]
    pub backward_replay: Option<bool>,
    /// Remember the last transition from every state-action and replay them all, sweep
    /// after sweep, after the last game (`--final-replay` or `--final-replay=false`)
    /// [default: the preset's: off paper, on optimal]
    #[arg(long, num_args = 0..=1, require_equals = true, default_missing_value = "true", value_name = "BOOL")]
    pub final_replay: Option<bool>,
    /// When the oracle chooses the action: none, oscillation (on oscillation, see
    /// --oscillation), or oscillation+P (also at each step with probability P).
    #[arg(long, default_value = "none")]
    pub assist: Assist,
    /// Where to write the trained model (a .safetensors file; checked before training).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub checkpointing: CheckpointArgs,
    /// Show the learning curve live in a browser, served on this loopback port while the run
    /// lasts (0: any free port; the link is printed on standard error).
    #[arg(long, value_name = "PORT", num_args = 0..=1, default_missing_value = "8080")]
    pub serve: Option<u16>,
}

impl TrainArgs {
    /// The training config these arguments describe: the library's resolver
    /// ([`TrainConfig::resolve`]: profile, then preset, then each flag given).
    pub fn config(&self) -> Result<TrainConfig> {
        let w = &self.world;
        let overrides = TrainOverrides {
            profile: self.profile.profile,
            preset: self.preset,
            blocks: w.blocks,
            grid: w.grid,
            goals: self
                .goals
                .as_deref()
                .map(|text| Goal::parse_list(text, w.blocks.unwrap_or(3)))
                .transpose()?,
            protocol: self.play.protocol,
            start: self.play.start.start,
            repr: self.repr,
            reward: w.reward,
            schedule: self.schedule,
            oracle: self.oracle,
            oscillation: self.oscillation,
            games: self.games,
            seed: Some(self.seed),
            alpha: self.alpha,
            gamma: self.gamma,
            epsilon: self.epsilon,
            initial_q: self.initial_q,
            exploring_starts: Some(self.exploring_starts),
            backward_replay: self.backward_replay,
            final_replay: self.final_replay,
            assist: Some(self.assist),
            horizon: w.horizon,
            backend: w.backend,
            view: w.view,
        };
        TrainConfig::resolve(&overrides).map_err(|e| match e {
            // The goals were the default's: say which flag chooses others.
            agent::AgentError::Sim(sim::SimError::TooManyGoals { .. }) if self.goals.is_none() => {
                anyhow::Error::new(e).context("without --goals every goal is used")
            }
            e => e.into(),
        })
    }
}

/// What `train` does beside playing: the progress bar and the live curve, and checkpoints.
struct Shown<'a> {
    bar: &'a ProgressBar,
    curve: Option<&'a serve::CurveHandle>,
    checkpoint: Option<&'a files::OutputPath>,
    every: u64,
}

impl agent::TrainHooks for Shown<'_> {
    fn after_game(&mut self, p: &agent::Progress) -> agent::Result<()> {
        if p.games_played.is_multiple_of(64) || p.games_played == p.games_target {
            if let Some(curve) = self.curve {
                curve.push(serve::CurvePoint {
                    games: p.games_played,
                    success_rate: p.recent_success_rate(),
                    mean_steps: p.recent_mean_steps,
                });
            }
            self.bar.set_position(p.games_played);
            let steps = p.recent_mean_steps.map_or("-".to_string(), |s| format!("{s:.1}"));
            self.bar.set_message(format!(
                "last {}: {:.0}% reached the goal, {steps} mean steps",
                p.recent_games,
                100.0 * p.recent_success_rate()
            ));
        }
        Ok(())
    }

    fn checkpoint_every(&self) -> Option<u64> {
        self.checkpoint.map(|_| self.every)
    }

    fn checkpoint(&mut self, trainer: &Trainer) -> agent::Result<()> {
        match self.checkpoint {
            Some(out) => trainer.write_checkpoint(out),
            None => Ok(()),
        }
    }
}

/// A tabular run's checkpoints.
const KIND: CheckpointKind = CheckpointKind {
    format: agent::checkpoint::CHECKPOINT_FORMAT,
    unit: "games",
};

/// Trains (or resumes a checkpointed run), showing a progress bar on a terminal, writing
/// checkpoints if asked, and saves the model.
pub fn train(args: TrainArgs) -> Result<()> {
    let out = files::OutputPath::check(&args.out)?;
    let checkpoint = args.checkpointing.output(&args.out, &out, &KIND)?;
    let mut trainer = match &args.checkpointing.resume {
        Some(path) => Trainer::resume(path)?,
        None => Trainer::new(args.config()?)?,
    };
    let config = trainer.config().clone();
    args.checkpointing
        .refuse_other_files(&KIND, |path| Trainer::resume_run(path, &config).is_ok())?;
    let total = args.games.unwrap_or(trainer.config().games);
    let played = trainer.report().games;
    anyhow::ensure!(
        total >= played,
        "--games {total}: the checkpoint has played {played} games already; --games is the total, so ask for {played} or more"
    );
    // Hidden by indicatif itself when stderr is not a terminal.
    let bar = ProgressBar::new(total);
    bar.set_position(played);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} games  {msg}  [{elapsed_precise}, eta {eta}]")
            .expect("a valid template"),
    );
    let curve = match args.serve {
        Some(port) => {
            let name = args
                .out
                .file_name()
                .map_or("-".into(), |n| n.to_string_lossy().into_owned());
            let title = format!("blockstack train: {name}, {} games", total);
            let handle = serve::serve_curve([127, 0, 0, 1].into(), port, &title, total)?;
            writeln!(std::io::stderr(), "learning curve: {}", handle.url)?;
            Some(handle)
        }
        None => None,
    };
    let clock = Instant::now();
    let mut hooks = Shown {
        bar: &bar,
        curve: curve.as_ref(),
        checkpoint: checkpoint.as_ref(),
        every: args
            .checkpointing
            .checkpoint_every
            .unwrap_or(agent::checkpoint::DEFAULT_EVERY),
    };
    trainer.run_until(total, &mut hooks)?;
    let config = trainer.config().clone();
    let trained = trainer.finish();
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
        config.world.reward,
        goals.join(":"),
        config.world.blocks,
        config.world.grid,
        config.world.backend,
        config.seed
    ))?;
    line(format_args!(
        "profile {}: protocol {}, start {}, schedule {}, games of up to {} steps",
        config.profile, config.world.protocol, config.world.start, config.schedule, config.world.horizon
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
    if let Some(out) = &checkpoint {
        line(format_args!("checkpoint {}", out.path().display()))?;
    }
    line(format_args!("saved {}", args.out.display()))
}
