//! The fixed-point formats of the lattice (numerics.md section 2.2) as an [`Arith`]
//! implementation, and the integer steps they are made of. See
//! [`FixedLattice`](super::FixedLattice) for the formats and the rounding.

use fixed::types::{I2F30, I3F29, I5F27, I24F40, U0F32};

use super::arith::Arith;

/// The fixed-point number formats of the lattice, as an [`Arith`] implementation.
// `pub` in a private module, as `Arith`: reachable by no one outside the crate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Q;

/// [`Arith::Params`] of [`Q`]: the forgetting factor and the energy floor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QParams {
    pub(crate) lambda: U0F32,
    pub(crate) floor: I24F40,
}

/// Fractional bits of the errors (I5F27).
pub(crate) const ERR_FRAC: u32 = 27;
const GAMMA_FRAC: u32 = 30;
/// Fractional bits of the reflection coefficients (I3F29).
pub(crate) const COEF_FRAC: u32 = 29;
/// Fractional bits of the energies and the weight (I24F40).
pub(crate) const ENERGY_FRAC: u32 = 40;
/// The running mean, Q56 in an `i64` (range +-128 internal units; the mean stays inside +-16).
pub(crate) const MEAN_FRAC: u32 = 56;

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
pub(crate) fn sat_i32(x: i64, clip: &mut u32) -> i32 {
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
pub(crate) fn sat_add(x: i64, y: i64, clip: &mut u32) -> i64 {
    x.checked_add(y).unwrap_or_else(|| {
        *clip = clip.saturating_add(1);
        if y < 0 { i64::MIN } else { i64::MAX }
    })
}

/// `e lambda` for a non-negative Q40 energy and a Q0.32 `lambda`, rounded to nearest: the
/// 96-bit product split into `hi lambda + (lo lambda) / 2^32`, both exact in 64 bits.
#[inline(always)]
pub(crate) fn decay(e: i64, lambda: u32) -> i64 {
    let e = e as u64;
    let low = ((e & 0xFFFF_FFFF) * u64::from(lambda) + (1 << 31)) >> 32;
    ((e >> 32) * u64::from(lambda) + low) as i64
}

/// `y / W` in Q56, for `y` in Q27 and the [`reciprocal`] of a Q40 weight `W >= 1`: one exact
/// `SMULL` and one rounding shift (relative error about 2^-29), never out of range.
#[inline(always)]
pub(crate) fn mean_step(y: i32, (r, lz): (i32, u32)) -> i64 {
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
pub(crate) fn reciprocal(e: i64) -> (i32, u32) {
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
