//! The lattice in fixed point, for MCUs and DSPs without an FPU and for bit-reproducible
//! firmware.
//!
//! [`FixedLattice`] runs the same recursion as the float [`Lattice`](crate::recursive::Lattice)
//! ([`Core`] over the typed steps of [`Arith`]), with one Q format per quantity
//! (numerics.md section 2.2), all in "internal units" (`scale` times the sensor's units):
//!
//! | quantity | type | range | resolution |
//! |---|---|---|---|
//! | errors `f`, `psi`, input `y` | [`I5F27`] | +-16 | 7.5e-9 |
//! | conversion factors `gamma` | [`I2F30`] | +-2 (kept in [0, 1]) | 9.3e-10 |
//! | reflection coefficients `kf`, `kb` | [`I3F29`] | +-4 | 1.9e-9 |
//! | energies `F`, `B`, weight `W` | [`I24F40`] | +-8.4e6 | 9.1e-13 |
//! | forgetting factor `lambda` | [`U0F32`] | [0, 1) | 2.3e-10 |
//!
//! Every product is formed exactly in `i64` (one `SMULL`) and rounded to nearest once; the
//! `fixed` crate's own `*` rounds toward minus infinity, a bias that the `lambda` recursions
//! would accumulate over `1/(1 - lambda)` samples. Divisions by an energy use its reciprocal,
//! computed once per energy and sample: the energy is normalised by its leading zeros (CLZ) to
//! a 32-bit mantissa `m`, and `r = 2^61 / m` comes from one 32/32-bit `UDIV` and one
//! Newton-Raphson step. A quotient `a b / e` normalises `a` and `b` (CLZ), takes the high words
//! of `a b` and of that times `r` (`SMMULR`), and shifts back by the exponents (relative error
//! about 2^-28). Every result that can leave its format is saturated, and each saturation is
//! counted in [`Health::clipped`].
//!
//! Scaling. The energies must hold `Var(y) / (1 - lambda)`, so `y` should stay well inside
//! +-16: choose `scale` so that the sensor's full range, offset included, maps inside +-16.
//! [`FixedConfig::for_counts`] does this for raw `i16` counts: one count is `2^-11` internal
//! units, so the whole `i16` range fits and no input can overflow; counts at the rails
//! (`-32768`, `-32767` and `32767`) are taken as a saturated sensor and rejected. The float input
//! [`FixedLattice::update`] rejects (and counts as saturated) any `x` with `|x scale| >= 16`.
//!
//! Host and target compute the same bits: integer arithmetic only on the per-sample path.

use fixed::types::{I2F30, I3F29, I5F27, I24F40, U0F32};

use crate::ArModel;
use crate::recursive::lattice::hold_after_restart;
use crate::recursive::{Arith, Config, ConfigError, Core, Health};

/// The fixed-point number formats of the lattice, as an [`Arith`] implementation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Q;

/// [`Arith::Params`] of [`Q`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QParams {
    lambda: U0F32,
    floor: I24F40,
}

const ERR_FRAC: u32 = 27;
const GAMMA_FRAC: u32 = 30;
const COEF_FRAC: u32 = 29;
const ENERGY_FRAC: u32 = 40;
/// The running mean, Q56 in an `i64` (range +-128 internal units; the mean stays inside +-16).
const MEAN_FRAC: u32 = 56;
/// Energies are floored at 16 LSB (1.5e-11 internal units^2).
const ENERGY_FLOOR: i64 = 16;
const TWO_32: f64 = 4_294_967_296.0;
/// The smallest forgetting factor of the fixed-point lattice: below it, a memory of a few
/// samples at high orders leaves the formats' precision (the differential tests cover
/// `[0.9, 1]`).
const FIXED_LAMBDA_MIN: f32 = 0.9;
/// The largest forgetting factor, `1 - 2^-22` in U0F32: a memory of 4.2 million samples. The
/// weight `W < 1/(1 - lambda) = 2^22` then fits I24F40 (which holds less than `2^23`).
const FIXED_LAMBDA_MAX_BITS: u32 = u32::MAX - (1 << 10) + 1;

