//! The fixed-point formats of the lattice (numerics.md section 2.2) as an [`Arith`]
//! implementation, and the integer steps they are made of. See
//! [`FixedLattice`](super::FixedLattice) for the formats and the rounding.

use fixed::types::{I2F30, I3F29, I3F61, I5F27, I24F40, U0F32};

use super::arith::Arith;
use super::lattice::Core;

/// The fixed-point number formats of the lattice, as an [`Arith`] implementation.
// `pub` in a private module, as `Arith`: reachable by no one outside the crate.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Q;

/// Energies start at or above 16 LSB (1.5e-11 internal units^2). Updated as
/// `round(lambda E) + gx x`, they never fall below 1 LSB: a rounded decay keeps a positive
/// energy positive (`round(lambda) = 1` for `lambda >= 0.9`), and the reciprocal needs no more.
pub(crate) const ENERGY_FLOOR: i64 = 16;

/// [`Arith::Params`] of [`Q`]: the forgetting factor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QParams {
    pub(crate) lambda: U0F32,
}

/// Fractional bits of the errors (I5F27).
pub(crate) const ERR_FRAC: u32 = 27;
const GAMMA_FRAC: u32 = 30;
/// Fractional bits of the reflection coefficients (I3F29).
pub(crate) const COEF_FRAC: u32 = 29;
/// Guard bits below them as a stage accumulates them (I3F61): the high word is the
/// coefficient.
const GUARD: u32 = 32;
/// Fractional bits of the energies and the weight (I24F40).
pub(crate) const ENERGY_FRAC: u32 = 40;
/// The running mean, Q56 in an `i64` (range +-128 internal units; the mean stays inside +-16).
pub(crate) const MEAN_FRAC: u32 = 56;

// The three integer primitives the cores differ in: a 32 x 32 -> 64-bit product (signed and
// unsigned) and the count of leading zeros. One `SMULL`, `UMULL` or `CLZ` where the core has
// it; ARMv6-M (Cortex-M0/M0+) multiplies 32 by 32 bits into 32 only and has no `CLZ`, so the
// compiler would call a 64 x 64-bit multiply and a library routine: there the products are
// formed from four 16 x 16-bit products and the zeros counted by a binary search in registers,
// with the same exact results.
#[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
use armv6m::{clz, wide, wide_unsigned};
#[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
use native::{clz, wide, wide_unsigned};

#[cfg_attr(
    all(target_arch = "arm", not(target_has_atomic = "32")),
    allow(dead_code)
)]
mod native {
    /// `x y`, exact.
    #[inline(always)]
    pub(super) fn wide(x: i32, y: i32) -> i64 {
        i64::from(x) * i64::from(y)
    }

    /// `x y` unsigned, exact.
    #[inline(always)]
    pub(super) fn wide_unsigned(x: u32, y: u32) -> u64 {
        u64::from(x) * u64::from(y)
    }

    /// Leading zeros of `x` (32 for 0).
    #[inline(always)]
    pub(super) fn clz(x: u32) -> u32 {
        x.leading_zeros()
    }
}

#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
mod armv6m {
    /// `x y` from four 16 x 16-bit products: `x = xh 2^16 + xl` with `xl` in `[0, 2^16)`, so
    /// that every partial product fits its type.
    #[inline(always)]
    pub(super) fn wide(x: i32, y: i32) -> i64 {
        let (xh, xl, yh, yl) = (x >> 16, x & 0xFFFF, y >> 16, y & 0xFFFF);
        let low = i64::from((xl as u32).wrapping_mul(yl as u32));
        let middle = i64::from(xh.wrapping_mul(yl)) + i64::from(xl.wrapping_mul(yh));
        (i64::from(xh.wrapping_mul(yh)) << 32)
            .wrapping_add(middle << 16)
            .wrapping_add(low)
    }

    /// `x y` unsigned from four 16 x 16-bit products.
    #[inline(always)]
    pub(super) fn wide_unsigned(x: u32, y: u32) -> u64 {
        let (xh, xl, yh, yl) = (x >> 16, x & 0xFFFF, y >> 16, y & 0xFFFF);
        let middle = u64::from(xh.wrapping_mul(yl)) + u64::from(xl.wrapping_mul(yh));
        (u64::from(xh.wrapping_mul(yh)) << 32)
            .wrapping_add(middle << 16)
            .wrapping_add(u64::from(xl.wrapping_mul(yl)))
    }

