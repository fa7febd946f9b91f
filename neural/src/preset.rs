//! The presets, and the one resolver of a preset and explicit settings.
//!
//! A run of `blockstack dqn` (or Python's `blockstack.train_dqn`) is described in two
//! layers, the second overriding the first:
//!
//! 1. a **preset** ([`Preset`]) gives every setting of a recipe for the number of blocks
//!    (module docs below); without one, the preset `--obs` (or `--net`) and `--loss` point to
//!    ([`Preset::default_for`]);
//! 2. every **explicit setting** ([`DqnOverrides`]) beats it.
//!
//! Both front ends call [`Recipe::resolve`] (a network's run through [`DqnConfig::resolve`],
//! the `general` preset's relational policy through [`general_config`]), so the same settings
//! give the same model file, byte for byte.
//!
//! # Presets
//!
//! - `paper`: the paper's DQN as section III-C and the authors' code describe it: pixels, the
//!   paper network with batch normalisation, buffer 1000, batch 64, RMSprop at 1e-4, MSE
//!   loss, the sparse reward, the target network refreshed every 3 training games (the
//!   paper's "every n epochs", n = 3 or 5), epsilon 0.1 throughout and gamma 0.1 (both from
//!   the authors' `DQN.py`; the paper gives neither), every action allowed (no mask), no
//!   demonstrations.
//! - `paper-dqfd`: the same with the paper's DQfD stage: pre-training on demonstrations
//!   (here 500 of the exact solver's, where the paper had people's) with the large-margin
//!   loss, then self-play with the demonstrations kept in the buffer.
//! - `dqn-planes`: ours without demonstrations: the small network on centred planes, Adam at
//!   1e-3 falling to 1e-4, Huber loss, double DQN, gamma 0.95, the sparse reward, a
//!   100,000-step buffer, the target refreshed every 500 gradient steps, epsilon from 1 to
//!   0.05 over the first half of 50,000 steps (2 blocks) or 300,000 (more), actions that
//!   change nothing masked, gradients clipped at norm 10.
//! - `dqfd-planes` (the recommended recipe): `dqn-planes` with DQfD (Hester et al. 2018):
//!   10,000 exact-solver demonstrations, 30,000 pre-training steps with the 1-step and
//!   10-step TD losses, the large-margin loss (margin 0.8) and L2 1e-5, then 30,000 steps of
//!   self-play (90,000 of each on 3 blocks; 40,000 demonstrations and 360,000 steps of
//!   each on 4 and more) with a quarter of every batch drawn from the demonstrations,
//!   epsilon from 0.1 to 0.01, the learning rate falling from 1e-3 to 1e-4, and loops corrected: the first
//!   time a game comes back to a state it was in, the exact solver demonstrates from there
//!   (the paper's demonstrators correcting the agent, section VI-C, as DQfD data).
//! - `her-planes`: `dqn-planes` with hindsight relabelling (HER, Andrychowicz et al. 2017,
//!   [`crate::hindsight`]): no demonstrations; every step stored again with 4 goals that
//!   stood later in its game.
//! - `dqfd-paper-screen` (called `dqfd-pixels` before; the old name is still read):
//!   `dqfd-planes` on the paper's screen with the paper's network (batch
//!   normalisation): the paper's network and input, our learner. Its budget is a few
//!   thousand steps (a step of that network costs twenty times one of ours): 1,000
//!   demonstrations, 6,000 pre-training and 6,000 self-play steps on 2 blocks (epsilon
//!   falling over the first 2,000); 5,000 and 15,000 on more (epsilon over 7,500).
//! - `dqfd-screen` (called `pixels` before; the old name is still read): `dqfd-planes`,
//!   every setting and budget, with the `conv` network on the compact screen ([`sim::screen`]): pixels at four a cell, every block in the colour of
//!   its place in the goal, read by a convolution of one cell ([`crate::net::NetKind::Conv`]).
//!   `--screen paper` puts the same network and learner on the paper's own screen (the
//!   goal a picture in the corner), a convolution of one of its cells ([`crate::net::conv_cell`]).
//! - `general`: not a Q-network but the relational policy of block moves in the side view
//!   ([`crate::relational`]), learnt from the optimum on problems of 2 to 20 blocks, that plays
//!   any number of blocks ([`RelationalConfig::general`]). It takes only the settings in
//!   [`GENERAL_SETTINGS`]; any other is refused, naming it ([`NeuralError::NotForGeneral`]).
//!
//! Why each of our choices, measured, is in the E8 section of `blockstack reproduce --only
//! E8 --long`'s report.

