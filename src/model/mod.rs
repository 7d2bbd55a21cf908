//! The fitted AR model and the forms a navigation Kalman filter needs.
//!
//! `x[n] = mean + sum_{k=1..P} a_k (x[n-k] - mean) + w[n]`, `Var w = noise_variance`, sampled
//! every `dt` seconds. Every estimator of the crate returns an [`ArModel`].
//!
//! The hand-over quantities (reflection coefficients, autocovariances, PSD, Allan variance,
//! state-space matrices, Gauss-Markov parameters) are computed in `f64` whatever `T` is and
//! rounded to `T` once; they are not per-sample work.

mod gauss_markov;

use core::fmt;

use crate::Scalar;

pub use gauss_markov::GaussMarkov;

/// A `P x P` matrix, row-major.
pub type Matrix<T, const P: usize> = [[T; P]; P];

/// Why a model, or a quantity derived from it, does not exist.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelError {
    /// A coefficient, the variance or the mean is NaN or infinite.
    NonFinite,
    /// The innovation variance is negative.
    NegativeVariance,
    /// The sample interval `dt` is not positive and finite.
    Interval,
    /// The model is not stationary: the reflection coefficient of this order is not inside
    /// (-1, 1) (a pole on or outside the unit circle).
    Unstable {
        /// The highest order whose reflection coefficient is out of range.
        order: usize,
    },
    /// An AR(1) with `phi <= 0` or `phi >= 1` has no first-order Gauss-Markov equivalent.
    NoGaussMarkov,
    /// A Gauss-Markov correlation time or sigma that is not positive and finite.
    InvalidGaussMarkov,
    /// The scalar type cannot represent the AR(1) sampling of a Gauss-Markov process: `dt` is
    /// so small against the correlation time that the coefficient nearest to
    /// `exp(-dt / T_c)` misses `1 - exp(-dt / T_c)` by more than 1 %, or the noise variance
    /// underflows to 0 or overflows (see [`GaussMarkov::to_ar1`]).
    Unrepresentable,
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NonFinite => f.write_str("model parameter is NaN or infinite"),
            Self::NegativeVariance => f.write_str("innovation variance is negative"),
            Self::Interval => f.write_str(INTERVAL),
            Self::Unstable { order } => write!(
                f,
                "model is not stationary (reflection coefficient {order} outside (-1, 1))"
            ),
            Self::NoGaussMarkov => {
                f.write_str("AR(1) coefficient outside (0, 1) has no Gauss-Markov equivalent")
            }
            Self::InvalidGaussMarkov => {
                f.write_str("Gauss-Markov correlation time and sigma must be positive and finite")
            }
            Self::Unrepresentable => f.write_str(
                "Gauss-Markov process not representable in this number type (sample interval \
                 too short against the correlation time, or noise variance out of range)",
            ),
        }
    }
}

impl core::error::Error for ModelError {}

/// What [`ModelError::Interval`], [`BatchError::Interval`](crate::batch::BatchError::Interval)
/// and [`ConfigError::Interval`](crate::recursive::ConfigError::Interval) say: one check,
/// `dt` positive and finite, everywhere a sample interval is given.
pub(crate) const INTERVAL: &str = "sample interval must be positive and finite";

/// An autoregressive model of order `P` with its innovation variance, mean and sample interval.
///
/// Convention: `x[n] = mean + sum_{k=1..P} a_k (x[n-k] - mean) + w[n]`, `Var w = noise_variance`.
/// MATLAB's `arburg`/`aryule`, Kay, Marple and `spectrum` return `[1, -a_1, .., -a_P]`.
///
/// ```
/// use imu_ar::ArModel;
///
/// // A first-order Gauss-Markov gyro drift: phi = 0.99 at 100 Hz.
/// let m = ArModel::new([0.99f64], 1e-6, 0.0, 0.01).unwrap();
/// assert!((m.predict(&[2.0]) - 1.98).abs() < 1e-12);
/// let gm = m.to_gauss_markov().unwrap();
/// assert!((gm.correlation_time() - 0.995).abs() < 1e-3); // -dt / ln(phi)
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ArModel<T, const P: usize> {
    a: [T; P],
    noise_variance: T,
    mean: T,
    dt: T,
}

