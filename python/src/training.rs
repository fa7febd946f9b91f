//! The tabular trainer in-process: one training run (and an optional evaluation) from the
//! flags of `blockstack train`, for Python and the Ray sweep.

use std::path::PathBuf;
use std::time::Instant;

use agent::eval::{EvalOverrides, EvalReport};
use agent::{Assist, TrainConfig, TrainHooks, TrainOverrides, Trainer};
use files::OutputPath;
use neural::AnyModel;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{Backend, Goal, RewardModel, View};

use crate::boundary::{OrValueError, guard, raise_signal, signal_checker, value_error};
use crate::config;

/// Training hooks, of the tabular trainer and the network's alike, that stop the run when
/// Ctrl-C is seen ([`signal_checker`]) and write its checkpoint every `every` games or steps
/// and after the last, when it has one.
pub(crate) struct Interruptible<'a, F> {
    /// The signal check, called after every game or step.
    pub check: F,
    /// Where the checkpoint goes, if the run has one.
    pub checkpoint: Option<&'a OutputPath>,
    /// Games or steps between two checkpoints.
    pub every: u64,
}

impl<F: FnMut() -> agent::Result<()>> TrainHooks for Interruptible<'_, F> {
    fn after_game(&mut self, _: &agent::Progress) -> agent::Result<()> {
        (self.check)()
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

impl<F: FnMut() -> agent::Result<()>> neural::TrainHooks for Interruptible<'_, F> {
    fn after_step(&mut self, _: &neural::Progress) -> neural::Result<()> {
        Ok((self.check)()?)
    }

    fn checkpoint_every(&self) -> Option<u64> {
        self.checkpoint.map(|_| self.every)
    }

    fn checkpoint(&mut self, trainer: &neural::Trainer) -> neural::Result<()> {
        match self.checkpoint {
            Some(out) => trainer.write_checkpoint(out),
            None => Ok(()),
        }
    }
}

/// A setting given by name (`None` keeps the profile's and preset's).
fn named<T: std::str::FromStr>(name: Option<&str>) -> PyResult<Option<T>>
where
    T::Err: std::fmt::Display,
{
    name.map(str::parse::<T>).transpose().or_value_error()
}