    /// Leading zeros of `x` (32 for 0) by a binary search.
    #[inline(always)]
    pub(super) fn clz(x: u32) -> u32 {
        let (mut x, mut n) = (x, 0u32);
        for bits in [16, 8, 4, 2, 1] {
            if x >> (32 - bits) == 0 {
                // Distinct powers of two: the sum is an or, at most 31.
                n |= bits;
                x <<= bits;
            }
        }
        n.wrapping_add(u32::from(x == 0))
    }
}

/// `x y / 2^s` rounded to nearest (ties up), for a constant `s` in `1..=62`: one `SMULL` and
/// a rounding shift.
#[inline(always)]
fn mul_shift(x: i32, y: i32, s: u32) -> i64 {
    (wide(x, y) + (1 << (s - 1))) >> s
}

/// `x y / 2^32` rounded to nearest: the high word of the product (`SMMULR`).
#[inline(always)]
fn mul_hi(x: i32, y: i32) -> i32 {
    // |x y| <= 2^62: the sum cannot overflow and the result fits in an i32.
    ((wide(x, y) + (1 << 31)) >> 32) as i32
}

/// `(x 2^n, n)` with `n` the redundant sign bits of `x`: `|x 2^n|` in `[2^30, 2^31]` unless
/// `x` is 0 (`n = 32`, and 0).
#[inline(always)]
fn normalise(x: i32) -> (i32, u32) {
    // A bit of `x ^ (x << 1)` is set where `x` changes from its sign to its magnitude.
    let n = clz((x ^ x.wrapping_shl(1)) as u32);
    // n = 32 only for x = 0, which any shift leaves 0.
    (x.wrapping_shl(n), n)
}

/// `x` saturated to `i32`, counting a saturation in `clip` (a sample's count, far below
/// `2^32`: it wraps nowhere, and a wrapping add is one instruction).
#[inline(always)]
pub(crate) fn sat_i32(x: i64, clip: &mut u32) -> i32 {
    // In range when the high word is the sign of the low one: one compare.
    let low = x as i32;
    if (x >> 32) as i32 == low >> 31 {
        low
    } else {
        core::hint::cold_path();
        *clip = clip.wrapping_add(1);
        if x < 0 { i32::MIN } else { i32::MAX }
    }
}

/// `x` saturated to `i64`, counting a saturation in `clip`.
#[cold]
fn sat_i64(x: i128, clip: &mut u32) -> i64 {
    i64::try_from(x).unwrap_or_else(|_| {
        *clip = clip.wrapping_add(1);
        if x < 0 { i64::MIN } else { i64::MAX }
    })
}

/// `x + y` saturated, counting a saturation in `clip`.
#[inline(always)]
pub(crate) fn sat_add(x: i64, y: i64, clip: &mut u32) -> i64 {
    x.checked_add(y).unwrap_or_else(|| {
        *clip = clip.wrapping_add(1);
        if y < 0 { i64::MIN } else { i64::MAX }
    })
}

/// `e lambda` for a non-negative Q40 energy and a Q0.32 `lambda`, rounded to nearest: the
/// 96-bit product split into `hi lambda + (lo lambda) / 2^32`, both exact in 64 bits.
#[inline(always)]
pub(crate) fn decay(e: i64, lambda: u32) -> i64 {
    let e = e as u64;
    let low = (wide_unsigned(e as u32, lambda) + (1 << 31)) >> 32;
    (wide_unsigned((e >> 32) as u32, lambda) + low) as i64
}

/// `y / W` in Q56, for `y` in Q27 and the [`reciprocal`] of a Q40 weight `W >= 1`: one exact
/// `SMULL` and one rounding shift (relative error about 2^-29), never out of range.
#[inline(always)]
pub(crate) fn mean_step(y: i32, (r, lz): (i32, u32)) -> i64 {
    // y / W = y r 2^(lz - 54 - 27) real = y r 2^(lz - 25) in Q56; W >= 1 (Q40) gives lz <= 23.
    let s = 25u32.saturating_sub(lz).clamp(1, 25);
    // |y r| < 2^62: the product and the rounding add stay inside `i64`.
    wide(y, r).wrapping_add(1 << (s - 1)) >> s
}