impl<T: Scalar, const P: usize> ArModel<T, P> {
    /// A model from coefficients `a_1..a_P`, innovation variance, mean and sample interval (s).
    ///
    /// Stationarity is not required here; [`ArModel::reflection`] checks it.
    ///
    /// # Errors
    ///
    /// [`ModelError::NonFinite`], [`ModelError::NegativeVariance`] or
    /// [`ModelError::Interval`].
    pub fn new(a: [T; P], noise_variance: T, mean: T, dt: T) -> Result<Self, ModelError> {
        const { assert!(P > 0, "the model order P must be at least 1") };
        if !(dt.is_finite() && dt > T::ZERO) {
            return Err(ModelError::Interval);
        }
        let finite =
            a.iter().all(|v| v.is_finite()) && noise_variance.is_finite() && mean.is_finite();
        if !finite {
            return Err(ModelError::NonFinite);
        }
        if noise_variance < T::ZERO {
            return Err(ModelError::NegativeVariance);
        }
        Ok(Self {
            a,
            noise_variance,
            mean,
            dt,
        })
    }

    /// Coefficients `a_1..a_P`.
    pub fn a(&self) -> &[T; P] {
        &self.a
    }

    /// Innovation variance `Var w`, in units^2.
    pub fn noise_variance(&self) -> T {
        self.noise_variance
    }

    /// Mean of the process, in units.
    pub fn mean(&self) -> T {
        self.mean
    }

    /// Sample interval `dt`, in seconds.
    pub fn dt(&self) -> T {
        self.dt
    }

    /// One-step prediction `mean + sum_k a_k (past[k-1] - mean)` of `x[n]`, where `past[0]` is
    /// `x[n-1]` and `past[P-1]` is `x[n-P]`.
    #[inline]
    pub fn predict(&self, past: &[T; P]) -> T {
        self.a
            .iter()
            .zip(past)
            .fold(self.mean, |acc, (&a, &x)| acc + a * (x - self.mean))
    }

    fn a_f64(&self) -> [f64; P] {
        self.a.map(Scalar::to_f64)
    }

    /// Reflection coefficients `kappa_1..kappa_P` by the step-down (reverse Levinson) recursion,
    /// in the error-filter convention (`kappa_P = -a_P`):
    /// `a_j^(m-1) = (a_j^(m) + k_m a_{m-j}^(m)) / (1 - k_m^2)`, `k_m = a_m^(m) = -kappa_m`.
    ///
    /// # Errors
    ///
    /// [`ModelError::Unstable`] when some `|kappa_m| >= 1`, i.e. the model is not stationary.
    pub fn reflection(&self) -> Result<[T; P], ModelError> {
        let (k, _) = step_down(&self.a_f64())?;
        Ok(k.map(|k| T::from_f64(-k)))
    }

    /// `true` when every pole is strictly inside the unit circle.
    pub fn is_stable(&self) -> bool {
        step_down(&self.a_f64()).is_ok()
    }

    /// The autocovariances `r(0), r(1), ...` of the stationary process, without end: `r(0..=P)`
    /// by the reverse Levinson recursion, then `r(k) = sum_j a_j r(k-j)`.
    ///
    /// # Errors
    ///
    /// [`ModelError::Unstable`] when the model is not stationary.
    pub fn autocovariances(&self) -> Result<Autocovariances<T, P>, ModelError> {
        Autocovariances::new(&self.a_f64(), self.noise_variance.to_f64())
    }

    /// Two-sided power spectral density at `f` Hz (`|f| <= 1/(2 dt)`), in units^2/Hz:
    /// `S(f) = sigma_w^2 dt / |1 - sum_k a_k exp(-i 2 pi f k dt)|^2`. The one-sided PSD is
    /// `2 S(f)`; `integral S df` over `[-1/(2dt), 1/(2dt)]` is `r(0)`.
    ///
    /// A non-stationary model has no spectrum (its variance grows without bound, and the
    /// formula would give a finite, meaningless value, or an infinite one on a pole).
    ///
    /// # Errors
    ///
    /// [`ModelError::Unstable`] when the model is not stationary ([`ArModel::is_stable`]);
    /// [`ModelError::NonFinite`] for a NaN or infinite frequency.
    pub fn psd(&self, f: T) -> Result<T, ModelError> {
        if !f.is_finite() {
            return Err(ModelError::NonFinite);
        }
        step_down(&self.a_f64())?;
        let dt = self.dt.to_f64();
        let w = 2.0 * core::f64::consts::PI * f.to_f64() * dt;
        let (mut re, mut im) = (1.0, 0.0);
        for (k, &a) in self.a.iter().enumerate() {
            let phase = w * (k + 1) as f64;
            re -= a.to_f64() * libm::cos(phase);
            im += a.to_f64() * libm::sin(phase);
        }
        Ok(T::from_f64(
            self.noise_variance.to_f64() * dt / (re * re + im * im),
        ))
    }

