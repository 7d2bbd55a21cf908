//! Recursive estimators: one sample in, an updated AR model out, online on the MCU.
//!
//! Both cores solve, after every sample, the prewindowed exponentially weighted least-squares
//! problem of numerics.md section 0 (`x_i = 0` for `i <= 0`):
//!
//! ```text
//! a_n = argmin_a  sum_{i=1..n} lambda^(n-i) (y_i - a^T phi_i)^2 + delta lambda^n a^T D a,
//! phi_i = [y_{i-1} .. y_{i-P}],   D = diag(lambda^(P-1), .., lambda, 1)
//! ```
//!
//! with `y = x - mean` (see [`RunningMean`]) or `y = x`. `D` is the one initial weighting that
//! the O(P) lattice can start from exactly; it is the problem's fictitious sample `sqrt(delta)` at
//! time `-P`. [`Rls`] can also start from the textbook `P_0 = I / delta` (ridge weight
//! `delta lambda^n ||a||^2`).
//!
//! | core | cost per sample | output |
//! |---|---|---|
//! | [`Rls`] | `O(P^2)` (Bierman U-D) | coefficients every sample |
//! | [`Lattice`] | `O(P)` (a-priori error-feedback LSL) | errors and energies of every order every sample; coefficients on request |
//!
//! A [`Config`] (forgetting factor, regularisation, sample interval, options) is validated once
//! and shared by the states of many channels. `update` is infallible and never panics: a NaN,
//! infinite or saturated sample is rejected and counted and changes nothing; a numerical
//! breakdown re-initialises the state while the last good model stays published
//! ([`Health`] counts all three).

mod arith;
pub(crate) mod lattice;
mod mean;
mod order;
mod rls;
mod sftf;

use core::fmt;

use crate::Scalar;

pub use arith::{Arith, FloatArith, FloatParams};
pub use lattice::{Core, Lattice};
pub use mean::RunningMean;
pub use order::{OrderRule, OrderSelector};
pub use rls::{Rls, RlsInit};
pub use sftf::Sftf;

/// Why a [`Config`] was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The forgetting factor is not in (0, 1].
    Lambda,
    /// The initial regularisation `delta` is not positive and finite.
    Delta,
    /// The sample interval is not positive and finite.
    Interval,
    /// The saturation limit is not positive.
    Saturation,
    /// The fixed-point scale is not positive and finite, or makes `delta` vanish in the
    /// energy format.
    Scale,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Lambda => "forgetting factor lambda must be in (0, 1]",
            Self::Delta => "regularisation delta must be positive and finite",
            Self::Interval => "sample interval must be positive and finite",
            Self::Saturation => "saturation limit must be positive",
            Self::Scale => "fixed-point scale must be positive and keep delta representable",
        })
    }
}

impl core::error::Error for ConfigError {}

/// Settings shared by the recursive estimators of many channels, validated once.
///
/// ```
/// use imu_ar::recursive::Config;
///
/// let config = Config::new(0.999f32, 0.1, 0.01).unwrap().with_saturation(250.0).unwrap();
/// assert_eq!(config.lambda(), 0.999);
/// assert!(Config::new(1.5f32, 0.1, 0.01).is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config<T> {
    lambda: T,
    delta: T,
    dt: T,
    demean: bool,
    saturation: Option<T>,
}

impl<T: Scalar> Config<T> {
    /// Forgetting factor `lambda` in (0, 1] (memory `1/(1 - lambda)` samples), initial
    /// regularisation `delta > 0` and sample interval `dt` (s). The running mean is removed.
    ///
    /// `delta` only shapes the first few `1/(1 - lambda)` samples; `0.01..1` times the expected
    /// variance of the input is a good choice.
    ///
    /// # Errors
    ///
    /// [`ConfigError`] naming the parameter out of range.
    pub fn new(lambda: T, delta: T, dt: T) -> Result<Self, ConfigError> {
        if !(lambda.is_finite() && lambda > T::ZERO && lambda <= T::ONE) {
            return Err(ConfigError::Lambda);
        }
        if !(delta.is_finite() && delta > T::ZERO) {
            return Err(ConfigError::Delta);
        }
        if !(dt.is_finite() && dt > T::ZERO) {
            return Err(ConfigError::Interval);
        }
        Ok(Self {
            lambda,
            delta,
            dt,
            demean: true,
            saturation: None,
        })
    }

    /// Whether to remove an exponentially weighted running mean (same `lambda`) before the
    /// estimator (default `true`).
    pub fn with_demean(self, demean: bool) -> Self {
        Self { demean, ..self }
    }

    /// Rejects (and counts as saturated) every sample with `|x| >= limit`: set it just inside
    /// the sensor's full scale, so that clipped samples do not bias the model.
    ///
    /// # Errors
    ///
    /// [`ConfigError::Saturation`] unless `limit` is positive (infinity disables the check).
    pub fn with_saturation(self, limit: T) -> Result<Self, ConfigError> {
        let positive = limit > T::ZERO;
        if !positive {
            return Err(ConfigError::Saturation);
        }
        Ok(Self {
            saturation: Some(limit),
            ..self
        })
    }

    /// The forgetting factor.
    pub fn lambda(&self) -> T {
        self.lambda
    }

    /// The initial regularisation.
    pub fn delta(&self) -> T {
        self.delta
    }

    /// The sample interval, in seconds.
    pub fn dt(&self) -> T {
        self.dt
    }

