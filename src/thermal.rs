//! Online compensation of the bias's temperature dependence, ahead of the AR estimators.
//!
//! A MEMS gyro's or accelerometer's bias moves with the die temperature (a few tenths of deg/s
//! and tens of mg over 20 K are common), and an error model fitted at one temperature is wrong
//! at another: the reason to estimate it online. [`ThermalBias`] learns, per axis and sample by
//! sample, the bias as a polynomial of degree `N - 1` in the normalised temperature
//!
//! ```text
//! u = (T - T_ref) / h,   T_ref = (t_min + t_max) / 2,   h = (t_max - t_min) / 2
//! bias(T) = sum_{k<N} c_k u^k = c^T phi(T),   phi = [1, u, .., u^(N-1)]
//! ```
//!
//! and hands on the residual `x - bias(T)`, which feeds the estimators and the noise fit. With
//! `N = 4` this is PX4's thermal model (`TemperatureCompensation::calc_thermal_offsets_3D`,
//! src/modules/temperature_compensation: `offset = x0 + x1 dT + x2 dT^2 + x3 dT^3`,
//! `dT = T - ref_temp`, the temperature clipped to the calibration range), learned online
//! instead of from a chamber run; [`ThermalBias::per_kelvin`] gives its coefficients about
//! `T_ref`. The normalisation keeps `|u| <= 1`, so that the powers of `u` stay of one size and
//! `f32` stays well conditioned.
//!
//! # The problem solved
//!
//! After the `n`-th learned sample, `c_n` is the exact solution of
//!
//! ```text
//! c_n = argmin_c  sum_{i<=n} lambda^(n-i) (x_i - c^T phi_i)^2
//!               + sum_{i<=n} lambda^(n-i) w (c_k(i) - p_k(i))^2 + delta lambda^n ||c - s||^2,
//! k(i) = (i - 1) mod N,   w = delta (1 - lambda^N)
//! ```
//!
//! with the prior `p` and the start `s`: both a stored calibration when one is given
//! ([`ThermalBias::with_prior`]); otherwise `p = 0` and `s = [x_1, 0, .., 0]`, a constant
//! bias equal to the first sample, as the estimators' running mean starts at the first sample
//! (the first residual is 0, not the whole bias, and the start is forgotten as the data come
//! in). The first sum is exponentially weighted least squares. The second is a regularisation
//! that is not forgotten: every sample adds one pseudo-observation `c_k = p_k` of weight `w`,
//! the coefficients taking turns, so that in the steady state each coefficient carries a prior
//! weight between `delta lambda^(N-1)` and `delta` (the `delta lambda^n` start decays into it).
//! This is the regularised tracking of Gunnarsson ("Combining tracking and regularization in
//! recursive least squares identification", CDC 1996), `R_n = lambda R_{n-1} + phi phi^T +
//! (1 - lambda) delta I`, with the full-rank term spread over `N` samples as rank-one terms.
//!
//! # A temperature that does not move
//!
//! At a constant temperature only `c^T phi(T)` is observed; the other `N - 1` directions are
//! unidentifiable. Plain exponential forgetting divides the covariance `P = R^-1` by `lambda`
//! every sample in them, and it grows without bound ("wind-up") until it overflows or a
//! temperature change makes a huge correction. Here the information matrix never falls below
//! the regularisation, `R_n >= delta lambda^(N-1) I`, so `P <= I / (delta lambda^(N-1))` at
//! every sample, whatever the temperature does ([`ThermalBias::leverage`] reads `phi^T P phi`).
//! The unidentifiable directions relax towards the prior with the memory's time constant, while
//! the bias at the temperature held stays fitted. This was chosen over directional forgetting
//! (forgetting only along excited directions) because it keeps the estimate the solution of a
//! stated least-squares problem, which the tests check against a direct solve at every sample,
//! and because it costs two rank-one updates: `O(N^2)` per sample, no matrix inverse.
//!
//! # Numerics
//!
//! `P` is kept as `U D U^T` and updated by Bierman's square-root-free algorithm (Bierman 1977),
//! as [`Rls`](crate::recursive::Rls) does: `P` stays symmetric and positive definite by
//! construction. About `3 N^2` multiplications and `3 N` divisions per sample.
//!
//! Measured against an `f64` direct solve of the problem above (host-tests/tests/host/thermal.rs,
//! 25 to 45 deg C ramps, cycles, steps and still spells, `lambda` 0.999 to 1, `delta` 0.01 and
//! 1): the `f64` coefficients agree to `1e-9` at every sample (measured: `2e-10`). In `f32`
//! the fitted bias and the residual stay within 0.0013 noise sigma of the reference's where the
//! temperature keeps moving; where it stands still or jumps to a temperature not met before,
//! the weakly excited directions carry rounding error, within a third of the estimate's own
//! standard error (`sigma sqrt(phi^T P phi)`, [`ThermalBias::leverage`]).
//!
//! # Per-sample path
//!
//! [`ThermalBias::update`] never panics and never returns NaN: a NaN or infinite sample or
//! temperature is rejected and counted, and changes nothing; so is a sample at or beyond the
//! saturation limit. A temperature outside `[t_min, t_max]` is compensated at the nearest end of
//! the range (as PX4 clips it) and not learned from. Every count is in [`ThermalHealth`].
//!
//! ```
//! use imu_ar::thermal::{ThermalBias, ThermalConfig};
//!
//! // Shared by the six axes: a memory of 10^5 samples (1000 s at 100 Hz), 25..45 deg C.
//! let config = ThermalConfig::<f32, 4>::new(0.99999, 25.0, 45.0)?;
//! let mut gx = ThermalBias::new(&config);
//! for i in 0..20_000u32 {
//!     let celsius = 25.0 + 20.0 * i as f32 / 20_000.0;
//!     let dt = celsius - 25.0;
//!     // A bias of 0.5 deg/s at 25 deg C, 0.02 deg/s per K, slightly curved.
//!     let x = 0.5 + 0.02 * dt - 3e-4 * dt * dt;
//!     let residual = gx.update(&config, x, celsius).unwrap();
//!     if i > 10_000 {
//!         assert!(residual.abs() < 1e-4, "{i}: {residual}");
//!     }
//! }
//! let bias_40 = gx.bias(&config, 40.0).unwrap();
//! assert!((bias_40 - (0.5 + 0.3 - 3e-4 * 225.0)).abs() < 1e-4);
//! // About T_ref = 35 deg C: 0.67 deg/s, 0.014 deg/s/K, -3e-4 deg/s/K^2, 0.
//! let b = gx.per_kelvin(&config);
//! assert!((b[0] - 0.67).abs() < 1e-4 && (b[1] - 0.014).abs() < 1e-5 && b[3].abs() < 1e-6);
//! # Ok::<(), imu_ar::thermal::ThermalError>(())
//! ```

