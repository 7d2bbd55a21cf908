//! The direct solve that the thermal compensation stage (`imu_ar::thermal`) must reproduce.

use nalgebra::{DMatrix, DVector};

/// The weighted, regularised least-squares problem of the `imu_ar::thermal` module docs,
/// solved directly as the stacked least-squares problem it is:
///
/// `c_n = argmin sum_{i<=n} lambda^(n-i) (x_i - c^T phi_i)^2
///      + sum_{i<=n} lambda^(n-i) w (c_k(i) - p_k(i))^2 + delta lambda^n ||c - s||^2`,
///
/// `phi_i = [1, u_i, .., u_i^(N-1)]`, `u = (T - T_ref)/h` with `T_ref` and `h` the middle and
/// half-width of `[t_min, t_max]`, `k(i) = (i - 1) mod N`, `w = delta (1 - lambda^N)`.
///
/// Every term is a weighted row `sqrt(weight) [h^T | y]` of one tall system `A c = b`. The
/// solve keeps its orthogonal triangularisation `A = Q [S; 0]` (Householder QR of `[S | z]`
/// with each new row, after the old rows are weighted by `sqrt(lambda)`) and solves
/// `S c = z` by back substitution: the conditioning of `A`, not of the normal equations
/// `A^T A` (whose accumulation loses the weakly excited directions when the temperature
/// stands still).
pub struct ThermalLs {
    n_coef: usize,
    lambda: f64,
    weight: f64,
    centre: f64,
    half: f64,
    prior: Vec<f64>,
    /// `[S | z]`, `n_coef x (n_coef + 1)`, `S` upper triangular.
    sz: DMatrix<f64>,
    next: usize,
}

impl ThermalLs {
    /// An empty problem with `n_coef` coefficients, prior and start 0.
    pub fn new(n_coef: usize, lambda: f64, t_min: f64, t_max: f64, delta: f64) -> Self {
        let mut sz = DMatrix::zeros(n_coef, n_coef + 1);
        for k in 0..n_coef {
            sz[(k, k)] = delta.sqrt();
        }
        Self {
            n_coef,
            lambda,
            weight: delta * (1.0 - lambda.powi(n_coef as i32)),
            centre: (t_min + t_max) / 2.0,
            half: (t_max - t_min) / 2.0,
            prior: vec![0.0; n_coef],
            sz,
            next: 0,
        }
    }

    /// The same (empty) problem with the prior `p`.
    pub fn with_prior(mut self, prior: &[f64]) -> Self {
        assert_eq!(prior.len(), self.n_coef);
        self.prior = prior.to_vec();
        self
    }

    /// The same (empty) problem with the start `s`.
    pub fn with_start(mut self, start: &[f64]) -> Self {
        assert_eq!(start.len(), self.n_coef);
        for (k, s) in start.iter().enumerate() {
            self.sz[(k, self.n_coef)] = self.sz[(k, k)] * s;
        }
        self
    }

    /// `phi(T)`, the temperature clamped to the range.
    pub fn regressor(&self, celsius: f64) -> Vec<f64> {
        let t = celsius.clamp(self.centre - self.half, self.centre + self.half);
        let u = (t - self.centre) / self.half;
        (0..self.n_coef).map(|k| u.powi(k as i32)).collect()
    }

    /// Takes a learned sample `x` at `celsius` (inside the range).
    pub fn push(&mut self, x: f64, celsius: f64) {
        let (n, k) = (self.n_coef, self.next);
        let phi = self.regressor(celsius);
        let mut m = DMatrix::zeros(n + 2, n + 1);
        m.view_mut((0, 0), (n, n + 1))
            .copy_from(&(&self.sz * self.lambda.sqrt()));
        for j in 0..n {
            m[(n, j)] = phi[j];
        }
        m[(n, n)] = x;
        let w = self.weight.sqrt();
        m[(n + 1, k)] = w;
        m[(n + 1, n)] = w * self.prior[k];
        let r = m.qr().r();
        self.sz = r.view((0, 0), (n, n + 1)).into_owned();
        self.next = (k + 1) % n;
    }

    /// `S`, with `S^T S = R_n`, the information matrix (the regularisation included).
    fn factor(&self) -> DMatrix<f64> {
        self.sz
            .view((0, 0), (self.n_coef, self.n_coef))
            .into_owned()
    }

    /// The information matrix `R_n = S^T S`.
    pub fn information(&self) -> DMatrix<f64> {
        let s = self.factor();
        s.transpose() * s
    }

    /// The solution `c_n`.
    pub fn solve(&self) -> Vec<f64> {
        let z = self.sz.column(self.n_coef).into_owned();
        let c = self
            .factor()
            .solve_upper_triangular(&z)
            .expect("the regularisation keeps S non-singular");
        c.iter().copied().collect()
    }

    /// `c^T phi(T)`.
    pub fn bias(&self, c: &[f64], celsius: f64) -> f64 {
        c.iter()
            .zip(self.regressor(celsius))
            .map(|(c, p)| c * p)
            .sum()
    }

    /// `phi^T R_n^-1 phi` at `celsius`, as `||S^-T phi||^2`.
    pub fn leverage(&self, celsius: f64) -> f64 {
        let phi = DVector::from_vec(self.regressor(celsius));
        self.factor()
            .transpose()
            .solve_lower_triangular(&phi)
            .expect("the regularisation keeps S non-singular")
            .norm_squared()
    }
}