/// `x y / 2^s` rounded to nearest (ties up), for a constant `s` in `1..=62`: one `SMULL` and
/// a rounding shift.
#[inline(always)]
fn mul_shift(x: i32, y: i32, s: u32) -> i64 {
    (i64::from(x) * i64::from(y) + (1 << (s - 1))) >> s
}

/// `x y / 2^32` rounded to nearest: the high word of the product (`SMMULR`).
#[inline(always)]
fn mul_hi(x: i32, y: i32) -> i32 {
    // |x y| <= 2^62: the sum cannot overflow and the result fits in an i32.
    ((i64::from(x) * i64::from(y) + (1 << 31)) >> 32) as i32
}

/// `(x 2^n, n)` with `n` the redundant sign bits of `x`: `|x 2^n|` in `[2^30, 2^31]` unless
/// `x` is 0 (`n = 31`).
#[inline(always)]
fn normalise(x: i32) -> (i32, u32) {
    // `x ^ (x >> 31)` is non-negative: at least one leading zero, no wrap.
    let n = (x ^ (x >> 31)).leading_zeros().wrapping_sub(1);
    (x.wrapping_shl(n), n)
}

/// `x` saturated to `i32`, counting a saturation in `clip`.
#[inline(always)]
fn sat_i32(x: i64, clip: &mut u32) -> i32 {
    match i32::try_from(x) {
        Ok(v) => v,
        Err(_) => {
            *clip = clip.saturating_add(1);
            if x < 0 { i32::MIN } else { i32::MAX }
        }
    }
}

/// `x + y` saturated, counting a saturation in `clip`.
#[inline(always)]
fn sat_add(x: i64, y: i64, clip: &mut u32) -> i64 {
    x.checked_add(y).unwrap_or_else(|| {
        *clip = clip.saturating_add(1);
        if y < 0 { i64::MIN } else { i64::MAX }
    })
}

/// `e lambda` for a non-negative Q40 energy and a Q0.32 `lambda`, rounded to nearest: the
/// 96-bit product split into `hi lambda + (lo lambda) / 2^32`, both exact in 64 bits.
#[inline(always)]
fn decay(e: i64, lambda: u32) -> i64 {
    let e = e as u64;
    let low = ((e & 0xFFFF_FFFF) * u64::from(lambda) + (1 << 31)) >> 32;
    ((e >> 32) * u64::from(lambda) + low) as i64
}

/// `y / W` in Q56, for `y` in Q27 and the [`reciprocal`] of a Q40 weight `W >= 1`: one exact
/// `SMULL` and one rounding shift (relative error about 2^-29), never out of range.
#[inline(always)]
fn mean_step(y: i32, (r, lz): (i32, u32)) -> i64 {
    // y / W = y r 2^(lz - 53 - 27) real = y r 2^(lz - 24) in Q56; W >= 1 (Q40) gives lz <= 23.
    let s = 24u32.saturating_sub(lz).clamp(1, 24);
    // |y r| < 2^61: the product and the rounding add stay well inside `i64`.
    (i64::from(y) * i64::from(r)).wrapping_add(1 << (s - 1)) >> s
}

/// A positive Q40 energy prepared for division: `(r, lz)` with `1/e_real = r 2^(lz - 53)`,
/// `r` in `(2^29, 2^30]` accurate to about 2^-29 relative.
///
/// `e` is normalised by its leading zeros (CLZ) to a mantissa `m` in `[2^31, 2^32)`; a 32/32
/// hardware division gives `2^48 / m` to 16 bits, and one Newton-Raphson step
/// `r <- r + r (2^61 - m r) / 2^61` doubles that.
#[inline(always)]
fn reciprocal(e: i64) -> (i32, u32) {
    let e = e.max(1) as u64;
    let (hi, lo) = ((e >> 32) as u32, e as u32);
    let (m, lz) = if hi != 0 {
        let z = hi.leading_zeros();
        // `(lo >> 1) >> (31 - z)` is `lo >> (32 - z)` without a shift by 32.
        ((hi << z) | ((lo >> 1) >> (31 - z)), z)
    } else {
        // `lo != 0` here (`e >= 1`), so `z < 32`.
        let z = lo.leading_zeros();
        (lo.wrapping_shl(z), 32 + z)
    };
    // `| 0x8000` changes nothing (the top bit is set) but proves the divisor non-zero.
    let r0 = (u32::MAX / ((m >> 16) | 0x8000)) << 13; // in (2^29, 2^30]
    let residual = (1u64 << 61).wrapping_sub(u64::from(m) * u64::from(r0)) as i64;
    let correction = (i64::from((residual >> 30) as i32) * i64::from(r0 as i32)) >> 31;
    ((r0 as i32).wrapping_add(correction as i32), lz)
}

