//! The boundary with Python: errors become `ValueError` with the Rust message, and a panic
//! is caught before it can unwind into the interpreter.

use std::fmt::Display;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::{Duration, Instant};

use pyo3::PyErr;
use pyo3::exceptions::{PyRuntimeError, PyValueError};

/// A `ValueError` carrying `error`'s message.
pub fn value_error(error: impl Display) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// Runs `f`, turning a panic into a `RuntimeError` that names it as a bug.
pub fn guard<T>(f: impl FnOnce() -> Result<T, PyErr>) -> Result<T, PyErr> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| panic.downcast_ref::<&str>().copied())
            .unwrap_or("no message");
        Err(PyRuntimeError::new_err(format!(
            "blockstack hit an internal error (a bug; please report it): {message}"
        )))
    })
}

/// Shorthand: a crate result as a Python result, its error a `ValueError`.
pub trait OrValueError<T> {
    /// The value, or a `ValueError` with the error's message.
    fn or_value_error(self) -> Result<T, PyErr>;
}

impl<T, E: Display> OrValueError<T> for Result<T, E> {
    fn or_value_error(self) -> Result<T, PyErr> {
        self.map_err(value_error)
    }
}

/// A progress hook for long native calls made with the GIL released: at most every 100 ms
/// it takes the GIL back to look for signals; a pending one (Ctrl-C's `KeyboardInterrupt`)
/// is kept in `signal` and stops the work with [`agent::AgentError::Interrupted`], and
/// [`raise_signal`] then raises it in place of the error.
pub fn signal_checker(signal: &mut Option<PyErr>) -> impl FnMut() -> agent::Result<()> + '_ {
    let mut looked = Instant::now();
    move || {
        if looked.elapsed() < Duration::from_millis(100) {
            return Ok(());
        }
        looked = Instant::now();
        match pyo3::Python::attach(|py| py.check_signals()) {
            Ok(()) => Ok(()),
            Err(e) => {
                *signal = Some(e);
                Err(agent::AgentError::Interrupted)
            }
        }
    }
}

/// The signal [`signal_checker`] kept, if it stopped the work; else `error`'s message as a
/// `ValueError`.
pub fn raise_signal(signal: Option<PyErr>, error: impl Display) -> PyErr {
    signal.unwrap_or_else(|| value_error(error))
}
