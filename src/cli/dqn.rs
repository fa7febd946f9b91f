//! `blockstack dqn`: train a deep Q-network (DQN, or DQfD from demonstrations) and save it.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neural::relational::{RelationalConfig, RelationalModel};
use neural::{
    DemoSource, DqnOverrides, LossKind, NetKind, ObsKind, OptimizerKind, Phase, Preset, Progress, Recipe, TdLoss,
};
use sim::{Goal, ScreenGoal};

use super::checkpoint::{CheckpointArgs, CheckpointKind};
use super::stdout::line;
use super::world::WorldArgs;

/// The flags that set up a run, which `--resume` takes from its checkpoint instead.
const RUN_FLAGS: [&str; 32] = [
    "preset",
    "obs",
    "net",
    "loss",
    "blocks",
    "goals",
    "grid",
    "steps",
    "pretrain",
    "demos",
    "demos_file",
    "reward",
    "gamma",
    "lr",
    "lr_final",
    "optimizer",
    "td_loss",
    "buffer",
    "batch",
    "hidden",
    "double",
    "mask_noops",
    "batch_norm",
    "screen",
    "margin",
    "hindsight",
    "demo_share",
    "horizon",
    "backend",
    "protocol",
    "view",
    "seed",
];

/// Arguments of `blockstack dqn`. Every setting starts from a preset and may be changed.
#[derive(Debug, Args)]
#[command(mut_arg("checkpoint_every", |a| a.help(
    "Steps (pre-training gradient steps, then self-play steps) between two checkpoints [default: 10000]"
)))]
#[command(mut_arg("resume", |a| a.conflicts_with_all(RUN_FLAGS).help(
    "Continue the run in this checkpoint file, with its settings, to its end; it goes on writing checkpoints to the \
     same file unless --checkpoint names another. The flags that set up a run (--steps included: the learning rate \
     falls over the planned steps) are refused with it: the network it saves is the one the run would have saved had \
     it never stopped, byte for byte."
)))]
#[command(mut_arg("blocks", |a| a.help("Number of blocks [default: 3; with --preset general, the most blocks of a training problem: 6]")))]
#[command(mut_arg("grid", |a| a.help("Grid size, WxH [default: 7x7]")))]
#[command(mut_arg("reward", |a| a.help("Reward model: sparse, dense, paper or step-cost [default: the preset's]")))]
#[command(mut_arg("horizon", |a| a.help("Steps before a training game is cut off [default: the preset's]")))]
#[command(mut_arg("backend", |a| a.help("World backend of the training games: grid (the same rules, faster) or physics [default: grid]")))]
#[command(mut_arg("view", |a| a.help("The world: top only (a network learns the paper's world) [default: top]")))]
pub struct DqnArgs {
    #[command(flatten)]
    pub world: WorldArgs,
    /// Start from this preset: paper (the paper's DQN on pixels), paper-dqfd (the same with
    /// DQfD on 500 exact-solver demonstrations), dqn-planes (ours, no demonstrations),
    /// dqfd-planes (ours with DQfD: the recommended recipe), her-planes (ours without
    /// demonstrations, with hindsight relabelling), dqfd-paper-screen (our DQfD recipe with
    /// the paper network on the paper screen; earlier releases called it dqfd-pixels),
    /// dqfd-screen (our DQfD recipe with the conv network on the compact screen; earlier
    /// releases called it pixels), general (a relational policy of block moves in the side view
    /// that plays any number of blocks, learnt from the optimum on up to 20; it takes
    /// --blocks, --steps, --batch, --lr, --lr-final, --hidden and --seed). Default: from
    /// --obs and --loss.
    #[arg(long)]
    pub preset: Option<Preset>,
    /// What the network sees: role-planes, paper-screen or screen (default: the preset's,
    /// else role-planes). Earlier releases called the first two planes and pixels.
    #[arg(long)]
    pub obs: Option<ObsKind>,
    /// The network: paper (the paper screen), small (centred planes), mlp (absolute
    /// planes), conv (the compact screen) [default: the preset's]
    #[arg(long)]
    pub net: Option<NetKind>,
    /// The losses: dqfd (with demonstrations) or dqn [default: the preset's; without a
    /// preset, dqfd when demonstrations are given]
    #[arg(long)]
    pub loss: Option<LossKind>,
    /// Goals to train on, separated by ':', e.g. 0,1,2:1,0,2 (default: every goal).
    #[arg(long)]
    pub goals: Option<String>,
    /// Environment steps of self-play [default: the preset's]
    #[arg(long)]
    pub steps: Option<u64>,
    /// Gradient steps on the demonstrations alone, before self-play [default: the preset's]
    #[arg(long)]
    pub pretrain: Option<u64>,
    /// Demonstrations from a planner: exact:K or oracle:K (K episodes), or none [default: the preset's]
    #[arg(long, conflicts_with = "demos_file")]
    pub demos: Option<DemoSource>,
    /// Demonstrations from a recording: blockstack-demos JSON Lines (`demo`/`correct
    /// --record`) or a trajectory file (`run --trajectory`).
    #[arg(long)]
    pub demos_file: Option<PathBuf>,
    /// Discount factor [default: the preset's]
    #[arg(long)]
    pub gamma: Option<f64>,
    /// Learning rate (the final rate follows in the preset's proportion unless --lr-final
    /// says) [default: the preset's]
    #[arg(long)]
    pub lr: Option<f64>,
    /// Learning rate at the end of the run (it falls linearly from --lr) [default: the
    /// preset's]
    #[arg(long)]
    pub lr_final: Option<f64>,
    /// Optimiser: rmsprop or adam [default: the preset's]
    #[arg(long)]
    pub optimizer: Option<OptimizerKind>,
    /// TD loss: huber or mse [default: the preset's]
    #[arg(long)]
    pub td_loss: Option<TdLoss>,
    /// Transitions the replay buffer holds [default: the preset's]
    #[arg(long)]
    pub buffer: Option<usize>,
    /// Transitions per gradient step [default: the preset's]
    #[arg(long)]
    pub batch: Option<usize>,
    /// Units of each hidden layer [default: the preset's]
    #[arg(long)]
    pub hidden: Option<usize>,
    /// Double DQN: true or false [default: the preset's]
    #[arg(long)]
    pub double: Option<bool>,
    /// Leave actions that change nothing out of every choice: true or false [default: the preset's]
    #[arg(long)]
    pub mask_noops: Option<bool>,
    /// Batch normalisation in the paper network: true or false [default: the preset's]
    #[arg(long)]
    pub batch_norm: Option<bool>,
    /// How the conv network's screen shows the goal: colours (the compact screen, every
    /// block in the colour of its place in the goal), strip (the compact screen, blocks in
    /// their own colours, the goal stack in a column of its own) or paper (the paper's own
    /// screen, the goal a picture in the corner; the network reads paper-screen)
    /// [default: the preset's]
    #[arg(long)]
    pub screen: Option<ScreenGoal>,
    /// The large-margin loss's margin [default: the preset's]
    #[arg(long)]
    pub margin: Option<f64>,
    /// Hindsight relabelling: store every self-play step again with up to K goals that stood
    /// later in its game (HER's future strategy); 0 for none [default: the preset's]
    #[arg(long, value_name = "K")]
    pub hindsight: Option<usize>,
    /// Share of every self-play batch drawn from the demonstrations [default: the preset's]
    #[arg(long)]
    pub demo_share: Option<f64>,
    /// Action protocol: free (every action legal; default) or paper (pick only with nothing
    /// held, move or drop only while holding). Every choice is masked to the legal actions.
    #[arg(long)]
    pub protocol: Option<sim::ActionProtocol>,
    /// Seed of the weights, starts, demonstrations and every random choice.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Where to write the network.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub checkpointing: CheckpointArgs,
}

