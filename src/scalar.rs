//! The number trait every estimator is generic over.
//!
//! [`Scalar`] is implemented for `f32` and `f64`; the float estimators, the batch fits and
//! [`ArModel`](crate::ArModel) are generic over it. It asks only for what they need (no
//! `num_traits::Num`). The fixed-point lattice does not run in a `Scalar`: it shares the
//! lattice recursion with the float one through a crate-private trait with one number format
//! per quantity, and hands its models over in `f32`.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// A real number type an estimator runs in.
///
/// Arithmetic follows the type's own rules: IEEE 754 round-to-nearest for `f32` and `f64`.
pub trait Scalar:
    Copy
    + Default
    + Debug
    + PartialEq
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// Machine epsilon: the distance from 1 to the next larger value.
    const EPSILON: Self;
    /// The smallest positive normal value (values below it lose precision, gradually to 0).
    const MIN_POSITIVE: Self;

    /// The value nearest to `x` (rounded to nearest, saturating where the type is bounded).
    fn from_f64(x: f64) -> Self;

    /// The value as an `f64` (exact for `f32` and `f64`).
    fn to_f64(self) -> f64;

    /// Absolute value.
    fn abs(self) -> Self;

    /// `false` for NaN and for infinities.
    fn is_finite(self) -> bool;
}

macro_rules! impl_scalar_float {
    ($($t:ty),*) => {$(
        impl Scalar for $t {
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const EPSILON: Self = <$t>::EPSILON;
            const MIN_POSITIVE: Self = <$t>::MIN_POSITIVE;

            #[inline]
            fn from_f64(x: f64) -> Self {
                x as $t
            }

            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }

            #[inline]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }

            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
        }
    )*};
}

impl_scalar_float!(f32, f64);

#[cfg(test)]
mod tests {
    use super::Scalar;

    #[test]
    fn float_conversions_round_to_nearest() {
        // 0.1 is not representable; `as f32` rounds to nearest, which is 0x3DCCCCCD.
        assert_eq!(<f32 as Scalar>::from_f64(0.1).to_bits(), 0x3DCC_CCCD);
        assert_eq!(<f64 as Scalar>::from_f64(0.1), 0.1);
        assert_eq!(Scalar::to_f64(0.5f32), 0.5);
        assert!(!Scalar::is_finite(f32::NAN));
        assert!(!Scalar::is_finite(f64::NEG_INFINITY));
        assert_eq!(Scalar::abs(-2.0f32), 2.0);
    }
}