/// `a b / e` in `Q(out_frac)`, for `a b` in `Q(ab_frac)` and the [`reciprocal`] of a positive
/// Q40 `e`: both factors normalised, two high-word products, one shift back (relative error
/// about 2^-28). Saturates (and counts) only beyond 2^61 LSB.
#[inline(always)]
fn quotient(
    a: i32,
    b: i32,
    ab_frac: u32,
    (r, lz): (i32, u32),
    out_frac: u32,
    clip: &mut u32,
) -> i64 {
    let (an, na) = normalise(a);
    let (bn, nb) = normalise(b);
    // q = a b r 2^(na + nb - 64), |q| <= 2^28.
    let q = mul_hi(mul_hi(an, bn), r);
    // a b / e in Q(out) = a b r 2^(lz - 53 - ab_frac + out) = q 2^shift.
    // Every term is below 128: the sums and the difference cannot wrap.
    let shift = (11u32.wrapping_add(lz).wrapping_add(out_frac) as i32)
        .wrapping_sub(ab_frac.wrapping_add(na).wrapping_add(nb) as i32);
    if shift < 0 {
        // |q| <= 2^28, so anything past 30 gives 0 and the rounded sum fits in 32 bits.
        let t = shift.unsigned_abs().min(30);
        i64::from(q.wrapping_add(1 << (t - 1)) >> t)
    } else if shift <= 32 {
        i64::from(q) << shift
    } else {
        if q != 0 {
            *clip = clip.saturating_add(1);
        }
        i64::from(q.signum()) * i64::MAX
    }
}

impl Arith for Q {
    type Err = I5F27;
    type Gamma = I2F30;
    type Coef = I3F29;
    type Energy = I24F40;
    type Recip = (i32, u32);
    type Params = QParams;

    const ERR_ZERO: I5F27 = I5F27::ZERO;
    const GAMMA_ONE: I2F30 = I2F30::ONE;
    const COEF_ZERO: I3F29 = I3F29::ZERO;

    #[inline(always)]
    fn gain(g: I2F30, x: I5F27, _: &mut u32) -> I5F27 {
        // |g x| <= |x|, since g is in [0, 1].
        I5F27::from_bits(mul_shift(g.to_bits(), x.to_bits(), GAMMA_FRAC) as i32)
    }

    #[inline(always)]
    fn energy(p: &QParams, e: I24F40, gx: I5F27, x: I5F27, clip: &mut u32) -> I24F40 {
        // gx x >= 0 (gx has the sign of x), and so is the sum.
        let add = mul_shift(gx.to_bits(), x.to_bits(), 2 * ERR_FRAC - ENERGY_FRAC);
        let e = sat_add(decay(e.to_bits(), p.lambda.to_bits()), add, clip);
        I24F40::from_bits(e.max(p.floor.to_bits()))
    }

    #[inline(always)]
    fn predict(x: I5F27, k: I3F29, y: I5F27, clip: &mut u32) -> I5F27 {
        let ky = mul_shift(k.to_bits(), y.to_bits(), COEF_FRAC);
        I5F27::from_bits(sat_i32(i64::from(x.to_bits()) - ky, clip))
    }

    #[inline(always)]
    fn recip(energy: I24F40) -> (i32, u32) {
        reciprocal(energy.to_bits())
    }