/// Trains a tabular Q-learner as `blockstack train` does: the same settings, resolved by the
/// same library call (`agent::TrainConfig::resolve`: the profile, then the preset, then each
/// setting given), so the same arguments give the same model file, byte for byte. In this
/// process, the GIL released. With `eval_episodes > 0`, then plays it `eval_episodes` times
/// on each of `eval_goals` (the training goals by default) from the starts `blockstack eval
/// --seed EVAL_SEED` plays, as `eval` does. `out` saves the model file (its folder is
/// checked before training).
///
/// With `check=True` it trains nothing: the settings are resolved and checked, and the dict
/// holds `describe` alone (what the Ray sweep calls for every run before Ray starts).
///
/// Returns a dict: the config's settings, the training totals (`games`, `successes`,
/// `steps`, `assisted_steps`, `replay_sweeps`, `train_seconds`) and, with an evaluation,
/// `eval_episodes`, `eval_failures`, `eval_mean_steps`, `eval_median_steps`,
/// `eval_mean_steps_failures_as_horizon`, `eval_mean_optimal_steps`,
/// `eval_mean_ratio_to_optimum` (`None` where no episode reached the goal).
///
/// `checkpoint` writes the run there every `checkpoint_every` games (1000 by default) and
/// after the last, as `blockstack train --checkpoint` does; if the file already holds a
/// checkpoint of this very run (the same settings), training continues from it (as `train
/// --resume` would) and ends with the same model, byte for byte, as a run that never
/// stopped; a checkpoint of another run is a `ValueError`. The dict's `resumed_at` is the
/// games the run had played when this call took it up (0 for a new run).
#[pyfunction]
#[pyo3(signature = (*, blocks=3, grid=None, profile=None, preset=None, protocol=None, start=None, repr=None, reward=None, schedule=None, oracle=None, oscillation=None, goals=None, games=None, seed=1, alpha=None, gamma=None, epsilon=None, initial_q=None, exploring_starts=false, backward_replay=None, final_replay=None, assist="none", horizon=None, backend="physics", view="top", eval_episodes=0, eval_goals=None, eval_seed=2, eval_epsilon=0.1, out=None, checkpoint=None, checkpoint_every=None, check=false))]
#[allow(clippy::too_many_arguments)]
pub fn train<'py>(
    py: Python<'py>,
    blocks: usize,
    grid: Option<&Bound<'py, PyAny>>,
    profile: Option<&str>,
    preset: Option<&str>,
    protocol: Option<&str>,
    start: Option<&str>,
    repr: Option<&str>,
    reward: Option<&str>,
    schedule: Option<&str>,
    oracle: Option<&str>,
    oscillation: Option<&str>,
    goals: Option<&str>,
    games: Option<u64>,
    seed: u64,
    alpha: Option<f64>,
    gamma: Option<f64>,
    epsilon: Option<f64>,
    initial_q: Option<f64>,
    exploring_starts: bool,
    backward_replay: Option<bool>,
    final_replay: Option<bool>,
    assist: &str,
    horizon: Option<u32>,
    backend: &str,
    view: &str,
    eval_episodes: u64,
    eval_goals: Option<&str>,
    eval_seed: u64,
    eval_epsilon: f64,
    out: Option<PathBuf>,
    checkpoint: Option<PathBuf>,
    checkpoint_every: Option<u64>,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let outputs = run_outputs(out, checkpoint, checkpoint_every, agent::checkpoint::DEFAULT_EVERY)?;
    let overrides = TrainOverrides {
        profile: named(profile)?,
        preset: named(preset)?,
        blocks: Some(blocks),
        grid: grid.map(config::grid_from).transpose()?,
        goals: goals
            .map(|text| Goal::parse_list(text, blocks))
            .transpose()
            .or_value_error()?,
        protocol: named(protocol)?,
        start: named(start)?,
        repr: named(repr)?,
        reward: reward.map(RewardModel::from_name).transpose().or_value_error()?,
        schedule: named(schedule)?,
        oracle: named(oracle)?,
        oscillation: named(oscillation)?,
        games,
        seed: Some(seed),
        alpha,
        gamma,
        epsilon,
        initial_q,
        exploring_starts: Some(exploring_starts),
        backward_replay,
        final_replay,
        assist: named::<Assist>(Some(assist))?,
        horizon,
        backend: named::<Backend>(Some(backend))?,
        view: named::<View>(Some(view))?,
    };
    let config = TrainConfig::resolve(&overrides).or_value_error()?;
    let eval_goals = match eval_goals {
        Some(text) => Goal::parse_list(text, blocks).or_value_error()?,
        None => config.goals.clone(),
    };
    if check {
        let d = PyDict::new(py);
        let describe = format!(
            "a {} Q-learner on {} blocks, {} games, seed {}",
            config.repr.name(),
            config.world.blocks,
            config.games,
            config.seed
        );
        d.set_item("describe", describe)?;
        return Ok(d);
    }
    let eval = EvalOverrides {
        goals: Some(eval_goals),
        episodes: eval_episodes,
        seed: eval_seed,
        backend: Some(config.world.backend),
        ..EvalOverrides::default()
    };
    let (trained, seconds, evaluation, resumed_at) =
        py.detach(|| guard(|| run_tabular(&config, &outputs, &eval, eval_epsilon)))?;
    tabular_dict(py, &config, &trained, seconds, resumed_at, evaluation)
}

/// What a tabular run gives back: the trained agent and its totals, the seconds it took,
/// its evaluation, and the games it had played when it was taken up from its checkpoint.
type TabularRun = (agent::Trained, f64, Option<EvalReport>, u64);

/// The tabular run of `config`: trained (from the checkpoint, if it holds this run), then
/// evaluated as `eval` plans (no episodes, no evaluation) and saved.
fn run_tabular(config: &TrainConfig, outputs: &RunOutputs, eval: &EvalOverrides, epsilon: f64) -> PyResult<TabularRun> {
    let clock = Instant::now();
    let mut trainer = match &outputs.checkpoint {
        Some((path, _)) if path.exists() => Trainer::resume_run(path, config).or_value_error()?,
        _ => Trainer::new(config.clone()).or_value_error()?,
    };
    let resumed_at = trainer.report().games;
    // The run's one loop (`Trainer::run_until`), with Ctrl-C looked for every 100 ms
    // (the GIL taken back only for that): it stops a long run with KeyboardInterrupt.
    let mut signal = None;
    let ran = trainer.run_until(
        config.games,
        &mut Interruptible {
            check: signal_checker(&mut signal),
            checkpoint: outputs.checkpoint.as_ref().map(|(_, out)| out),
            every: outputs.every,
        },
    );
    ran.map_err(|e| raise_signal(signal, e))?;
    let trained = trainer.finish();
    let seconds = clock.elapsed().as_secs_f64();
    // Evaluated as `blockstack eval` and `Model.evaluate` evaluate a model file (the
    // one plan builder, `AnyModel::eval_plan_with`): in the training world, on its
    // backend, games ending at the goal within the paper's 1000 steps.
    let model = AnyModel::Q(Box::new(trained.agent));
    let evaluation = if eval.episodes > 0 {
        let plan = model.eval_plan_with(eval).or_value_error()?;
        let mut signal = None;
        let evaluated = model.evaluate(&plan, "", epsilon, &mut signal_checker(&mut signal));
        Some(evaluated.map_err(|e| raise_signal(signal, e))?.report)
    } else {
        None
    };
    let AnyModel::Q(agent) = model else {
        unreachable!("made a tabular model above")
    };
    if let Some(out) = &outputs.out {
        let bytes = agent.to_bytes().map_err(value_error)?;
        out.write(&bytes).or_value_error()?;
    }
    let trained = agent::Trained {
        agent: *agent,
        report: trained.report,
    };
    Ok((trained, seconds, evaluation, resumed_at))
}