use core::fmt;

use crate::Scalar;

/// Why a thermal setting was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ThermalError {
    /// The forgetting factor is not in (0, 1].
    Lambda,
    /// The temperature range is not finite with `t_min < t_max`.
    Range,
    /// `delta` is not positive and finite, or `delta` or `delta lambda^N` is outside the
    /// scalar's range (see [`ThermalConfig::with_delta`]).
    Delta,
    /// A prior coefficient is not finite or exceeds the magnitude limit.
    Prior,
    /// The saturation limit is not positive.
    Saturation,
}

impl fmt::Display for ThermalError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Lambda => "forgetting factor lambda must be in (0, 1]",
            Self::Range => "temperature range must be finite with t_min < t_max",
            Self::Delta => {
                "regularisation delta must be positive and finite, with delta and \
                 delta lambda^N within the scalar's range"
            }
            Self::Prior => "prior coefficients must be finite and within the magnitude limit",
            Self::Saturation => "saturation limit must be positive",
        })
    }
}

impl core::error::Error for ThermalError {}

/// What the thermal stages of a sensor's axes share, validated once: the forgetting factor,
/// the temperature range (which sets the normalisation) and the regularisation `delta`, for
/// polynomials of `N` coefficients (degree `N - 1`; PX4 uses `N = 4`).
///
/// ```
/// use imu_ar::thermal::{ThermalConfig, ThermalError};
///
/// let config = ThermalConfig::<f32, 4>::new(0.9999, -10.0, 70.0)?;
/// assert_eq!((config.reference(), config.half_width()), (30.0, 40.0));
/// assert_eq!(ThermalConfig::<f32, 4>::new(0.9999, 70.0, -10.0), Err(ThermalError::Range));
/// assert_eq!(config.with_delta(0.0), Err(ThermalError::Delta));
/// # Ok::<(), ThermalError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ThermalConfig<T, const N: usize> {
    lambda: T,
    inv_lambda: T,
    t_min: T,
    t_max: T,
    centre: T,
    inv_half: T,
    delta: T,
    /// `delta (1 - lambda^N)`, the weight of one pseudo-observation of the prior.
    weight: T,
    /// `1 / weight` (unused when `weight` is 0, at `lambda = 1`).
    inv_weight: T,
}

