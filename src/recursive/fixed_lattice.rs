//! The lattice in fixed point: its settings, shared and per channel, and the estimator.

use fixed::types::{I3F29, I3F61, I5F27, I24F40, U0F32};

use super::config::{Channel, Config, ConfigError, Gate, Rejection};
use super::estimator::Estimator;
use super::estimator::sealed::{Sealed, Settings};
use super::fixed_arith::{
    COEF_FRAC, ENERGY_FLOOR, ENERGY_FRAC, ERR_FRAC, MEAN_FRAC, Q, QParams, decay, mean_step,
    reciprocal, sat_add, sat_i32,
};
use super::ladder::Ladder;
use super::lattice::{Core, lattice_accessors};
use super::shell::{Format, Shell};

const TWO_32: f64 = 4_294_967_296.0;
/// The smallest forgetting factor of the fixed-point lattice: below it, a memory of a few
/// samples at high orders leaves the formats' precision (the differential tests cover
/// `[0.9, 1]`).
const FIXED_LAMBDA_MIN: f32 = 0.9;
/// The largest forgetting factor, `1 - 2^-22` in U0F32: a memory of 4.2 million samples. The
/// weight `W < 1/(1 - lambda) = 2^22` then fits I24F40 (which holds less than `2^23`).
const FIXED_LAMBDA_MAX_BITS: u32 = u32::MAX - (1 << 10) + 1;

/// What the channels of a [`FixedLattice`] share: a validated [`Config`] with its forgetting
/// factor converted to the fixed format once.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedConfig {
    params: QParams,
    /// The forgetting factor used, for `delta lambda^k` and the hold after a restart.
    lambda: f64,
    dt: f32,
    demean: bool,
    /// The gate: `k^2` in Q16 (saturated), the weight `W_n` from which it tests (Q40), and
    /// the gate itself.
    gate: Option<(u64, i64, Gate)>,
}

impl FixedConfig {
    /// From a float configuration. `lambda` is rounded to 32 fractional bits.
    ///
    /// # Errors
    ///
    /// [`ConfigError::FixedLambda`] for `lambda` below 0.9. A `lambda` above `1 - 2^-22`
    /// (`lambda = 1` included) is taken as `1 - 2^-22`, a memory of 4.2 million samples, so
    /// that the weight stays inside its format ([`FixedConfig::lambda`] gives the value used).
    ///
    /// ```
    /// use imu_ar::recursive::{Config, FixedConfig};
    ///
    /// let config = Config::new(0.999f32, 0.01).unwrap();
    /// let fixed = FixedConfig::new(&config).unwrap();
    /// assert!((fixed.lambda() - 0.999).abs() < 1e-7);
    /// ```
    pub fn new(config: &Config<f32>) -> Result<Self, ConfigError> {
        if config.lambda() < FIXED_LAMBDA_MIN {
            return Err(ConfigError::FixedLambda);
        }
        // By hand rather than `saturating_from_num`, which has a panic path (for NaN); at most
        // `1 - 2^-22`, so that the Q40 weight, below `1/(1 - lambda)`, stays inside I24F40.
        let lambda = U0F32::from_bits(
            (libm::round(f64::from(config.lambda()) * TWO_32) as u32).min(FIXED_LAMBDA_MAX_BITS),
        );
        Ok(Self {
            params: QParams { lambda },
            lambda: f64::from(lambda.to_bits()) / TWO_32,
            dt: config.dt(),
            demean: config.demean(),
            gate: config.gate().map(|g| {
                // `as` saturates: a k beyond 2^24 is a gate that never fires. `k >= 1`: k^2
                // to 2^-17 relative.
                let k2 = libm::round(f64::from(g.k()) * f64::from(g.k()) * 65_536.0) as u64;
                // The weight from which it tests, Q40 (at most 20 << 40).
                let settled = libm::ceil(
                    Gate::settled(f64::from(config.lambda())) * (1u64 << ENERGY_FRAC) as f64,
                );
                (k2, settled as i64, g)
            }),
        })
    }