    #[inline(always)]
    fn adapt(
        k: I3F29,
        gx: I5F27,
        e: I5F27,
        _: I24F40,
        recip: &(i32, u32),
        clip: &mut u32,
    ) -> I3F29 {
        let delta = quotient(
            gx.to_bits(),
            e.to_bits(),
            2 * ERR_FRAC,
            *recip,
            COEF_FRAC,
            clip,
        );
        I3F29::from_bits(sat_i32(sat_add(i64::from(k.to_bits()), delta, clip), clip))
    }

    #[inline(always)]
    fn convert(
        _: &QParams,
        g: I2F30,
        gx: I5F27,
        _: I24F40,
        _: I24F40,
        recip: &(i32, u32),
    ) -> I2F30 {
        let mut ignored = 0;
        let delta = quotient(
            gx.to_bits(),
            gx.to_bits(),
            2 * ERR_FRAC,
            *recip,
            GAMMA_FRAC,
            &mut ignored,
        );
        let g = i64::from(g.to_bits())
            .saturating_sub(delta)
            .clamp(0, 1 << GAMMA_FRAC);
        I2F30::from_bits(g as i32)
    }
}

/// Settings of [`FixedLattice`], shared by many channels: a validated [`Config`] and the
/// scale from sensor units to internal units, converted to the fixed formats once.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FixedConfig {
    params: QParams,
    /// `delta lambda^k` in Q40, `k = 0..=P` is computed from these at construction.
    delta: f64,
    lambda: f64,
    scale: f32,
    dt: f32,
    demean: bool,
    /// `|x scale|` at or above this (Q27 bits) is saturated.
    limit: i64,
    /// Counts at or beyond these are taken as a saturated sensor.
    count_limit: (i16, i16),
}