    /// Allan variance of the model at `tau = m dt` (numerics.md section 6), in units^2:
    /// `AVAR(m) = [m r(0) + sum_{k=1}^{m-1} (2m - 3k) r(k) + sum_{k=m}^{2m-1} (k - 2m) r(k)] / m^2`,
    /// which is the expectation of the overlapping Allan variance estimator for this process.
    /// `O(m P)` operations; `m = 0` returns 0.
    ///
    /// # Errors
    ///
    /// [`ModelError::Unstable`] when the model is not stationary.
    pub fn allan_variance(&self, m: u32) -> Result<T, ModelError> {
        let mut r = Autocovariances::<T, P>::new(&self.a_f64(), self.noise_variance.to_f64())?;
        if m == 0 {
            return Ok(T::ZERO);
        }
        let m = u64::from(m);
        let mut sum = m as f64 * r.next_f64();
        for k in 1..2 * m {
            let c = if k < m {
                2.0 * m as f64 - 3.0 * k as f64
            } else {
                k as f64 - 2.0 * m as f64
            };
            sum += c * r.next_f64();
        }
        Ok(T::from_f64(sum / (m as f64 * m as f64)))
    }

    /// The companion-form transition matrix at the model's `dt`:
    /// `Phi = [[a_1 .. a_P]; [I_{P-1} 0]]`, for the state `s_k = [x_k, .., x_{k-P+1}] - mean`.
    pub fn transition(&self) -> Matrix<T, P> {
        to_t(&companion(&self.a_f64()))
    }

    /// The process noise `Q = sigma_w^2 e_1 e_1^T` that goes with [`ArModel::transition`].
    pub fn process_noise(&self) -> Matrix<T, P> {
        let mut q = [[T::ZERO; P]; P];
        q[0][0] = self.noise_variance;
        q
    }

    /// The pair `(Phi^M, Q_M)` for a filter step of `M dt`: `Q_M = sum_{j<M} Phi^j Q Phi^jT`.
    /// `M = 0` gives `(I, 0)`. `O(P^3 log M)` operations (square and multiply).
    pub fn discretize(&self, steps: u32) -> (Matrix<T, P>, Matrix<T, P>) {
        let phi = companion(&self.a_f64());
        let mut q = [[0.0; P]; P];
        q[0][0] = self.noise_variance.to_f64();
        // (A, S) describes `s -> A s + noise of covariance S`; composing two such steps gives
        // (A2 A1, A2 S1 A2^T + S2); every factor here is a power of Phi, so they commute.
        let mut result = (identity::<P>(), [[0.0; P]; P]);
        let mut base = (phi, q);
        let mut m = steps;
        while m > 0 {
            if m & 1 == 1 {
                result = compose(&result, &base);
            }
            base = compose(&base, &base);
            m >>= 1;
        }
        (to_t(&result.0), to_t(&result.1))
    }

    /// The stationary state covariance, the solution of `P = Phi P Phi^T + Q`: the Toeplitz
    /// matrix of `r(0..P-1)`. Initialises a Kalman filter at the process's steady state.
    ///
    /// # Errors
    ///
    /// [`ModelError::Unstable`] when the model is not stationary.
    pub fn stationary_covariance(&self) -> Result<Matrix<T, P>, ModelError> {
        let mut r = [0.0; P];
        for (slot, v) in r.iter_mut().zip(self.autocovariances()?) {
            *slot = v.to_f64();
        }
        Ok(core::array::from_fn(|i| {
            core::array::from_fn(|j| T::from_f64(r[i.abs_diff(j)]))
        }))
    }
}

/// Autocovariances `r(0), r(1), ...` of a stationary AR model; see [`ArModel::autocovariances`].
#[derive(Clone, Debug)]
pub struct Autocovariances<T, const P: usize> {
    a: [f64; P],
    /// `r(1..=P)` from the reverse Levinson recursion.
    head: [f64; P],
    r0: f64,
    /// Lags handed out so far.
    k: usize,
    /// `r(k-1), .., r(k-P)`, newest first, once `k > P`.
    last: [f64; P],
    _t: core::marker::PhantomData<T>,
}