    /// The forgetting factor actually used (rounded to 32 fractional bits).
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// The sample interval, in seconds.
    pub fn dt(&self) -> f32 {
        self.dt
    }
}

impl Settings<f32> for FixedConfig {
    fn dt(&self) -> f32 {
        self.dt
    }
}

/// What belongs to one channel of a [`FixedLattice`]: a validated [`Channel`] (`delta` in
/// sensor units^2, the saturation limit in sensor units) and `scale`, the internal units per
/// sensor unit, converted to the fixed formats once.
///
/// Scaling. The energies must hold `Var(y) / (1 - lambda)`, so `y` should stay well inside
/// +-16 internal units: choose `scale` so that the sensor's full range, offset included, maps
/// inside +-16. [`FixedChannel::for_counts`] does this for raw `i16` counts: one count is
/// `2^-11` internal units, so the whole `i16` range fits and no input can overflow; counts at
/// the rails (`-32768`, `-32767` and `32767`) are taken as a saturated sensor and rejected. The
/// float input ([`Estimator::update`]) rejects (and counts as saturated) any `x` with
/// `|x scale| >= 16`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedChannel {
    /// `delta` in internal units^2: `delta lambda^k` in Q40 is computed from it.
    delta: f64,
    scale: f32,
    /// `|x scale|` at or above this (Q27 bits) is saturated.
    limit: i64,
    /// Counts at or beyond these are taken as a saturated sensor.
    count_limit: (i16, i16),
}

impl FixedChannel {
    /// From a float channel and `scale`, the internal units per sensor unit. `delta` is taken
    /// in sensor units^2; a saturation limit of `channel` applies in sensor units, and
    /// `|x scale| >= 16` is always saturated.
    ///
    /// # Errors
    ///
    /// [`ConfigError::Scale`] unless `scale` is positive and finite and `delta scale^2` is at
    /// least 1e-9 internal units^2 (far above the energy format's resolution) and below 1e6.
    ///
    /// ```
    /// use imu_ar::recursive::{Channel, FixedChannel};
    ///
    /// // A gyro of +-250 deg/s: map the full range to +-12.5 internal units.
    /// let gyro = Channel::new(0.01f32).unwrap().with_saturation(249.99).unwrap();
    /// let fixed = FixedChannel::new(&gyro, 0.05).unwrap();
    /// assert_eq!(fixed.scale(), 0.05);
    /// ```
    pub fn new(channel: &Channel<f32>, scale: f32) -> Result<Self, ConfigError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(ConfigError::Scale);
        }
        let s = f64::from(scale);
        let delta = f64::from(channel.delta()) * s * s;
        if !(1e-9..1e6).contains(&delta) {
            return Err(ConfigError::Scale);
        }
        let user_limit = channel.saturation().map_or(f64::INFINITY, |l| {
            f64::from(l) * s * (1u64 << ERR_FRAC) as f64
        });
        let format_limit = (16i64 << ERR_FRAC) as f64;
        Ok(Self {
            delta,
            scale,
            limit: user_limit.min(format_limit) as i64,
            count_limit: (-32767, 32767),
        })
    }

    /// For raw `i16` counts of `lsb` sensor units each: `scale = 2^-11 / lsb`, so one count is
    /// `2^-11` internal units and the whole `i16` range fits. Use
    /// [`FixedLattice::update_counts`]; counts at the rails (`<= -32767` or `>= 32767`) are
    /// rejected as saturated.
    ///
    /// # Errors
    ///
    /// As [`FixedChannel::new`].
    pub fn for_counts(channel: &Channel<f32>, lsb: f32) -> Result<Self, ConfigError> {
        if !(lsb.is_finite() && lsb > 0.0) {
            return Err(ConfigError::Scale);
        }
        Self::new(channel, 1.0 / (2048.0 * lsb))
    }

    /// Internal units per sensor unit.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    fn delta_lambda_pow(&self, lambda: f64, k: usize) -> I24F40 {
        let v = (0..k).fold(self.delta, |acc, _| acc * lambda);
        // `as` saturates (and maps NaN to 0): no panic path.
        I24F40::from_bits((libm::round(v * (1u64 << ENERGY_FRAC) as f64) as i64).max(ENERGY_FLOOR))
    }

    /// Screens a float sample in sensor units and converts it to Q27 internal units.
    fn screen(&self, x: f32) -> Result<i32, Rejection> {
        if !x.is_finite() {
            return Err(Rejection::NonFinite);
        }
        let bits = f64::from(x) * f64::from(self.scale) * (1u64 << ERR_FRAC) as f64;
        if bits.abs() >= self.limit as f64 {
            return Err(Rejection::Saturated);
        }
        Ok(libm::round(bits) as i32)
    }

    /// Screens a raw count: `count << 16` in Q27, unless it is at a rail.
    fn screen_count(&self, count: i16) -> Result<i32, Rejection> {
        let (lo, hi) = self.count_limit;
        let bits = i32::from(count) << 16;
        if count <= lo || count >= hi || i64::from(bits).abs() >= self.limit {
            return Err(Rejection::Saturated);
        }
        Ok(bits)
    }
}

