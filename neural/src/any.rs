//! A model file of any kind (tabular, network, relational), loaded and played through one type.
//!
//! `blockstack train` writes tabular Q-agents ([`agent::QAgent`]), `blockstack dqn` writes
//! networks ([`Dqn`]) and, with `--preset general`, relational policies
//! ([`RelationalModel`]); all are safetensors containers whose header names their format.
//! [`AnyModel::load`] reads the header and the file with the reader of its kind, so that
//! `blockstack eval`, `blockstack run --model`, Python's `blockstack.load` and the
//! experiments all load, describe and play a model the same way. It lives in `neural`
//! because `neural` is the lowest crate that knows every kind.
//!
//! # The default-play rule
//!
//! A loaded model knows how it plays when nothing says otherwise, and every front end
//! (`run`, `eval`, Python's `Model`, `serve`'s worlds) asks it rather than keeping a rule of
//! its own:
//!
//! - its **epsilon** ([`AnyModel::default_epsilon`]): the test policy of its profile (the
//!   paper's 0.1) for a Q-agent or a network; 0 (greedy) for a relational policy, which is
//!   measured greedy;
//! - its **world** ([`AnyModel::world`]): the one it trained in, with games of at most 1000
//!   steps ending at the goal;
//! - its **reward** and rules ([`AnyModel::parts`]): its training world's reward, action
//!   protocol and start rule (a tabular model's file that does not say: its profile's).

use std::path::Path;

use agent::eval::{EvalOverrides, EvalPlan, Evaluation};
use agent::{AgentError, PlayingModel, Policy, PolicyKind, QAgent};
use oracle::ExactSolver;
use sim::{Action, Backend, EnvConfig, Goal, GoalSpec, Grid, Observation, Profile, ProfileParts, RewardModel, View};

use crate::error::Result;
use crate::model::{Dqn, FORMAT, MAX_NETWORK_BYTES};
use crate::relational::RelationalModel;

/// A trained agent read from a model file.
pub enum AnyModel {
    /// A tabular Q-agent (`blockstack train`).
    Q(Box<QAgent>),
    /// A network (`blockstack dqn`).
    Dqn(Box<Dqn>),
    /// A relational policy (`blockstack dqn --preset general`): block moves in the side
    /// view, at any number of blocks.
    Relational(Box<RelationalModel>),
}

/// The world a relational policy is shown in when nothing says otherwise: the side view of
/// the most blocks it trained on, on the side view's default grid for them
/// ([`Grid::side_default`]).
fn relational_world(model: &RelationalModel) -> EnvConfig {
    let blocks = model.config().max_blocks;
    EnvConfig {
        grid: Grid::side_default(blocks),
        blocks,
        view: sim::View::Side,
        reward: RewardModel::from_name("step-cost").expect("a reward model"),
        ..Profile::Spec.world()
    }
}

impl AnyModel {
    /// Reads the model file at `path`, whichever kind it is: the container names its format
    /// in its header; a training checkpoint is refused in its own format's name; anything
    /// else is read as a tabular model (whose reader says what is wrong with a file that is
    /// none). A pipe, socket or device is
    /// refused before it is opened, whoever asks (the command line, Python, `serve`): the
    /// file is read twice (its header says which reader reads it), a pipe's second reading
    /// finds it empty, and opening a pipe with no writer would wait forever.
    pub fn load(path: &Path) -> Result<AnyModel> {
        refuse_special(path)?;
        match files::container::format_of(path, MAX_NETWORK_BYTES) {
            Some(format) if format == FORMAT => Ok(AnyModel::Dqn(Box::new(Dqn::load(path)?))),
            Some(format) if format == crate::relational::model::FORMAT => {
                Ok(AnyModel::Relational(Box::new(RelationalModel::load(path)?)))
            }
            // A run's checkpoint is not a model: say so in its own format's name, not the
            // tabular reader's.
            Some(format)
                if format == crate::checkpoint::CHECKPOINT_FORMAT || format == agent::checkpoint::CHECKPOINT_FORMAT =>
            {
                Err(AgentError::Model {
                    path: path.display().to_string(),
                    reason: format!(
                        "it is a training checkpoint ({format}), not a model: `--resume` continues its run, \
                         which saves its model with --out"
                    ),
                }
                .into())
            }
            _ => Ok(AnyModel::Q(Box::new(QAgent::load(path)?))),
        }
    }

    /// The grid it plays on (a relational policy plays any: the grid of its default world).
    pub fn grid(&self) -> Grid {
        match self {
            AnyModel::Q(q) => q.grid(),
            AnyModel::Dqn(d) => d.grid(),
            AnyModel::Relational(r) => relational_world(r).grid,
        }
    }