/// The default regularisation: the prior counts as a hundredth of a sample per coefficient.
const DEFAULT_DELTA: f64 = 0.01;

impl<T: Scalar, const N: usize> ThermalConfig<T, N> {
    /// Forgetting factor `lambda` in (0, 1] (memory `1/(1 - lambda)` samples: the bias's
    /// temperature law changes slowly, so choose a long one, `0.9999` to `1`) and the range of
    /// temperatures met in operation, in deg C (`t_min < t_max`). The polynomial is in
    /// `u = (T - T_ref)/h`, the range mapped to `[-1, 1]`: a range much wider than the
    /// temperatures actually met conditions the fit less well. `delta` is 0.01
    /// ([`ThermalConfig::with_delta`]).
    ///
    /// # Errors
    ///
    /// [`ThermalError::Lambda`], [`ThermalError::Range`], or [`ThermalError::Delta`] when
    /// `0.01 lambda^N` is below the scalar's range.
    pub fn new(lambda: T, t_min: T, t_max: T) -> Result<Self, ThermalError> {
        const { assert!(N > 0, "the polynomial needs at least one coefficient") };
        if !(lambda.is_finite() && lambda > T::ZERO && lambda <= T::ONE) {
            return Err(ThermalError::Lambda);
        }
        let (lo, hi) = (t_min.to_f64(), t_max.to_f64());
        let half = (hi - lo) / 2.0;
        let inv_half = T::from_f64(1.0 / half);
        if !(t_min.is_finite() && t_max.is_finite() && half > 0.0 && inv_half.is_finite()) {
            return Err(ThermalError::Range);
        }
        Self {
            lambda,
            inv_lambda: T::from_f64(1.0 / lambda.to_f64()),
            t_min,
            t_max,
            centre: T::from_f64(lo + half),
            inv_half,
            delta: T::ZERO,
            weight: T::ZERO,
            inv_weight: T::ZERO,
        }
        .with_delta(T::from_f64(DEFAULT_DELTA))
    }