/// The running mean (Q56, held directly: fixed point has the same resolution everywhere in its
/// range, so no origin is needed) and the weight `W_n = lambda W_{n-1} + 1` (Q40).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedMoments {
    mean: i64,
    weight: i64,
    started: bool,
}

impl Format for Q {
    type Out = f32;
    type Channel = FixedChannel;
    type Moments = FixedMoments;
    type Energy = I24F40;

    fn mean(moments: &FixedMoments, channel: &FixedChannel) -> f32 {
        (moments.mean as f64 / (1u64 << MEAN_FRAC) as f64 / f64::from(channel.scale)) as f32
    }

    fn per_sample(moments: &FixedMoments, channel: &FixedChannel, energy: I24F40) -> Option<f32> {
        if moments.weight <= 0 {
            return None;
        }
        let s = f64::from(channel.scale);
        let e = energy.to_bits() as f64;
        Some((e / moments.weight as f64 / (s * s)) as f32)
    }
}

/// The EF-LSL lattice of [`Lattice`](super::Lattice) in fixed point, for MCUs and DSPs without
/// an FPU and for bit-reproducible firmware: the same recursion, the same outputs, with one Q
/// format per quantity (numerics.md section 2.2), all in "internal units" (`scale` times the
/// sensor's units, see [`FixedChannel`]):
///
/// | quantity | type | range | resolution |
/// |---|---|---|---|
/// | errors `f`, `psi`, input `y` | [`I5F27`] | +-16 | 7.5e-9 |
/// | conversion factors `gamma` | [`I2F30`](fixed::types::I2F30) | +-2 (kept in [0, 1]) | 9.3e-10 |
/// | reflection coefficients `kf`, `kb` | [`I3F29`] | +-4 | 1.9e-9 |
/// | the same, as a stage accumulates them | [`I3F61`] | +-4 | 4.3e-19 |
/// | energies `F`, `B`, weight `W` | [`I24F40`] | +-8.4e6 | 9.1e-13 |
/// | forgetting factor `lambda` | [`U0F32`] | [0, 1) | 2.3e-10 |
///
/// Every product is formed exactly in `i64` (one `SMULL`) and rounded to nearest once; the
/// `fixed` crate's own `*` rounds toward minus infinity, a bias that the `lambda` recursions
/// would accumulate over `1/(1 - lambda)` samples. The stages run in gain form: each energy
/// is inverted once per sample (normalised by its leading zeros to a 32-bit mantissa `m`,
/// `2^62 / m` from one 32/32-bit `UDIV` and one Newton-Raphson step on the high word) into a
/// gain `gx / E` in block-floating form (a 32-bit mantissa and a shift), and every
/// division of the recursion is a product with a gain: the error is normalised (`CLZ`), one
/// high-word product (`SMMULR`) and one rounding shift (relative error about 2^-28). Stage
/// `i` keeps the gain `gamma_i psi_i / B_i` between samples: it is the next sample's `kf`
/// step and, the same sample, the conversion factor's, so the stage divides twice, not
/// three times. The energies start at or above 16 LSB and decay with rounding to nearest,
/// which never takes a positive energy to 0: they need no floor test. Every result that can
/// leave its format is saturated, and each saturation is counted in
/// [`Health::clipped`](super::Health::clipped). Host and target compute the
/// same bits: integer arithmetic only on the per-sample path. `docs/fixed-point.md` gives
/// the cost of each step on the Cortex-M4F, M3 and M0+.
///
/// A coefficient moves by one small step per sample, and a step rounded to I3F29 would add
/// its rounding to the coefficient every time: over a memory of `1/(1 - lambda)` samples that
/// random walk reaches tens of LSB. Each coefficient (and each ladder coefficient) therefore
/// accumulates its steps with 32 guard bits, as an I3F61; its high word, the I3F29 value, is
/// what the predictions use and the model is built from.
///
/// A sample in which anything saturates (the centred input, an error, an energy, a
/// coefficient or the weight) restarts the lattice: its state is never published. Where the
/// float estimators hold a snapshot taken every
/// [`snapshot_interval`](super::snapshot_interval)`(P)` samples (their breakdown shows only
/// once the state is lost), the fixed-point lattice keeps what one sample overwrites (the
/// reflection coefficients it replaced stay in the history ring; `F_P`, the weight and the
/// mean are copied) and, on a saturation, holds the
/// model from just before that sample: [`Estimator::model`] publishes it for
/// `3/(1 - lambda)` samples after the restart, through the same shell as the float
/// estimators (so a lattice that restarts again and again, every few samples, still
/// publishes a model).
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
///
/// // An MPU-6050 gyro at +-250 deg/s: 1/131 deg/s per count.
/// let config = Config::new(0.999f32, 0.01).unwrap();
/// let fixed = FixedConfig::new(&config).unwrap();
/// let gyro = FixedChannel::for_counts(&Channel::new(0.01).unwrap(), 1.0 / 131.0).unwrap();
/// let mut lattice = FixedLattice::<2>::new(&fixed, &gyro);
/// for n in 0..1000i32 {
///     let counts = (590 + (n * 37 % 11) - 5) as i16; // an offset of 4.5 deg/s and some noise
///     lattice.update_counts(&fixed, counts);
/// }
/// assert_eq!(lattice.update_counts(&fixed, i16::MAX), None); // at the rail: saturated
/// assert_eq!(lattice.health().saturated, 1);
/// let model = lattice.model(&fixed).unwrap();
/// assert!((model.mean() - 4.5).abs() < 0.05);
/// ```
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedLattice<const P: usize> {
    core: Core<Q, P>,
    /// The joint-process ladder of a lattice with a prior.
    ladder: Option<Ladder<Q, P>>,
    shell: Shell<Q, P>,
    /// What the last sample overwrote: enough to rebuild the model from before it.
    undo: Undo<P>,
}