    /// The number of blocks it plays with (a relational policy plays any number: the most
    /// it trained on).
    pub fn blocks(&self) -> usize {
        match self {
            AnyModel::Q(q) => q.blocks(),
            AnyModel::Dqn(d) => d.blocks(),
            AnyModel::Relational(r) => r.config().max_blocks,
        }
    }

    /// Its name in reports.
    pub fn name(&self) -> String {
        match self {
            AnyModel::Q(q) => q.name(),
            AnyModel::Dqn(d) => d.name(),
            AnyModel::Relational(r) => r.name(),
        }
    }

    /// The probability of a random legal action it plays with unless told otherwise (the
    /// default-play rule, module docs): 0 for a relational policy, else its profile's test
    /// epsilon.
    pub fn default_epsilon(&self) -> f64 {
        match self {
            // Measured greedy: a random block move only spoils its plan.
            AnyModel::Relational(_) => 0.0,
            AnyModel::Q(_) | AnyModel::Dqn(_) => agent::LearnerProfile::of(self.profile()).test_epsilon,
        }
    }

    /// The profile its world's rules came from: a tabular model's training profile (`spec`
    /// when the file does not say); `spec` for a network (`blockstack dqn` trains there).
    pub fn profile(&self) -> Profile {
        match self {
            AnyModel::Q(q) => q.training().map_or(Profile::Spec, |t| t.profile),
            AnyModel::Dqn(_) | AnyModel::Relational(_) => Profile::Spec,
        }
    }

    /// The profile parts of its training world, as a run starts from them before its own
    /// flags (the default-play rule, module docs): a tabular model's protocol, start rule and
    /// reward under its profile; a network's or relational policy's protocol and reward in
    /// the `spec` profile's world (`blockstack dqn` trains there, from uniform starts).
    pub fn parts(&self) -> ProfileParts {
        let world = self.world();
        match self {
            AnyModel::Q(_) => ProfileParts {
                protocol: world.protocol,
                start: world.start,
                reward: world.reward,
                ..ProfileParts::of(self.profile())
            },
            AnyModel::Dqn(_) | AnyModel::Relational(_) => ProfileParts {
                protocol: world.protocol,
                reward: world.reward,
                ..ProfileParts::of(Profile::Spec)
            },
        }
    }

    /// The world it was trained in, as games are played in to test it: its grid, blocks,
    /// reward, backend, action protocol and start rule, games ending at the goal after at
    /// most 1000 steps (the paper's tests), the goal drawn. A tabular model whose file does
    /// not say plays in its profile's world.
    pub fn world(&self) -> EnvConfig {
        let trained = match self {
            AnyModel::Q(q) => q.training().map_or_else(|| Profile::Spec.world(), |t| t.world.clone()),
            AnyModel::Dqn(d) => d.config().world.clone(),
            AnyModel::Relational(r) => relational_world(r),
        };
        EnvConfig {
            grid: self.grid(),
            blocks: self.blocks(),
            goal: GoalSpec::Random,
            horizon: sim::DEFAULT_HORIZON,
            termination: sim::Termination::Goal,
            ..trained
        }
    }

    /// The evaluation `overrides` describe in the model's own world ([`AnyModel::world`]):
    /// its size and view (another is refused), its rules and reward ([`AnyModel::parts`])
    /// under the profile, rules and reward named,
    /// games of at most 1000 steps on the physics backend unless named; every goal of its
    /// world unless goals are named. `blockstack eval`, Python's `Model.evaluate` and
    /// `blockstack.train(eval_episodes=...)` all plan their evaluation here.
    pub fn eval_plan_with(&self, o: &EvalOverrides) -> Result<EvalPlan> {
        let own = self.world();
        self.check_world(o.grid.unwrap_or(own.grid), o.blocks.unwrap_or(own.blocks))?;
        self.check_view(o.view.unwrap_or(own.view))?;
        let goals = match &o.goals {
            Some(goals) => goals.clone(),
            None => Goal::all_in(own.view, own.blocks)?,
        };
        let rules = self.parts().overridden(o.profile, o.protocol, o.start, o.reward);
        let world = EnvConfig {
            horizon: o.horizon.unwrap_or(sim::DEFAULT_HORIZON),
            backend: o.backend.unwrap_or(Backend::Physics),
            ..rules.apply(own)
        };
        world.validate()?;
        Ok(EvalPlan {
            world,
            profile: rules.profile,
            goals,
            episodes: o.episodes,
            seed: o.seed,
        })
    }

    /// An error unless a world of `blocks` blocks on `grid` is the model's (a relational
    /// policy plays any, of at least one block).
    pub fn check_world(&self, grid: Grid, blocks: usize) -> Result<()> {
        match self {
            AnyModel::Q(q) => q.check_world(grid, blocks)?,
            AnyModel::Dqn(d) => d.check_world(grid, blocks)?,
            AnyModel::Relational(_) if blocks == 0 => {
                return Err(crate::NeuralError::Mismatch(
                    "the relational policy plays worlds of at least 1 block".into(),
                ));
            }
            AnyModel::Relational(_) => {}
        }
        Ok(())
    }

