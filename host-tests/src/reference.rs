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