/// The part of the state one sample overwrites that the model is built from and the ring does
/// not keep: `F_P`, the weight and the mean.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Undo<const P: usize> {
    f_energy_p: I24F40,
    weight: i64,
    mean: i64,
    /// The ladder's coefficients and energy (kept only with a prior).
    ladder: ([I3F61; P], I24F40),
}

impl<const P: usize> FixedLattice<P> {
    /// A lattice for `channel` at the initial state: `F_i = delta lambda^P`,
    /// `B_i = delta lambda^(P-i)`.
    pub fn new(config: &FixedConfig, channel: &FixedChannel) -> Self {
        const { assert!(P > 0, "the model order P must be at least 1") };
        Self {
            core: Self::initial_core(config, channel),
            ladder: None,
            shell: Shell::new(*channel),
            undo: Undo {
                f_energy_p: I24F40::ZERO,
                weight: 0,
                mean: 0,
                ladder: ([I3F61::ZERO; P], I24F40::ZERO),
            },
        }
    }

    /// A lattice that starts from the prior model `a0` (in `f32`, rounded to the coefficient
    /// format I3F29) with the weight `delta` of `channel`: the problem centred on `a0`, as
    /// [`Lattice::with_prior`](super::Lattice::with_prior) describes, by the same
    /// joint-process ladder in fixed point. The ladder's coefficients (the correction
    /// `a - a0` in the backward errors' basis) share the format of the reflection
    /// coefficients. A prior the formats cannot carry (the centred input
    /// `d_n = y_n - a0^T phi_n` beyond +-16, or a correction beyond +-4) saturates: the
    /// lattice then restarts, as on any saturation, and goes on without the prior (centred on
    /// 0), so that a prior far from the data never loops on restarts. With `a0 = 0` it gives
    /// the errors, restarts and coefficients of [`FixedLattice::new`] (a zero coefficient may
    /// come out as `+0.0` for `-0.0`); a saturation is then counted in
    /// [`Health::clipped`](super::Health::clipped) by the ladder as well as by the lattice.
    ///
    /// # Errors
    ///
    /// [`ConfigError::Prior`] if an entry of `a0` is not finite or lies outside `(-4, 4)`.
    pub fn with_prior(
        config: &FixedConfig,
        channel: &FixedChannel,
        a0: &[f32; P],
    ) -> Result<Self, ConfigError> {
        let lsb = (1u64 << COEF_FRAC) as f32;
        let mut centre = [I3F29::ZERO; P];
        for (c, &a) in centre.iter_mut().zip(a0) {
            if !(a.is_finite() && a.abs() < 4.0) {
                return Err(ConfigError::Prior);
            }
            // |a| < 4: inside I3F29 (`as` saturates the one value that rounds to 2^31).
            *c = I3F29::from_bits(libm::roundf(a * lsb) as i32);
        }
        let mut lattice = Self::new(config, channel);
        lattice.ladder = Some(Ladder::new(centre, lattice.core.f_energy_p));
        Ok(lattice)
    }

