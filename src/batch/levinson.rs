//! Levinson-Durbin recursion: AR models of every order from autocovariances.

use core::fmt;

use crate::Scalar;

/// The AR models of orders `1..=P` that match the autocovariances `r(0..=P)`.
///
/// Coefficients follow the crate convention `x[n] = sum_{k=1..m} a_k x[n-k] + w[n]`; reflection
/// coefficients follow the error-filter convention of MATLAB, Kay and Marple, so that the order-1
/// model has `a_1 = -reflection[0]`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Levinson<T, const P: usize> {
    /// `a_1..a_P` of the order-`P` model.
    pub a: [T; P],
    /// Reflection coefficients `kappa_1..kappa_P` (error-filter convention; `|kappa_m| < 1`).
    pub reflection: [T; P],
    /// Innovation variance of the order-`m` model at index `m - 1`:
    /// `E_m = E_{m-1} (1 - kappa_m^2)`, `E_0 = r(0)`.
    pub error_power: [T; P],
    /// `r(0)`, the innovation variance of the order-0 model.
    pub r0: T,
}

impl<T: Scalar, const P: usize> Levinson<T, P> {
    /// Innovation variance of the order-`m` model, `m` in `0..=P` (`r(0)` for `m = 0`).
    ///
    /// Returns `None` for `m > P`.
    pub fn innovation_variance(&self, m: usize) -> Option<T> {
        match m {
            0 => Some(self.r0),
            _ => self.error_power.get(m - 1).copied(),
        }
    }
}

/// Why [`levinson_durbin`] could not solve the normal equations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LevinsonError {
    /// Fewer than `P + 1` autocovariances were given.
    TooFewLags {
        /// `P + 1`.
        needed: usize,
        /// The length of the slice.
        given: usize,
    },
    /// A given autocovariance is NaN or infinite.
    NonFinite,
    /// The Toeplitz matrix of `r` is not positive definite: `r(0) <= 0` (`order` 0) or the
    /// reflection coefficient of model `order` is not inside (-1, 1).
    NotPositiveDefinite {
        /// The first order whose model does not exist.
        order: usize,
    },
}

impl fmt::Display for LevinsonError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::TooFewLags { needed, given } => {
                write!(f, "{needed} autocovariances needed, {given} given")
            }
            Self::NonFinite => f.write_str("autocovariance is NaN or infinite"),
            Self::NotPositiveDefinite { order } => write!(
                f,
                "autocovariances are not positive definite (no AR model of order {order})"
            ),
        }
    }
}

impl core::error::Error for LevinsonError {}

/// Solves the Yule-Walker equations `sum_k a_k r(|j - k|) = r(j)`, `j = 1..=P`, by the
/// Levinson-Durbin recursion (Levinson 1947; Durbin 1960), returning the models of every order.
///
/// For `m = 1..=P`:
///
/// ```text
/// k_m        = (r(m) - sum_{j<m} a_j^(m-1) r(m-j)) / E_{m-1}
/// a_j^(m)    = a_j^(m-1) - k_m a_{m-j}^(m-1),  j < m;   a_m^(m) = k_m
/// E_m        = E_{m-1} (1 - k_m^2),                     E_0 = r(0)
/// ```
///
/// and `reflection[m-1] = -k_m`. `O(P^2)` operations, no allocation. Only `r[..=P]` is read.
///
/// # Errors
///
/// [`LevinsonError`] when `r` is shorter than `P + 1`, holds a non-finite value, or is not a
/// positive definite autocovariance sequence.
///
/// # Example
///
/// `r = [1, 1/2, 1/10, 1/20]` gives `a = [5/8, -11/40, 1/8]` and `E_3 = 567/800`:
///
/// ```
/// use imu_ar::batch::levinson_durbin;
///
/// let fit = levinson_durbin::<f64, 3>(&[1.0, 0.5, 0.1, 0.05]).unwrap();
/// let a = [5.0 / 8.0, -11.0 / 40.0, 1.0 / 8.0];
/// for (x, y) in fit.a.iter().zip(a) {
///     assert!((x - y).abs() < 1e-15);
/// }
/// assert!((fit.error_power[2] - 567.0 / 800.0).abs() < 1e-15);
/// assert_eq!(fit.reflection[0], -0.5);
/// ```
pub fn levinson_durbin<T: Scalar, const P: usize>(
    r: &[T],
) -> Result<Levinson<T, P>, LevinsonError> {
    const { assert!(P > 0, "the model order P must be at least 1") };
    let Some(r) = r.get(..=P) else {
        return Err(LevinsonError::TooFewLags {
            needed: P + 1,
            given: r.len(),
        });
    };
    levinson(r[0], &core::array::from_fn(|k| r[k + 1]))
}

