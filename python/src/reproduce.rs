//! The reproduction from Python (`python -m blockstack.reproduce`): the experiments run
//! here as `blockstack reproduce` runs them, but E8's arms, each a network trained for up
//! to an hour, may be run by a Python callable (the Ray driver sends them to a cluster's
//! nodes, each running [`run_e8_arm`]). Every arm is fixed by its seed, so the report's
//! figures are the same wherever its arms ran.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

use experiments::reproduce::{self as experiments_reproduce, ArmRun, ArmRunner, Options, Report, ReproduceError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::boundary::{OrValueError, guard, value_error};

fn options(seed: u64, quick: bool, long: bool, only: Vec<String>) -> PyResult<Options> {
    if quick && long {
        return Err(value_error("quick and long: choose one budget"));
    }
    Report::Paper.check(&only).or_value_error()?;
    Ok(Options {
        report: Report::Paper,
        seed,
        quick,
        long,
        only,
    })
}

/// The names of E8's arms at this budget, in the order [`run_e8_arm`] numbers them; a
/// `ValueError` for settings a run refuses (`only` naming no experiment of the paper's).
#[pyfunction]
#[pyo3(signature = (*, seed=1, quick=false, long=false, only=Vec::new()))]
pub fn e8_arms(seed: u64, quick: bool, long: bool, only: Vec<String>) -> PyResult<Vec<String>> {
    experiments_reproduce::e8_arm_names(&options(seed, quick, long, only)?).or_value_error()
}

/// The indices of E8's arms (as [`e8_arms`] lists them) in the order to start them: the
/// costliest first, so that on a few CPUs the longest arm is not left to the end.
#[pyfunction]
#[pyo3(signature = (*, seed=1, quick=false, long=false, only=Vec::new()))]
pub fn e8_start_order(seed: u64, quick: bool, long: bool, only: Vec<String>) -> PyResult<Vec<usize>> {
    experiments_reproduce::e8_start_order(&options(seed, quick, long, only)?).or_value_error()
}

/// Trains and tests E8's arm `index` as the reproduction with these settings does, in this
/// process with the GIL released; returns its games as JSON text (for [`reproduce`]'s
/// `e8_runs`). With `checkpoint`, the arm is written there at every point of its learning
/// curve, and goes on from that file if it exists.
#[pyfunction]
#[pyo3(signature = (index, *, seed=1, quick=false, long=false, checkpoint=None))]
pub fn run_e8_arm(
    py: Python<'_>,
    index: usize,
    seed: u64,
    quick: bool,
    long: bool,
    checkpoint: Option<PathBuf>,
) -> PyResult<String> {
    let options = options(seed, quick, long, Vec::new())?;
    py.detach(|| {
        guard(|| {
            let run = experiments_reproduce::run_e8_arm(&options, index, checkpoint.as_deref()).or_value_error()?;
            serde_json::to_string(&run).map_err(value_error)
        })
    })
}

/// E8's arms run by a Python callable: `e8_runs(count)` returns the JSON text of arms
/// `0..count` in order. An exception it raises is kept, to be raised again in place of the
/// reproduction's error.
struct PythonArms {
    e8_runs: Py<PyAny>,
    raised: Mutex<Option<PyErr>>,
}

impl ArmRunner for PythonArms {
    fn run_arms(
        &self,
        start: &[usize],
        _here: &(dyn Fn(usize) -> experiments_reproduce::Result<ArmRun> + Sync),
    ) -> experiments_reproduce::Result<Vec<ArmRun>> {
        // Ray was handed every arm, in this order, when the run began.
        let count = start.len();
        let texts = Python::attach(|py| {
            self.e8_runs
                .call1(py, (count,))
                .and_then(|list| list.extract::<Vec<String>>(py))
        });
        let texts = texts.map_err(|e| {
            let message = e.to_string();
            *self.raised.lock().expect("not poisoned") = Some(e);
            ReproduceError::Arms(message)
        })?;
        if texts.len() != count {
            return Err(ReproduceError::Arms(format!(
                "{} runs came back for {count} arms",
                texts.len()
            )));
        }
        texts
            .iter()
            .map(|t| serde_json::from_str(t).map_err(|e| ReproduceError::Arms(format!("a run does not read: {e}"))))
            .collect()
    }
}

/// Runs the experiments and writes the report into `out`, as `blockstack reproduce` does
/// with the same settings, on `jobs` threads (default: one per core); with `e8_runs`, E8's
/// arms are that callable's (see [`PythonArms`]). The GIL is released but while `e8_runs`
/// runs. Returns a dict: `experiments` (each id with its one-paragraph reading), `seconds`,
/// `threads`, and the files written (`readme`, `results`, `summary`, `pictures`).
#[pyfunction]
#[pyo3(signature = (out, *, seed=1, quick=false, long=false, only=Vec::new(), jobs=None, e8_runs=None))]
#[allow(clippy::too_many_arguments)]
pub fn reproduce<'py>(
    py: Python<'py>,
    out: PathBuf,
    seed: u64,
    quick: bool,
    long: bool,
    only: Vec<String>,
    jobs: Option<usize>,
    e8_runs: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let options = options(seed, quick, long, only)?;
    if jobs == Some(0) {
        return Err(value_error("jobs must be at least 1"));
    }
    // Before minutes of work, not after.
    files::prepare_folder(&out).or_value_error()?;
    let arms = e8_runs.map(|e8_runs| PythonArms {
        e8_runs,
        raised: Mutex::new(None),
    });
    let (results, written, seconds, threads) = py.detach(|| {
        guard(|| {
            let mut pool = rayon::ThreadPoolBuilder::new();
            if let Some(n) = jobs {
                pool = pool.num_threads(n);
            }
            let pool = pool.build().map_err(value_error)?;
            let clock = Instant::now();
            let results = pool.install(|| match &arms {
                Some(arms) => experiments_reproduce::reproduce_on(&options, &(), arms),
                None => experiments_reproduce::reproduce(&options, &()),
            });
            let results = match (
                results,
                arms.as_ref()
                    .and_then(|a| a.raised.lock().expect("not poisoned").take()),
            ) {
                (Err(_), Some(raised)) => return Err(raised),
                (results, _) => results.or_value_error()?,
            };
            let seconds = clock.elapsed().as_secs_f64();
            let ran = experiments_reproduce::Ran::here(pool.current_num_threads());
            let written = experiments_reproduce::write_report(&results, &ran, &out).or_value_error()?;
            Ok((results, written, seconds, pool.current_num_threads()))
        })
    })?;
    let d = PyDict::new(py);
    let readings: Vec<(String, String)> = results
        .experiments
        .iter()
        .map(|e| (e.id.clone(), e.reading.clone()))
        .collect();
    d.set_item("experiments", readings)?;
    d.set_item("seconds", seconds)?;
    d.set_item("threads", threads)?;
    d.set_item("readme", written.readme)?;
    d.set_item("results", written.results)?;
    d.set_item("summary", written.summary)?;
    d.set_item("pictures", written.pictures)?;
    Ok(d)
}