/// A tabular run's dict (`train`'s docs).
fn tabular_dict<'py>(
    py: Python<'py>,
    config: &TrainConfig,
    trained: &agent::Trained,
    seconds: f64,
    resumed_at: u64,
    evaluation: Option<EvalReport>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("profile", config.profile.to_string())?;
    d.set_item("blocks", config.world.blocks)?;
    d.set_item("grid", config.world.grid.to_string())?;
    d.set_item("repr", config.repr.name())?;
    d.set_item("reward", config.world.reward.to_string())?;
    d.set_item(
        "goals",
        config.goals.iter().map(Goal::to_string).collect::<Vec<_>>().join(":"),
    )?;
    d.set_item("seed", config.seed)?;
    d.set_item("alpha", config.params.alpha)?;
    d.set_item("gamma", config.params.gamma)?;
    d.set_item("epsilon", config.params.epsilon)?;
    d.set_item("initial_q", config.params.initial_q)?;
    d.set_item("assist", config.assist.to_string())?;
    d.set_item("backend", config.world.backend.to_string())?;
    d.set_item("view", config.world.view.to_string())?;
    let r = trained.report;
    d.set_item("games", r.games)?;
    d.set_item("successes", r.successes)?;
    d.set_item("steps", r.steps)?;
    d.set_item("assisted_steps", r.assisted_steps)?;
    d.set_item("replay_sweeps", r.replay_sweeps)?;
    d.set_item("train_seconds", seconds)?;
    d.set_item("resumed_at", resumed_at)?;
    if let Some(e) = evaluation {
        eval_items(&d, &e)?;
    }
    Ok(d)
}

/// A run's files, checked before any work (as the CLI checks them: a missing folder must not
/// cost a training run): the model file `out`, the checkpoint file (not `out`) and the steps
/// or games between two checkpoints.
pub(crate) struct RunOutputs {
    /// Where the model goes, if anywhere.
    pub out: Option<files::OutputPath>,
    /// The checkpoint file as given, and as an output.
    pub checkpoint: Option<(PathBuf, files::OutputPath)>,
    /// Steps or games between two checkpoints.
    pub every: u64,
}

/// [`RunOutputs`] of `out`, `checkpoint` and `checkpoint_every` (`default` unless given); a
/// `ValueError` for a file that cannot be written, one file named twice, `checkpoint_every`
/// without a checkpoint, or 0.
pub(crate) fn run_outputs(
    out: Option<PathBuf>,
    checkpoint: Option<PathBuf>,
    checkpoint_every: Option<u64>,
    default: u64,
) -> PyResult<RunOutputs> {
    let out = out.map(files::OutputPath::check).transpose().or_value_error()?;
    let checkpoint = checkpoint
        .map(|path| files::OutputPath::check(&path).map(|output| (path, output)))
        .transpose()
        .or_value_error()?;
    if let (Some(out), Some((path, _))) = (&out, &checkpoint) {
        files::refuse_same_file(out.path(), path).or_value_error()?;
    }
    let every = match (checkpoint_every, &checkpoint) {
        (Some(0), _) => return Err(value_error("checkpoint_every must be at least 1")),
        (Some(_), None) => return Err(value_error("checkpoint_every needs checkpoint")),
        (every, _) => every.unwrap_or(default),
    };
    Ok(RunOutputs { out, checkpoint, every })
}

/// The evaluation's figures into a run's dict: `eval_episodes`, `eval_failures`,
/// `eval_mean_steps`, `eval_median_steps`, `eval_mean_steps_failures_as_horizon`,
/// `eval_mean_optimal_steps`, `eval_mean_ratio_to_optimum`.
pub(crate) fn eval_items(d: &Bound<'_, PyDict>, e: &EvalReport) -> PyResult<()> {
    let (summary, o) = (e.run.summary, e.optimality);
    d.set_item("eval_episodes", summary.episodes)?;
    d.set_item("eval_failures", summary.failures)?;
    d.set_item("eval_mean_steps", summary.mean_steps)?;
    d.set_item("eval_median_steps", summary.median_steps)?;
    d.set_item(
        "eval_mean_steps_failures_as_horizon",
        e.run.mean_steps_failures_as_horizon,
    )?;
    d.set_item("eval_mean_optimal_steps", o.mean_optimal_steps)?;
    d.set_item("eval_mean_ratio_to_optimum", o.mean_ratio_to_optimum)
}
