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
