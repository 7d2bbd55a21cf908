//! AR(1) to and from a first-order Gauss-Markov process (Brown & Hwang, *Introduction to
//! Random Signals and Applied Kalman Filtering*, 4th ed. 2012).

use super::{ArModel, ModelError};
use crate::Scalar;

impl<T: Scalar> ArModel<T, 1> {
    /// The first-order Gauss-Markov process this AR(1) samples (Brown & Hwang 2012):
    /// `T_c = -dt / ln(phi)`, `sigma^2 = sigma_w^2 / (1 - phi^2)`.
    ///
    /// # Errors
    ///
    /// [`ModelError::NoGaussMarkov`] when `phi <= 0` or `phi >= 1`.
    pub fn to_gauss_markov(&self) -> Result<GaussMarkov<T>, ModelError> {
        let phi = self.a[0].to_f64();
        if !(phi > 0.0 && phi < 1.0) {
            return Err(ModelError::NoGaussMarkov);
        }
        let tc = -self.dt.to_f64() / libm::log(phi);
        let sigma = libm::sqrt(self.noise_variance.to_f64() / (1.0 - phi * phi));
        GaussMarkov::new(T::from_f64(tc), T::from_f64(sigma))
    }
}

/// A first-order Gauss-Markov process `dx/dt = -x / T_c + u`, stationary standard deviation
/// `sigma`; the driving white noise `u` has two-sided PSD `q = 2 sigma^2 / T_c`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GaussMarkov<T> {
    correlation_time: T,
    sigma: T,
}

impl<T: Scalar> GaussMarkov<T> {
    /// A process with correlation time `T_c` (s) and stationary sigma (units).
    ///
    /// # Errors
    ///
    /// [`ModelError::InvalidGaussMarkov`] unless both are positive and finite.
    pub fn new(correlation_time: T, sigma: T) -> Result<Self, ModelError> {
        let ok = correlation_time.is_finite()
            && sigma.is_finite()
            && correlation_time > T::ZERO
            && sigma > T::ZERO;
        if !ok {
            return Err(ModelError::InvalidGaussMarkov);
        }
        Ok(Self {
            correlation_time,
            sigma,
        })
    }

    /// Correlation time `T_c`, in seconds.
    pub fn correlation_time(&self) -> T {
        self.correlation_time
    }

    /// Stationary standard deviation, in units.
    pub fn sigma(&self) -> T {
        self.sigma
    }

    /// Two-sided PSD of the driving noise, `q = 2 sigma^2 / T_c`, in units^2/s.
    pub fn driving_psd(&self) -> T {
        let s = self.sigma.to_f64();
        T::from_f64(2.0 * s * s / self.correlation_time.to_f64())
    }

    /// The exact AR(1) sampling of this process every `dt` seconds:
    /// `phi = exp(-dt / T_c)`, `sigma_w^2 = sigma^2 (1 - phi^2)`.
    ///
    /// `phi` is rounded to `T` once, and the noise variance is made from that rounded `phi`
    /// (`1 - phi^2 = (1 - phi)(1 + phi)`, with `1 - phi` exact in `f64`), so that the model's
    /// stationary variance is `sigma^2` whatever the rounding. The rounding moves the
    /// correlation time the model implies, `-dt / ln phi`, by the relative error of `1 - phi`
    /// against `-expm1(-dt / T_c)`; where that exceeds 1 % the process is not representable in
    /// `T`. In `f32` (spacing `6e-8` below 1) that can happen only for `dt / T_c` below `3e-6`
    /// (for example `dt = 1e-4` s against `T_c = 1000` s), and `phi` rounds to 1 below `3e-8`;
    /// in `f64` only below `6e-15`.
    ///
    /// # Errors
    ///
    /// [`ModelError::Interval`] for a bad `dt`, [`ModelError::NonFinite`] for a bad `mean`;
    /// [`ModelError::Unrepresentable`] where `T` cannot represent the process, as above
    /// (including `phi` rounding to 1, which would be a random walk, not this process), and
    /// where the noise variance `sigma^2 (1 - phi^2)` underflows to 0 or overflows in `T`
    /// (in `f32`, `sigma` below about `1e-19` or above about `1e19`).
    pub fn to_ar1(&self, dt: T, mean: T) -> Result<ArModel<T, 1>, ModelError> {
        if !(dt.is_finite() && dt > T::ZERO) {
            return Err(ModelError::Interval);
        }
        if !mean.is_finite() {
            return Err(ModelError::NonFinite);
        }
        let ratio = dt.to_f64() / self.correlation_time.to_f64();
        // 1 - exp(-dt/T_c), to full relative precision however small dt/T_c is.
        let exact = -libm::expm1(-ratio);
        let phi = T::from_f64(libm::exp(-ratio));
        // Exact in f64 for phi in [0.5, 1] (Sterbenz), and f64 holds every f32 exactly.
        let one_minus = 1.0 - phi.to_f64();
        if !(exact > 0.0 && one_minus > 0.0)
            || libm::fabs(one_minus - exact) > GAUSS_MARKOV_TOLERANCE * exact
        {
            return Err(ModelError::Unrepresentable);
        }
        let s = self.sigma.to_f64();
        // The noise variance must be a positive, finite `T`: one that underflows to 0 would
        // make a noise-free model (stationary variance 0), one that overflows no model.
        let variance = T::from_f64(s * s * one_minus * (1.0 + phi.to_f64()));
        if !(variance.is_finite() && variance > T::ZERO) {
            return Err(ModelError::Unrepresentable);
        }
        ArModel::new([phi], variance, mean, dt)
    }
}

/// Largest relative error of `1 - phi` that [`GaussMarkov::to_ar1`] accepts.
const GAUSS_MARKOV_TOLERANCE: f64 = 1e-2;
