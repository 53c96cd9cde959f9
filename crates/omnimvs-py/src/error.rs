//! Library errors as Python exceptions, and the one way long work runs without the GIL.

use std::error::Error;
use std::io::ErrorKind;
use std::panic::{AssertUnwindSafe, catch_unwind};

use omnimvs_data::DataError;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;

/// The Python exception of a library error, with the library's message (which names the
/// file, the field or the argument): `FileNotFoundError` when a file or a frame's image is
/// missing, `OSError` for any other failure to read or write, `ValueError` for the rest
/// (bad configuration, sizes, parameters).
pub fn to_py_err(err: &(dyn Error + 'static)) -> PyErr {
    with_context(String::new(), err)
}

/// As [`to_py_err`], the message prefixed by `context` (e.g. `weights FILE: `).
pub fn with_context(context: String, err: &(dyn Error + 'static)) -> PyErr {
    let message = format!("{context}{err}");
    let mut cause: Option<&(dyn Error + 'static)> = Some(err);
    while let Some(e) = cause {
        if let Some(io) = e.downcast_ref::<std::io::Error>() {
            return match io.kind() {
                ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
                _ => PyOSError::new_err(message),
            };
        }
        if let Some(DataError::MissingFrame { .. }) = e.downcast_ref::<DataError>() {
            return PyFileNotFoundError::new_err(message);
        }
        cause = e.source();
    }
    PyValueError::new_err(message)
}

/// Converts a library `Result` (see [`to_py_err`]).
pub trait IntoPyResult<T> {
    /// # Errors
    /// The Python exception of the library error.
    fn py_err(self) -> PyResult<T>;
}

impl<T, E: Error + 'static> IntoPyResult<T> for Result<T, E> {
    fn py_err(self) -> PyResult<T> {
        self.map_err(|e| to_py_err(&e))
    }
}

/// A `ValueError` about the argument `name`.
pub fn bad_argument(name: &str, message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{name}: {message}"))
}

/// A `TypeError` about the argument `name`.
pub fn bad_type(name: &str, message: impl std::fmt::Display) -> PyErr {
    PyTypeError::new_err(format!("{name}: {message}"))
}

/// Runs `work` with the GIL released (other Python threads go on meanwhile). A panic, which
/// would be a bug of the library, becomes a `RuntimeError` instead of killing the
/// interpreter's thread with a `PanicException`.
///
/// # Errors
/// What `work` returns, or the `RuntimeError` of a panic.
pub fn detached<T: Send>(py: Python<'_>, work: impl FnOnce() -> PyResult<T> + Send) -> PyResult<T> {
    py.detach(|| catch_unwind(AssertUnwindSafe(work)))
        .unwrap_or_else(|panic| {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| (*s).to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown cause".into());
            Err(PyRuntimeError::new_err(format!(
                "omnimvs internal error (please report it): {what}"
            )))
        })
}