use serde::{Deserialize, Serialize};
use sim::{ActionProtocol, Backend, EnvConfig, Goal, GoalSpec, Grid, RewardModel, ScreenGoal, View};

use crate::config::{DemoSource, DqnConfig, Epsilon, LossKind, TargetEvery, TdLoss};
use crate::error::{NeuralError, Result};
use crate::input::{self, ObsKind};
use crate::net::{NetConfig, NetKind};
use crate::optim::OptimizerKind;
use crate::relational::RelationalConfig;

/// The blocks of a run whose settings do not say.
pub const DEFAULT_BLOCKS: usize = 3;

/// A recipe of every setting (`dqn --preset`; module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The paper's DQN on its screen, as its authors configured it.
    Paper,
    /// `paper` with the paper's DQfD stage.
    PaperDqfd,
    /// Ours without demonstrations, on centred planes.
    DqnPlanes,
    /// Ours with DQfD on centred planes: the recommended recipe.
    DqfdPlanes,
    /// `dqn-planes` with hindsight relabelling.
    HerPlanes,
    /// `dqfd-planes`' learner with the paper's network on the paper's screen.
    #[serde(alias = "dqfd-pixels")]
    DqfdPaperScreen,
    /// `dqfd-planes`' learner with the `conv` network on the compact screen.
    #[serde(alias = "pixels")]
    DqfdScreen,
    /// The relational policy of block moves ([`crate::relational`]), not a Q-network.
    General,
}

sim::names!(Preset {
    Paper = "paper",
    PaperDqfd = "paper-dqfd",
    DqnPlanes = "dqn-planes",
    DqfdPlanes = "dqfd-planes",
    HerPlanes = "her-planes",
    DqfdPaperScreen = "dqfd-paper-screen",
    DqfdScreen = "dqfd-screen",
    General = "general",
} aliases {
    // Their names before each said its screen (docs/results/dqn's records use them).
    "dqfd-pixels" => DqfdPaperScreen,
    "pixels" => DqfdScreen,
} unknown(name) -> NeuralError {
    NeuralError::Config(format!("unknown preset {name:?}: choose {}", Preset::NAMES.join(", ")))
});

impl Preset {
    /// The preset a run takes when none is named: the paper's on its screen, ours on
    /// planes; with DQfD when `dqfd`.
    pub fn default_for(obs: ObsKind, dqfd: bool) -> Preset {
        match (obs, dqfd) {
            (ObsKind::PaperScreen, false) => Preset::Paper,
            (ObsKind::PaperScreen, true) => Preset::PaperDqfd,
            (ObsKind::Screen, _) => Preset::DqfdScreen,
            (_, false) => Preset::DqnPlanes,
            (_, true) => Preset::DqfdPlanes,
        }
    }
}

