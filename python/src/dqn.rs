//! The network trainer in-process: one run of `blockstack dqn` from its flags, for Python.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

use agent::eval::EvalOverrides;
use neural::relational::{RelationalConfig, RelationalModel};
use neural::{AnyModel, DemoSource, DqnConfig, DqnOverrides, Recipe, Trainer};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{Goal, RewardModel};

use crate::boundary::{OrValueError, guard, raise_signal, signal_checker};
use crate::config;
use crate::training::{Interruptible, RunOutputs, eval_items, run_outputs};

/// A setting given by name (`None` keeps the preset's).
fn named<T: std::str::FromStr>(name: Option<&str>) -> PyResult<Option<T>>
where
    T::Err: std::fmt::Display,
{
    name.map(str::parse::<T>).transpose().or_value_error()
}

/// Trains a deep Q-network as `blockstack dqn` does: the same settings, resolved by the same
/// library call (`neural::DqnConfig::resolve`: the preset, then each setting given), so the
/// same arguments give the same network file, byte for byte. In this process, the GIL
/// released; Ctrl-C stops it with `KeyboardInterrupt`. `demos` names a planner's
/// demonstrations (`exact:K`, `oracle:K` or `none`), `demos_file` a recording. `out` saves
/// the network file (its folder is checked before training); `blockstack.load(out)` plays
/// and evaluates it.
///
/// With `eval_episodes > 0`, it then plays the network that many times on each of
/// `eval_goals` (the training goals by default) in its training world, games of up to 1000
/// steps, from the starts `blockstack eval --seed EVAL_SEED` plays, as `blockstack.train`
/// evaluates a tabular agent.
///
/// `checkpoint` writes the run there every `checkpoint_every` steps (pre-training gradient
/// steps, then self-play steps; 10,000 by default) and at its end, the file `blockstack dqn
/// --checkpoint` writes; if the file already holds a checkpoint of this very run (the same
/// settings), training goes on from it (as `dqn --resume` does) and ends with the network
/// file a run that never stopped writes, byte for byte; a checkpoint of another run is a
/// `ValueError`.
///
/// With `check=True` it trains nothing: the settings are resolved and checked, and the
/// recording `demos_file` names read as the run would read it; the dict holds `describe`
/// alone (what the Ray sweep calls for every run before Ray starts).
///
/// Returns a dict: `describe` (the run in one line, as `blockstack dqn` prints
/// it), `blocks`, `grid`, `goals`, `seed`, the training totals (`demo_episodes`,
/// `demo_transitions`, `pretrain_steps`, `steps`, `games`, `successes`, `corrections`,
/// `relabelled`, `gradient_steps`, `train_seconds`), `resumed_at` (the steps the run had
/// done when this call took it up from its checkpoint; 0 for a new run) and, with an
/// evaluation, `blockstack.train`'s `eval_*` figures.
#[pyfunction]
#[pyo3(signature = (*, preset=None, obs=None, net=None, loss=None, blocks=None, goals=None, grid=None, steps=None, pretrain=None, demos=None, demos_file=None, reward=None, gamma=None, lr=None, lr_final=None, optimizer=None, td_loss=None, buffer=None, batch=None, hidden=None, double=None, mask_noops=None, batch_norm=None, screen=None, margin=None, hindsight=None, demo_share=None, horizon=None, backend=None, protocol=None, view=None, seed=1, eval_episodes=0, eval_goals=None, eval_seed=2, eval_epsilon=0.1, out=None, checkpoint=None, checkpoint_every=None, check=false))]
#[allow(clippy::too_many_arguments)]
pub fn train_dqn<'py>(
    py: Python<'py>,
    preset: Option<&str>,
    obs: Option<&str>,
    net: Option<&str>,
    loss: Option<&str>,
    blocks: Option<usize>,
    goals: Option<&str>,
    grid: Option<&Bound<'py, PyAny>>,
    steps: Option<u64>,
    pretrain: Option<u64>,
    demos: Option<&str>,
    demos_file: Option<PathBuf>,
    reward: Option<&str>,
    gamma: Option<f64>,
    lr: Option<f64>,
    lr_final: Option<f64>,
    optimizer: Option<&str>,
    td_loss: Option<&str>,
    buffer: Option<usize>,
    batch: Option<usize>,
    hidden: Option<usize>,
    double: Option<bool>,
    mask_noops: Option<bool>,
    batch_norm: Option<bool>,
    screen: Option<&str>,
    margin: Option<f64>,
    hindsight: Option<usize>,
    demo_share: Option<f64>,
    horizon: Option<u32>,
    backend: Option<&str>,
    protocol: Option<&str>,
    view: Option<&str>,
    seed: u64,
    eval_episodes: u64,
    eval_goals: Option<&str>,
    eval_seed: u64,
    eval_epsilon: f64,
    out: Option<PathBuf>,
    checkpoint: Option<PathBuf>,
    checkpoint_every: Option<u64>,
    check: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let outputs = run_outputs(out, checkpoint, checkpoint_every, neural::checkpoint::DEFAULT_EVERY)?;
    let demos = demo_source(demos, demos_file, outputs.out.as_ref())?;
    let goal_blocks = blocks.unwrap_or(neural::preset::DEFAULT_BLOCKS);
    let overrides = DqnOverrides {
        preset: named(preset)?,
        obs: named(obs)?,
        net: named(net)?,
        loss: named(loss)?,
        blocks,
        goals: goal_list(goals, goal_blocks)?,
        grid: grid.map(config::grid_from).transpose()?,
        steps,
        pretrain,
        demos,
        reward: reward.map(RewardModel::from_name).transpose().or_value_error()?,
        gamma,
        lr,
        lr_final,
        optimizer: named(optimizer)?,
        td_loss: named(td_loss)?,
        buffer,
        batch,
        hidden,
        double,
        mask_noops,
        batch_norm,
        screen: named(screen)?,
        margin,
        hindsight,
        demo_share,
        horizon,
        backend: named(backend)?,
        protocol: named(protocol)?,
        view: named(view)?,
        seed: Some(seed),
    };
    let eval = Evaluation {
        episodes: eval_episodes,
        goals: goal_list(eval_goals, goal_blocks)?,
        seed: eval_seed,
        epsilon: eval_epsilon,
    };
    let recipe = Recipe::resolve(&overrides).or_value_error()?;
    match recipe {
        _ if check => checked(py, &recipe),
        Recipe::Network(config) => network(py, *config, &outputs, eval),
        Recipe::Relational(_) if outputs.checkpoint.is_some() => Err(crate::boundary::value_error(
            "checkpoint is a network run's: the general preset trains in minutes and writes none",
        )),
        Recipe::Relational(config) => relational(py, &config, outputs.out.as_ref(), &eval),
    }
}