/// A positive Q40 energy (at least 1 LSB, as every energy of the lattice is) prepared for
/// division: `(r0, d8, lz)`, the parts of its reciprocal `r` (see
/// [`reciprocal`]) with `1/e_real = r 2^(lz - 54)`, `r` in `(2^30, 2^31)` accurate to about
/// 2^-30 relative.
///
/// `e` is normalised by its leading zeros (CLZ) to a mantissa `m` in `[2^31, 2^32)`; a 32/32
/// hardware division gives `2^48 / m` to 16 bits, and one Newton-Raphson step
/// `r <- r + r (2^62 - m r) / 2^62` doubles that.
#[inline(always)]
fn newton(e: u64) -> (i32, i32, u32) {
    let (hi, lo) = ((e >> 32) as u32, e as u32);
    let (m, lz) = if hi != 0 {
        let z = clz(hi);
        // `(lo >> 1) >> (31 - z)` is `lo >> (32 - z)` without a shift by 32.
        ((hi << z) | ((lo >> 1) >> (31 - z)), z)
    } else {
        // `lo != 0` here (`e >= 1`), so `z < 32`.
        let z = clz(lo);
        (lo.wrapping_shl(z), 32 + z)
    };
    // `| 0x8000` changes nothing (the top bit is set) but proves the divisor non-zero.
    // In (2^30, 2^31 - 2^14], within 2^-15 of 2^62 / m.
    let r0 = (u32::MAX / ((m >> 16) | 0x8000)) << 14;
    // Newton-Raphson on the high word alone: m r0 = 2^62 (1 + d), |d| < 2^-15, so the high
    // word `2^30 (1 + d)` carries d to 2^-30, and `r0 (1 - d)` is then good to about 2^-30.
    let high = (wide_unsigned(m, r0) >> 32) as u32;
    // (2^30 - high) 4 = -d 2^32, in wrapping arithmetic: |d| 2^32 < 2^18.
    let d4 = (high << 2).wrapping_neg() as i32;
    (r0 as i32, d4, lz)
}

/// The reciprocal of [`newton`]: `r = r0 + r0 d`. For a mantissa of exactly `2^31` (`e` a
/// power of two) that is `2^31`, one past `i32`: it is saturated to `2^31 - 1` (`2^-31` off).
#[inline(always)]
pub(crate) fn reciprocal(e: u64) -> (i32, u32) {
    let (r0, d8, lz) = newton(e);
    (r0.saturating_add(mul_hi(r0, d8)), lz)
}

/// `-r` for the [`reciprocal`] `r` of `e` (to the same precision): `-r0 - r0 d`.
#[inline(always)]
fn negative_reciprocal(e: u64) -> (i32, u32) {
    let (r0, d8, lz) = newton(e);
    let n0 = r0.wrapping_neg();
    (n0.wrapping_add(mul_hi(n0, d8)), lz)
}

/// A gain `kappa = gx / E`, an error `gx` (Q27) over a positive energy `E` (Q40), kept
/// negated in block-floating form for its products with errors: `-4 kappa = m 2^-(s + 32)`
/// (the factor 4 turns a Q27 error into a Q29 coefficient step), `|m|` in `[2^28, 2^30]`, or
/// 0. Negated, because it is made from a negative reciprocal, whose product with an error of
/// either sign is one `SMMULR` (a reciprocal known to be positive is multiplied as unsigned,
/// in three instructions); the updates subtract it.
///
/// Made once per energy and sample from the energy's [`reciprocal`], it is all that a
/// coefficient update needs: `kappa e` is one high-word product (`SMMULR`) and one shift.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gain {
    m: i32,
    s: i32,
}

impl Gain {
    /// The gain of a stage before its first sample (`psi(n-1) = 0`).
    pub(crate) const ZERO: Self = Self { m: 0, s: 0 };