/// The settings a user gave explicitly; `None` keeps what the preset says. The field names
/// are `blockstack dqn`'s flags and Python's keyword arguments (`--demos-file` is
/// `demos_file`, given here as [`DemoSource::File`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DqnOverrides {
    /// `--preset` (default [`Preset::default_for`] the observation and the loss).
    pub preset: Option<Preset>,
    /// `--obs`: a network of the preset's kind that reads it, unless `net` names one.
    pub obs: Option<ObsKind>,
    /// `--net`.
    pub net: Option<NetKind>,
    /// `--loss` (default: the preset's; without a preset, DQfD when demonstrations are
    /// given).
    pub loss: Option<LossKind>,
    /// `--blocks` (default 3).
    pub blocks: Option<usize>,
    /// `--goals` (default every goal of the block count).
    pub goals: Option<Vec<Goal>>,
    /// `--grid` (default 7 x 7).
    pub grid: Option<Grid>,
    /// `--steps`.
    pub steps: Option<u64>,
    /// `--pretrain`.
    pub pretrain: Option<u64>,
    /// `--demos` or `--demos-file` (a file as [`DemoSource::File`]); `none` also drops the
    /// preset's pre-training.
    pub demos: Option<DemoSource>,
    /// `--reward`.
    pub reward: Option<RewardModel>,
    /// `--gamma`.
    pub gamma: Option<f64>,
    /// `--lr`: the final rate follows in the preset's proportion unless `lr_final` says.
    pub lr: Option<f64>,
    /// `--lr-final`.
    pub lr_final: Option<f64>,
    /// `--optimizer`.
    pub optimizer: Option<OptimizerKind>,
    /// `--td-loss`.
    pub td_loss: Option<TdLoss>,
    /// `--buffer`.
    pub buffer: Option<usize>,
    /// `--batch`.
    pub batch: Option<usize>,
    /// `--hidden`.
    pub hidden: Option<usize>,
    /// `--double`.
    pub double: Option<bool>,
    /// `--mask-noops`.
    pub mask_noops: Option<bool>,
    /// `--batch-norm`.
    pub batch_norm: Option<bool>,
    /// `--screen`: how the compact screen shows the goal (the `conv` network).
    pub screen: Option<ScreenGoal>,
    /// `--margin`.
    pub margin: Option<f64>,
    /// `--hindsight`.
    pub hindsight: Option<usize>,
    /// `--demo-share`.
    pub demo_share: Option<f64>,
    /// `--horizon`.
    pub horizon: Option<u32>,
    /// `--backend`.
    pub backend: Option<Backend>,
    /// `--protocol`.
    pub protocol: Option<ActionProtocol>,
    /// `--view`: a network learns the top view, the relational policy the side view; the
    /// other is refused.
    pub view: Option<View>,
    /// `--seed` (default 1).
    pub seed: Option<u64>,
}

/// What a run trains: a Q-network's run, or the `general` preset's relational policy.
#[derive(Clone, Debug, PartialEq)]
pub enum Recipe {
    /// A deep Q-network (every preset but `general`).
    Network(Box<DqnConfig>),
    /// The relational policy of block moves (`general`).
    Relational(RelationalConfig),
}

impl Recipe {
    /// The run the settings describe: the relational policy's ([`general_config`]) for the
    /// `general` preset, else the network's ([`DqnConfig::resolve`]). `blockstack dqn` and
    /// Python's `train_dqn` both call it.
    pub fn resolve(settings: &DqnOverrides) -> Result<Recipe> {
        match settings.preset {
            Some(Preset::General) => Ok(Recipe::Relational(general_config(settings)?)),
            _ => Ok(Recipe::Network(Box::new(DqnConfig::resolve(settings)?))),
        }
    }
}

/// The settings the `general` preset takes, by their names in [`DqnOverrides`] (the flags
/// and keyword arguments): the most blocks of a training problem, the gradient steps per
/// DAgger iteration, the batch, the learning rates, the hidden width and the seed.
pub const GENERAL_SETTINGS: [&str; 7] = ["blocks", "steps", "batch", "lr", "lr_final", "hidden", "seed"];

