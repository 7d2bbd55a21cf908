//! The direct solve that the thermal compensation stage (`imu_ar::thermal`) must reproduce.

use nalgebra::{DMatrix, DVector};

/// The weighted, regularised least-squares problem of the `imu_ar::thermal` module docs,
/// accumulated sample by sample and solved directly (Cholesky):
///
/// `c_n = argmin sum_{i<=n} lambda^(n-i) (x_i - c^T phi_i)^2
///      + sum_{i<=n} lambda^(n-i) w (c_k(i) - p_k(i))^2 + delta lambda^n ||c - p||^2`,
///
/// `phi_i = [1, u_i, .., u_i^(N-1)]`, `u = (T - T_ref)/h` with `T_ref` and `h` the middle and
/// half-width of `[t_min, t_max]`, `k(i) = (i - 1) mod N`, `w = delta (1 - lambda^N)`.
pub struct ThermalLs {
    n_coef: usize,
    lambda: f64,
    delta: f64,
    weight: f64,
    centre: f64,
    half: f64,
    prior: Vec<f64>,
    r: DMatrix<f64>,
    b: DVector<f64>,
    lambda_n: f64,
    next: usize,
}

impl ThermalLs {
    /// An empty problem with `n_coef` coefficients and prior `prior` (zeros when empty).
    pub fn new(n_coef: usize, lambda: f64, t_min: f64, t_max: f64, delta: f64) -> Self {
        Self {
            n_coef,
            lambda,
            delta,
            weight: delta * (1.0 - lambda.powi(n_coef as i32)),
            centre: (t_min + t_max) / 2.0,
            half: (t_max - t_min) / 2.0,
            prior: vec![0.0; n_coef],
            r: DMatrix::zeros(n_coef, n_coef),
            b: DVector::zeros(n_coef),
            lambda_n: 1.0,
            next: 0,
        }
    }

    /// The same problem with the prior `p`.
    pub fn with_prior(self, prior: &[f64]) -> Self {
        assert_eq!(prior.len(), self.n_coef);
        Self {
            prior: prior.to_vec(),
            ..self
        }
    }

    /// `phi(T)`, the temperature clamped to the range.
    pub fn regressor(&self, celsius: f64) -> Vec<f64> {
        let t = celsius.clamp(self.centre - self.half, self.centre + self.half);
        let u = (t - self.centre) / self.half;
        (0..self.n_coef).map(|k| u.powi(k as i32)).collect()
    }

    /// Takes a learned sample `x` at `celsius` (inside the range).
    pub fn push(&mut self, x: f64, celsius: f64) {
        let phi = self.regressor(celsius);
        let (lambda, k) = (self.lambda, self.next);
        self.r *= lambda;
        self.b *= lambda;
        for i in 0..self.n_coef {
            for j in 0..self.n_coef {
                self.r[(i, j)] += phi[i] * phi[j];
            }
            self.b[i] += phi[i] * x;
        }
        self.r[(k, k)] += self.weight;
        self.b[k] += self.weight * self.prior[k];
        self.lambda_n *= lambda;
        self.next = (k + 1) % self.n_coef;
    }

    /// The information matrix `R_n` (the regularisation included).
    pub fn information(&self) -> DMatrix<f64> {
        let mut r = self.r.clone();
        for k in 0..self.n_coef {
            r[(k, k)] += self.delta * self.lambda_n;
        }
        r
    }

    /// The solution `c_n`.
    pub fn solve(&self) -> Vec<f64> {
        let mut b = self.b.clone();
        for k in 0..self.n_coef {
            b[k] += self.delta * self.lambda_n * self.prior[k];
        }
        let c = self
            .information()
            .cholesky()
            .expect("regularised system is positive definite")
            .solve(&b);
        c.iter().copied().collect()
    }

    /// `c^T phi(T)`.
    pub fn bias(&self, c: &[f64], celsius: f64) -> f64 {
        c.iter()
            .zip(self.regressor(celsius))
            .map(|(c, p)| c * p)
            .sum()
    }

    /// `phi^T R_n^-1 phi` at `celsius`, as `||L^-1 phi||^2` with `R_n = L L^T`.
    pub fn leverage(&self, celsius: f64) -> f64 {
        let phi = DVector::from_vec(self.regressor(celsius));
        let chol = self
            .information()
            .cholesky()
            .expect("regularised system is positive definite");
        chol.l()
            .solve_lower_triangular(&phi)
            .expect("non-singular factor")
            .norm_squared()
    }
}
