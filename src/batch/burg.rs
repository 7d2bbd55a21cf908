//! Burg's method (maximum entropy).

use super::{BatchConfig, BatchError, Fit, finish, prepare};
use crate::Scalar;

/// Burg AR fit (Burg 1967; Kay & Marple 1981): order by order, the reflection coefficient that
/// minimises the sum of forward and backward error energies over `n = m..N-1`,
///
/// ```text
/// k_m = 2 sum f_{m-1}(n) b_{m-1}(n-1) / sum [f_{m-1}(n)^2 + b_{m-1}(n-1)^2]
/// ```
///
/// with the Levinson step-up `a_j^(m) = a_j^(m-1) - k_m a_{m-j}^(m-1)`, `a_m^(m) = k_m`, and the
/// innovation variance `E_m = E_{m-1} (1 - k_m^2)`, `E_0 = (1/N) sum y_n^2`
/// (`y = x - mean(x)`). The model is always stationary (`|kappa_m| <= 1`).
///
/// The coefficients equal statsmodels `burg(x, order=P, demean=True)` and, without mean
/// removal, MATLAB `arburg` and `spectrum.arburg`, whose variance `E_P` this is as well
/// (statsmodels normalises its `sigma2` differently). Burg is the reference AR estimator for
/// inertial-sensor errors (Nassar, Schwarz, El-Sheimy & Noureldin 2004).
///
/// The forward and backward errors are recomputed from the current coefficients at each order
/// instead of being stored, so the fit needs no buffer: `O(N P^2)` operations.
///
/// # Errors
///
/// [`BatchError::TooShort`] below `P + 2` samples (`P + 1` without mean removal: one residual
/// degree of freedom), [`BatchError::NonFinite`], [`BatchError::Overflow`],
/// [`BatchError::ZeroVariance`] when the data (or the errors of some order) have no energy.
pub fn burg<T: Scalar, const P: usize>(
    x: &[T],
    config: &BatchConfig<T>,
) -> Result<Fit<T, P>, BatchError> {
    const { assert!(P > 0, "the model order P must be at least 1") };
    let mean = prepare(x, P, config)?;
    let y = |i: usize| x[i].to_f64() - mean;
    let n = x.len();

    let e0 = (0..n).map(|i| y(i) * y(i)).sum::<f64>() / n as f64;
    if e0 == 0.0 {
        return Err(BatchError::ZeroVariance);
    }
    let mut a = [0.0f64; P];
    let mut reflection = [0.0f64; P];
    let mut variances = [0.0f64; P];
    let mut e = e0;
    for m in 1..=P {
        // f_{m-1}(t) = y_t - sum_j a_j y_{t-j};  b_{m-1}(t-1) = y_{t-m} - sum_j a_j y_{t-m+j}.
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for t in m..n {
            let (mut f, mut b) = (y(t), y(t - m));
            for (j, aj) in a[..m - 1].iter().enumerate() {
                f -= aj * y(t - 1 - j);
                b -= aj * y(t - m + 1 + j);
            }
            num += f * b;
            den += f * f + b * b;
        }
        if den == 0.0 {
            return Err(BatchError::ZeroVariance);
        }
        let k = 2.0 * num / den;
        let prev = a;
        for j in 1..m {
            a[j - 1] = prev[j - 1] - k * prev[m - j - 1];
        }
        a[m - 1] = k;
        e *= 1.0 - k * k;
        reflection[m - 1] = -k;
        variances[m - 1] = e;
    }
    finish(&a, e0, &variances, Some(&reflection), mean, n, config)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// numerics.md section 7 vector 3 (`spectrum` package test), without mean removal.
    #[test]
    fn spectrum_package_vector() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, -8.0];
        let config = BatchConfig::new(1.0).unwrap().with_demean(false);
        let fit = burg::<f64, 4>(&x, &config).unwrap();
        assert_eq!(fit.variance0, 25.5);
        assert!((fit.reflection.unwrap()[0] + 16.0 / 49.0).abs() < 1e-15);
        let kappa = [-0.32653061, 0.02256837, 0.06664801, 0.09885273];
        let big_a = [-0.3258074, 3.4571e-4, 0.03378978, 0.09885273];
        for m in 0..4 {
            let k = fit.reflection.unwrap()[m];
            assert!(
                (k - kappa[m]).abs() < 1e-8,
                "kappa_{}: {k} vs {}",
                m + 1,
                kappa[m]
            );
            let a = fit.model.a()[m];
            assert!(
                (a + big_a[m]).abs() < 1e-8,
                "a_{}: {a} vs {}",
                m + 1,
                -big_a[m]
            );
        }
        assert!((fit.model.noise_variance() - 22.44687609887804).abs() < 1e-12);
    }
}