/// The `general` preset's relational policy with the settings it takes
/// ([`GENERAL_SETTINGS`]), checked; any other setting given is refused, naming it.
pub fn general_config(s: &DqnOverrides) -> Result<RelationalConfig> {
    let given = [
        ("obs", s.obs.is_some()),
        ("net", s.net.is_some()),
        ("loss", s.loss.is_some()),
        ("goals", s.goals.is_some()),
        ("grid", s.grid.is_some()),
        ("pretrain", s.pretrain.is_some()),
        ("demos", s.demos.is_some()),
        ("reward", s.reward.is_some()),
        ("gamma", s.gamma.is_some()),
        ("optimizer", s.optimizer.is_some()),
        ("td_loss", s.td_loss.is_some()),
        ("buffer", s.buffer.is_some()),
        ("double", s.double.is_some()),
        ("mask_noops", s.mask_noops.is_some()),
        ("batch_norm", s.batch_norm.is_some()),
        ("screen", s.screen.is_some()),
        ("margin", s.margin.is_some()),
        ("hindsight", s.hindsight.is_some()),
        ("demo_share", s.demo_share.is_some()),
        ("horizon", s.horizon.is_some()),
        ("backend", s.backend.is_some()),
        ("protocol", s.protocol.is_some()),
        ("view", s.view == Some(View::Top)),
    ];
    if let Some(&(setting, _)) = given.iter().find(|(_, g)| *g) {
        let setting = match (setting, &s.demos) {
            // A recording is its own flag.
            ("demos", Some(DemoSource::File(_))) => "demos_file",
            _ => setting,
        };
        return Err(NeuralError::NotForGeneral { setting });
    }
    let mut c = RelationalConfig::general();
    c.seed = s.seed.unwrap_or(1);
    if let Some(b) = s.blocks {
        c.max_blocks = b;
    }
    if let Some(steps) = s.steps {
        c.steps = steps;
    }
    if let Some(b) = s.batch {
        c.batch = b;
    }
    if let Some(lr) = s.lr {
        c.lr_final *= lr / c.lr;
        c.lr = lr;
    }
    if let Some(lr) = s.lr_final {
        c.lr_final = lr;
    }
    if let Some(h) = s.hidden {
        c.shape.hidden = h;
    }
    c.validate()?;
    Ok(c)
}

/// The network of `kind` as a preset would build it: the paper's with its batch
/// normalisation, the perceptrons with the small network's width.
fn network(kind: NetKind) -> NetConfig {
    match kind {
        NetKind::Paper => NetConfig::paper(),
        NetKind::Conv => NetConfig::conv(),
        kind => NetConfig {
            kind,
            ..NetConfig::small()
        },
    }
}

/// The network a preset puts on `obs`.
fn network_for(obs: ObsKind) -> NetConfig {
    match obs {
        ObsKind::PaperScreen => NetConfig::paper(),
        ObsKind::Screen => NetConfig::conv(),
        _ => NetConfig::small(),
    }
}

impl DqnConfig {
    /// The run the settings describe (module docs: the preset, then each explicit
    /// setting), checked.
    pub fn resolve(settings: &DqnOverrides) -> Result<DqnConfig> {
        let s = settings;
        if s.view == Some(View::Side) {
            return Err(NeuralError::Config(
                "view side: a network learns the top view only (train a tabular learner for the side view, \
                 or the relational policy: the general preset)"
                    .into(),
            ));
        }
        if let Some(obs) = s.obs {
            input::check_network_obs(obs)?;
        }
        let blocks = s.blocks.unwrap_or(DEFAULT_BLOCKS);
        let preset = match s.preset {
            Some(p) => p,
            None => {
                let obs = s.obs.or(s.net.map(|kind| network(kind).obs()));
                let dqfd = match s.loss {
                    Some(loss) => loss == LossKind::Dqfd,
                    None => s.demos.as_ref().is_some_and(|d| *d != DemoSource::None),
                };
                Preset::default_for(obs.unwrap_or(ObsKind::RolePlanes), dqfd)
            }
        };
        let mut c = DqnConfig::preset(preset, blocks)?;
        c.world.grid = s.grid.unwrap_or_default();
        if let Some(goals) = &s.goals {
            c.goals = goals.clone();
        }
        c.seed = s.seed.unwrap_or(1);
        if let Some(kind) = s.net {
            c = c.with_net(network(kind));
            if let Some(obs) = s.obs {
                c.net.validate(obs)?;
            }
        } else if let Some(obs) = s.obs
            && obs != c.obs()
        {
            c = c.with_net(network_for(obs));
        }
        if let Some(d) = &s.demos {
            if *d == DemoSource::None {
                c.pretrain_steps = 0;
            }
            c.demos = d.clone();
        }
        macro_rules! set {
            ($($field:ident = $value:expr),* $(,)?) => {
                $(if let Some(v) = $value { c.$field = v; })*
            };
        }
        set!(
            loss = s.loss,
            steps = s.steps,
            pretrain_steps = s.pretrain,
            gamma = s.gamma,
            optimizer = s.optimizer,
            td_loss = s.td_loss,
            buffer = s.buffer,
            batch = s.batch,
            double = s.double,
            mask_noops = s.mask_noops,
            margin = s.margin,
            demo_share = s.demo_share,
            hindsight = s.hindsight,
        );
        if let Some(h) = s.horizon {
            c.world.horizon = h;
        }
        if let Some(lr) = s.lr {
            c.lr_final *= lr / c.lr;
            c.lr = lr;
        }
        if let Some(lr) = s.lr_final {
            c.lr_final = lr;
        }
        if let Some(r) = s.reward {
            c.world.reward = r;
        }
        if let Some(b) = s.backend {
            c.world.backend = b;
        }
        if let Some(p) = s.protocol {
            c.world.protocol = p;
        }
        if let Some(h) = s.hidden {
            c.net.hidden = h;
        }
        if let Some(bn) = s.batch_norm {
            c.net.batch_norm = bn;
        }
        if let Some(screen) = s.screen {
            c.net.screen = screen;
        }
        c.validate()?;
        Ok(c)
    }

