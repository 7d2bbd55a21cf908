//! Direct solves that the library's recursions must reproduce.

use nalgebra::{DMatrix, DVector};

/// Yule-Walker coefficients `a_1..a_p` from autocovariances `r(0..=p)` by a dense Cholesky solve
/// of the Toeplitz system `sum_k a_k r(|j - k|) = r(j)`, `j = 1..=p`, and the innovation
/// variance `r(0) - a^T r(1..=p)`.
///
/// Returns `None` when the Toeplitz matrix is not positive definite.
pub fn yule_walker(r: &[f64], p: usize) -> Option<(Vec<f64>, f64)> {
    assert!(r.len() > p, "need r(0..={p})");
    let toeplitz = DMatrix::from_fn(p, p, |i, j| r[i.abs_diff(j)]);
    let rhs = DVector::from_column_slice(&r[1..=p]);
    let a = toeplitz.cholesky()?.solve(&rhs);
    let variance = r[0] - a.dot(&rhs);
    Some((a.iter().copied().collect(), variance))
}

/// Biased sample autocovariance `r(k) = (1/N) sum_{n} (x_n - m)(x_{n+k} - m)`, `k = 0..=p`,
/// of the mean-removed data (always a positive semidefinite sequence).
pub fn autocovariance(x: &[f64], p: usize) -> Vec<f64> {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    (0..=p)
        .map(|k| {
            x.iter()
                .zip(&x[k..])
                .map(|(a, b)| (a - mean) * (b - mean))
                .sum::<f64>()
                / n
        })
        .collect()
}

/// Conditional least-squares AR(p) fit by an SVD solve of the `(N - p) x p` data matrix:
/// `argmin sum_{n=p}^{N-1} (y_n - a^T [y_{n-1} .. y_{n-p}])^2`, `y = x - mean(x)` when `demean`.
/// Returns `a` and the innovation variance `SSR / (N - p)`.
pub fn covariance_ls(x: &[f64], p: usize, demean: bool) -> (Vec<f64>, f64) {
    let mean = if demean {
        x.iter().sum::<f64>() / x.len() as f64
    } else {
        0.0
    };
    let y: Vec<f64> = x.iter().map(|v| v - mean).collect();
    let rows = y.len() - p;
    let data = DMatrix::from_fn(rows, p, |r, k| y[r + p - 1 - k]);
    let target = DVector::from_iterator(rows, y[p..].iter().copied());
    let a = data
        .clone()
        .svd(true, true)
        .solve(&target, 1e-14)
        .expect("SVD with U and V^T");
    let resid = target - data * &a;
    (
        a.iter().copied().collect(),
        resid.norm_squared() / rows as f64,
    )
}