/// The goals `text` lists (`:`-separated), of `blocks` blocks, if given.
fn goal_list(text: Option<&str>, blocks: usize) -> PyResult<Option<Vec<Goal>>> {
    text.map(|text| Goal::parse_list(text, blocks))
        .transpose()
        .or_value_error()
}

/// The demonstrations `demos` (a planner's, by name) or `demos_file` (a recording, not the
/// file `out`) name; a `ValueError` for both.
fn demo_source(
    demos: Option<&str>,
    demos_file: Option<PathBuf>,
    out: Option<&files::OutputPath>,
) -> PyResult<Option<DemoSource>> {
    match (demos, demos_file) {
        (Some(_), Some(_)) => Err(crate::boundary::value_error(
            "demos and demos_file both name demonstrations: give one",
        )),
        (_, Some(path)) => {
            if let Some(out) = out {
                files::refuse_same_file(out.path(), &path).or_value_error()?;
            }
            Ok(Some(DemoSource::File(path.display().to_string())))
        }
        (demos, None) => named(demos),
    }
}

/// A network's run of `config`: trained (from the checkpoint, if it holds this run), saved,
/// evaluated if asked; its dict (`train_dqn`'s docs).
fn network<'py>(
    py: Python<'py>,
    config: DqnConfig,
    outputs: &RunOutputs,
    eval: Evaluation,
) -> PyResult<Bound<'py, PyDict>> {
    let eval = Evaluation {
        goals: Some(eval.goals.clone().unwrap_or_else(|| config.goals.clone())),
        ..eval
    };
    let (report, seconds, resumed_at, evaluation) = py.detach(|| {
        guard(|| {
            let clock = Instant::now();
            let mut trainer = match &outputs.checkpoint {
                Some((path, _)) if path.exists() => Trainer::resume_run(path, &config).or_value_error()?,
                _ => Trainer::new(config.clone()).or_value_error()?,
            };
            let resumed_at = trainer.steps_done();
            run_interruptible(&mut trainer, outputs)?;
            let dqn = trainer.finish().or_value_error()?;
            let seconds = clock.elapsed().as_secs_f64();
            if let Some(out) = &outputs.out {
                dqn.save(out.path()).or_value_error()?;
            }
            let report = *dqn.report();
            let evaluation = evaluate(&AnyModel::Dqn(Box::new(dqn)), &eval)?;
            Ok((report, seconds, resumed_at, evaluation))
        })
    })?;
    let d = PyDict::new(py);
    d.set_item("describe", config.describe())?;
    d.set_item("blocks", config.blocks())?;
    d.set_item("grid", config.grid().to_string())?;
    d.set_item(
        "goals",
        config.goals.iter().map(Goal::to_string).collect::<Vec<_>>().join(":"),
    )?;
    d.set_item("seed", config.seed)?;
    d.set_item("demo_episodes", report.demo_episodes)?;
    d.set_item("demo_transitions", report.demo_transitions)?;
    d.set_item("pretrain_steps", report.pretrain_steps)?;
    d.set_item("steps", report.steps)?;
    d.set_item("games", report.games)?;
    d.set_item("successes", report.successes)?;
    d.set_item("corrections", report.corrections)?;
    d.set_item("relabelled", report.relabelled)?;
    d.set_item("gradient_steps", report.gradient_steps)?;
    d.set_item("train_seconds", seconds)?;
    d.set_item("resumed_at", resumed_at)?;
    if let Some(e) = evaluation {
        eval_items(&d, &e)?;
    }
    Ok(d)
}