    fn initial_core(config: &FixedConfig, channel: &FixedChannel) -> Core<Q, P> {
        Core::new(
            channel.delta_lambda_pow(config.lambda, P),
            core::array::from_fn(|i| channel.delta_lambda_pow(config.lambda, P - i)),
        )
    }

    /// Takes one raw sensor reading, for a channel made by [`FixedChannel::for_counts`]: the
    /// count is exactly `count << 16` in Q27, and no float operation is on the way. Returns
    /// the a-priori order-`P` prediction error in internal units (divide by
    /// [`FixedChannel::scale`] for sensor units), or `None` for a reading at a rail (rejected
    /// as saturated and counted). A reading that saturates the state restarts the lattice and
    /// returns the error it made; [`Estimator::update`] returns `None` for it.
    pub fn update_counts(&mut self, config: &FixedConfig, count: i16) -> Option<I5F27> {
        let x = self.gated(config, self.shell.channel().screen_count(count))?;
        Some(self.accept(config, x))
    }

    /// A screened sample through the gate (if any), then counted: `None` for a sample the
    /// screening or the gate rejected (each counted).
    #[inline]
    fn gated(&mut self, config: &FixedConfig, screened: Result<i32, Rejection>) -> Option<i32> {
        if let (Some((k2, settled, gate)), Ok(x)) = (config.gate, screened) {
            let outlier = self.outlier(config, (k2, settled), x);
            if !self.shell.pass(&gate, outlier) {
                return None;
            }
        }
        self.shell.admit(screened)
    }

