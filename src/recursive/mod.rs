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
    /// The initial regularisation `delta` is not positive and finite, or is too small or
    /// too large for the scalar to carry through the recursion (see [`Config::new`]).
    Delta,
    /// The sample interval `dt` is not positive and finite.
    Interval,
    /// The saturation limit is not positive.
    Saturation,
    /// The fixed-point scale is not positive and finite, or makes `delta` vanish in the
    /// energy format.
    Scale,
    /// The forgetting factor is below the fixed-point lattice's range, `[0.9, 1]`.
    FixedLambda,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Lambda => "forgetting factor lambda must be in (0, 1]",
            Self::Delta => {
                "regularisation delta must be positive and finite, and within the scalar's range \
                 (about 1e-31..1e31 in f32, 1e-292..1e292 in f64)"
            }
            Self::Interval => crate::model::INTERVAL,
            Self::Saturation => "saturation limit must be positive",
            Self::Scale => "fixed-point scale must be positive and keep delta representable",
            Self::FixedLambda => "the fixed-point lattice needs lambda in [0.9, 1]",
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
    /// Added to every energy update of the float estimators: `delta EPSILON^2`, at least the
    /// smallest normal value. Relative to `delta`, so that a record in other units (with
    /// `delta` in those units) takes the same path through the recursion.
    floor: T,
    /// Ceiling of the entries of the RLS factor `D`: `1e29 / delta`, at most `1 / MIN_POSITIVE`.
    ceiling: T,
}