    /// The paper's DQN (module docs) on `blocks` blocks, every goal.
    pub fn paper(blocks: usize) -> Result<DqnConfig> {
        let net = NetConfig::paper();
        Ok(DqnConfig {
            world: EnvConfig {
                grid: Grid::default(),
                blocks,
                goal: GoalSpec::Random,
                horizon: sim::DEFAULT_HORIZON,
                reward: RewardModel::from_name("sparse")?,
                backend: Backend::Grid,
                protocol: ActionProtocol::Free,
                ..EnvConfig::default()
            },
            goals: Goal::all(blocks)?,
            net,
            seed: 1,
            // A gradient step of the paper network costs about 100 ms here: 5,000 steps
            // are minutes, where the paper trained for 2-8 hours.
            steps: 5_000,
            pretrain_steps: 0,
            demos: DemoSource::None,
            loss: LossKind::Dqn,
            td_loss: TdLoss::Mse,
            optimizer: OptimizerKind::Rmsprop,
            lr: 1e-4,
            lr_final: 1e-4,
            gamma: 0.1,
            buffer: 1000,
            batch: 64,
            train_every: 1,
            learning_starts: 64,
            target_every: TargetEvery::Games(3),
            epsilon: Epsilon {
                start: 0.1,
                end: 0.1,
                steps: 0,
            },
            double: false,
            clip_norm: None,
            n_step: 10,
            margin: agent::correction::DEFAULT_MARGIN,
            lambda_n_step: 1.0,
            lambda_margin: 1.0,
            l2: 1e-5,
            demo_share: 0.25,
            mask_noops: false,
            correct_loops: false,
            hindsight: 0,
        })
    }

    /// The preset `preset` for `blocks` blocks, every goal, seed 1; an error for `general`,
    /// which trains no network ([`Recipe::resolve`]).
    pub fn preset(preset: Preset, blocks: usize) -> Result<DqnConfig> {
        let paper = DqnConfig::paper(blocks)?;
        Ok(match preset {
            Preset::General => {
                return Err(NeuralError::Config(
                    "the general preset trains a relational policy, not a network".into(),
                ));
            }
            Preset::Paper => paper,
            Preset::PaperDqfd => DqnConfig {
                demos: DemoSource::Exact(500),
                loss: LossKind::Dqfd,
                pretrain_steps: 2_000,
                steps: 3_000,
                ..paper
            },
            Preset::DqnPlanes => DqnConfig::dqn_planes(paper),
            Preset::DqfdPlanes => DqnConfig::dqfd_planes(paper),
            Preset::HerPlanes => DqnConfig::her_planes(paper),
            Preset::DqfdPaperScreen => DqnConfig::dqfd_paper_screen(paper),
            Preset::DqfdScreen => DqnConfig::dqfd_screen(paper),
        })
    }