    /// The regularisation `delta > 0`: the weight of the prior, in samples, per coefficient
    /// (dimensionless: the coefficients are in the sample's units and `|u| <= 1`). It bounds the
    /// covariance, `P <= I / (delta lambda^(N-1))`, so it sets how far the coefficients can
    /// move when the temperature starts to move after a long still spell; and it pulls the
    /// unidentifiable directions to the prior. Any value well below `1/(1 - lambda)` leaves the
    /// fit of an excited polynomial practically unbiased.
    ///
    /// # Errors
    ///
    /// [`ThermalError::Delta`] unless `delta` and `delta lambda^N` lie in
    /// `[MIN_POSITIVE / EPSILON, EPSILON / MIN_POSITIVE]` of the scalar (about `1e-31..1e31`
    /// in `f32`), where `1/delta` and the bound on `P` are representable.
    pub fn with_delta(self, delta: T) -> Result<Self, ThermalError> {
        let low = T::MIN_POSITIVE.to_f64() / T::EPSILON.to_f64();
        let high = T::EPSILON.to_f64() / T::MIN_POSITIVE.to_f64();
        let (d, lambda) = (delta.to_f64(), self.lambda.to_f64());
        // 1 - lambda^N = (1 - lambda)(1 + lambda + .. + lambda^(N-1)): no cancellation.
        let (mut power, mut sum) = (1.0, 0.0);
        for _ in 0..N {
            sum += power;
            power *= lambda;
        }
        if !(delta.is_finite() && d >= low && d <= high && d * power >= low) {
            return Err(ThermalError::Delta);
        }
        let weight = d * (1.0 - lambda) * sum;
        Ok(Self {
            delta,
            weight: T::from_f64(weight),
            inv_weight: if weight > 0.0 {
                T::from_f64(1.0 / weight)
            } else {
                T::ZERO
            },
            ..self
        })
    }

    /// The forgetting factor.
    pub fn lambda(&self) -> T {
        self.lambda
    }

    /// The regularisation `delta`.
    pub fn delta(&self) -> T {
        self.delta
    }

    /// `(t_min, t_max)`, deg C: the temperatures learned from, and the clamp of the others.
    pub fn range(&self) -> (T, T) {
        (self.t_min, self.t_max)
    }

    /// `T_ref`, the middle of the range, deg C.
    pub fn reference(&self) -> T {
        self.centre
    }

    /// `h`, half the range, K.
    pub fn half_width(&self) -> T {
        T::ONE / self.inv_half
    }

    /// `phi(T)` at `celsius` clamped to the range, and whether it was inside.
    #[inline]
    fn regressor(&self, celsius: T) -> ([T; N], bool) {
        let inside = celsius >= self.t_min && celsius <= self.t_max;
        let t = if celsius < self.t_min {
            self.t_min
        } else if celsius > self.t_max {
            self.t_max
        } else {
            celsius
        };
        let u = (t - self.centre) * self.inv_half;
        let mut phi = [T::ONE; N];
        for k in 1..N {
            phi[k] = phi[k - 1] * u;
        }
        (phi, inside)
    }
}

/// Counters that say what happened to the samples a [`ThermalBias`] was given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ThermalHealth {
    /// Samples learned from.
    pub samples: u64,
    /// Samples rejected because the sample or its temperature was NaN or infinite.
    pub non_finite: u64,
    /// Samples rejected at or beyond the saturation limit.
    pub saturated: u64,
    /// Samples whose temperature was outside the range: compensated at the clamped
    /// temperature, not learned from.
    pub out_of_range: u64,
    /// Re-initialisations (to the prior, or to the next sample) after a numerical breakdown.
    pub restarts: u64,
}

impl ThermalHealth {
    /// All rejected samples (no residual returned).
    pub fn rejected(&self) -> u64 {
        self.non_finite.saturating_add(self.saturated)
    }
}

/// The largest sample magnitude the stage accepts, `EPSILON / sqrt(MIN_POSITIVE)` (about
/// `1.1e12` in `f32`, `1.5e138` in `f64`): below it no product of the recursion can overflow.
fn magnitude_limit<T: Scalar>() -> T {
    T::from_f64(T::EPSILON.to_f64() * libm::sqrt(1.0 / T::MIN_POSITIVE.to_f64()))
}

