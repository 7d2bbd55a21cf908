//! Covariance method: conditional least squares without windowing.

use super::{BatchConfig, BatchError, Fit, finish, prepare};
use crate::Scalar;

/// Covariance-method (conditional least-squares) AR fit:
/// `a = argmin sum_{n=P}^{N-1} (y_n - sum_k a_k y_{n-k})^2` with `y = x - mean(x)`.
///
/// Equals statsmodels `AutoReg(x - x.mean(), lags=P, trend='n').fit()`: the same coefficients,
/// and the innovation variance `SSR / (N - P)` (its `sigma2`).
///
/// The normal equations are formed in `O(N P)` (the shifted structure gives every row from the
/// first) and solved by Cholesky. Because all orders share the sample `n = P..N-1`, the leading
/// `m x m` block of the factor solves order `m`, so the innovation variances of every order
/// `0..=P` come from the same factorisation (`Fit::variances`, divided by `N - P`; the order-`P`
/// entry is recomputed from the residuals). `Fit::reflection` is `None`.
///
/// # Errors
///
/// [`BatchError::TooShort`] below `2P + 2` samples (`2P + 1` without mean removal): the
/// `N - P` equations keep at least one residual degree of freedom after the `P` coefficients
/// and the mean. [`BatchError::NonFinite`], [`BatchError::Overflow`],
/// [`BatchError::ZeroVariance`] for constant data, [`BatchError::Singular`] when the regressors
/// are linearly dependent.
///
/// ```
/// use imu_ar::batch::{BatchConfig, covariance};
///
/// // y_n = 0.5 y_{n-1} exactly: the fit recovers a_1 = 0.5 with zero residual.
/// let x: Vec<f64> = (0..20).map(|n| 0.5f64.powi(n)).collect();
/// let fit = covariance::<f64, 1>(&x, &BatchConfig::new(1.0).unwrap().with_demean(false)).unwrap();
/// assert!((fit.model.a()[0] - 0.5).abs() < 1e-12);
/// ```
pub fn covariance<T: Scalar, const P: usize>(
    x: &[T],
    config: &BatchConfig<T>,
) -> Result<Fit<T, P>, BatchError> {
    const { assert!(P > 0, "the model order P must be at least 1") };
    let mean = prepare(x, 2 * P, config)?;
    let y = |i: usize| x[i].to_f64() - mean;
    let n = x.len();

    // R_ij = sum_{t=P}^{N-1} y_{t-1-i} y_{t-1-j}, b_i = sum y_{t-1-i} y_t, yy = sum y_t^2.
    let mut r = [[0.0f64; P]; P];
    let mut b = [0.0f64; P];
    let mut yy = 0.0;
    for t in P..n {
        let yt = y(t);
        let y1 = y(t - 1);
        yy += yt * yt;
        for i in 0..P {
            let yi = y(t - 1 - i);
            b[i] += yi * yt;
            r[0][i] += y1 * yi;
        }
    }
    // R_ij = R_{i-1,j-1} + y_{P-1-i} y_{P-1-j} - y_{N-1-i} y_{N-1-j}, for 1 <= i <= j.
    for i in 1..P {
        for j in i..P {
            r[i][j] = r[i - 1][j - 1] + y(P - 1 - i) * y(P - 1 - j) - y(n - 1 - i) * y(n - 1 - j);
        }
    }
    if yy == 0.0 {
        return Err(BatchError::ZeroVariance);
    }

    // Cholesky R = L L^T (upper triangle read), then z = L^-1 b.
    let mut l = [[0.0f64; P]; P];
    let scale = (0..P).map(|i| r[i][i]).fold(0.0, f64::max);
    for j in 0..P {
        let d = r[j][j] - l[j][..j].iter().map(|v| v * v).sum::<f64>();
        if d.is_nan() || d <= 1e-13 * scale {
            return Err(BatchError::Singular { order: j + 1 });
        }
        let d = libm::sqrt(d);
        l[j][j] = d;
        for i in j + 1..P {
            let dot: f64 = l[i][..j].iter().zip(&l[j][..j]).map(|(p, q)| p * q).sum();
            l[i][j] = (r[j][i] - dot) / d;
        }
    }
    let mut z = [0.0f64; P];
    for i in 0..P {
        let dot: f64 = l[i][..i].iter().zip(&z[..i]).map(|(p, q)| p * q).sum();
        z[i] = (b[i] - dot) / l[i][i];
    }
    let mut a = [0.0f64; P];
    for i in (0..P).rev() {
        let dot: f64 = (i + 1..P).map(|k| l[k][i] * a[k]).sum();
        a[i] = (z[i] - dot) / l[i][i];
    }

    // Residual energy of order m on the common sample: yy - sum_{i<m} z_i^2.
    let dof = (n - P) as f64;
    let mut variances = [0.0f64; P];
    let mut energy = yy;
    for (v, zi) in variances.iter_mut().zip(&z) {
        energy -= zi * zi;
        *v = energy.max(0.0) / dof;
    }
    // The order-P variance from the residuals themselves, free of the cancellation above.
    let ssr: f64 = (P..n)
        .map(|t| {
            let e = (0..P).fold(y(t), |e, k| e - a[k] * y(t - 1 - k));
            e * e
        })
        .sum();
    variances[P - 1] = ssr / dof;
    finish(&a, yy / dof, &variances, None, mean, n - P, config)
}
