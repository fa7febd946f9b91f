//! The network trainer in-process: one run of `blockstack dqn` from its flags, for Python.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::{Duration, Instant};

use agent::eval::EvalOverrides;
use neural::{AnyModel, DemoSource, DqnConfig, DqnOverrides, Trainer};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use sim::{Goal, RewardModel};

use crate::boundary::{OrValueError, guard, raise_signal, signal_checker};
use crate::config;
use crate::training::{RunOutputs, eval_items, run_outputs};

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
/// Returns a dict: `describe` (the run in one line, as `blockstack dqn` prints
/// it), `blocks`, `grid`, `goals`, `seed`, the training totals (`demo_episodes`,
/// `demo_transitions`, `pretrain_steps`, `steps`, `games`, `successes`, `corrections`,
/// `relabelled`, `gradient_steps`, `train_seconds`), `resumed_at` (the steps the run had
/// done when this call took it up from its checkpoint; 0 for a new run) and, with an
/// evaluation, `blockstack.train`'s `eval_*` figures.
#[pyfunction]
#[pyo3(signature = (*, preset=None, obs=None, net=None, loss=None, blocks=3, goals=None, grid=None, steps=None, pretrain=None, demos=None, demos_file=None, reward=None, gamma=None, lr=None, lr_final=None, optimizer=None, td_loss=None, buffer=None, batch=None, hidden=None, double=None, mask_noops=None, batch_norm=None, screen=None, margin=None, hindsight=None, demo_share=None, horizon=None, backend=None, protocol=None, seed=1, eval_episodes=0, eval_goals=None, eval_seed=2, eval_epsilon=0.1, out=None, checkpoint=None, checkpoint_every=None))]
#[allow(clippy::too_many_arguments)]
pub fn train_dqn<'py>(
    py: Python<'py>,
    preset: Option<&str>,
    obs: Option<&str>,
    net: Option<&str>,
    loss: Option<&str>,
    blocks: usize,
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
    seed: u64,
    eval_episodes: u64,
    eval_goals: Option<&str>,
    eval_seed: u64,
    eval_epsilon: f64,
    out: Option<PathBuf>,
    checkpoint: Option<PathBuf>,
    checkpoint_every: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    let RunOutputs {
        out: out_path,
        checkpoint,
        every,
    } = run_outputs(out, checkpoint, checkpoint_every, neural::checkpoint::DEFAULT_EVERY)?;
    let demos = match (demos, &demos_file) {
        (Some(_), Some(_)) => {
            return Err(crate::boundary::value_error(
                "demos and demos_file both name demonstrations: give one",
            ));
        }
        (_, Some(path)) => {
            if let Some(out) = &out_path {
                files::refuse_same_file(out.path(), path).or_value_error()?;
            }
            Some(DemoSource::File(path.display().to_string()))
        }
        (demos, None) => named(demos)?,
    };
    let overrides = DqnOverrides {
        preset: named(preset)?,
        obs: named(obs)?,
        net: named(net)?,
        loss: named(loss)?,
        blocks: Some(blocks),
        goals: goals
            .map(|text| Goal::parse_list(text, blocks))
            .transpose()
            .or_value_error()?,
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
        seed: Some(seed),
    };
    let config = DqnConfig::resolve(&overrides).or_value_error()?;
    let eval_goals = match eval_goals {
        Some(text) => Goal::parse_list(text, blocks).or_value_error()?,
        None => config.goals.clone(),
    };
    let (report, seconds, resumed_at, evaluation) = py.detach(|| {
        guard(|| {
            let clock = Instant::now();
            let mut trainer = match &checkpoint {
                Some((path, _)) if path.exists() => Trainer::resume_run(path, &config).or_value_error()?,
                _ => Trainer::new(config.clone()).or_value_error()?,
            };
            let resumed_at = trainer.steps_done();
            // The run's one loop on a thread of rayon's pool, as `blockstack dqn` runs it
            // (`Trainer::run_until_on_pool`: the same steps, so the CLI's network), while this
            // thread looks for Ctrl-C every 100 ms (the GIL taken back only for that; only
            // the main thread sees signals): it stops a long run with KeyboardInterrupt.
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
                        &mut agent::RunHooks {
                            after: |_: &neural::Progress| match stop.load(Ordering::Acquire) {
                                true => Err(agent::AgentError::Interrupted.into()),
                                false => Ok(()),
                            },
                            checkpoints: agent::Checkpoints::to(checkpoint.as_ref().map(|(_, out)| out), every),
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
            ran.map_err(|e| raise_signal(signal, e))?;
            let dqn = trainer.finish().or_value_error()?;
            let seconds = clock.elapsed().as_secs_f64();
            if let Some(out) = &out_path {
                dqn.save(out.path()).or_value_error()?;
            }
            let report = *dqn.report();
            let evaluation = if eval_episodes > 0 {
                let backend = dqn.config().world.backend;
                let model = AnyModel::Dqn(Box::new(dqn));
                // Planned as `blockstack.train` plans its evaluation: on the training backend.
                let plan = model
                    .eval_plan_with(&EvalOverrides {
                        goals: Some(eval_goals),
                        episodes: eval_episodes,
                        seed: eval_seed,
                        backend: Some(backend),
                        ..EvalOverrides::default()
                    })
                    .or_value_error()?;
                let mut signal = None;
                let evaluated = model.evaluate(&plan, "", eval_epsilon, &mut signal_checker(&mut signal));
                Some(evaluated.map_err(|e| raise_signal(signal, e))?.report)
            } else {
                None
            };
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
