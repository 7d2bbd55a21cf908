//! The settings of the recursive estimators, validated once: what the channels of a sensor
//! share ([`Config`]) and what belongs to one channel ([`Channel`]).

use core::fmt;

use crate::Scalar;

/// Why a [`Config`], a [`Channel`] or a fixed-point setting was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The forgetting factor is not in (0, 1].
    Lambda,
    /// The initial regularisation `delta` is not positive and finite, or is too small or
    /// too large for the scalar to carry through the recursion (see [`Channel::new`]).
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
    /// The innovation gate's threshold is not finite and at least 1, or its run bound is 0.
    Gate,
    /// A prior model's coefficient is not finite, beyond `2 C(P, k)` (twice the largest
    /// `|a_k|` of an AR(`P`) model with its roots in the unit disc), or (fixed point) outside
    /// the coefficient format's range, +-4.
    Prior,
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
            Self::Gate => "the gate needs a finite k of at least 1 and a run bound of at least 1",
            Self::Prior => {
                "prior coefficients must be finite, |a_k| <= 2 C(P, k) (and within +-4 for the fixed-point lattice)"
            }
        })
    }
}

impl core::error::Error for ConfigError {}

/// What the channels of a sensor share, validated once: the forgetting factor, the sample
/// interval and whether the running mean is removed. What differs between channels (the
/// initial regularisation and the saturation limit, both in the channel's units) is a
/// [`Channel`], given to each estimator when it is made.
///
/// ```
/// use imu_ar::recursive::{Config, ConfigError};
///
/// let config = Config::new(0.999f32, 0.01).unwrap();
/// assert_eq!(config.lambda(), 0.999);
/// assert_eq!(Config::new(1.5f32, 0.01), Err(ConfigError::Lambda));
/// assert_eq!(Config::new(0.999f32, 0.0), Err(ConfigError::Interval));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config<T> {
    lambda: T,
    dt: T,
    demean: bool,
    gate: Option<Gate>,
}

/// An innovation gate ([`Config::with_gate`]): a sample whose a-priori prediction error
/// exceeds `k` times the current innovation standard deviation is rejected and counted in
/// [`Health::outliers`](super::Health::outliers), unless `run` samples in a row have just been
/// rejected.
///
/// The rule, so that a genuine change (a step in the level, a new noise level) is never
/// rejected for good: after `run` consecutive rejections the gate opens, and it stays open
/// (every sample is taken) until a sample passes the test again. So at most `run` samples in
/// a row are ever rejected: a step is taken from its `run + 1`-th sample on, and the
/// estimator follows it as its forgetting factor says. A rejected sample changes nothing (the
/// mean, the weight and the state stay as they were); the sample after it is taken as the
/// next in time (the gate drops samples, as the NaN screening does). The test applies once the
/// innovation variance stands on a weight `W_n` of at least [`Gate::settled`] samples (20, or
/// half the memory `1/(1 - lambda)` where that is less: `W_n` never reaches 20 at
/// `lambda <= 0.95`); before that every sample is taken.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gate {
    k: f32,
    run: u32,
}

impl Gate {
    /// The weight `W_n` from which the gate tests, where the memory allows: 20 samples.
    pub const SETTLED: f32 = 20.0;

    /// A gate at `k` standard deviations (`k >= 1`; 4 to 6 is usual: a gate below one standard
    /// deviation would reject most samples) that opens after `run` consecutive rejections
    /// (`run >= 1`).
    ///
    /// # Errors
    ///
    /// [`ConfigError::Gate`].
    pub fn new(k: f32, run: u32) -> Result<Self, ConfigError> {
        if !(k.is_finite() && k >= 1.0 && run >= 1) {
            return Err(ConfigError::Gate);
        }
        Ok(Self { k, run })
    }

    /// The threshold, in standard deviations.
    pub fn k(&self) -> f32 {
        self.k
    }

    /// The largest number of consecutive rejections.
    pub fn run(&self) -> u32 {
        self.run
    }

    /// The weight `W_n` from which the gate tests at forgetting factor `lambda`:
    /// [`Gate::SETTLED`], or half the memory `1/(1 - lambda)` where that is less.
    pub fn settled(lambda: f64) -> f64 {
        let settled = f64::from(Self::SETTLED);
        if lambda < 1.0 {
            settled.min(0.5 / (1.0 - lambda))
        } else {
            settled
        }
    }
}

impl<T: Scalar> Config<T> {
    /// Forgetting factor `lambda` in (0, 1] (memory `1/(1 - lambda)` samples) and sample
    /// interval `dt` (s). The running mean is removed.
    ///
    /// # Errors
    ///
    /// [`ConfigError::Lambda`] or [`ConfigError::Interval`].
    pub fn new(lambda: T, dt: T) -> Result<Self, ConfigError> {
        if !(lambda.is_finite() && lambda > T::ZERO && lambda <= T::ONE) {
            return Err(ConfigError::Lambda);
        }
        if !(dt.is_finite() && dt > T::ZERO) {
            return Err(ConfigError::Interval);
        }
        Ok(Self {
            lambda,
            dt,
            demean: true,
            gate: None,
        })
    }

    /// With an innovation gate (off by default): see [`Gate`].
    pub fn with_gate(self, gate: Gate) -> Self {
        Self {
            gate: Some(gate),
            ..self
        }
    }

    /// The innovation gate, if any.
    pub fn gate(&self) -> Option<Gate> {
        self.gate
    }

    /// Whether to remove an exponentially weighted running mean (same `lambda`) before the
    /// estimator (default `true`).
    pub fn with_demean(self, demean: bool) -> Self {
        Self { demean, ..self }
    }

    /// The forgetting factor.
    pub fn lambda(&self) -> T {
        self.lambda
    }

