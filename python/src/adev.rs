//! The overlapping Allan variance at many averaging factors at once, as `imu-ar adev` computes
//! it: one pass over the phase per factor, the factors spread over the machine's cores.

use imu_ar::allan::AllanError;
use imu_ar_cli::adev::octaves;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;

use crate::errors::{guarded, to_py_checked};
use imu_ar_cli::error::Fail;

/// The overlapping Allan variances of `x` at the averaging factors `ms` (each with
/// `2 m <= n`), on up to `threads` threads: the tool's (`imu-ar adev`) passes over the phase,
/// [`imu_ar_cli::adev::octaves`]; in the order of `ms`.
///
/// # Errors
///
/// The library's [`AllanError`] for a factor out of range or a sample that is not finite.
pub fn avars(x: &[f64], ms: &[usize], threads: usize) -> Result<Vec<f64>, AllanError> {
    octaves(x, ms, threads)
}

/// `_native.octave_avar(x, ms)`: the overlapping Allan variance of `x` at each averaging factor
/// of `ms`, as a float64 array. Releases the GIL.
#[pyfunction]
pub fn octave_avar<'py>(
    py: Python<'py>,
    x: PyReadonlyArray1<'py, f64>,
    ms: Vec<usize>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let x = x.as_slice()?;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let v = py
        .detach(|| guarded(|| avars(x, &ms, threads).map_err(|e| Fail(e.to_string()))))
        .map_err(to_py_checked)?;
    Ok(v.into_pyarray(py))
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_ar::allan::overlapping_avar;

    #[test]
    fn threads_give_the_library_s_values_in_order() {
        let x: Vec<f64> = (0..1000).map(|i| ((i * 7919) % 113) as f64).collect();
        let ms = [1, 2, 4, 8, 16, 32, 64, 128, 256, 500];
        let one = avars(&x, &ms, 1).unwrap_or_default();
        let three = avars(&x, &ms, 3).unwrap_or_default();
        assert_eq!(one.len(), ms.len());
        assert_eq!(one, three);
        for (m, v) in ms.iter().zip(&one) {
            let slow = overlapping_avar(&x, *m).unwrap_or(f64::NAN);
            assert!((v / slow - 1.0).abs() < 1e-12, "m = {m}: {v} {slow}");
        }
        assert!(avars(&x, &[501], 2).is_err());
    }
}