    /// Whether the Q27 sample `x` is an outlier: its a-priori error `e` (Q27) against the
    /// order-`P` energy `E` and the weight `W` (both Q40), `e^2 W > k^2 E` in integers, once
    /// `W` has reached [`Gate::settled`] (`settled`, Q40).
    fn outlier(&self, config: &FixedConfig, (k2, settled): (u64, i64), x: i32) -> bool {
        let m = &self.shell.moments;
        if m.weight < settled {
            return false;
        }
        let mut clip = 0;
        let y = if !config.demean {
            x
        } else if m.started {
            let mean = ((m.mean >> (MEAN_FRAC - ERR_FRAC - 1)) + 1) >> 1;
            sat_i32(i64::from(x) - mean, &mut clip)
        } else {
            0
        };
        let y = I5F27::from_bits(y);
        let e = match &self.ladder {
            Some(l) => l.a_priori(&self.core, y),
            None => self.core.a_priori(y),
        };
        let e = u64::from(e.to_bits().unsigned_abs());
        // e^2 (Q54) W (Q40), shifted to Q56, against k^2 (Q16) E (Q40), Q56. No product
        // wraps (`e < 2^32`: `e^2 < 2^64`, `e^2 W < 2^127`, `k^2 E < 2^128`); wrapping
        // operations say so to the overflow checks.
        let e2 = u128::from(e.wrapping_mul(e));
        let lhs = e2.wrapping_mul(u128::from(m.weight.unsigned_abs())) >> 38;
        let rhs = u128::from(k2).wrapping_mul(u128::from(self.energy_p().to_bits().unsigned_abs()));
        lhs > rhs
    }

    /// One in-range sample `x` (Q27). Any saturation inside (the centred input, an error, an
    /// energy, a coefficient or the weight) invalidates the state: the lattice restarts and
    /// holds the model from before this sample, unless a restart is still settling.
    fn accept(&mut self, config: &FixedConfig, x: i32) -> I5F27 {
        // Field by field, in place: no copy of the record through the stack.
        let u = &mut self.undo;
        u.f_energy_p = self.core.f_energy_p;
        u.weight = self.shell.moments.weight;
        u.mean = self.shell.moments.mean;
        if let Some(l) = &self.ladder {
            u.ladder = (l.c, l.energy);
        }
        let mut clip = 0u32;
        let m = &mut self.shell.moments;
        let weight = decay(m.weight, config.params.lambda.to_bits());
        m.weight = sat_add(weight, 1 << ENERGY_FRAC, &mut clip);
        let y = if config.demean {
            if !m.started {
                m.mean = i64::from(x) << (MEAN_FRAC - ERR_FRAC);
                m.started = true;
            }
            // The mean rounded to Q27: `(m / 2^28 + 1) / 2`, no sum that could overflow.
            let mean = ((m.mean >> (MEAN_FRAC - ERR_FRAC - 1)) + 1) >> 1;
            // |x| < 2^31 and |mean| < 2^36: the difference is exact in i64.
            let y = sat_i32(i64::from(x) - mean, &mut clip);
            m.mean = m
                .mean
                .saturating_add(mean_step(y, reciprocal(m.weight.max(1).unsigned_abs())));
            y
        } else {
            x
        };
        let y = I5F27::from_bits(y);
        // The ladder counts its saturations apart: a counter whose address it took would
        // live in memory through the forward stages too.
        let mut ladder_clip = 0u32;
        let ladder = self
            .ladder
            .as_mut()
            .map(|l| l.step(&self.core, &config.params, y, true, &mut ladder_clip));
        let f = self.core.step(&config.params, y, &mut clip);
        let f = ladder.unwrap_or(f);
        let clip = clip.saturating_add(ladder_clip);
        if clip != 0 {
            self.shell.health.clipped = self.shell.health.clipped.saturating_add(u64::from(clip));
            self.restart_after_saturation(config);
        }
        f
    }