/// The run's one loop on a thread of rayon's pool, as `blockstack dqn` runs it
/// (`Trainer::run_until_on_pool`: the same steps, so the CLI's network), writing the
/// checkpoint `outputs` names, while this thread looks for Ctrl-C every 100 ms (the GIL
/// taken back only for that; only the main thread sees signals): it stops a long run with
/// `KeyboardInterrupt`.
fn run_interruptible(trainer: &mut Trainer, outputs: &RunOutputs) -> PyResult<()> {
    let mut signal = None;
    let stop = AtomicBool::new(false);
    let total = trainer.total_steps();
    let ran = std::thread::scope(|scope| {
        let (ended, end) = mpsc::channel::<()>();
        let run = scope.spawn(|| {
            // Sends when dropped, even by a panic: the wait below ends either way.
            let _ended = ended;
            trainer.run_until_on_pool(
                total,
                &mut Interruptible {
                    check: || match stop.load(Ordering::Acquire) {
                        true => Err(agent::AgentError::Interrupted),
                        false => Ok(()),
                    },
                    checkpoint: outputs.checkpoint.as_ref().map(|(_, out)| out),
                    every: outputs.every,
                },
            )
        });
        let mut look = signal_checker(&mut signal);
        while let Err(RecvTimeoutError::Timeout) = end.recv_timeout(Duration::from_millis(100)) {
            if look().is_err() {
                stop.store(true, Ordering::Release);
            }
        }
        run.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    });
    ran.map_err(|e| raise_signal(signal, e))
}