impl FixedConfig {
    /// From a float configuration and `scale`, the internal units per sensor unit (see the
    /// [module docs](self) for how to choose it). `lambda` is rounded to 32 fractional bits
    /// (`lambda = 1` becomes `1 - 2^-32`); `delta` is taken in sensor units^2; a saturation
    /// limit of `config` applies in sensor units, and `|x scale| >= 16` is always saturated.
    ///
    /// # Errors
    ///
    /// [`ConfigError::Scale`] unless `scale` is positive and finite and `delta scale^2` is at
    /// least 1e-9 internal units^2 (far above the energy format's resolution);
    /// [`ConfigError::FixedLambda`] for `lambda` below 0.9. A `lambda` above `1 - 2^-22`
    /// (`lambda = 1` included) is taken as `1 - 2^-22`, a memory of 4.2 million samples, so
    /// that the weight stays inside its format ([`FixedConfig::lambda`] gives the value used).
    ///
    /// ```
    /// use imu_ar::fixed_point::FixedConfig;
    /// use imu_ar::recursive::Config;
    ///
    /// // A gyro of +-250 deg/s: map the full range to +-12.5 internal units.
    /// let config = Config::new(0.999f32, 0.01, 0.01).unwrap();
    /// let fixed = FixedConfig::new(&config, 0.05).unwrap();
    /// assert!((fixed.lambda() - 0.999).abs() < 1e-7);
    /// ```
    pub fn new(config: &Config<f32>, scale: f32) -> Result<Self, ConfigError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(ConfigError::Scale);
        }
        let s = f64::from(scale);
        let delta = f64::from(config.delta()) * s * s;
        if !(1e-9..1e6).contains(&delta) {
            return Err(ConfigError::Scale);
        }
        if config.lambda() < FIXED_LAMBDA_MIN {
            return Err(ConfigError::FixedLambda);
        }
        // By hand rather than `saturating_from_num`, which has a panic path (for NaN); at most
        // `1 - 2^-22`, so that the Q40 weight, below `1/(1 - lambda)`, stays inside I24F40.
        let lambda = U0F32::from_bits(
            (libm::round(f64::from(config.lambda()) * TWO_32) as u32).min(FIXED_LAMBDA_MAX_BITS),
        );
        let user_limit = config.saturation().map_or(f64::INFINITY, |l| {
            f64::from(l) * s * (1u64 << ERR_FRAC) as f64
        });
        let format_limit = (16i64 << ERR_FRAC) as f64;
        Ok(Self {
            params: QParams {
                lambda,
                floor: I24F40::from_bits(ENERGY_FLOOR),
            },
            delta,
            lambda: f64::from(lambda.to_bits()) / TWO_32,
            scale,
            dt: config.dt(),
            demean: config.demean(),
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
    /// As [`FixedConfig::new`].
    pub fn for_counts(config: &Config<f32>, lsb: f32) -> Result<Self, ConfigError> {
        if !(lsb.is_finite() && lsb > 0.0) {
            return Err(ConfigError::Scale);
        }
        Self::new(config, 1.0 / (2048.0 * lsb))
    }

    /// The forgetting factor actually used (rounded to 32 fractional bits).
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// Internal units per sensor unit.
    pub fn scale(&self) -> f32 {
        self.scale
    }

    fn delta_lambda_pow(&self, k: usize) -> I24F40 {
        let v = (0..k).fold(self.delta, |acc, _| acc * self.lambda);
        // `as` saturates (and maps NaN to 0): no panic path.
        I24F40::from_bits(libm::round(v * (1u64 << ENERGY_FRAC) as f64) as i64)
    }
}

/// The EF-LSL lattice of [`Lattice`](crate::recursive::Lattice) in fixed point: the same
/// recursion ([`Core`]), the same outputs, the Q formats of the [module docs](self).
///
/// ```
/// use imu_ar::fixed_point::{FixedConfig, FixedLattice};
/// use imu_ar::recursive::Config;
///
/// // An MPU-6050 gyro at +-250 deg/s: 1/131 deg/s per count.
/// let config = Config::new(0.999f32, 0.01, 0.01).unwrap();
/// let fixed = FixedConfig::for_counts(&config, 1.0 / 131.0).unwrap();
/// let mut lattice = FixedLattice::<2>::new(&fixed);
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
    /// The weighted running mean, Q56 (held directly: fixed point has the same resolution
    /// everywhere in its range, so no origin is needed).
    mean: i64,
    /// `W_n = lambda W_{n-1} + 1`, Q40.
    weight: i64,
    started: bool,
    health: Health,
    /// What the last sample overwrote: enough to rebuild the model from before it.
    undo: Undo<P>,
    /// The last good model, kept by a restart: published while `hold` lasts.
    held: Option<ArModel<f32, P>>,
    hold: u32,
}

/// The part of the state one sample overwrites that the model is built from: the oldest
/// reflection coefficients of the ring, `F_P`, the weight and the mean.
#[derive(Clone, Copy, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Undo<const P: usize> {
    kf: [I3F29; P],
    kb: [I3F29; P],
    f_energy_p: I24F40,
    weight: i64,
    mean: i64,
}

impl<const P: usize> FixedLattice<P> {
    /// A lattice at the initial state: `F_i = delta lambda^P`, `B_i = delta lambda^(P-i)`.
    pub fn new(config: &FixedConfig) -> Self {
        const { assert!(P > 0, "the model order P must be at least 1") };
        Self {
            core: Self::initial_core(config),
            mean: 0,
            weight: 0,
            started: false,
            health: Health::default(),
            undo: Undo {
                kf: [I3F29::ZERO; P],
                kb: [I3F29::ZERO; P],
                f_energy_p: I24F40::ZERO,
                weight: 0,
                mean: 0,
            },
            held: None,
            hold: 0,
        }
    }

    fn initial_core(config: &FixedConfig) -> Core<Q, P> {
        Core::new(
            config.delta_lambda_pow(P),
            core::array::from_fn(|i| config.delta_lambda_pow(P - i)),
        )
    }