    /// A saturation in the last sample: the model from before it becomes the held one
    /// (unless a restart is settling), then a restart.
    #[cold]
    #[inline(never)]
    fn restart_after_saturation(&mut self, config: &FixedConfig) {
        // In place (the state is re-initialised next): no copy of the state on the stack.
        let u = self.undo;
        self.core.rewind(u.f_energy_p);
        self.shell.moments.weight = u.weight;
        self.shell.moments.mean = u.mean;
        if let Some(l) = &mut self.ladder {
            (l.c, l.energy) = u.ladder;
        }
        self.restart(config);
        // A prior the formats cannot carry (`d_n = y_n - a0^T phi_n` beyond +-16, a
        // correction beyond +-4) would saturate again after every restart: the lattice goes
        // on without it.
        self.ladder = None;
    }

    lattice_accessors!(
        I5F27,
        I3F29,
        I24F40,
        f32,
        "in internal units",
        "`F_m / W_n / scale^2`"
    );

    /// The exact least-squares coefficients of order `m <= P`, as for the float lattice,
    /// evaluated in `f32` from the fixed-point reflection coefficients.
    pub fn coefficients(&self, m: usize) -> Option<[f32; P]> {
        coefficients(&self.core, self.ladder.as_ref(), m)
    }

    /// The order-`P` energy of the published problem: the ladder's with a prior, else `F_P`.
    fn energy_p(&self) -> I24F40 {
        self.ladder
            .as_ref()
            .map_or(self.core.f_energy_p, |l| l.energy)
    }

    /// Re-initialises the state (counted as a restart). Unless a restart is already settling,
    /// the current model becomes the one held: [`Estimator::model`] returns it for
    /// `3/(1 - lambda)` samples. The lattice restarts by itself when any internal quantity
    /// saturates (counted in [`Health::clipped`](super::Health::clipped)), holding the model
    /// from before that sample.
    pub fn restart(&mut self, config: &FixedConfig) {
        let (core, ladder) = (&self.core, self.ladder.as_ref());
        self.shell
            .keep(config.dt, self.energy_p(), || coefficients(core, ladder, P));
        self.core = Self::initial_core(config, self.shell.channel());
        if let Some(l) = &mut self.ladder {
            *l = Ladder::new(l.centre, self.core.f_energy_p);
        }
        self.shell.restart(config.lambda);
    }
}

/// The coefficients of order `m` of a fixed-point core, in `f32`.
fn coefficients<const P: usize>(
    core: &Core<Q, P>,
    ladder: Option<&Ladder<Q, P>>,
    m: usize,
) -> Option<[f32; P]> {
    let lsb = 1.0 / (1u32 << COEF_FRAC) as f32;
    core.coefficients(m, ladder, |k| k.to_bits() as f32 * lsb)
}

impl<const P: usize> Sealed<f32, P> for FixedLattice<P> {
    type Format = Q;

    fn shell(&self) -> &Shell<Q, P> {
        &self.shell
    }

    fn energy(&self) -> I24F40 {
        self.energy_p()
    }

    fn current(&self) -> Option<[f32; P]> {
        coefficients(&self.core, self.ladder.as_ref(), P)
    }
}

impl<const P: usize> Estimator<f32, P> for FixedLattice<P> {
    type Config = FixedConfig;

    /// Takes one sample in sensor units, converted to internal units by the channel's
    /// `scale`: a sample with `|x scale| >= 16` is rejected as saturated, as one beyond the
    /// channel's own limit. The error comes back in sensor units; a sample that saturated the
    /// state and restarted the lattice returns `None`.
    fn update(&mut self, config: &FixedConfig, x: f32) -> Option<f32> {
        let x = self.gated(config, self.shell.channel().screen(x))?;
        let restarts = self.shell.health.restarts;
        let f = self.accept(config, x);
        let scale = f64::from(self.shell.channel().scale);
        let e = f64::from(f.to_bits()) / (1u64 << ERR_FRAC) as f64 / scale;
        (self.shell.health.restarts == restarts).then_some(e as f32)
    }
}