    /// Whether a running mean is removed.
    pub fn demean(&self) -> bool {
        self.demean
    }

    /// The saturation limit, if any.
    pub fn saturation(&self) -> Option<T> {
        self.saturation
    }

    /// Effective sample size `(1 + lambda) / (1 - lambda)` (variance-equivalent), or `None`
    /// for `lambda = 1` (growing memory).
    pub fn effective_samples(&self) -> Option<T> {
        (self.lambda < T::ONE).then(|| (T::ONE + self.lambda) / (T::ONE - self.lambda))
    }

    /// Classifies a raw sample: `Ok` when it may enter the estimator.
    #[inline]
    pub(crate) fn screen(&self, x: T) -> Result<(), Rejection> {
        if !x.is_finite() {
            return Err(Rejection::NonFinite);
        }
        match self.saturation {
            Some(limit) if x.abs() >= limit => Err(Rejection::Saturated),
            _ => Ok(()),
        }
    }

    /// `delta lambda^k`, by `k` multiplications.
    pub(crate) fn delta_lambda_pow(&self, k: usize) -> T {
        (0..k).fold(self.delta, |acc, _| acc * self.lambda)
    }
}

/// Why a sample was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rejection {
    NonFinite,
    Saturated,
}

/// Counters that say what happened to the samples a state was given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Health {
    /// Samples that entered the estimator.
    pub samples: u64,
    /// Samples rejected as NaN or infinite.
    pub non_finite: u64,
    /// Samples rejected as saturated ([`Config::with_saturation`]).
    pub saturated: u64,
    /// Re-initialisations after a numerical breakdown.
    pub restarts: u64,
    /// Internal values saturated to their number format (fixed point only; 0 for floats).
    pub clipped: u64,
}

impl Health {
    /// All rejected samples.
    pub fn rejected(&self) -> u64 {
        self.non_finite + self.saturated
    }

    pub(crate) fn reject(&mut self, why: Rejection) {
        match why {
            Rejection::NonFinite => self.non_finite = self.non_finite.saturating_add(1),
            Rejection::Saturated => self.saturated = self.saturated.saturating_add(1),
        }
    }
}

/// Exponentially weighted sample count `W_n = lambda W_{n-1} + 1`, the normaliser of the
/// innovation variance `s_w^2 = E_n / W_n` (`= E_n (1-lambda)/(1-lambda^n)` for `lambda < 1`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct WeightSum<T>(pub(crate) T);

impl<T: Scalar> WeightSum<T> {
    #[inline]
    pub(crate) fn push(&mut self, lambda: T) {
        self.0 = lambda * self.0 + T::ONE;
    }
}

/// What every float estimator keeps around its recursion: the running mean, the weight sum,
/// the health counters, and the published model held through a restart.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct Shell<T, const P: usize> {
    pub(crate) mean: RunningMean<T>,
    pub(crate) weight: WeightSum<T>,
    pub(crate) health: Health,
    published: Option<crate::ArModel<T, P>>,
    /// Samples to go before a restarted estimator publishes again.
    hold: u32,
}

impl<T: Scalar, const P: usize> Shell<T, P> {
    pub(crate) fn new() -> Self {
        Self {
            mean: RunningMean::new(),
            weight: WeightSum(T::ZERO),
            health: Health::default(),
            published: None,
            hold: 0,
        }
    }

    /// Screens `x` (a rejection is counted and changes nothing else) and returns the sample
    /// the recursion takes: `x` less the running mean, or `x`.
    #[inline]
    pub(crate) fn intake(&mut self, config: &Config<T>, x: T) -> Option<T> {
        if let Err(why) = config.screen(x) {
            self.health.reject(why);
            return None;
        }
        self.health.samples = self.health.samples.saturating_add(1);
        self.hold = self.hold.saturating_sub(1);
        let lambda = config.lambda();
        let y = if config.demean() {
            self.mean.center(lambda, x)
        } else {
            x
        };
        self.weight.push(lambda);
        Some(y)
    }

    /// Counts a restart, forgets the mean and the weight, and holds the published model for
    /// `3/(1 - lambda)` samples.
    pub(crate) fn restart(&mut self, config: &Config<T>) {
        self.health.restarts = self.health.restarts.saturating_add(1);
        self.mean = RunningMean::new();
        self.weight = WeightSum(T::ZERO);
        self.hold = lattice::hold_after_restart(config.lambda().to_f64());
    }

    /// `E / W_n`, the innovation variance of an energy; `None` before the first sample.
    pub(crate) fn per_sample(&self, energy: T) -> Option<T> {
        (self.weight.0 > T::ZERO).then(|| energy / self.weight.0)
    }

    /// The model of coefficients `a` (computed only when needed) and energy `energy`
    /// (innovation variance `energy / W_n`), unless a restarted estimator is still settling:
    /// then, and when no valid model can be made, the last one published.
    pub(crate) fn model(
        &mut self,
        config: &Config<T>,
        energy: T,
        a: impl FnOnce() -> Option<[T; P]>,
    ) -> Option<crate::ArModel<T, P>> {
        if self.hold == 0
            && let Some(variance) = self.per_sample(energy)
            && let Some(a) = a()
            && let Ok(m) = crate::ArModel::new(a, variance, self.mean.mean(), config.dt())
        {
            self.published = Some(m);
        }
        self.published
    }
}
