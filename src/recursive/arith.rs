//! The arithmetic of one lattice stage, per number format.
//!
//! The lattice recursion ([`Core`](super::lattice::Core)) is written once, in terms of the
//! typed steps of [`Arith`]; `f32` and `f64` implement them with plain float operations, and
//! [`Q`](crate::fixed_point::Q) with the fixed-point formats of numerics.md section 2.2.

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
    /// A divisor prepared once for several divisions by the same energy: nothing for floats
    /// (they divide by the energy), the normalised reciprocal for fixed point.
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

    /// `lambda e + gx x`, floored at a tiny positive value.
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

    /// `g - gx^2 / energy`, not below 0: the next order's conversion factor (never above `g`,
    /// since `energy >= gx^2 / g`).
    fn convert(
        g: Self::Gamma,
        gx: Self::Err,
        energy: Self::Energy,
        recip: &Self::Recip,
    ) -> Self::Gamma;
}

/// [`Arith::Params`] of the float formats.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FloatParams<T> {
    /// Forgetting factor.
    pub lambda: T,
    /// Floor of the energies.
    pub floor: T,
}

macro_rules! impl_arith_float {
    ($($t:ty),*) => {$(
        impl Arith for $t {
            type Err = $t;
            type Gamma = $t;
            type Coef = $t;
            type Energy = $t;
            type Recip = ();
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
                let e = p.lambda * e + gx * x;
                if e > p.floor { e } else { p.floor }
            }

            #[inline(always)]
            fn predict(x: $t, k: $t, y: $t, _: &mut u32) -> $t {
                x - k * y
            }

            #[inline(always)]
            fn recip(_: $t) {}

            #[inline(always)]
            fn adapt(k: $t, gx: $t, e: $t, energy: $t, _: &(), _: &mut u32) -> $t {
                k + gx * e / energy
            }

            #[inline(always)]
            fn convert(g: $t, gx: $t, energy: $t, _: &()) -> $t {
                // Subtracting a non-negative number: only rounding can take it below 0.
                let g = g - gx * gx / energy;
                if g > 0.0 { g } else { 0.0 }
            }
        }
    )*};
}

impl_arith_float!(f32, f64);

/// The float types, for which every quantity of the lattice is the float itself.
pub trait FloatArith:
    Scalar + Arith<Err = Self, Gamma = Self, Coef = Self, Energy = Self, Params = FloatParams<Self>>
{
}

impl FloatArith for f32 {}
impl FloatArith for f64 {}

/// The float parameters of a configuration.
pub(crate) fn float_params<T: Scalar>(lambda: T) -> FloatParams<T> {
    FloatParams {
        lambda,
        floor: T::from_f64(1e-30),
    }
}
