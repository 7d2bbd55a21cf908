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

/// The exact problem of every recursive core (numerics.md section 0), accumulated sample by
/// sample and solved directly:
///
/// `a_n = argmin sum_{i<=n} lambda^(n-i) (y_i - a^T phi_i)^2 + delta lambda^n a^T D a`, with
/// prewindowed `phi_i = [y_{i-1} .. y_{i-p}]` (`y_i = 0` for `i <= 0`) and
/// `D = diag(lambda^(p-1), .., lambda^(p-m))` for order `m <= p`, or `D = I` for the ridge form.
pub struct Section0 {
    p: usize,
    lambda: f64,
    delta: f64,
    r: DMatrix<f64>,
    b: DVector<f64>,
    yy: f64,
    phi: Vec<f64>,
    lambda_n: f64,
    n: usize,
}

/// Which regularisation [`Section0`] solves with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Regularisation {
    /// `delta lambda^n a^T D a`, `D = diag(lambda^(p-1), .., lambda^(p-m))`.
    ShiftConsistent,
    /// `delta lambda^n ||a||^2`.
    Ridge,
}

impl Section0 {
    /// An empty problem of order up to `p`.
    pub fn new(p: usize, lambda: f64, delta: f64) -> Self {
        Self {
            p,
            lambda,
            delta,
            r: DMatrix::zeros(p, p),
            b: DVector::zeros(p),
            yy: 0.0,
            phi: vec![0.0; p],
            lambda_n: 1.0,
            n: 0,
        }
    }

    /// Takes the next sample `y_n`.
    pub fn push(&mut self, y: f64) {
        let (lambda, p) = (self.lambda, self.p);
        for i in 0..p {
            for j in 0..p {
                self.r[(i, j)] = lambda * self.r[(i, j)] + self.phi[i] * self.phi[j];
            }
            self.b[i] = lambda * self.b[i] + self.phi[i] * y;
        }
        self.yy = lambda * self.yy + y * y;
        self.phi.rotate_right(1);
        self.phi[0] = y;
        self.lambda_n *= lambda;
        self.n += 1;
    }

    /// Samples taken.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The order-`m` solution `a` and the energy `min J + delta lambda^(n+p)`.
    pub fn solve(&self, m: usize, reg: Regularisation) -> (Vec<f64>, f64) {
        let mut r = self.r.view((0, 0), (m, m)).into_owned();
        for k in 0..m {
            let d = match reg {
                Regularisation::ShiftConsistent => self.lambda.powi((self.p - 1 - k) as i32),
                Regularisation::Ridge => 1.0,
            };
            r[(k, k)] += self.delta * self.lambda_n * d;
        }
        let b = self.b.rows(0, m).into_owned();
        let a = r
            .cholesky()
            .expect("regularised system is positive definite")
            .solve(&b);
        let energy =
            self.yy - b.dot(&a) + self.delta * self.lambda_n * self.lambda.powi(self.p as i32);
        (a.iter().copied().collect(), energy)
    }

    /// The order-`p` solution of the problem centred on `a0` (shift-consistent `D`):
    /// `argmin sum lambda^(n-i) (y_i - a^T phi_i)^2 + delta lambda^n (a - a0)^T D (a - a0)`,
    /// from the normal equations `(R + delta lambda^n D) a = b + delta lambda^n D a0`, and its
    /// energy `min J + delta lambda^(n+p)`, `min J = yy + delta lambda^n a0^T D a0 - c^T a`
    /// with `c` the right-hand side.
    pub fn solve_centred(&self, a0: &[f64]) -> (Vec<f64>, f64) {
        let p = self.p;
        let mut r = self.r.clone();
        let mut c = self.b.clone();
        let mut prior = 0.0;
        for k in 0..p {
            let w = self.delta * self.lambda_n * self.lambda.powi((p - 1 - k) as i32);
            r[(k, k)] += w;
            c[k] += w * a0[k];
            prior += w * a0[k] * a0[k];
        }
        let a = r
            .cholesky()
            .expect("regularised system is positive definite")
            .solve(&c);
        let energy =
            self.yy + prior - c.dot(&a) + self.delta * self.lambda_n * self.lambda.powi(p as i32);
        (a.iter().copied().collect(), energy)
    }

    /// Takes a history sample: it enters the delay line and the regressors' Gram matrix
    /// (weighted as any row), but adds no equation: its row's desired value is its
    /// prediction by the centre `a0`, so that in `b = a - a0` it is `(0 - b^T phi)^2`.
    pub fn push_history(&mut self, y: f64, a0: &[f64]) {
        let desired = a0.iter().zip(&self.phi).map(|(a, p)| a * p).sum::<f64>();
        self.push(desired);
        self.phi[0] = y;
    }

    /// The a-priori error `y - a^T phi` of a coming sample `y` under coefficients `a`.
    pub fn a_priori_error(&self, a: &[f64], y: f64) -> f64 {
        y - a.iter().zip(&self.phi).map(|(a, p)| a * p).sum::<f64>()
    }
}

/// The exponentially weighted running mean removal the recursive cores document, in `f64`:
/// `y_n = x_n - m_{n-1}` (`m_0 = x_1`), `m_n = m_{n-1} + y_n / W_n`, `W_n = lambda W_{n-1} + 1`.
pub fn running_mean_removed(x: &[f64], lambda: f64) -> Vec<f64> {
    let mut mean = x.first().copied().unwrap_or(0.0);
    let mut w = 0.0;
    x.iter()
        .map(|&v| {
            let y = v - mean;
            w = lambda * w + 1.0;
            mean += y / w;
            y
        })
        .collect()
}
