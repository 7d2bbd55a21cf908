//! Yule-Walker (autocorrelation) method.

use super::levinson::levinson;
use super::{BatchConfig, BatchError, Fit, LevinsonError, finish, prepare};
use crate::Scalar;

/// Yule-Walker AR fit: the biased autocovariance `r(k) = (1/N) sum_{n=0}^{N-1-k} y_n y_{n+k}`
/// of `y = x - mean(x)`, then the Levinson-Durbin recursion.
///
/// Equals statsmodels `yule_walker(x, order=P, method='mle', demean=True)` (its `sigma` is the
/// square root of the innovation variance here). The model is always stationary
/// (`|kappa_m| < 1`), at the price of a bias towards zero near the unit circle (Tjostheim &
/// Paulsen 1983) that the other two estimators do not have.
///
/// # Errors
///
/// [`BatchError::TooShort`] below `P + 2` samples (`P + 1` without mean removal: one residual
/// degree of freedom), [`BatchError::NonFinite`], [`BatchError::Overflow`],
/// [`BatchError::ZeroVariance`] for constant data, [`BatchError::Singular`] when the
/// autocovariances are not positive definite (an exactly predictable record).
pub fn yule_walker<T: Scalar, const P: usize>(
    x: &[T],
    config: &BatchConfig<T>,
) -> Result<Fit<T, P>, BatchError> {
    const { assert!(P > 0, "the model order P must be at least 1") };
    let mean = prepare(x, P, config)?;
    let n = x.len();
    let mut r = [0.0f64; P];
    let mut r0 = 0.0;
    for (i, xi) in x.iter().enumerate() {
        let yi = xi.to_f64() - mean;
        r0 += yi * yi;
        for (k, rk) in r.iter_mut().enumerate().take(n - 1 - i) {
            *rk += yi * (x[i + k + 1].to_f64() - mean);
        }
    }
    if r0 == 0.0 {
        return Err(BatchError::ZeroVariance);
    }
    let nf = n as f64;
    let fit = levinson(r0 / nf, &r.map(|v| v / nf)).map_err(|e| match e {
        LevinsonError::NotPositiveDefinite { order } => BatchError::Singular { order },
        _ => BatchError::ZeroVariance,
    })?;
    finish(
        &fit.a,
        fit.r0,
        &fit.error_power,
        Some(&fit.reflection),
        mean,
        n,
        config,
    )
}
