//! `blockstack dqn`: train a deep Q-network (DQN, or DQfD from demonstrations) and save it.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neural::{
    DemoSource, DqnConfig, DqnOverrides, LossKind, NetKind, ObsKind, OptimizerKind, Phase, Preset, Progress, TdLoss,
};
use sim::{ActionProtocol, Backend, Goal, Grid, RewardModel, ScreenGoal};

use super::stdout::line;

/// Arguments of `blockstack dqn`. Every setting starts from a preset and may be changed.
#[derive(Debug, Args)]
pub struct DqnArgs {
    /// Start from this preset: paper (the paper's DQN on pixels), paper-dqfd (the same with
    /// DQfD on 500 exact-solver demonstrations), dqn-planes (ours, no demonstrations),
    /// dqfd-planes (ours with DQfD: the recommended recipe), her-planes (ours without
    /// demonstrations, with hindsight relabelling), dqfd-pixels (our DQfD recipe with the
    /// paper network on the paper screen), pixels (our DQfD recipe with the conv network on
    /// the compact screen). Default: from --obs and --loss.
    #[arg(long)]
    pub preset: Option<Preset>,
    /// What the network sees: role-planes, paper-screen or screen (default: the preset's,
    /// else role-planes). Earlier releases called the first two planes and pixels.
    #[arg(long)]
    pub obs: Option<ObsKind>,
    /// The network: paper (the paper screen), small (centred planes), mlp (absolute
    /// planes), conv (the compact screen).
    #[arg(long)]
    pub net: Option<NetKind>,
    /// The losses: dqfd (with demonstrations) or dqn (default: dqfd when demonstrations
    /// are given).
    #[arg(long)]
    pub loss: Option<LossKind>,
    /// Number of blocks.
    #[arg(long, default_value_t = 3)]
    pub blocks: usize,
    /// Goals to train on, separated by ':', e.g. 0,1,2:1,0,2 (default: every goal).
    #[arg(long)]
    pub goals: Option<String>,
    /// Grid size, WxH.
    #[arg(long, default_value = "7x7")]
    pub grid: String,
    /// Environment steps of self-play.
    #[arg(long)]
    pub steps: Option<u64>,
    /// Gradient steps on the demonstrations alone, before self-play.
    #[arg(long)]
    pub pretrain: Option<u64>,
    /// Demonstrations from a planner: exact:K or oracle:K (K episodes), or none.
    #[arg(long, conflicts_with = "demos_file")]
    pub demos: Option<DemoSource>,
    /// Demonstrations from a recording: blockstack-demos JSON Lines (`demo`/`correct
    /// --record`) or a trajectory file (`run --trajectory`).
    #[arg(long)]
    pub demos_file: Option<PathBuf>,
    /// Reward model: sparse, dense, paper or step-cost.
    #[arg(long)]
    pub reward: Option<String>,
    /// Discount factor.
    #[arg(long)]
    pub gamma: Option<f64>,
    /// Learning rate (the final rate follows in the preset's proportion unless --lr-final says).
    #[arg(long)]
    pub lr: Option<f64>,
    /// Learning rate at the end of the run (it falls linearly from --lr).
    #[arg(long)]
    pub lr_final: Option<f64>,
    /// Optimiser: rmsprop or adam.
    #[arg(long)]
    pub optimizer: Option<OptimizerKind>,
    /// TD loss: huber or mse.
    #[arg(long)]
    pub td_loss: Option<TdLoss>,
    /// Transitions the replay buffer holds.
    #[arg(long)]
    pub buffer: Option<usize>,
    /// Transitions per gradient step.
    #[arg(long)]
    pub batch: Option<usize>,
    /// Units of each hidden layer.
    #[arg(long)]
    pub hidden: Option<usize>,
    /// Double DQN: true or false.
    #[arg(long)]
    pub double: Option<bool>,
    /// Leave actions that change nothing out of every choice: true or false.
    #[arg(long)]
    pub mask_noops: Option<bool>,
    /// Batch normalisation in the paper network: true or false.
    #[arg(long)]
    pub batch_norm: Option<bool>,
    /// How the compact screen (--obs screen, the conv network) shows the goal: colours
    /// (every block in the colour of its place in the goal) or strip (blocks in their own
    /// colours, the goal stack in a column of its own).
    #[arg(long)]
    pub screen: Option<ScreenGoal>,
    /// The large-margin loss's margin.
    #[arg(long)]
    pub margin: Option<f64>,
    /// Hindsight relabelling: store every self-play step again with up to K goals that stood
    /// later in its game (HER's future strategy); 0 for none.
    #[arg(long, value_name = "K")]
    pub hindsight: Option<usize>,
    /// Share of every self-play batch drawn from the demonstrations.
    #[arg(long)]
    pub demo_share: Option<f64>,
    /// Steps before a training game is cut off.
    #[arg(long)]
    pub horizon: Option<u32>,
    /// World backend of the training games: grid (default; the same rules, faster) or physics.
    #[arg(long)]
    pub backend: Option<String>,
    /// Action protocol: free (every action legal; default) or paper (pick only with nothing
    /// held, move or drop only while holding). Every choice is masked to the legal actions.
    #[arg(long)]
    pub protocol: Option<String>,
    /// Seed of the weights, starts, demonstrations and every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Where to write the network.
    #[arg(long)]
    pub out: PathBuf,
}