    /// `gx / e`, for `gx` [`normalise`]d (`gx_n = gx 2^na`) and the [`negative_reciprocal`]
    /// `-r` of `e`.
    #[inline(always)]
    fn new((gx_n, na): (i32, u32), (r, lz): (i32, u32)) -> Self {
        // With gx, e the Q27 and Q40 bits: 4 kappa = gx 2^15 / e, 1/e = r 2^(lz - 94), and
        // m = -gx_n r 2^-32 = -gx r 2^(na - 32): -4 kappa = m 2^(lz - na - 47).
        // |m| <= 2^30; na <= 32, lz < 64: no wrap.
        Self {
            m: mul_hi(gx_n, r),
            s: (na as i32).wrapping_add(15).wrapping_sub(lz as i32),
        }
    }

    /// `-kappa x` in `Q(out_frac)`, for a Q27 `x` [`normalise`]d (`x_n = x 2^n`), rounded to
    /// nearest: `t = m x_n 2^-32` (`|t| <= 2^29`) shifted right by `s + n + 29 - out_frac`.
    /// `Ok` for a product below `2^29` in magnitude (the shift is to the right), `Err` for a
    /// larger one (start-up, a shock), exact in `i64`.
    #[inline(always)]
    fn times(self, (x_n, n): (i32, u32), out_frac: u32) -> Result<i32, i64> {
        let t = mul_hi(self.m, x_n);
        // Every term is below 128 in magnitude: no wrap.
        let r = self
            .s
            .wrapping_add(n as i32)
            .wrapping_add(29)
            .wrapping_sub(out_frac as i32);
        if (r.wrapping_sub(1) as u32) < 31 {
            // 1 <= r <= 31: `((t >> (r - 1)) + 1) >> 1` is `t / 2^r` rounded to nearest.
            Ok((t >> r.wrapping_sub(1)).wrapping_add(1) >> 1)
        } else if r > 0 {
            // From `r = 32` on (as from 31), `t / 2^r` rounds to 0 (|t| <= 2^29).
            core::hint::cold_path();
            Ok(0)
        } else {
            core::hint::cold_path();
            // |t| <= 2^29: shifted by up to 32 it stays inside i64; anything beyond
            // saturates where it is added.
            Err(i64::from(t).wrapping_shl(r.unsigned_abs().min(32)))
        }
    }

    /// `-kappa x` in Q61 (a coefficient step with its [`GUARD`] bits), for a Q27 `x`
    /// [`normalise`]d: `t = m x_n 2^-32` as in [`Gain::times`], times `2^(32 - r)` for
    /// `r = s + n`. Exact (`t` is the only rounding) for `r` in `1..=31`, the usual case: two
    /// shifts into the two words. `Err` for any other `r`: a step of 2^-3 or more in magnitude
    /// (`r <= 0`, with `|t| >= 2^26` unless 0: start-up, a shock; exact in `i128`) or of 2^-32
    /// or less (`r >= 32`: rounded to nearest).
    #[inline(always)]
    fn coefficient_step(self, (x_n, n): (i32, u32)) -> Result<i64, i128> {
        let t = mul_hi(self.m, x_n);
        // Both terms are below 128 in magnitude: no wrap.
        let r = self.s.wrapping_add(n as i32);
        if (r.wrapping_sub(1) as u32) < GUARD - 1 {
            // 1 <= r <= 31: t 2^(32 - r) = (t >> r) 2^32 + ((t << (32 - r)) mod 2^32).
            let low = (t as u32).wrapping_shl(GUARD.wrapping_sub(r as u32));
            Ok((i64::from(t >> r) << GUARD) | i64::from(low))
        } else {
            core::hint::cold_path();
            Err(if r <= 0 {
                // t 2^(32 - r), exact; a shift beyond 96 (|t| >= 2^26 unless t = 0)
                // saturates wherever it is added. (The shift is at least 32 here; the clamp
                // bounds it for the compiler, which then needs no overflow check.)
                i128::from(t) << (GUARD as i32).wrapping_sub(r).clamp(32, 96)
            } else if r == GUARD as i32 {
                i128::from(t)
            } else {
                // r > 32: t / 2^(r - 32) rounded to nearest (ties up), 0 from r = 63 on
                // (|t| <= 2^29).
                let right = r.wrapping_sub(GUARD as i32) as u32;
                i128::from(t.unbounded_shr(right.wrapping_sub(1)).wrapping_add(1) >> 1)
            })
        }
    }
}

