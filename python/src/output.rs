//! Output files from Python, through `files`, the one output helper: destinations checked
//! before work starts, regular files replaced atomically, devices and `-` written directly.

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::boundary::OrValueError;

/// Checks that `path` can be written (its folder exists and is writable, it is not a
/// folder); a `ValueError` naming the problem otherwise. Call it before long work whose
/// result goes there.
#[pyfunction]
pub fn check_output(path: PathBuf) -> PyResult<()> {
    files::OutputPath::check(path).or_value_error().map(|_| ())
}

/// Writes `contents` as the whole of `path` (atomically for a regular file; `-` is standard
/// output).
#[pyfunction]
pub fn write_output(py: Python<'_>, path: PathBuf, contents: Vec<u8>) -> PyResult<()> {
    py.detach(|| files::write(path, &contents).or_value_error())
}

/// The most a sweep's config file may be: a study file's order of size (a sweep of the most
/// combinations it allows is a few kilobytes).
const MAX_CONFIG_BYTES: u64 = 2 << 20;

/// The most a file a sweep's run reads (a recording of demonstrations) may be.
const MAX_RUN_INPUT_BYTES: u64 = agent::demos::MAX_RECORDING_BYTES;

/// The bytes of a sweep's config file, read through `files::open_bounded`: a pipe, a device
/// or a file over 2 MiB is a `ValueError` at once, never read until memory runs out.
#[pyfunction]
pub fn read_config_file(py: Python<'_>, path: PathBuf) -> PyResult<Vec<u8>> {
    py.detach(|| {
        use std::io::Read;
        let mut bytes = Vec::new();
        let mut reader = files::open_bounded(&path, MAX_CONFIG_BYTES, "a sweep config").or_value_error()?;
        reader
            .read_to_end(&mut bytes)
            .map_err(|e| files::FilesError::read(&path.display().to_string(), files::ReadProblem::Io(e.to_string())))
            .or_value_error()?;
        Ok(bytes)
    })
}

/// The SHA-256 of a file a run reads, as hex (`files::digest_file`): part of a sweep run's
/// key, so that a changed file is a new run.
#[pyfunction]
pub fn file_digest(py: Python<'_>, path: PathBuf) -> PyResult<String> {
    py.detach(|| files::digest_file(&path, MAX_RUN_INPUT_BYTES, "a file a run reads").or_value_error())
}

/// Makes the folder `path` if it is missing and checks that it can be written; a
/// `ValueError` naming the problem otherwise (a report's folder, before the run).
#[pyfunction]
pub fn check_folder(path: PathBuf) -> PyResult<()> {
    files::prepare_folder(path).or_value_error()
}

/// A bar from Python: its name, its value, and an interval `(low, high)` or `None`.
type PyBar = (String, f64, Option<(f64, f64)>);

/// Draws a bar chart with the `plots` crate (the reproduction's charts' look) and writes
/// `<stem>.png` and `<stem>.svg`; returns their paths. `bars` holds `(name, value,
/// (low, high) or None)`; `interval_label` names the intervals in the legend.
#[pyfunction]
#[pyo3(signature = (stem, *, title, y_label, bars, value_label, interval_label="", note=""))]
#[allow(clippy::too_many_arguments)]
pub fn bar_chart(
    py: Python<'_>,
    stem: PathBuf,
    title: String,
    y_label: String,
    bars: Vec<PyBar>,
    value_label: String,
    interval_label: &str,
    note: &str,
) -> PyResult<Vec<PathBuf>> {
    let chart = plots::BarChart {
        title,
        y_label,
        bars: bars
            .into_iter()
            .map(|(name, value, interval)| plots::Bar {
                name,
                value,
                interval,
                second: None,
            })
            .collect(),
        value_label,
        interval_label: interval_label.into(),
        second_label: String::new(),
        reference: None,
        log_scale: false,
        note: note.into(),
    };
    py.detach(|| {
        crate::boundary::guard(|| {
            let files = plots::bar_chart(&chart, &stem).or_value_error()?;
            Ok(vec![files.png, files.svg])
        })
    })
}