/// The temperature-dependent bias of one channel, learned online by recursive least squares
/// (the [module docs](self) state the problem), and the residual `x - bias(T)`.
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
/// use imu_ar::thermal::{ThermalBias, ThermalConfig};
///
/// let thermal = ThermalConfig::<f32, 4>::new(0.99999, 20.0, 50.0)?;
/// let config = Config::new(0.999f32, 0.01).unwrap();
/// let mut stage = ThermalBias::new(&thermal).with_saturation(249.99)?;
/// let mut lattice = Lattice::<f32, 4>::new(&config, &Channel::new(1e-4).unwrap());
/// let (x, celsius) = (0.51f32, 31.2f32); // one gyro sample, deg/s, and its die temperature
/// if let Some(residual) = stage.update(&thermal, x, celsius) {
///     lattice.update(&config, residual);
/// }
/// assert_eq!(stage.update(&thermal, f32::NAN, celsius), None);
/// assert_eq!((stage.health().samples, stage.health().non_finite), (1, 1));
/// # Ok::<(), imu_ar::thermal::ThermalError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ThermalBias<T: Scalar, const N: usize> {
    c: [T; N],
    prior: [T; N],
    /// Strictly upper part of `U`, by columns: `ut[j][i] = U[i][j]` for `i < j`.
    ut: [[T; N]; N],
    d: [T; N],
    /// The coefficient whose pseudo-observation the next learned sample adds.
    next: usize,
    /// Whether a prior was given ([`ThermalBias::with_prior`]): it is also the start.
    given: bool,
    /// Whether the start is set: given, or taken from the first accepted sample.
    started: bool,
    limit: T,
    health: ThermalHealth,
}

impl<T: Scalar, const N: usize> ThermalBias<T, N> {
    /// A stage that starts at the first accepted sample `x_1`, `c = s = [x_1, 0, .., 0]`
    /// and `P_0 = I / delta`, regularised towards the prior `p = 0`.
    pub fn new(config: &ThermalConfig<T, N>) -> Self {
        let mut s = Self {
            c: [T::ZERO; N],
            prior: [T::ZERO; N],
            ut: [[T::ZERO; N]; N],
            d: [T::ZERO; N],
            next: 0,
            given: false,
            started: false,
            limit: magnitude_limit(),
            health: ThermalHealth::default(),
        };
        s.initialise(config);
        s
    }

    /// A stage that starts from, and is regularised towards, the coefficients `prior` (in
    /// the normalised temperature of `config`, as [`ThermalBias::coefficients`] gives them): a
    /// calibration stored from an earlier run.
    ///
    /// # Errors
    ///
    /// [`ThermalError::Prior`] unless every coefficient is finite and below the magnitude
    /// limit (see [`ThermalBias::with_saturation`]).
    pub fn with_prior(config: &ThermalConfig<T, N>, prior: [T; N]) -> Result<Self, ThermalError> {
        let limit = magnitude_limit::<T>();
        if !prior.iter().all(|p| p.is_finite() && p.abs() < limit) {
            return Err(ThermalError::Prior);
        }
        let mut s = Self::new(config);
        s.prior = prior;
        s.given = true;
        s.initialise(config);
        Ok(s)
    }

    /// Rejects (and counts as saturated) every sample with `|x| >= limit`, in the channel's
    /// units: set it just inside the sensor's full scale
    /// ([`Scale::gyro_saturation`](crate::sensor::Scale::gyro_saturation)). Without it, and
    /// above it, the magnitude limit `EPSILON / sqrt(MIN_POSITIVE)` applies (about `1.1e12` in
    /// `f32`), below which nothing in the recursion can overflow.
    ///
    /// # Errors
    ///
    /// [`ThermalError::Saturation`] unless `limit` is positive.
    pub fn with_saturation(self, limit: T) -> Result<Self, ThermalError> {
        let positive = limit > T::ZERO;
        if !positive {
            return Err(ThermalError::Saturation);
        }
        let max = magnitude_limit::<T>();
        Ok(Self {
            limit: if limit < max { limit } else { max },
            ..self
        })
    }