impl Arith for Q {
    type Err = I5F27;
    type Gamma = I2F30;
    type Coef = I3F29;
    type Acc = I3F61;
    type Energy = I24F40;
    type Kept = Gain;
    type Params = QParams;

    const ERR_ZERO: I5F27 = I5F27::ZERO;
    const GAMMA_ONE: I2F30 = I2F30::ONE;
    const COEF_ZERO: I3F29 = I3F29::ZERO;
    const ACC_ZERO: I3F61 = I3F61::ZERO;

    #[inline(always)]
    fn gain(g: I2F30, x: I5F27, _: &mut u32) -> I5F27 {
        // |g x| <= |x|, since g is in [0, 1].
        I5F27::from_bits(mul_shift(g.to_bits(), x.to_bits(), GAMMA_FRAC) as i32)
    }

    #[inline(always)]
    fn energy(p: &QParams, e: I24F40, gx: I5F27, x: I5F27, clip: &mut u32) -> I24F40 {
        // gx x >= 0 (gx has the sign of x, or is 0), rounded to Q40.
        let add = mul_shift(gx.to_bits(), x.to_bits(), 2 * ERR_FRAC - ENERGY_FRAC);
        // Both terms are below 2^63: their sum cannot wrap as a u64.
        let sum = (decay(e.to_bits(), p.lambda.to_bits()) as u64).wrapping_add(add as u64);
        match i64::try_from(sum) {
            Ok(e) => I24F40::from_bits(e),
            Err(_) => {
                core::hint::cold_path();
                *clip = clip.wrapping_add(1);
                I24F40::MAX
            }
        }
    }

    #[inline(always)]
    fn predict(x: I5F27, k: I3F29, y: I5F27, clip: &mut u32) -> I5F27 {
        let ky = mul_shift(k.to_bits(), y.to_bits(), COEF_FRAC);
        I5F27::from_bits(sat_i32(i64::from(x.to_bits()) - ky, clip))
    }

    /// The high word: the guard bits truncated (floor). The error feedback makes the
    /// coefficient the predictions use, this one, the estimate: a bias of the truncation is
    /// fed back like any other error.
    #[inline(always)]
    fn coef(k: I3F61) -> I3F29 {
        I3F29::from_bits((k.to_bits() >> GUARD) as i32)
    }

    #[inline(always)]
    fn acc(k: I3F29) -> I3F61 {
        I3F61::from_bits(i64::from(k.to_bits()) << GUARD)
    }

    #[inline(always)]
    fn kept(_: I24F40) -> Gain {
        Gain::ZERO
    }

    #[inline(always)]
    fn feedback(k: I3F61, _: I5F27, e: I5F27, gain: &Gain, clip: &mut u32) -> I3F61 {
        let k = k.to_bits();
        // `coefficient_step` gives `-kappa e`.
        let sum = match gain.coefficient_step(normalise(e.to_bits())) {
            // |delta| < 2^60: below 3.5 in magnitude (a high word inside +-(2^31 - 2^28), one
            // compare), the coefficient cannot leave its format.
            Ok(delta) if ((k >> GUARD) as u32).wrapping_add(0x7000_0000) < 0xE000_0000 => {
                Ok(k.wrapping_sub(delta))
            }
            Ok(delta) => Err(i128::from(k) - i128::from(delta)),
            // |k| < 2^63, |delta| < 2^126: the difference is exact.
            Err(delta) => Err(i128::from(k).wrapping_sub(delta)),
        };
        I3F61::from_bits(sum.unwrap_or_else(|wide| sat_i64(wide, clip)))
    }