impl DqnArgs {
    /// The settings these arguments give, by name ([`DqnOverrides`]): what Python's
    /// `train_dqn` takes as keyword arguments.
    pub fn overrides(&self) -> Result<DqnOverrides> {
        let w = &self.world;
        Ok(DqnOverrides {
            preset: self.preset,
            obs: self.obs,
            net: self.net,
            loss: self.loss,
            blocks: w.blocks,
            goals: self
                .goals
                .as_deref()
                .map(|text| Goal::parse_list(text, w.blocks.unwrap_or(neural::preset::DEFAULT_BLOCKS)))
                .transpose()?,
            grid: w.grid,
            steps: self.steps,
            pretrain: self.pretrain,
            demos: match (&self.demos, &self.demos_file) {
                (_, Some(path)) => Some(DemoSource::File(path.display().to_string())),
                (demos, None) => demos.clone(),
            },
            reward: w.reward,
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
            horizon: w.horizon,
            backend: w.backend,
            protocol: self.protocol,
            view: w.view,
            seed: Some(self.seed),
        })
    }

    /// What these arguments train: the library's resolver ([`Recipe::resolve`]: the
    /// preset, then each flag given), its refusals in the flags' words.
    pub fn recipe(&self) -> Result<Recipe> {
        Recipe::resolve(&self.overrides()?).map_err(|e| match e {
            // The goals were the default's: say which flag chooses others.
            neural::NeuralError::Sim(sim::SimError::TooManyGoals { .. }) if self.goals.is_none() => {
                anyhow::Error::new(e).context("without --goals every goal is used")
            }
            neural::NeuralError::NotForGeneral { setting } => anyhow::anyhow!(
                "{} does not apply to --preset general (a relational policy learnt from the optimum): it takes {}",
                match setting {
                    "view" => "--view top".to_string(),
                    s => flag(s),
                },
                neural::preset::GENERAL_SETTINGS.map(flag).join(", ")
            ),
            e => e.into(),
        })
    }
}

/// The flag of a setting named as [`DqnOverrides`] names it.
fn flag(setting: &str) -> String {
    format!("--{}", setting.replace('_', "-"))
}

/// A network run's checkpoints.
const KIND: CheckpointKind = CheckpointKind {
    format: neural::checkpoint::CHECKPOINT_FORMAT,
    unit: "steps",
};

/// How often the progress bar is redrawn, in steps.
const DRAW_EVERY: u64 = 100;