    /// `c = p` (the start, when the prior was given; else until the first accepted sample),
    /// `P = I / delta`, the pseudo-observations from the first coefficient on.
    fn initialise(&mut self, config: &ThermalConfig<T, N>) {
        self.c = self.prior;
        self.ut = [[T::ZERO; N]; N];
        self.d = [T::ONE / config.delta; N];
        self.next = 0;
        self.started = self.given;
    }

    /// Takes one sample `x` (any unit) and its die temperature in deg C, and returns the
    /// a-priori residual `x - c_{n-1}^T phi(T)`: the sample less the bias learned before it.
    ///
    /// Returns `None`, counts the sample in [`ThermalHealth`] and changes nothing else when
    /// `x` or the temperature is NaN or infinite, or `|x|` reaches the saturation limit. A
    /// temperature outside the range gives the residual at the clamped temperature and is not
    /// learned from. The first accepted sample of a stage without a prior sets its start (see
    /// the [module docs](self)), so its residual is 0. Never panics; the residual is always
    /// finite. `O(N^2)`.
    ///
    /// A numerical breakdown (a non-finite state, out of reach below the magnitude limit)
    /// would re-initialise the stage and count a restart in [`ThermalHealth::restarts`].
    pub fn update(&mut self, config: &ThermalConfig<T, N>, x: T, celsius: T) -> Option<T> {
        if !(x.is_finite() && celsius.is_finite()) {
            self.health.non_finite = self.health.non_finite.saturating_add(1);
            return None;
        }
        if x.abs() >= self.limit {
            self.health.saturated = self.health.saturated.saturating_add(1);
            return None;
        }
        if !self.started {
            self.started = true;
            self.c[0] = x;
        }
        let (phi, inside) = config.regressor(celsius);
        let e = x - dot(T::ZERO, &self.c, &phi, |s, p| s + p);
        if !inside {
            self.health.out_of_range = self.health.out_of_range.saturating_add(1);
            return Some(e);
        }
        // R <- lambda R: P <- P / lambda.
        for d in &mut self.d {
            *d *= config.inv_lambda;
        }
        // The sample: x = c^T phi + v, Var v = 1.
        let mut f = phi;
        for j in 1..N {
            f[j] = dot(phi[j], &self.ut[j][..j], &phi[..j], |s, p| s + p);
        }
        self.observe(f, 0, e, (T::ONE, T::ONE));
        // The prior's turn: c_k = p_k with weight w (none at lambda = 1).
        let k = self.next;
        if config.weight > T::ZERO {
            // U^T e_k: column k of U^T, zero above k.
            let f: [T; N] = core::array::from_fn(|j| match j.cmp(&k) {
                core::cmp::Ordering::Less => T::ZERO,
                core::cmp::Ordering::Equal => T::ONE,
                core::cmp::Ordering::Greater => self.ut[j].get(k).copied().unwrap_or(T::ZERO),
            });
            let at = |v: &[T; N]| v.get(k).copied().unwrap_or(T::ZERO);
            let innovation = at(&self.prior) - at(&self.c);
            self.observe(f, k, innovation, (config.inv_weight, config.weight));
        }
        self.next = match k.checked_add(1) {
            Some(next) if next < N => next,
            _ => 0,
        };
        self.health.samples = self.health.samples.saturating_add(1);
        // Not reachable below the magnitude limit; kept so that no state can go non-finite.
        // (`D` stays positive by construction: each update multiplies it by a ratio of
        // positive sums.)
        let sum = self
            .c
            .iter()
            .zip(&self.d)
            .fold(T::ZERO, |s, (c, d)| s + *c + *d);
        if !sum.is_finite() {
            self.health.restarts = self.health.restarts.saturating_add(1);
            self.initialise(config);
        }
        Some(e)
    }