    /// An error unless `view` is the one the model learnt: a model plays its own view.
    pub fn check_view(&self, view: View) -> Result<()> {
        let own = self.world().view;
        if view == own {
            return Ok(());
        }
        Err(AgentError::ModelMismatch(format!(
            "the model learnt the {own} view; it cannot play the {view} view"
        ))
        .into())
    }

    /// The Q-value of every action legal in `obs`, in action-index order: a tabular
    /// model's table row, a network's forward pass (its output columns mapped back to
    /// actions). What a person watching the model is shown beside its greedy choice.
    pub fn legal_q_values(&self, obs: &Observation) -> Result<Vec<(Action, f32)>> {
        let legal = obs.legal_actions();
        let by_action = match self {
            AnyModel::Relational(_) => {
                return Err(crate::NeuralError::Mismatch(
                    "the relational policy scores block moves, not gripper actions".into(),
                ));
            }
            AnyModel::Q(q) => q.q_values(obs)?,
            AnyModel::Dqn(d) => {
                let by_column = d.q_values(obs)?;
                let input = d.net().input();
                let mut by_action = vec![0.0; by_column.len()];
                for (column, &v) in by_column.iter().enumerate() {
                    by_action[input.action(&obs.goal, column).index()] = v;
                }
                by_action
            }
        };
        Ok(legal.iter().map(|a| (a, by_action[a.index()])).collect())
    }

    /// The model playing with a random legal action with probability `epsilon`.
    pub fn policy(&self, epsilon: f64) -> Result<Box<dyn Policy + '_>> {
        Ok(match self {
            AnyModel::Q(q) => Box::new(q.policy(epsilon)?),
            AnyModel::Dqn(d) => Box::new(d.policy(epsilon)?),
            AnyModel::Relational(r) => Box::new(r.policy(epsilon)?),
        })
    }

    /// Evaluates the model on `plan` ([`agent::eval::evaluate`]) with the exact solver of the
    /// plan's world (protocol and view), `model` naming where it came from; `tick` after every episode
    /// played and every start solved.
    pub fn evaluate(
        &self,
        plan: &EvalPlan,
        model: &str,
        epsilon: f64,
        tick: &mut dyn FnMut() -> agent::Result<()>,
    ) -> Result<Evaluation> {
        let solver = ExactSolver::for_world(&plan.world);
        self.evaluate_with(plan, model, epsilon, &solver, tick)
    }

    /// [`AnyModel::evaluate`] with a solver of the caller's (a node budget of its own).
    pub fn evaluate_with(
        &self,
        plan: &EvalPlan,
        model: &str,
        epsilon: f64,
        solver: &ExactSolver,
        tick: &mut dyn FnMut() -> agent::Result<()>,
    ) -> Result<Evaluation> {
        self.check_world(plan.world.grid, plan.world.blocks)?;
        Ok(agent::eval::evaluate(
            plan,
            self.name(),
            model.to_string(),
            epsilon,
            solver,
            &mut || Ok(self.policy(epsilon)?),
            tick,
        )?)
    }
}

/// An error if `path` is a pipe, a socket or a device ([`AnyModel::load`]).
fn refuse_special(path: &Path) -> Result<()> {
    use std::os::unix::fs::FileTypeExt;
    // `metadata` does not open the file, so it does not wait for a pipe's writer.
    let Ok(meta) = std::fs::metadata(path) else {
        return Ok(());
    };
    let kind = meta.file_type();
    if kind.is_fifo() || kind.is_socket() || kind.is_char_device() || kind.is_block_device() {
        return Err(AgentError::Model {
            path: path.display().to_string(),
            reason:
                "a pipe or a device is not supported as a model file (it is read twice); save the model to a file first"
                    .into(),
        }
        .into());
    }
    Ok(())
}

impl PlayingModel for AnyModel {
    fn kind(&self) -> PolicyKind {
        match self {
            AnyModel::Q(_) => PolicyKind::Q,
            AnyModel::Dqn(_) => PolicyKind::Dqn,
            AnyModel::Relational(_) => PolicyKind::Relational,
        }
    }

    fn model_name(&self) -> String {
        self.name()
    }

    fn playing(&self, epsilon: f64) -> agent::Result<Box<dyn Policy + '_>> {
        self.policy(epsilon).map_err(|e| match e {
            crate::NeuralError::Agent(e) => e,
            // The same words: a network's settings are checked as a table's are.
            crate::NeuralError::Config(reason) => AgentError::Config(reason),
            e => AgentError::ModelMismatch(e.to_string()),
        })
    }
}
