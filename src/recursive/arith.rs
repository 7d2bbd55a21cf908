//! The arithmetic of one lattice stage, per number format.
//!
//! The lattice recursion (`Core` in `lattice.rs`) is written once, in terms of the typed steps
//! of [`Arith`]; `f32` and `f64` implement them with plain float operations, and `Q`
//! (`fixed_arith.rs`) with the fixed-point formats of numerics.md section 2.2. Both traits are
//! sealed: [`Arith`] is unreachable from outside the crate, and [`FloatArith`] only names the
//! float types.

use core::fmt::Debug;

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
    /// Reflection coefficients `kf`, `kb`.
    type Coef: Copy + Debug + PartialEq;
    /// Weighted energies `F`, `B`, positive.
    type Energy: Copy + Debug + PartialEq;
    /// A divisor prepared once for several divisions by the same energy: the reciprocal for
    /// floats, the normalised reciprocal for fixed point.
    type Recip: Copy + Debug;
    /// What the steps need from the configuration (the forgetting factor in its format).
    type Params: Copy + Debug;

    /// Zero error.
    const ERR_ZERO: Self::Err;
    /// Unit conversion factor.
    const GAMMA_ONE: Self::Gamma;
    /// Zero reflection coefficient.
    const COEF_ZERO: Self::Coef;

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

    /// Prepares divisions by `energy`.
    fn recip(energy: Self::Energy) -> Self::Recip;

    /// `k + gx e / energy`: the error-feedback update of a reflection coefficient; `recip` is
    /// `recip(energy)`.
    fn adapt(
        k: Self::Coef,
        gx: Self::Err,
        e: Self::Err,
        energy: Self::Energy,
        recip: &Self::Recip,
        clip: &mut u32,
    ) -> Self::Coef;

    /// The next order's conversion factor `g - gx^2 / energy = g lambda old / energy`, where
    /// `energy = lambda old + gx^2 / g` is the energy made from `old` by [`Arith::energy`]:
    /// in `[0, g]`.
    fn convert(
        p: &Self::Params,
        g: Self::Gamma,
        gx: Self::Err,
        old: Self::Energy,
        energy: Self::Energy,
        recip: &Self::Recip,
    ) -> Self::Gamma;
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
            type Energy = $t;
            type Recip = $t;
            type Params = FloatParams<$t>;

            const ERR_ZERO: $t = 0.0;
            const GAMMA_ONE: $t = 1.0;
            const COEF_ZERO: $t = 0.0;

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
            fn recip(energy: $t) -> $t {
                1.0 / energy
            }

            #[inline(always)]
            fn adapt(k: $t, gx: $t, e: $t, _: $t, recip: &$t, _: &mut u32) -> $t {
                k + gx * e * recip
            }

            #[inline(always)]
            fn convert(p: &FloatParams<$t>, g: $t, _: $t, old: $t, _: $t, recip: &$t) -> $t {
                // The ratio form needs no clamp: `energy >= lambda old` holds after rounding.
                g * (p.lambda * old) * recip
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
    Scalar + Arith<Err = Self, Gamma = Self, Coef = Self, Energy = Self, Params = FloatParams<Self>>
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