    /// The stages in gain form: what stage `i` keeps between samples is the gain
    /// `gamma_i psi_i / B_i` of its next `kf` update, which is also the gain of its
    /// conversion factor, `gamma_{i+1} = gamma_i - (gamma_i psi_i / B_i) gamma_i psi_i`. Two
    /// reciprocals per stage (`F_i(n)`, `B_i(n)`), three gain products, no other division.
    #[inline(always)]
    fn step<const P: usize>(core: &mut Core<Q, P>, p: &QParams, y: I5F27, clip: &mut u32) -> I5F27 {
        let new = core.next_head();
        let (mut f, mut psi, mut g) = (y, y, I2F30::ONE);
        for (kept, stage) in core.ring[new].iter_mut().zip(&core.stages) {
            *kept = stage.k.map(Q::coef);
        }
        for stage in &mut core.stages {
            // The backward half first: it needs only `g` and `psi`, so that little stays live
            // through the forward half.
            let gpsi = Q::gain(g, psi, clip);
            let be = Q::energy(p, stage.b_energy, gpsi, psi, clip);
            let gpsi_n = normalise(gpsi.to_bits());
            let kappa_b = Gain::new(gpsi_n, negative_reciprocal(be.to_bits() as u64));
            // `times` gives -gpsi^2 / B_i(n) <= 0 (t has the sign of -gpsi^2), so the result
            // is at most g.
            let g_next = match kappa_b.times(gpsi_n, GAMMA_FRAC) {
                // dg <= 0, g <= 2^30 and |dg| <= 2^30: no wrap.
                Ok(dg) => g.to_bits().wrapping_add(dg).max(0),
                Err(dg) => i64::from(g.to_bits()).wrapping_add(dg).max(0) as i32,
            };
            let (bp, gp, kappa_b_old) = (stage.bp, stage.gp, stage.b_kept);
            stage.b_energy = be;
            stage.b_kept = kappa_b;
            stage.bp = psi;
            stage.gp = g;
            // The forward half. The coefficients are read where they are used: held in
            // registers from the start, they would push other values onto the stack.
            let gf = Q::gain(gp, f, clip);
            let fe = Q::energy(p, stage.f_energy, gf, f, clip);
            let f_next = Q::predict(f, Q::coef(stage.k[0]), bp, clip);
            let psi_next = Q::predict(bp, Q::coef(stage.k[1]), f, clip);
            let kappa_f = Gain::new(
                normalise(gf.to_bits()),
                negative_reciprocal(fe.to_bits() as u64),
            );
            stage.k[0] = Q::feedback(stage.k[0], gf, f_next, &kappa_b_old, clip);
            stage.k[1] = Q::feedback(stage.k[1], gf, psi_next, &kappa_f, clip);
            stage.f_energy = fe;
            stage.error = f_next;
            f = f_next;
            psi = psi_next;
            g = I2F30::from_bits(g_next);
        }
        let gf = Q::gain(core.gp_p, f, clip);
        let f_energy_p = Q::energy(p, core.f_energy_p, gf, f, clip);
        core.finish(f_energy_p, g, y, new);
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift64*).
    struct Bits(u64);

    impl Bits {
        fn next(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
        }
    }

    const EDGES: [i32; 12] = [
        0,
        1,
        -1,
        0xFFFF,
        0x1_0000,
        -0x1_0000,
        0x7FFF,
        -0x8000,
        i32::MAX,
        i32::MIN,
        i32::MAX - 1,
        i32::MIN + 1,
    ];

    #[test]
    fn the_armv6m_products_and_leading_zeros_are_exact() {
        for &x in &EDGES {
            for &y in &EDGES {
                assert_eq!(armv6m::wide(x, y), i64::from(x) * i64::from(y), "{x} {y}");
                let (u, v) = (x as u32, y as u32);
                assert_eq!(armv6m::wide_unsigned(u, v), u64::from(u) * u64::from(v));
            }
            assert_eq!(armv6m::clz(x as u32), (x as u32).leading_zeros(), "{x}");
        }
        for k in 0..32 {
            for x in [1u32 << k, (1u32 << k) - 1, (1u32 << k) | 1] {
                assert_eq!(armv6m::clz(x), x.leading_zeros(), "{x:#x}");
            }
        }
        let mut bits = Bits(0x9E37_79B9_7F4A_7C15);
        for _ in 0..2_000_000 {
            let r = bits.next();
            let (x, y) = (r as i32, (r >> 32) as i32);
            assert_eq!(armv6m::wide(x, y), i64::from(x) * i64::from(y), "{x} {y}");
            let (u, v) = (x as u32, y as u32);
            assert_eq!(armv6m::wide_unsigned(u, v), u64::from(u) * u64::from(v));
            // Leading zeros of every magnitude, not only of uniform words.
            let z = u >> (r >> 59);
            assert_eq!(armv6m::clz(z), z.leading_zeros(), "{z:#x}");
        }
    }