    /// Takes one sample in sensor units; returns the a-priori order-`P` prediction error in
    /// internal units (divide by [`FixedConfig::scale`] for sensor units), or `None` when the
    /// sample was rejected: NaN or infinite, beyond the configured saturation limit, or
    /// `|x scale| >= 16` (counted in [`FixedLattice::health`]; the state is unchanged).
    pub fn update(&mut self, config: &FixedConfig, x: f32) -> Option<I5F27> {
        if !x.is_finite() {
            self.health.non_finite = self.health.non_finite.saturating_add(1);
            return None;
        }
        let bits = f64::from(x) * f64::from(config.scale) * (1u64 << ERR_FRAC) as f64;
        if bits.abs() >= config.limit as f64 {
            self.health.saturated = self.health.saturated.saturating_add(1);
            return None;
        }
        Some(self.accept(config, libm::round(bits) as i32))
    }

    /// Takes one raw sensor reading, for a configuration made by [`FixedConfig::for_counts`]:
    /// the count is exactly `count << 16` in Q27. Readings at the rails are rejected as
    /// saturated and counted.
    pub fn update_counts(&mut self, config: &FixedConfig, count: i16) -> Option<I5F27> {
        let (lo, hi) = config.count_limit;
        let bits = i32::from(count) << 16;
        if count <= lo || count >= hi || i64::from(bits).abs() >= config.limit {
            self.health.saturated = self.health.saturated.saturating_add(1);
            return None;
        }
        Some(self.accept(config, bits))
    }

    /// One in-range sample `x` (Q27). Any saturation inside (the centred input, an error, an
    /// energy, a coefficient or the weight) invalidates the state: the lattice restarts and
    /// keeps the model from before this sample, if it was publishing one.
    fn accept(&mut self, config: &FixedConfig, x: i32) -> I5F27 {
        self.health.samples = self.health.samples.saturating_add(1);
        let settled = self.hold == 0;
        self.hold = self.hold.saturating_sub(1);
        let (kf, kb) = self.core.next_slot();
        self.undo = Undo {
            kf: *kf,
            kb: *kb,
            f_energy_p: self.core.f_energy_p,
            weight: self.weight,
            mean: self.mean,
        };
        let mut clip = 0u32;
        let weight = decay(self.weight, config.params.lambda.to_bits());
        self.weight = sat_add(weight, 1 << ENERGY_FRAC, &mut clip);
        let y = if config.demean {
            if !self.started {
                self.mean = i64::from(x) << (MEAN_FRAC - ERR_FRAC);
                self.started = true;
            }
            // The mean rounded to Q27: `(m / 2^28 + 1) / 2`, no sum that could overflow.
            let mean = ((self.mean >> (MEAN_FRAC - ERR_FRAC - 1)) + 1) >> 1;
            // |x| < 2^31 and |mean| < 2^36: the difference is exact in i64.
            let y = sat_i32(i64::from(x) - mean, &mut clip);
            self.mean = self
                .mean
                .saturating_add(mean_step(y, reciprocal(self.weight)));
            y
        } else {
            x
        };
        let f = self
            .core
            .step(&config.params, I5F27::from_bits(y), &mut clip);
        if clip != 0 {
            self.health.clipped = self.health.clipped.saturating_add(u64::from(clip));
            self.restart_after_saturation(config, settled);
        }
        f
    }

    /// A saturation in the last sample: the model from before it becomes the held one (if the
    /// lattice was publishing; a restarted lattice still settling keeps what it holds), then a
    /// restart.
    #[cold]
    #[inline(never)]
    fn restart_after_saturation(&mut self, config: &FixedConfig, settled: bool) {
        if settled {
            // In place (the state is re-initialised next): no copy of the state on the stack.
            let u = self.undo;
            self.core.rewind(&u.kf, &u.kb, u.f_energy_p);
            if let Some(m) = Self::model_of(&self.core, u.weight, u.mean, config) {
                self.held = Some(m);
            }
        }
        self.reset(config);
    }

    /// The model of a state, if it makes one.
    fn model_of(
        core: &Core<Q, P>,
        weight: i64,
        mean: i64,
        config: &FixedConfig,
    ) -> Option<ArModel<f32, P>> {
        if weight <= 0 {
            return None;
        }
        let lsb = 1.0 / (1u32 << COEF_FRAC) as f32;
        let a = core.coefficients(P, |k| k.to_bits() as f32 * lsb)?;
        let s = f64::from(config.scale);
        let e = core.f_energy_p.to_bits() as f64;
        let variance = (e / weight as f64 / (s * s)) as f32;
        ArModel::new(a, variance, Self::mean_of(mean, config), config.dt).ok()
    }