/// The evaluation a run asks for after training (`eval_*`).
struct Evaluation {
    /// Episodes per goal; 0 for none.
    episodes: u64,
    /// The goals (default: the model's training goals, or its world's).
    goals: Option<Vec<Goal>>,
    /// Base seed of the starts, as `blockstack eval --seed`.
    seed: u64,
    /// The probability of a random legal action.
    epsilon: f64,
}

/// `model` evaluated as `eval` asks (none for 0 episodes), planned as `blockstack.train`
/// plans its evaluation: in the model's world, on its training backend.
fn evaluate(model: &AnyModel, eval: &Evaluation) -> PyResult<Option<agent::eval::EvalReport>> {
    if eval.episodes == 0 {
        return Ok(None);
    }
    let plan = model
        .eval_plan_with(&EvalOverrides {
            goals: eval.goals.clone(),
            episodes: eval.episodes,
            seed: eval.seed,
            backend: Some(model.world().backend),
            ..EvalOverrides::default()
        })
        .or_value_error()?;
    let mut signal = None;
    let evaluated = model.evaluate(&plan, "", eval.epsilon, &mut signal_checker(&mut signal));
    Ok(Some(evaluated.map_err(|e| raise_signal(signal, e))?.report))
}

/// The `general` preset's run: the relational policy trained ([`RelationalModel::train`],
/// as `blockstack dqn --preset general` trains it), saved to `out`, evaluated if asked. The
/// dict holds `describe` (the model's name), `blocks` (the most of a training problem),
/// `seed`, `iterations`, `steps` (gradient steps in all), the last DAgger iteration's
/// `examples`, `success` and `moves_ratio`, `train_seconds`, `resumed_at` (0) and the
/// `eval_*` figures of an evaluation.
fn relational<'py>(
    py: Python<'py>,
    config: &RelationalConfig,
    out: Option<&files::OutputPath>,
    eval: &Evaluation,
) -> PyResult<Bound<'py, PyDict>> {
    let (model, seconds, evaluation) = py.detach(|| {
        guard(|| {
            let clock = Instant::now();
            let model = RelationalModel::train(config, &mut |_| {}).or_value_error()?;
            let seconds = clock.elapsed().as_secs_f64();
            if let Some(out) = out {
                model.save(out.path()).or_value_error()?;
            }
            let model = AnyModel::Relational(Box::new(model));
            let evaluation = evaluate(&model, eval)?;
            Ok((model, seconds, evaluation))
        })
    })?;
    let d = PyDict::new(py);
    d.set_item("describe", model.name())?;
    d.set_item("blocks", config.max_blocks)?;
    d.set_item("seed", config.seed)?;
    d.set_item("iterations", config.iterations)?;
    d.set_item("steps", config.total_steps())?;
    if let AnyModel::Relational(r) = &model
        && let Some(last) = r.report().last()
    {
        d.set_item("examples", last.examples)?;
        d.set_item("success", last.success)?;
        d.set_item("moves_ratio", last.moves_ratio)?;
    }
    d.set_item("train_seconds", seconds)?;
    d.set_item("resumed_at", 0)?;
    if let Some(e) = evaluation {
        eval_items(&d, &e)?;
    }
    Ok(d)
}

/// `check=True`'s answer: the run described, once its settings resolved (`recipe`) and the
/// recording it would read read, in the run's world.
fn checked<'py>(py: Python<'py>, recipe: &Recipe) -> PyResult<Bound<'py, PyDict>> {
    let describe = match recipe {
        Recipe::Network(config) => {
            if let DemoSource::File(path) = &config.demos {
                let world = agent::demos::RunWorld::of(&config.world);
                py.detach(|| neural::demos::read(std::path::Path::new(path), world))
                    .or_value_error()?;
            }
            config.describe()
        }
        Recipe::Relational(config) => format!(
            "the general preset's relational policy: problems of 2 to {} blocks, seed {}",
            config.max_blocks, config.seed
        ),
    };
    let d = PyDict::new(py);
    d.set_item("describe", describe)?;
    Ok(d)
}