impl<T: Scalar> Config<T> {
    /// Forgetting factor `lambda` in (0, 1] (memory `1/(1 - lambda)` samples), initial
    /// regularisation `delta > 0` and sample interval `dt` (s). The running mean is removed.
    ///
    /// `delta` only shapes the first few `1/(1 - lambda)` samples; `0.01..1` times the expected
    /// variance of the input is a good choice. It also sets the scale of the estimators' only
    /// absolute safeguards (the energy floor `delta EPSILON^2` and the RLS ceiling
    /// `1e29 / delta`): with `delta` in the data's units squared, data in other units (scaled
    /// by `s`, `delta` by `s^2`) gives the same coefficients as far as the scalar's exponent
    /// range allows.
    ///
    /// `delta` must lie in `[MIN_POSITIVE / EPSILON, EPSILON / MIN_POSITIVE]` of the scalar
    /// (about `1e-31..1e31` in `f32`, `1e-292..1e292` in `f64`): a smaller one (a subnormal,
    /// say) makes the initial energies `delta lambda^k` lose their precision or their
    /// reciprocals overflow, so that the recursion breaks down on every sample. For the same
    /// reason the initial energies `delta lambda^k` (`k` up to the order `P`) are held at or
    /// above that smallest `delta`: a small `delta` with a small `lambda` and a high order
    /// (`delta lambda^P` below `1e-31` in `f32`) starts from a slightly stronger
    /// regularisation of the highest lags instead of breaking down. Above it (every
    /// practical `f64` configuration) the start is exactly the problem's.
    ///
    /// # Errors
    ///
    /// [`ConfigError`] naming the parameter out of range.
    pub fn new(lambda: T, delta: T, dt: T) -> Result<Self, ConfigError> {
        if !(lambda.is_finite() && lambda > T::ZERO && lambda <= T::ONE) {
            return Err(ConfigError::Lambda);
        }
        let (low, high) = (min_delta::<T>(), T::EPSILON / T::MIN_POSITIVE);
        if !(delta.is_finite() && delta >= low && delta <= high) {
            return Err(ConfigError::Delta);
        }
        if !(dt.is_finite() && dt > T::ZERO) {
            return Err(ConfigError::Interval);
        }
        let relative = delta * T::EPSILON * T::EPSILON;
        let floor = if relative > T::MIN_POSITIVE {
            relative
        } else {
            T::MIN_POSITIVE
        };
        let ceiling = (1e29 / delta.to_f64()).min(1.0 / T::MIN_POSITIVE.to_f64());
        Ok(Self {
            lambda,
            delta,
            dt,
            demean: true,
            saturation: None,
            floor,
            ceiling: T::from_f64(ceiling),
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
    /// for `lambda = 1` (growing memory: there the effective sample size is the number of
    /// samples, which only the estimator knows; see [`Lattice::weight`]).
    pub fn effective_samples(&self) -> Option<T> {
        (self.lambda < T::ONE).then(|| (T::ONE + self.lambda) / (T::ONE - self.lambda))
    }

    /// The energy floor of the float estimators, `delta EPSILON^2` (at least the smallest
    /// normal value).
    pub(crate) fn floor(&self) -> T {
        self.floor
    }

    /// The ceiling of the RLS factor `D`, `1e29 / delta` (at most `1 / MIN_POSITIVE`).
    pub(crate) fn ceiling(&self) -> T {
        self.ceiling
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

    /// `delta lambda^k`, by `k` multiplications, held at or above `MIN_POSITIVE / EPSILON`
    /// (the smallest accepted `delta`; see [`Config::new`]).
    pub(crate) fn delta_lambda_pow(&self, k: usize) -> T {
        let low = min_delta::<T>();
        (0..k).fold(self.delta, |acc, _| {
            let next = acc * self.lambda;
            if next > low { next } else { low }
        })
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
/// the health counters, and the last good model, held through a restart.
///
/// The estimator refreshes the snapshot itself ([`Shell::refresh`]) every
/// [`snapshot_interval`] accepted samples while no restart is settling, so that the model held
/// after a restart does not depend on when, or whether, the caller asked for one.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) struct Shell<T, const P: usize> {
    pub(crate) mean: RunningMean<T>,
    pub(crate) weight: WeightSum<T>,
    pub(crate) health: Health,
    /// The last good model, held while a restarted estimator settles.
    snapshot: Option<crate::ArModel<T, P>>,
    /// Samples to go before a restarted estimator publishes again.
    hold: u32,
}

/// The smallest `delta` [`Config::new`] accepts, `MIN_POSITIVE / EPSILON`, and the floor of
/// the initial energies `delta lambda^k`.
fn min_delta<T: Scalar>() -> T {
    T::MIN_POSITIVE / T::EPSILON
}

/// The largest weight `W_n` a float estimator lets grow: `1/(4 EPSILON)`, `2^21` in `f32`
/// (`2^50` in `f64`, never reached). Beyond it `W_n + 1` and `E + e^2` lose their precision
/// (`W_n` stops at `2^24` in `f32` while the energy keeps growing), so at the limit the weight
/// and the energies are halved together: the memory of an `f32` estimator at `lambda = 1` stops
/// growing at about two million samples, and its innovation variance stays right.
fn weight_limit<T: Scalar>() -> T {
    T::ONE / (T::from_f64(4.0) * T::EPSILON)
}

/// Accepted samples between two snapshots of the model an order-`P` float estimator holds
/// through a restart: `4 P^2`, at least 32, rounded up to a power of two (so that the test on
/// the sample count is a mask). Making the lattice's coefficients costs `O(P^3/3)`, so the
/// snapshot adds `O(P/12)` operations per sample on average (with the test, 1 to 7
/// instructions per stage of the `f32` lattice on a Cortex-M4F, `cargo qemu bench`); for
/// [`Rls`] and [`Sftf`] it is a copy of `P` coefficients, and no measurable cost.
/// Saturates for orders too large for the product (`2^63` at most), no panic.
pub const fn snapshot_interval(p: usize) -> u64 {
    let p = p as u64;
    let quadratic = p.saturating_mul(p).saturating_mul(4);
    let at_least = if quadratic > 32 { quadratic } else { 32 };
    match at_least.checked_next_power_of_two() {
        Some(interval) => interval,
        None => 1 << 63,
    }
}

impl<T: Scalar, const P: usize> Shell<T, P> {
    pub(crate) fn new() -> Self {
        Self {
            mean: RunningMean::new(),
            weight: WeightSum(T::ZERO),
            health: Health::default(),
            snapshot: None,
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

    /// Counts a restart, forgets the mean and the weight, and holds the snapshot for
    /// `3/(1 - lambda)` samples, at most 30 000. A restart while a hold runs does not extend
    /// it: an estimator restarted again and again (the SFTF on data it cannot follow) still
    /// publishes its own model, and refreshes its snapshot, once the first hold is over.
    pub(crate) fn restart(&mut self, config: &Config<T>) {
        self.health.restarts = self.health.restarts.saturating_add(1);
        self.mean = RunningMean::new();
        self.weight = WeightSum(T::ZERO);
        if self.hold == 0 {
            self.hold = lattice::hold_after_restart(config.lambda().to_f64());
        }
    }

    /// Whether the weight has reached [`weight_limit`]: then the estimator halves its
    /// energies and calls [`Shell::halve_weight`], so that energy and weight keep growing
    /// together (at `lambda = 1`, or a `lambda` within `1/weight_limit` of 1).
    #[inline]
    pub(crate) fn weight_full(&self) -> bool {
        self.weight.0 >= weight_limit::<T>()
    }

    /// Halves the weight `W_n` (with the estimator's energies: see [`Shell::weight_full`]).
    pub(crate) fn halve_weight(&mut self) {
        self.weight.0 *= T::from_f64(0.5);
    }

    /// `E / W_n`, the innovation variance of an energy; `None` before the first sample.
    pub(crate) fn per_sample(&self, energy: T) -> Option<T> {
        (self.weight.0 > T::ZERO).then(|| energy / self.weight.0)
    }

    /// The model of the current state: coefficients `a` (computed only when called) and
    /// innovation variance `energy / W_n`; `None` if it is not a valid model.
    fn current(
        &self,
        config: &Config<T>,
        energy: T,
        a: impl FnOnce() -> Option<[T; P]>,
    ) -> Option<crate::ArModel<T, P>> {
        let variance = self.per_sample(energy)?;
        crate::ArModel::new(a()?, variance, self.mean.mean(), config.dt()).ok()
    }

    /// Called by the estimator after every healthy update: every [`snapshot_interval`]
    /// accepted samples, unless a restart is settling, the current model (if valid) becomes
    /// the one held through the next restart.
    #[inline]
    pub(crate) fn refresh(
        &mut self,
        config: &Config<T>,
        energy: T,
        a: impl FnOnce() -> Option<[T; P]>,
    ) {
        if self.health.samples & (snapshot_interval(P) - 1) == 0
            && self.hold == 0
            && let Some(m) = self.current(config, energy, a)
        {
            self.snapshot = Some(m);
        }
    }

    /// The model of the current state, unless a restarted estimator is still settling: then,
    /// and when the current state makes no valid model, the last snapshot.
    pub(crate) fn model(
        &self,
        config: &Config<T>,
        energy: T,
        a: impl FnOnce() -> Option<[T; P]>,
    ) -> Option<crate::ArModel<T, P>> {
        if self.hold == 0 {
            self.current(config, energy, a).or(self.snapshot)
        } else {
            self.snapshot
        }
    }
}