    /// Bierman's update of `U D U^T` and `c` by one observation `y = h^T c + v`,
    /// `Var v = r`, given `f = U^T h` (zero before index `first`), the innovation
    /// `y - h^T c` and `(r, 1/r)`. One division per column.
    #[inline(always)]
    fn observe(&mut self, f: [T; N], first: usize, innovation: T, (r, inv_r): (T, T)) {
        let v: [T; N] = core::array::from_fn(|j| self.d[j] * f[j]);
        let mut gain = v;
        let (mut alpha, mut inv_alpha) = (r, inv_r);
        for j in first..N {
            let (beta, inv_beta) = (alpha, inv_alpha);
            alpha += v[j] * f[j];
            inv_alpha = T::ONE / alpha;
            self.d[j] = self.d[j] * beta / alpha;
            let mu = -f[j] * inv_beta;
            let (column, gains) = (&mut self.ut[j][..j], &mut gain[..j]);
            for (u, g) in column.iter_mut().zip(gains) {
                let t = *u;
                *u = t + *g * mu;
                *g += v[j] * t;
            }
        }
        let scale = innovation * inv_alpha;
        for (c, g) in self.c.iter_mut().zip(&gain) {
            *c += *g * scale;
        }
    }

    /// `x - bias(T)` with the current coefficients, learning nothing (a frozen
    /// compensation). `None` for a NaN or infinite `x` or temperature, or a result that is not
    /// finite; the temperature is clamped to the range.
    pub fn compensate(&self, config: &ThermalConfig<T, N>, x: T, celsius: T) -> Option<T> {
        let bias = self.bias(config, celsius)?;
        let r = x - bias;
        r.is_finite().then_some(r)
    }

    /// The current bias at `celsius` (clamped to the range), in the samples' units; `None`
    /// for a NaN or infinite temperature.
    pub fn bias(&self, config: &ThermalConfig<T, N>, celsius: T) -> Option<T> {
        if !celsius.is_finite() {
            return None;
        }
        let (phi, _) = config.regressor(celsius);
        Some(dot(T::ZERO, &self.c, &phi, |s, p| s + p))
    }

    /// `phi^T P phi` at `celsius` (clamped to the range): the variance of the fitted bias there
    /// divided by the residual variance (for white residuals), about one over the number of
    /// effective samples that inform it. At most `N / (delta lambda^(N-1))`, however long the
    /// temperature stands still; `None` for a NaN or infinite temperature.
    pub fn leverage(&self, config: &ThermalConfig<T, N>, celsius: T) -> Option<T> {
        if !celsius.is_finite() {
            return None;
        }
        let (phi, _) = config.regressor(celsius);
        let mut sum = T::ZERO;
        for j in 0..N {
            let f = dot(phi[j], &self.ut[j][..j], &phi[..j], |s, p| s + p);
            sum += self.d[j] * f * f;
        }
        Some(sum)
    }

    /// The coefficients `c_0..c_(N-1)` of the polynomial in the normalised temperature
    /// `u = (T - T_ref)/h`, in the samples' units.
    pub fn coefficients(&self) -> &[T; N] {
        &self.c
    }

    /// The coefficients per kelvin about [`ThermalConfig::reference`]:
    /// `bias(T) = sum_k b_k (T - T_ref)^k`, `b_k = c_k / h^k` (PX4's `x0..x3` when its
    /// `TREF` is `T_ref`).
    pub fn per_kelvin(&self, config: &ThermalConfig<T, N>) -> [T; N] {
        let mut scale = T::ONE;
        let mut b = self.c;
        for v in &mut b {
            *v *= scale;
            scale *= config.inv_half;
        }
        b
    }

    /// What happened to the samples so far.
    pub fn health(&self) -> ThermalHealth {
        self.health
    }
}

/// `init (op) x_i y_i` over the pairs, in order.
#[inline(always)]
fn dot<T: Scalar>(init: T, x: &[T], y: &[T], op: impl Fn(T, T) -> T) -> T {
    x.iter().zip(y).fold(init, |s, (&a, &b)| op(s, a * b))
}