    fn dqfd_planes(paper: DqnConfig) -> DqnConfig {
        // Greedy failures are loops that fade with gradient steps (measured on 3,000 test
        // games of 3 blocks: 1.9 % at 30,000 + 30,000 steps, 0.8 % at three times that,
        // 0.4 % at four; on 12,000 of 4 blocks: 14.9 % at 90,000 + 90,000 with 10,000
        // demonstrations, 9.7 % at twice both, 3.1 % at four times): 3 blocks get three times
        // 2 blocks' steps, 4 blocks and more four times 3 blocks' steps and demonstrations.
        let (steps, demos) = match paper.world.blocks {
            ..=2 => (30_000, 10_000),
            3 => (90_000, 10_000),
            _ => (360_000, 40_000),
        };
        DqnConfig {
            steps,
            pretrain_steps: steps,
            demos: DemoSource::Exact(demos),
            loss: LossKind::Dqfd,
            learning_starts: 1_000,
            epsilon: Epsilon {
                start: 0.1,
                end: 0.01,
                steps: 15_000,
            },
            correct_loops: true,
            ..DqnConfig::dqn_planes(paper)
        }
    }

    fn dqfd_paper_screen(paper: DqnConfig) -> DqnConfig {
        let blocks = paper.world.blocks;
        // A DQfD step of the paper network costs about 40 ms here, a step of the small one
        // 2 ms: a budget of minutes buys a few thousand steps, so the demonstrations carry
        // most of the learning and the budget grows with the blocks. On 2 blocks, 4,000 steps
        // of each left one goal at 94.6 %; 6,000 reach 95 % on every goal (epsilon falling
        // over the first 2,000 self-play steps, as it did at 4,000).
        let (demos, steps, fall) = if blocks <= 2 {
            (1_000, 6_000, 2_000)
        } else {
            (5_000, 15_000, 7_500)
        };
        let net = paper.net;
        DqnConfig {
            demos: DemoSource::Exact(demos),
            pretrain_steps: steps,
            steps,
            learning_starts: 500,
            epsilon: Epsilon {
                start: 0.1,
                end: 0.01,
                steps: fall,
            },
            ..DqnConfig::dqfd_planes(paper).with_net(net)
        }
    }

    fn dqfd_screen(paper: DqnConfig) -> DqnConfig {
        let planes = DqnConfig::dqfd_planes(paper).with_net(NetConfig::conv());
        // On 2 blocks two thirds of the planes' budget reach every goal on every test start
        // (1,000 of 1,000 at 1.000x with 20,000 + 20,000 steps, docs/results/dqn), in about
        // two thirds of the time.
        if planes.world.blocks <= 2 {
            DqnConfig {
                steps: 20_000,
                pretrain_steps: 20_000,
                ..planes
            }
        } else {
            planes
        }
    }

    fn her_planes(paper: DqnConfig) -> DqnConfig {
        let planes = DqnConfig::dqn_planes(paper);
        DqnConfig { hindsight: 4, ..planes }
    }

