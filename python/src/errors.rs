//! The tool's errors as Python exceptions.

use std::panic::{AssertUnwindSafe, catch_unwind};

use imu_ar_cli::error::Fail;
use pyo3::PyErr;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};

/// The tool's one-line error as the exception a Python user expects: `FileNotFoundError` for
/// a file that is not there, `OSError` for one that cannot be opened or read, `ValueError`
/// for everything else (bad settings, bad data), with the tool's message.
pub fn to_py(Fail(msg): Fail) -> PyErr {
    if msg.contains("(os error 2)") {
        PyFileNotFoundError::new_err(msg)
    } else if msg.contains("os error") || msg.contains("cannot open") {
        PyOSError::new_err(msg)
    } else {
        PyValueError::new_err(msg)
    }
}

/// Runs `f`, turning a panic into an error (it never crosses into Python as one).
pub fn guarded<T>(f: impl FnOnce() -> Result<T, Fail>) -> Result<T, Fail> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let what = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(Fail(format!("{PANIC}{what}")))
        }
    }
}

/// The start of the message of a caught panic.
const PANIC: &str = "internal error (please report it): ";

/// [`to_py`], with a caught panic as a `RuntimeError`.
pub fn to_py_checked(fail: Fail) -> PyErr {
    if fail.0.starts_with(PANIC) {
        PyRuntimeError::new_err(fail.0)
    } else {
        to_py(fail)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_is_an_error() {
        let r: Result<(), Fail> = guarded(|| panic!("boom"));
        let e = r.err().map(|f| f.0).unwrap_or_default();
        assert!(e.starts_with(PANIC) && e.ends_with("boom"), "{e}");
    }
}