    /// The sample interval, in seconds.
    pub fn dt(&self) -> T {
        self.dt
    }

    /// Whether a running mean is removed.
    pub fn demean(&self) -> bool {
        self.demean
    }

    /// Effective sample size `(1 + lambda) / (1 - lambda)` (variance-equivalent), or `None`
    /// for `lambda = 1` (growing memory: there the effective sample size is the number of
    /// samples, which only the estimator knows; see
    /// [`Lattice::weight`](super::Lattice::weight)).
    pub fn effective_samples(&self) -> Option<T> {
        (self.lambda < T::ONE).then(|| (T::ONE + self.lambda) / (T::ONE - self.lambda))
    }
}

/// What belongs to one channel, in that channel's units: the initial regularisation `delta`
/// (units^2) and the saturation limit (units). An estimator keeps its channel from
/// construction on; a gyro axis in deg/s and an accelerometer axis in g share a [`Config`]
/// but not a `Channel`.
///
/// ```
/// use imu_ar::recursive::{Channel, ConfigError};
///
/// // A gyro in deg/s (variance about 1e-3) and an accelerometer in g (about 1e-5), each
/// // with the limit half a count below its rail.
/// let gyro = Channel::new(1e-4f32)?.with_saturation(249.99)?;
/// let accel = Channel::new(1e-6f32)?.with_saturation(1.99997)?;
/// assert_eq!(gyro.saturation(), Some(249.99));
/// assert_eq!(accel.delta(), 1e-6);
/// assert_eq!(Channel::new(-1.0f32), Err(ConfigError::Delta));
/// # Ok::<(), ConfigError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Channel<T> {
    delta: T,
    saturation: Option<T>,
    /// Added to every energy update of the float estimators: `delta EPSILON^2`, at least the
    /// smallest normal value. Relative to `delta`, so that a record in other units (with
    /// `delta` in those units) takes the same path through the recursion.
    floor: T,
    /// Ceiling of the entries of the RLS factor `D`: `1e29 / delta`, at most `1 / MIN_POSITIVE`.
    ceiling: T,
}

impl<T: Scalar> Channel<T> {
    /// Initial regularisation `delta > 0`, in the channel's units squared; no saturation
    /// limit.
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
    /// [`ConfigError::Delta`].
    pub fn new(delta: T) -> Result<Self, ConfigError> {
        let (low, high) = (min_delta::<T>(), T::EPSILON / T::MIN_POSITIVE);
        if !(delta.is_finite() && delta >= low && delta <= high) {
            return Err(ConfigError::Delta);
        }
        let relative = delta * T::EPSILON * T::EPSILON;
        let floor = if relative > T::MIN_POSITIVE {
            relative
        } else {
            T::MIN_POSITIVE
        };
        let ceiling = (1e29 / delta.to_f64()).min(1.0 / T::MIN_POSITIVE.to_f64());
        Ok(Self {
            delta,
            saturation: None,
            floor,
            ceiling: T::from_f64(ceiling),
        })
    }

    /// Rejects (and counts as saturated) every sample with `|x| >= limit`, in the channel's
    /// units: set it just inside the sensor's full scale (see
    /// [`Scale::gyro_saturation`](crate::sensor::Scale::gyro_saturation)), so that clipped
    /// samples do not bias the model.
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

    /// The initial regularisation.
    pub fn delta(&self) -> T {
        self.delta
    }

    /// The saturation limit, if any.
    pub fn saturation(&self) -> Option<T> {
        self.saturation
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
    pub(crate) fn screen(&self, x: T) -> Result<T, Rejection> {
        if !x.is_finite() {
            return Err(Rejection::NonFinite);
        }
        match self.saturation {
            Some(limit) if x.abs() >= limit => Err(Rejection::Saturated),
            _ => Ok(x),
        }
    }

    /// `delta lambda^k`, by `k` multiplications, held at or above `MIN_POSITIVE / EPSILON`
    /// (the smallest accepted `delta`; see [`Channel::new`]).
    pub(crate) fn delta_lambda_pow(&self, lambda: T, k: usize) -> T {
        let low = min_delta::<T>();
        (0..k).fold(self.delta, |acc, _| {
            let next = acc * lambda;
            if next > low { next } else { low }
        })
    }
}

/// A float estimator's prior `a0`, checked ([`ConfigError::Prior`]): every entry finite and
/// `|a_k| <= 2 C(P, k)`, twice the largest `a_k` of any AR(`P`) model whose roots lie in the
/// unit disc (stable or on the edge of it: `(1 - z^-1)^P` reaches `C(P, k)`). A prior beyond
/// that predicts with a gain the data cannot have; far enough beyond, its prediction errors
/// overflow and the estimator would restart on every sample.
pub(crate) fn finite_prior<T: Scalar, const P: usize>(a0: &[T; P]) -> Result<[T; P], ConfigError> {
    // k and C(P, k) counted in f64 (exact for every P a model can have): no integer count
    // with an overflow path.
    let (mut binomial, mut k) = (1.0f64, 0.0f64);
    for a in a0 {
        k += 1.0;
        binomial = binomial * (P as f64 - k + 1.0) / k;
        if !(a.is_finite() && a.to_f64().abs() <= 2.0 * binomial) {
            return Err(ConfigError::Prior);
        }
    }
    Ok(*a0)
}

/// Why a sample was not used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Rejection {
    NonFinite,
    Saturated,
}

/// The smallest `delta` [`Channel::new`] accepts, `MIN_POSITIVE / EPSILON`, and the floor of
/// the initial energies `delta lambda^k`.
fn min_delta<T: Scalar>() -> T {
    T::MIN_POSITIVE / T::EPSILON
}
