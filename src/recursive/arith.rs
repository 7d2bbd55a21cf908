//! The arithmetic of one lattice stage, per number format.
//!
//! The lattice recursion (`Core` in `lattice.rs`) is written once, in terms of the typed steps
//! of [`Arith`]; `f32` and `f64` implement them with plain float operations, and `Q`
//! (`fixed_arith.rs`) with the fixed-point formats of numerics.md section 2.2. Both traits are
//! sealed: [`Arith`] is unreachable from outside the crate, and [`FloatArith`] only names the
//! float types.

use core::fmt::Debug;

use super::lattice::Core;
use crate::Scalar;

/// The number formats and the steps of the lattice recursion.
///
/// Each quantity has its own type, so that a fixed-point implementation can give each the Q
/// format its range needs; the float implementations use the float type for all of them.
/// `clip` counts values the implementation had to saturate to its format (never for floats).
pub trait Arith: Copy + Debug {
    /// Prediction errors `f`, `psi` and the input `y`.
    type Err: Copy + Debug + PartialEq;
    /// Conversion factors `gamma`, in `[0, 1]`.
    type Gamma: Copy + Debug + PartialEq;
    /// Reflection coefficients `kf`, `kb`, as the predictions use them and the model is built
    /// from.
    type Coef: Copy + Debug + PartialEq;
    /// A reflection (or ladder) coefficient as its stage accumulates it: the [`Arith::Coef`]
    /// with guard bits below it, so that the rounding of many small steps does not add up (for
    /// floats, the `Coef` itself).
    type Acc: Copy + Debug + PartialEq;
    /// Weighted energies `F`, `B`, positive.
    type Energy: Copy + Debug + PartialEq;
    /// What stage `i` keeps from one sample for the next one's update of `kf_{i+1}` (and of a
    /// ladder coefficient), where the divisor is `B_i(n-1)`: its reciprocal for floats, the
    /// whole gain `gamma_i(n-1) psi_i(n-1) / B_i(n-1)` for fixed point.
    type Kept: Copy + Debug;
    /// What the steps need from the configuration (the forgetting factor in its format).
    type Params: Copy + Debug;

    /// Zero error.
    const ERR_ZERO: Self::Err;
    /// Unit conversion factor.
    const GAMMA_ONE: Self::Gamma;
    /// Zero reflection coefficient.
    const COEF_ZERO: Self::Coef;
    /// Zero accumulated coefficient.
    const ACC_ZERO: Self::Acc;

    /// `g x`, the shared product of the energy and coefficient updates.
    fn gain(g: Self::Gamma, x: Self::Err, clip: &mut u32) -> Self::Err;

    /// `lambda e + gx x`, kept above a tiny positive value.
    fn energy(
        p: &Self::Params,
        e: Self::Energy,
        gx: Self::Err,
        x: Self::Err,
        clip: &mut u32,
    ) -> Self::Energy;

    /// `x - k y`: an order update of an error.
    fn predict(x: Self::Err, k: Self::Coef, y: Self::Err, clip: &mut u32) -> Self::Err;

    /// The coefficient of an accumulated one: its guard bits dropped.
    fn coef(k: Self::Acc) -> Self::Coef;

    /// A coefficient with zero guard bits.
    fn acc(k: Self::Coef) -> Self::Acc;

    /// What a stage keeps before its first sample, for the backward energy `energy`.
    fn kept(energy: Self::Energy) -> Self::Kept;

    /// `k + gx e / B`: the error-feedback update of a reflection (or ladder) coefficient by the
    /// a-priori error `e`, for `gx = gamma_i(n-1) psi_i(n-1)` and what stage `i` kept for
    /// `B = B_i(n-1)`.
    fn feedback(
        k: Self::Acc,
        gx: Self::Err,
        e: Self::Err,
        kept: &Self::Kept,
        clip: &mut u32,
    ) -> Self::Acc;

    /// One sample `y` through every stage of `core`; returns `f_P(n)`. The recursion is the
    /// one of [`Lattice`](super::Lattice); each format writes it in the operations it is
    /// cheapest in.
    fn step<const P: usize>(
        core: &mut Core<Self, P>,
        params: &Self::Params,
        y: Self::Err,
        clip: &mut u32,
    ) -> Self::Err;
}

/// [`Arith::Params`] of the float formats.
// `pub` in a private module: named by `FloatArith`'s bound, reachable by no one.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FloatParams<T> {
    /// Forgetting factor.
    pub lambda: T,
    /// Added to every energy update, so that the energies stay positive (and divisible)
    /// however long the input is exactly zero: `delta EPSILON^2` (at least the smallest normal
    /// value), so that it scales with the data.
    pub floor: T,
}

macro_rules! impl_arith_float {
    ($($t:ty),*) => {$(
        impl Arith for $t {
            type Err = $t;
            type Gamma = $t;
            type Coef = $t;
            type Acc = $t;
            type Energy = $t;
            type Kept = $t;
            type Params = FloatParams<$t>;

            const ERR_ZERO: $t = 0.0;
            const GAMMA_ONE: $t = 1.0;
            const COEF_ZERO: $t = 0.0;
            const ACC_ZERO: $t = 0.0;

            #[inline(always)]
            fn gain(g: $t, x: $t, _: &mut u32) -> $t {
                g * x
            }

            #[inline(always)]
            fn energy(p: &FloatParams<$t>, e: $t, gx: $t, x: $t, _: &mut u32) -> $t {
                p.lambda * e + gx * x + p.floor
            }

            #[inline(always)]
            fn predict(x: $t, k: $t, y: $t, _: &mut u32) -> $t {
                x - k * y
            }

            #[inline(always)]
            fn coef(k: $t) -> $t {
                k
            }

            #[inline(always)]
            fn acc(k: $t) -> $t {
                k
            }

            #[inline(always)]
            fn kept(energy: $t) -> $t {
                1.0 / energy
            }

            #[inline(always)]
            fn feedback(k: $t, gx: $t, e: $t, recip: &$t, _: &mut u32) -> $t {
                k + gx * e * recip
            }

            #[inline(always)]
            fn step<const P: usize>(
                core: &mut Core<$t, P>,
                params: &FloatParams<$t>,
                y: $t,
                _: &mut u32,
            ) -> $t {
                core.float_step(params, y)
            }
        }
    )*};
}

impl_arith_float!(f32, f64);

/// The float types the [`Lattice`](super::Lattice) runs in, `f32` and `f64`: every quantity of
/// the lattice is the float itself. Sealed: it names the two types for generic code
/// (`fn run<T: FloatArith>(lattice: &mut Lattice<T, 4>)`) and cannot be implemented outside
/// this crate.
pub trait FloatArith:
    Scalar
    + Arith<
        Err = Self,
        Gamma = Self,
        Coef = Self,
        Acc = Self,
        Energy = Self,
        Kept = Self,
        Params = FloatParams<Self>,
    >
{
}

impl FloatArith for f32 {}
impl FloatArith for f64 {}

/// The float parameters of a channel: the shared forgetting factor and the channel's energy
/// floor (relative to its `delta`, see [`Channel::new`](super::Channel::new)).
pub(crate) fn float_params<T: Scalar>(
    config: &super::Config<T>,
    channel: &super::Channel<T>,
) -> FloatParams<T> {
    FloatParams {
        lambda: config.lambda(),
        floor: channel.floor(),
    }
}