impl<T: Scalar, const P: usize> Autocovariances<T, P> {
    fn new(a: &[f64; P], noise_variance: f64) -> Result<Self, ModelError> {
        let (k, prod) = step_down(a)?;
        // r(0) = sigma_w^2 / prod (1 - k_m^2); then r(m) by the forward Levinson recursion.
        let r0 = noise_variance / prod;
        let mut head = [0.0; P];
        let mut poly = [0.0; P];
        let mut e = r0;
        for m in 1..=P {
            let km = at(&k, m - 1);
            let past: f64 = (1..m)
                .map(|j| at(&poly, j - 1) * r_at(r0, &head, m - j))
                .sum();
            set(&mut head, m - 1, past + km * e);
            let prev = poly;
            for j in 1..m {
                set(
                    &mut poly,
                    j - 1,
                    at(&prev, j - 1) - km * at(&prev, m - j - 1),
                );
            }
            set(&mut poly, m - 1, km);
            e *= 1.0 - km * km;
        }
        let mut last = head;
        last.reverse();
        Ok(Self {
            a: *a,
            head,
            r0,
            k: 0,
            last,
            _t: core::marker::PhantomData,
        })
    }

    fn next_f64(&mut self) -> f64 {
        let k = self.k;
        self.k = self.k.saturating_add(1);
        if k <= P {
            return r_at(self.r0, &self.head, k);
        }
        let r = self.a.iter().zip(&self.last).map(|(a, r)| a * r).sum();
        // The newest first.
        if P > 0 {
            self.last.rotate_right(1);
        }
        set(&mut self.last, 0, r);
        r
    }
}

impl<T: Scalar, const P: usize> Iterator for Autocovariances<T, P> {
    type Item = T;

    fn next(&mut self) -> Option<T> {
        Some(T::from_f64(self.next_f64()))
    }
}

fn r_at<const P: usize>(r0: f64, head: &[f64; P], lag: usize) -> f64 {
    lag.checked_sub(1).map_or(r0, |i| at(head, i))
}

/// `v[i]`, or 0 past the end: the recursions index within bounds, and this keeps them free of
/// panic paths where the compiler cannot prove it.
fn at(v: &[f64], i: usize) -> f64 {
    v.get(i).copied().unwrap_or(0.0)
}

/// `v[i] = x` within bounds, as [`at`] reads.
fn set(v: &mut [f64], i: usize, x: f64) {
    if let Some(slot) = v.get_mut(i) {
        *slot = x;
    }
}

/// Step-down: the partial autocorrelations `k_1..k_P` (`k_m = a_m^(m)`) and the lower-order
/// coefficient vectors are implied; returns `k` and the product `prod (1 - k_m^2)`.
fn step_down<const P: usize>(a: &[f64; P]) -> Result<([f64; P], f64), ModelError> {
    let mut cur = *a;
    let mut k = [0.0; P];
    let mut prod = 1.0;
    for m in (1..=P).rev() {
        let km = at(&cur, m - 1);
        let inside_unit_circle = km.abs() < 1.0;
        if !inside_unit_circle {
            return Err(ModelError::Unstable { order: m });
        }
        set(&mut k, m - 1, km);
        let d = 1.0 - km * km;
        prod *= d;
        let prev = cur;
        for j in 1..m {
            set(
                &mut cur,
                j - 1,
                (at(&prev, j - 1) + km * at(&prev, m - j - 1)) / d,
            );
        }
    }
    Ok((k, prod))
}

fn companion<const P: usize>(a: &[f64; P]) -> Matrix<f64, P> {
    let mut phi = [[0.0; P]; P];
    phi[0] = *a;
    // The subdiagonal: row i + 1 has its 1 in column i.
    for (row, i) in phi.iter_mut().skip(1).zip(0..P) {
        set(row, i, 1.0);
    }
    phi
}

fn identity<const P: usize>() -> Matrix<f64, P> {
    core::array::from_fn(|i| core::array::from_fn(|j| if i == j { 1.0 } else { 0.0 }))
}

fn matmul<const P: usize>(x: &Matrix<f64, P>, y: &Matrix<f64, P>) -> Matrix<f64, P> {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..P).map(|k| x[i][k] * y[k][j]).sum()))
}