    fn dqn_planes(paper: DqnConfig) -> DqnConfig {
        // Exploration alone must find the goal: far longer on 3 blocks than on 2.
        let steps = if paper.world.blocks <= 2 { 50_000 } else { 300_000 };
        let net = NetConfig::small();
        DqnConfig {
            net,
            steps,
            td_loss: TdLoss::Huber,
            optimizer: OptimizerKind::Adam,
            lr: 1e-3,
            lr_final: 1e-4,
            gamma: 0.95,
            buffer: 100_000,
            learning_starts: 5_000,
            target_every: TargetEvery::Steps(500),
            epsilon: Epsilon {
                start: 1.0,
                end: 0.05,
                steps: steps / 2,
            },
            double: true,
            clip_norm: Some(10.0),
            mask_noops: true,
            ..paper
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_is_valid_and_the_paper_is_the_papers() {
        for preset in Preset::ALL {
            assert_eq!(preset.name().parse::<Preset>().unwrap(), preset);
            if preset != Preset::General {
                DqnConfig::preset(preset, 3).unwrap().validate().unwrap();
            }
        }
        let p = DqnConfig::preset(Preset::Paper, 3).unwrap();
        assert_eq!(
            (p.buffer, p.batch, p.lr, p.obs()),
            (1000, 64, 1e-4, ObsKind::PaperScreen)
        );
        assert_eq!(p.optimizer, OptimizerKind::Rmsprop);
        assert_eq!(p.world.reward.name(), "sparse");
        // The names before each said its screen are still read.
        assert_eq!("pixels".parse::<Preset>().unwrap(), Preset::DqfdScreen);
        assert_eq!("dqfd-pixels".parse::<Preset>().unwrap(), Preset::DqfdPaperScreen);
        assert!(!Preset::NAMES.contains(&"pixels"));
        let e = "nope".parse::<Preset>().unwrap_err().to_string();
        assert!(e.contains("unknown preset") && e.contains("dqfd-planes"), "{e}");
    }

    #[test]
    fn dqfd_planes_budget_grows_with_the_blocks_and_the_screens_keep_their_own() {
        let budget = |preset, blocks| {
            let c = DqnConfig::preset(preset, blocks).unwrap();
            (c.demos, c.pretrain_steps, c.steps)
        };
        assert_eq!(
            budget(Preset::DqfdPlanes, 2),
            (DemoSource::Exact(10_000), 30_000, 30_000)
        );
        assert_eq!(
            budget(Preset::DqfdPlanes, 3),
            (DemoSource::Exact(10_000), 90_000, 90_000)
        );
        for blocks in [4, 5] {
            assert_eq!(
                budget(Preset::DqfdPlanes, blocks),
                (DemoSource::Exact(40_000), 360_000, 360_000)
            );
            assert_eq!(
                budget(Preset::DqfdPaperScreen, blocks),
                (DemoSource::Exact(5_000), 15_000, 15_000)
            );
        }
        assert_eq!(
            budget(Preset::DqfdScreen, 2),
            (DemoSource::Exact(10_000), 20_000, 20_000)
        );
        assert_eq!(budget(Preset::DqfdScreen, 3), budget(Preset::DqfdPlanes, 3));
    }

    #[test]
    fn without_a_preset_the_observation_and_the_loss_choose_one() {
        let resolved = |o: DqnOverrides| DqnConfig::resolve(&o).unwrap();
        let preset = |p| DqnConfig::preset(p, 3).unwrap();
        assert_eq!(resolved(DqnOverrides::default()), preset(Preset::DqnPlanes));
        let demos = DqnOverrides {
            demos: Some(DemoSource::Exact(10_000)),
            ..DqnOverrides::default()
        };
        assert_eq!(resolved(demos.clone()), preset(Preset::DqfdPlanes));
        let screen = DqnOverrides {
            obs: Some(ObsKind::PaperScreen),
            ..DqnOverrides::default()
        };
        assert_eq!(resolved(screen.clone()), preset(Preset::Paper));
        // --loss beats what the demonstrations imply.
        let dqn = resolved(DqnOverrides {
            loss: Some(LossKind::Dqn),
            ..demos
        });
        assert_eq!((dqn.loss, dqn.pretrain_steps, dqn.gamma), (LossKind::Dqn, 0, 0.95));
        let net = DqnOverrides {
            net: Some(NetKind::Paper),
            loss: Some(LossKind::Dqfd),
            ..DqnOverrides::default()
        };
        assert_eq!(resolved(net), preset(Preset::PaperDqfd));
    }

    #[test]
    fn explicit_settings_beat_the_preset() {
        let c = DqnConfig::resolve(&DqnOverrides {
            preset: Some(Preset::DqfdPlanes),
            blocks: Some(2),
            obs: Some(ObsKind::PaperScreen),
            lr: Some(5e-4),
            demos: Some(DemoSource::None),
            loss: Some(LossKind::Dqn),
            hidden: Some(64),
            seed: Some(7),
            backend: Some(Backend::Physics),
            goals: Some(vec!["1,0".parse().unwrap()]),
            ..DqnOverrides::default()
        })
        .unwrap();
        // The screen takes the paper network; the learner stays the preset's.
        assert_eq!(
            (c.net.kind, c.net.hidden, c.obs()),
            (NetKind::Paper, 64, ObsKind::PaperScreen)
        );
        assert_eq!((c.lr, c.lr_final), (5e-4, 5e-5));
        assert_eq!((c.demos.clone(), c.pretrain_steps), (DemoSource::None, 0));
        assert_eq!((c.seed, c.world.backend, c.goals.len()), (7, Backend::Physics, 1));
        assert!(c.correct_loops && c.double);
        for (bad, says) in [
            (
                DqnOverrides {
                    obs: Some(ObsKind::RolePlanes),
                    net: Some(NetKind::Paper),
                    ..DqnOverrides::default()
                },
                "reads paper-screen",
            ),
            (
                DqnOverrides {
                    obs: Some(ObsKind::Planes),
                    ..DqnOverrides::default()
                },
                "called role-planes now",
            ),
            (
                DqnOverrides {
                    pretrain: Some(5),
                    demos: Some(DemoSource::None),
                    ..DqnOverrides::default()
                },
                "pre-training needs demonstrations",
            ),
        ] {
            let e = DqnConfig::resolve(&bad).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        }
    }

    #[test]
    fn the_general_preset_resolves_to_the_relational_policy_with_the_settings_it_takes() {
        let general = |o: DqnOverrides| {
            Recipe::resolve(&DqnOverrides {
                preset: Some(Preset::General),
                ..o
            })
        };
        assert_eq!(
            general(DqnOverrides::default()).unwrap(),
            Recipe::Relational(RelationalConfig::general())
        );
        let Recipe::Relational(c) = general(DqnOverrides {
            blocks: Some(4),
            steps: Some(20),
            lr: Some(6e-3),
            seed: Some(9),
            view: Some(View::Side),
            ..DqnOverrides::default()
        })
        .unwrap() else {
            panic!("not the relational policy")
        };
        assert_eq!((c.max_blocks, c.steps, c.seed), (4, 20, 9));
        assert!((c.lr_final - 6e-4).abs() < 1e-12, "{}", c.lr_final);
        for (bad, setting) in [
            (
                DqnOverrides {
                    gamma: Some(0.9),
                    ..DqnOverrides::default()
                },
                "gamma",
            ),
            (
                DqnOverrides {
                    demos: Some(DemoSource::File("d.jsonl".into())),
                    ..DqnOverrides::default()
                },
                "demos_file",
            ),
            (
                DqnOverrides {
                    view: Some(View::Top),
                    ..DqnOverrides::default()
                },
                "view",
            ),
        ] {
            match general(bad) {
                Err(NeuralError::NotForGeneral { setting: s }) => assert_eq!(s, setting),
                other => panic!("{other:?}"),
            }
        }
        assert!(
            general(DqnOverrides {
                blocks: Some(65),
                ..DqnOverrides::default()
            })
            .is_err()
        );
        // A network's run is the network resolver's; the side view is not a network's.
        assert_eq!(
            Recipe::resolve(&DqnOverrides::default()).unwrap(),
            Recipe::Network(Box::new(DqnConfig::preset(Preset::DqnPlanes, 3).unwrap()))
        );
        let side = DqnOverrides {
            view: Some(View::Side),
            ..DqnOverrides::default()
        };
        assert!(
            Recipe::resolve(&side)
                .unwrap_err()
                .to_string()
                .contains("top view only")
        );
        assert!(DqnConfig::preset(Preset::General, 3).is_err());
    }

    #[test]
    fn sizes_that_cannot_be_allocated_are_refused_up_front() {
        let base = || DqnConfig::preset(Preset::DqnPlanes, 3).unwrap();
        let refused = |c: DqnConfig, words: &str| {
            let e = c.validate().unwrap_err().to_string();
            assert!(e.contains(words), "{e}");
        };
        refused(
            DqnConfig {
                batch: 1_000_000_000_000,
                ..base()
            },
            "--batch 1000000000000",
        );
        refused(
            DqnConfig {
                batch: 1_000_000,
                buffer: 1_000_000,
                ..base()
            },
            "--batch 1000000",
        );
        refused(
            DqnConfig {
                batch: 2_000,
                buffer: 1_000,
                ..base()
            },
            "larger than the buffer",
        );
        refused(
            DqnConfig {
                demos: DemoSource::Exact(1_000_000_000),
                ..base()
            },
            "--demos exact:1000000000",
        );
        refused(
            DqnConfig {
                buffer: usize::MAX,
                steps: u64::MAX,
                ..base()
            },
            "--buffer",
        );
        // A large buffer is fine when the run is too short to fill it.
        DqnConfig {
            buffer: usize::MAX,
            ..base()
        }
        .validate()
        .unwrap();
    }
}