    fn mean_of(mean: i64, config: &FixedConfig) -> f32 {
        (mean as f64 / (1u64 << MEAN_FRAC) as f64 / f64::from(config.scale)) as f32
    }

    /// A-priori forward prediction errors `f_1(n)..f_P(n)` of the last accepted sample, in
    /// internal units.
    pub fn errors(&self) -> &[I5F27; P] {
        &self.core.errors
    }

    /// The last accepted sample after mean removal, in internal units.
    pub fn input(&self) -> I5F27 {
        self.core.input
    }

    /// Forward energy of order `m` in `0..=P`, in internal units^2; `None` above `P`.
    pub fn energy(&self, m: usize) -> Option<I24F40> {
        self.core.energy(m)
    }

    /// Innovation variance of order `m` in sensor units^2: `F_m / W_n / scale^2`.
    pub fn innovation_variance(&self, config: &FixedConfig, m: usize) -> Option<f32> {
        if self.weight <= 0 {
            return None;
        }
        let e = self.energy(m)?.to_bits() as f64;
        let w = self.weight as f64;
        let s = f64::from(config.scale);
        Some((e / w / (s * s)) as f32)
    }

    /// Forward reflection coefficients `kf_1..kf_P`.
    pub fn forward_reflection(&self) -> &[I3F29; P] {
        self.core.forward_reflection()
    }

    /// Backward reflection coefficients `kb_1..kb_P`.
    pub fn backward_reflection(&self) -> &[I3F29; P] {
        self.core.backward_reflection()
    }

    /// The weighted running mean, in sensor units.
    pub fn mean(&self, config: &FixedConfig) -> f32 {
        Self::mean_of(self.mean, config)
    }

    /// What happened to the samples so far, including internal saturations (`clipped`).
    pub fn health(&self) -> Health {
        self.health
    }

    /// The exact least-squares coefficients of order `m <= P`, as for the float lattice,
    /// evaluated in `f32` from the fixed-point reflection coefficients.
    pub fn coefficients(&self, m: usize) -> Option<[f32; P]> {
        let lsb = 1.0 / (1u32 << COEF_FRAC) as f32;
        self.core.coefficients(m, |k| k.to_bits() as f32 * lsb)
    }

    /// The order-`P` model in sensor units after the last sample, or, while a restarted
    /// lattice settles (`3/(1 - lambda)` samples), the last good model from before the
    /// restart (`None` if there was none). A state in which anything saturated is never
    /// published: the lattice restarts instead (see [`FixedLattice::restart`]). Calling this
    /// changes nothing.
    pub fn model(&self, config: &FixedConfig) -> Option<ArModel<f32, P>> {
        if self.hold == 0 {
            Self::model_of(&self.core, self.weight, self.mean, config)
        } else {
            self.held
        }
    }

    /// Re-initialises the state (counted as a restart); the last good model (see
    /// [`FixedLattice::model`]) stays published for `3/(1 - lambda)` samples. The lattice
    /// does this by itself when any internal quantity saturates (counted in
    /// [`Health::clipped`]), keeping the model from before that sample.
    pub fn restart(&mut self, config: &FixedConfig) {
        if self.hold == 0
            && let Some(m) = Self::model_of(&self.core, self.weight, self.mean, config)
        {
            self.held = Some(m);
        }
        self.reset(config);
    }

    /// Counts a restart and re-initialises the state; `held` is left as it is.
    fn reset(&mut self, config: &FixedConfig) {
        self.health.restarts = self.health.restarts.saturating_add(1);
        self.core = Self::initial_core(config);
        self.mean = 0;
        self.weight = 0;
        self.started = false;
        // A restart during a hold does not extend it (as for the float estimators).
        if self.hold == 0 {
            self.hold = hold_after_restart(config.lambda);
        }
    }
}