    /// `1/e_real` from `(r, lz)`: `r 2^(lz - 54)`.
    fn inverse((r, lz): (i32, u32)) -> f64 {
        f64::from(r) * 2f64.powi(lz as i32 - 54)
    }

    #[test]
    fn reciprocals_are_positive_and_within_2_to_the_minus_29_at_powers_of_two_and_beyond() {
        let mut energies: Vec<u64> = (0..63).flat_map(|k| [1u64 << k, (1u64 << k) + 1]).collect();
        energies.extend((1..63).map(|k| (1u64 << k) - 1));
        let mut bits = Bits(7);
        energies.extend((0..200_000).map(|_| bits.next() >> (bits.next() % 63) | 1));
        for e in energies {
            let exact = 1.0 / (e as f64 * 2f64.powi(-40));
            let (r, lz) = reciprocal(e);
            assert!(r > 0, "reciprocal({e}) = {r}");
            let relative = (inverse((r, lz)) / exact - 1.0).abs();
            assert!(relative < 2f64.powi(-29), "reciprocal({e}): {relative:e}");
            let (n, lz) = negative_reciprocal(e);
            assert!(n < 0, "negative_reciprocal({e}) = {n}");
            let relative = (-inverse((n, lz)) / exact - 1.0).abs();
            assert!(
                relative < 2f64.powi(-29),
                "negative_reciprocal({e}): {relative:e}"
            );
        }
    }

    #[test]
    fn the_mean_step_at_unit_weight_is_the_sample() {
        // W = 1 (Q40): a power of two, the reciprocal's edge. y / W = y, Q27 to Q56.
        for y in [1i32, -1, 1 << 27, -(1 << 27), i32::MAX, i32::MIN] {
            let step = mean_step(y, reciprocal(1 << ENERGY_FRAC));
            let exact = i64::from(y) << 29;
            assert!(
                (step - exact).abs() <= (exact.abs() >> 29) + 1,
                "{y}: {step} {exact}"
            );
        }
    }

    /// A coefficient step in Q61 against `gx x / e` in `f64`: within 2^-26 relative (the
    /// roundings of the reciprocal, 2^-29, of `m`, 2^-29, and of `t`, 2^-27 for the smallest
    /// `|t|` of 2^26) or 1 LSB, on every path of `coefficient_step`
    /// (steps of order 1 and beyond, the usual ones, and those below 2^-61).
    #[test]
    fn coefficient_steps_are_gx_x_over_e_on_every_path() {
        let mut bits = Bits(0x5DEE_CE66_D1CE_4E5B);
        let mut paths = [0u32; 3];
        for _ in 0..1_000_000 {
            let (a, b) = (bits.next(), bits.next());
            // gx and x of every magnitude and sign (Q27), e of every magnitude (Q40, >= 1).
            let gx = (a as i32) >> (a >> 59);
            let x = ((a >> 32) as i32) >> ((b >> 59) & 31);
            let e = (b >> (b % 64)) | 1;
            let kappa = Gain::new(normalise(gx), negative_reciprocal(e));
            let exact = -f64::from(gx) * f64::from(x) / e as f64 * 2f64.powi(61 - 54 + 40);
            let got = match kappa.coefficient_step(normalise(x)) {
                Ok(step) => {
                    paths[0] += 1;
                    step as f64
                }
                Err(step) => {
                    paths[usize::from(exact.abs() < 1.0) + 1] += 1;
                    step as f64
                }
            };
            let error = (got - exact).abs();
            assert!(
                error <= exact.abs() * 2f64.powi(-26) + 1.0,
                "gx {gx} x {x} e {e}: {got:e} against {exact:e}"
            );
        }
        assert!(paths.iter().all(|&n| n > 1000), "paths taken: {paths:?}");
    }
}
