//! The native module of the Python package `imu_ar` (`imu_ar._native`): the readers, fits and
//! checks of the `imu-ar` tool (the crate `imu-ar-cli`) and the device's recursive estimators
//! (the crate `imu-ar`), with numpy arrays in and out. The Python layer (`python/imu_ar/`)
//! turns keyword arguments into the tool's flags and the tool's JSON into Python objects; this
//! crate runs the tool's own code on them, so that a result from Python is the tool's result.
//!
//! Every entry point returns a Python exception for an error, never a panic: the tool's
//! one-line errors ([`errors`]), and a `RuntimeError` for a panic caught at the boundary. The
//! long calls release the GIL.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod adev;
pub mod commands;
pub mod errors;
pub mod estimators;

use pyo3::prelude::*;

/// The native module `imu_ar._native`.
#[pymodule]
#[pyo3(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(adev::octave_avar, m)?)?;
    m.add_function(wrap_pyfunction!(commands::noise, m)?)?;
    m.add_function(wrap_pyfunction!(commands::fit, m)?)?;
    m.add_function(wrap_pyfunction!(commands::order, m)?)?;
    m.add_function(wrap_pyfunction!(commands::characterise, m)?)?;
    m.add_function(wrap_pyfunction!(commands::read, m)?)?;
    m.add_function(wrap_pyfunction!(commands::kind, m)?)?;
    m.add_function(wrap_pyfunction!(commands::csv_columns, m)?)?;
    m.add_function(wrap_pyfunction!(commands::parity_input, m)?)?;
    m.add_function(wrap_pyfunction!(commands::parity, m)?)?;
    m.add_function(wrap_pyfunction!(commands::centre, m)?)?;
    m.add_class::<estimators::Estimator>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