/// [`levinson_durbin`] on `r(0)` and `r(1..=P)`, for callers that hold them apart.
pub(crate) fn levinson<T: Scalar, const P: usize>(
    r0: T,
    r: &[T; P],
) -> Result<Levinson<T, P>, LevinsonError> {
    if !r0.is_finite() || !r.iter().all(|v| v.is_finite()) {
        return Err(LevinsonError::NonFinite);
    }
    if r0 <= T::ZERO {
        return Err(LevinsonError::NotPositiveDefinite { order: 0 });
    }
    let mut a = [T::ZERO; P];
    let mut reflection = [T::ZERO; P];
    let mut error_power = [T::ZERO; P];
    let mut e = r0;
    for m in 1..=P {
        // k_m = (r(m) - sum_{j=1}^{m-1} a_j r(m-j)) / E_{m-1}
        let acc = a[..m - 1]
            .iter()
            .zip(r[..m - 1].iter().rev())
            .fold(r[m - 1], |acc, (&aj, &rj)| acc - aj * rj);
        let k = acc / e;
        // Written so that a NaN `k` (E_{m-1} underflowed to zero) is rejected as well.
        let inside_unit_circle = k.abs() < T::ONE;
        if !inside_unit_circle {
            return Err(LevinsonError::NotPositiveDefinite { order: m });
        }
        let prev = a;
        for (j, aj) in a[..m - 1].iter_mut().enumerate() {
            *aj = prev[j] - k * prev[m - 2 - j];
        }
        a[m - 1] = k;
        e *= T::ONE - k * k;
        reflection[m - 1] = -k;
        error_power[m - 1] = e;
    }
    Ok(Levinson {
        a,
        reflection,
        error_power,
        r0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// numerics.md section 7, vector 2 (`spectrum` package test): error-filter coefficients
    /// `A` and final error power for `r` below.
    #[test]
    fn spectrum_package_vector() {
        let r = [5.0, -1.545, -3.9547, 3.9331, 1.4681, -4.75];
        let big_a = [
            0.614739427,
            0.989813712,
            4.20968656e-4,
            3.44472001e-3,
            -7.70967347e-3,
        ];
        let fit = levinson_durbin::<f64, 5>(&r).unwrap();
        for (m, (a, big)) in fit.a.iter().zip(big_a).enumerate() {
            assert!(
                (a + big).abs() < 1e-9,
                "a_{} = {a}, expected {}",
                m + 1,
                -big
            );
        }
        assert!((fit.error_power[4] - 0.179145151638).abs() < 1e-11);
    }

    /// numerics.md section 7, vector 1 in exact rationals, run in f32.
    #[test]
    fn exact_rationals_in_f32() {
        let fit = levinson_durbin::<f32, 3>(&[1.0, 0.5, 0.1, 0.05]).unwrap();
        let cases = [
            ("a_1", fit.a[0], 5.0 / 8.0),
            ("a_2", fit.a[1], -11.0 / 40.0),
            ("a_3", fit.a[2], 1.0 / 8.0),
            ("kappa_1", fit.reflection[0], -0.5),
            ("kappa_2", fit.reflection[1], 0.2),
            ("kappa_3", fit.reflection[2], -0.125),
            ("E_3", fit.error_power[2], 567.0 / 800.0),
        ];
        for (name, got, want) in cases {
            assert!(
                (got - want).abs() <= 2.0 * f32::EPSILON,
                "{name}: {got} vs {want}"
            );
        }
        assert_eq!(fit.innovation_variance(0), Some(1.0));
        assert_eq!(fit.innovation_variance(3), Some(fit.error_power[2]));
        assert_eq!(fit.innovation_variance(4), None);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let cases: [(&[f64], LevinsonError); 5] = [
            (
                &[1.0, 0.5],
                LevinsonError::TooFewLags {
                    needed: 3,
                    given: 2,
                },
            ),
            (&[1.0, f64::NAN, 0.1], LevinsonError::NonFinite),
            (
                &[0.0, 0.0, 0.0],
                LevinsonError::NotPositiveDefinite { order: 0 },
            ),
            (
                &[1.0, 1.0, 1.0],
                LevinsonError::NotPositiveDefinite { order: 1 },
            ),
            // |k_2| = 1: r(2) = 2 r(1)^2 - 1 puts the order-2 model on the unit circle.
            (
                &[1.0, 0.5, -0.5],
                LevinsonError::NotPositiveDefinite { order: 2 },
            ),
        ];
        for (r, want) in cases {
            assert_eq!(levinson_durbin::<f64, 2>(r), Err(want), "r = {r:?}");
        }
    }
}