/// `(A1, S1)` then `(A2, S2)`: `(A2 A1, A2 S1 A2^T + S2)`.
fn compose<const P: usize>(
    first: &(Matrix<f64, P>, Matrix<f64, P>),
    second: &(Matrix<f64, P>, Matrix<f64, P>),
) -> (Matrix<f64, P>, Matrix<f64, P>) {
    let (a1, s1) = first;
    let (a2, s2) = second;
    let a2s1 = matmul(a2, s1);
    let s = core::array::from_fn(|i| {
        core::array::from_fn(|j| (0..P).map(|k| a2s1[i][k] * a2[j][k]).sum::<f64>() + s2[i][j])
    });
    (matmul(a2, a1), s)
}

fn to_t<T: Scalar, const P: usize>(m: &Matrix<f64, P>) -> Matrix<T, P> {
    m.map(|row| row.map(T::from_f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Percival & Walden AR(4), numerics.md section 7 vector 4: exact autocovariances and
    /// reflection coefficients from the literature.
    const PW: [f64; 4] = [2.7607, -3.8106, 2.6535, -0.9238];

    #[test]
    fn percival_walden_autocovariances_and_reflection() {
        let m = ArModel::new(PW, 1.0, 0.0, 1.0).unwrap();
        let r: [f64; 5] = core::array::from_fn({
            let mut it = m.autocovariances().unwrap();
            move |_| it.next().unwrap()
        });
        let want = [761.71729, 545.75308, 27.14232, -487.66472, -705.24319];
        for (k, (got, want)) in r.iter().zip(want).enumerate() {
            assert!((got - want).abs() < 1e-5, "r({k}) = {got}, expected {want}");
        }
        let kappa = m.reflection().unwrap();
        let want = [-0.716477207, 0.981601358, -0.703750833, 0.9238];
        for (k, (got, want)) in kappa.iter().zip(want).enumerate() {
            assert!(
                (got - want).abs() < 1e-9,
                "kappa_{} = {got}, expected {want}",
                k + 1
            );
        }
        // Levinson on those r returns a.
        let fit = crate::batch::levinson_durbin::<f64, 4>(&r).unwrap();
        for (got, want) in fit.a.iter().zip(PW) {
            assert!((got - want).abs() < 1e-9, "{got} vs {want}");
        }
    }

    /// numerics.md section 7 vector 5: AR(1) phi = 0.9, sigma_w^2 = 1.
    #[test]
    fn ar1_allan_variance_vector() {
        let m = ArModel::new([0.9f64], 1.0, 0.0, 0.01).unwrap();
        let cases = [
            (1, 0.5263158),
            (2, 0.725),
            (5, 1.3042822),
            (10, 1.8201231),
            (50, 1.4354799),
        ];
        for (mm, want) in cases {
            let got = m.allan_variance(mm).unwrap();
            assert!(
                (got - want).abs() < 5e-8,
                "AVAR({mm}) = {got}, expected {want}"
            );
        }
    }

    #[test]
    fn unstable_and_invalid_models_are_errors() {
        assert_eq!(
            ArModel::new([1.0f64], 1.0, 0.0, 1.0).unwrap().reflection(),
            Err(ModelError::Unstable { order: 1 })
        );
        assert!(
            !ArModel::new([0.5f32, 0.6], 1.0, 0.0, 1.0)
                .unwrap()
                .is_stable()
        );
        assert_eq!(
            ArModel::new([f32::NAN], 1.0, 0.0, 1.0),
            Err(ModelError::NonFinite)
        );
        assert_eq!(
            ArModel::new([0.5f32], -1.0, 0.0, 1.0),
            Err(ModelError::NegativeVariance)
        );
        assert_eq!(
            ArModel::new([0.5f32], 1.0, 0.0, 0.0),
            Err(ModelError::Interval)
        );
        for phi in [0.0, -0.5, 1.0] {
            let m = ArModel::new([phi], 1.0, 0.0, 1.0).unwrap();
            assert_eq!(
                m.to_gauss_markov(),
                Err(ModelError::NoGaussMarkov),
                "phi = {phi}"
            );
        }
    }

    #[test]
    fn stationary_covariance_solves_the_lyapunov_equation() {
        let m = ArModel::new([1.2f64, -0.5, 0.1, 0.05], 0.3, 0.0, 0.01).unwrap();
        let p = m.stationary_covariance().unwrap();
        let phi = m.transition();
        let q = m.process_noise();
        let pp = compose(&(identity(), p), &(phi, q)).1; // Phi P Phi^T + Q
        for i in 0..4 {
            for j in 0..4 {
                assert!((pp[i][j] - p[i][j]).abs() < 1e-12 * p[0][0]);
            }
        }
    }
}