/// Trains (or resumes a checkpointed run), showing a progress bar on a terminal, writing
/// checkpoints if asked, and saves the network.
pub fn dqn(args: DqnArgs) -> Result<()> {
    // Before minutes of work, not after.
    let out = files::OutputPath::check(&args.out)?;
    let c = &args.checkpointing;
    // A resumed run takes its settings from its checkpoint.
    let config = match &c.resume {
        Some(_) => None,
        None => match args.recipe()? {
            Recipe::Network(config) => Some(config),
            Recipe::Relational(config) => {
                anyhow::ensure!(
                    c.checkpoint.is_none(),
                    "--checkpoint is a network run's: --preset general trains in minutes and writes none"
                );
                super::stdout::claim_for_data(&[Some(&out)])?;
                return general(&args, &config);
            }
        },
    };
    let checkpoint = c.output(&args.out, &out, &KIND)?;
    if let Some(demos) = &args.demos_file {
        files::refuse_same_file(&args.out, demos).context("--out and --demos-file")?;
    }
    let clock = Instant::now();
    // A resumed run is read first: its settings say which checkpoint is its own.
    let resumed = c.resume.as_deref().map(neural::Trainer::resume).transpose()?;
    let settings = resumed
        .as_ref()
        .map_or_else(|| config.as_deref().cloned(), |t| Some(t.config().clone()));
    if let Some(settings) = &settings {
        c.refuse_other_files(&KIND, |path| neural::Trainer::resume_run(path, settings).is_ok())?;
    }
    let mut trainer = match (resumed, config) {
        (Some(trainer), _) => trainer,
        (None, Some(config)) => neural::Trainer::new(*config)?,
        (None, None) => anyhow::bail!("--resume or the run's settings: neither was given"),
    };
    let config = trainer.config().clone();
    let resumed_at = trainer.steps_done();
    let before = trainer.report();
    let demo_seconds = clock.elapsed().as_secs_f64();
    // Hidden by indicatif itself when stderr is not a terminal.
    let bar = ProgressBar::new(config.pretrain_steps);
    bar.set_position(trainer.report().pretrain_steps);
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
                    p.recent.games,
                    100.0 * p.recent.success_rate(),
                    p.loss.total
                ),
            });
        }
    };
    let every = c.checkpoint_every.unwrap_or(neural::checkpoint::DEFAULT_EVERY);
    let mut hooks = agent::RunHooks {
        after: |p: &Progress| {
            show(p);
            Ok(())
        },
        checkpoints: agent::Checkpoints::to(checkpoint.as_ref(), every),
    };
    trainer.run_until_on_pool(trainer.total_steps(), &mut hooks)?;
    let dqn = trainer.finish()?;
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
    if let Some(path) = &c.resume {
        line(format_args!(
            "resumed at step {resumed_at} of {} from {}",
            config.pretrain_steps + config.steps,
            path.display()
        ))?;
    }
    let made = match &c.resume {
        Some(_) => format!("{demo_seconds:.1} s to read the checkpoint"),
        None => format!("{demo_seconds:.1} s to make"),
    };
    line(format_args!(
        "{} demonstrated episodes ({} transitions, {made}), {} pre-training steps; \
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
        (r.steps - before.steps) as f64 / (seconds - demo_seconds).max(1e-9),
        (r.gradient_steps - before.gradient_steps) as f64 / (seconds - demo_seconds).max(1e-9)
    ))?;
    if let Some(out) = &checkpoint {
        line(format_args!("checkpoint {}", out.path().display()))?;
    }
    line(format_args!("saved {}", args.out.display()))
}

/// `--preset general`: trains the relational policy, showing a progress bar on a terminal
/// (one tick per DAgger iteration), and saves it.
fn general(args: &DqnArgs, config: &RelationalConfig) -> Result<()> {
    let clock = Instant::now();
    let bar = ProgressBar::new(config.iterations);
    bar.set_style(
        ProgressStyle::with_template("DAgger {bar:30} {pos}/{len}  {msg}  [{elapsed_precise}, eta {eta}]")
            .expect("a valid template"),
    );
    let model = RelationalModel::train(config, &mut |r| {
        bar.set_position(r.iteration);
        bar.set_message(format!(
            "{} examples, loss {:.4}, {:.1}% of games reached the goal",
            r.examples,
            r.loss,
            100.0 * r.success
        ));
    })?;
    let seconds = clock.elapsed().as_secs_f64();
    bar.finish_and_clear();
    model
        .save(&args.out)
        .with_context(|| "the policy was trained but not saved")?;
    line(format_args!("trained {}", model.name()))?;
    if let Some(last) = model.report().last() {
        line(format_args!(
            "{} DAgger iterations of {} gradient steps on problems of 2 to {} blocks, {} labelled examples; \
             the last iteration's games: {:.1}% reached the goal, {:.3}x the fewest moves",
            config.iterations,
            config.steps,
            config.max_blocks,
            last.examples,
            100.0 * last.success,
            last.moves_ratio
        ))?;
    }
    line(format_args!("trained in {seconds:.1} s"))?;
    line(format_args!("saved {}", args.out.display()))
}