impl DqnArgs {
    /// The training config these arguments describe: the library's resolver
    /// ([`DqnConfig::resolve`]: the preset, then each flag given).
    pub fn config(&self) -> Result<DqnConfig> {
        let overrides = DqnOverrides {
            preset: self.preset,
            obs: self.obs,
            net: self.net,
            loss: self.loss,
            blocks: Some(self.blocks),
            goals: self
                .goals
                .as_deref()
                .map(|text| Goal::parse_list(text, self.blocks))
                .transpose()?,
            grid: Some(self.grid.parse::<Grid>()?),
            steps: self.steps,
            pretrain: self.pretrain,
            demos: match (&self.demos, &self.demos_file) {
                (_, Some(path)) => Some(DemoSource::File(path.display().to_string())),
                (demos, None) => demos.clone(),
            },
            reward: self.reward.as_deref().map(RewardModel::from_name).transpose()?,
            gamma: self.gamma,
            lr: self.lr,
            lr_final: self.lr_final,
            optimizer: self.optimizer,
            td_loss: self.td_loss,
            buffer: self.buffer,
            batch: self.batch,
            hidden: self.hidden,
            double: self.double,
            mask_noops: self.mask_noops,
            batch_norm: self.batch_norm,
            screen: self.screen,
            margin: self.margin,
            hindsight: self.hindsight,
            demo_share: self.demo_share,
            horizon: self.horizon,
            backend: self.backend.as_deref().map(str::parse::<Backend>).transpose()?,
            protocol: self.protocol.as_deref().map(str::parse::<ActionProtocol>).transpose()?,
            seed: Some(self.seed),
        };
        DqnConfig::resolve(&overrides).map_err(|e| match e {
            // The goals were the default's: say which flag chooses others.
            neural::NeuralError::Sim(sim::SimError::TooManyGoals { .. }) if self.goals.is_none() => {
                anyhow::Error::new(e).context("without --goals every goal is used")
            }
            e => e.into(),
        })
    }
}

/// How often the progress bar is redrawn, in steps.
const DRAW_EVERY: u64 = 100;

/// Trains, showing a progress bar on a terminal, and saves the network.
pub fn dqn(args: DqnArgs) -> Result<()> {
    // Before minutes of work, not after.
    let out = files::OutputPath::check(&args.out)?;
    super::stdout::claim_for_data(&[Some(&out)])?;
    if let Some(demos) = &args.demos_file {
        files::refuse_same_file(&args.out, demos).context("--out and --demos-file")?;
    }
    let config = args.config()?;
    let clock = Instant::now();
    let trainer = neural::Trainer::new(config.clone())?;
    let demo_seconds = clock.elapsed().as_secs_f64();
    // Hidden by indicatif itself when stderr is not a terminal.
    let bar = ProgressBar::new(config.pretrain_steps);
    bar.set_style(
        ProgressStyle::with_template("{prefix} {bar:30} {pos}/{len}  {msg}  [{elapsed_precise}, eta {eta}]")
            .expect("a valid template"),
    );
    let mut phase = Phase::Pretrain;
    bar.set_prefix("pre-training");
    let mut stretch = (Instant::now(), 0u64);
    let mut show = |p: &Progress| {
        if p.phase != phase {
            phase = p.phase;
            bar.set_prefix("self-play");
            bar.set_length(p.target);
            stretch = (Instant::now(), p.done.saturating_sub(1));
        }
        if p.done.is_multiple_of(DRAW_EVERY) || p.done == p.target {
            bar.set_position(p.done);
            let rate = (p.done - stretch.1) as f64 / stretch.0.elapsed().as_secs_f64().max(1e-9);
            let unit = if p.phase == Phase::Pretrain {
                "gradient steps/s"
            } else {
                "steps/s"
            };
            bar.set_message(match p.phase {
                Phase::Pretrain => format!(
                    "loss {:.4} (margin {:.3})  {rate:.0} {unit}",
                    p.loss.total, p.loss.margin
                ),
                Phase::SelfPlay => format!(
                    "{} games, last {}: {:.0}% reached the goal, loss {:.4}, {rate:.0} {unit}",
                    p.games,
                    p.recent_games,
                    100.0 * p.recent_success_rate(),
                    p.loss.total
                ),
            });
        }
    };
    let dqn = trainer.run(&mut show)?;
    let seconds = clock.elapsed().as_secs_f64();
    bar.finish_and_clear();
    dqn.save(&args.out)
        .with_context(|| "the network was trained but not saved")?;
    for warning in dqn.warnings() {
        // On standard error, as main prints errors: a warning that cannot be shown has nowhere
        // else to go, and the file records it anyway.
        let _ = writeln!(
            std::io::stderr(),
            "blockstack: warning: {warning} (recorded in {})",
            args.out.display()
        );
    }
    let r = dqn.report();
    line(format_args!("trained {}: {}", dqn.name(), config.describe()))?;
    line(format_args!(
        "{} demonstrated episodes ({} transitions, {demo_seconds:.1} s to make), {} pre-training steps; \
         {} self-play steps in {} games, {} reached the goal; {} demonstrations from a loop; {} relabelled transitions; {} gradient steps",
        r.demo_episodes,
        r.demo_transitions,
        r.pretrain_steps,
        r.steps,
        r.games,
        r.successes,
        r.corrections,
        r.relabelled,
        r.gradient_steps
    ))?;
    line(format_args!(
        "trained in {seconds:.1} s ({:.0} environment steps/s, {:.0} gradient steps/s)",
        r.steps as f64 / (seconds - demo_seconds).max(1e-9),
        r.gradient_steps as f64 / (seconds - demo_seconds).max(1e-9)
    ))?;
    line(format_args!("saved {}", args.out.display()))
}
