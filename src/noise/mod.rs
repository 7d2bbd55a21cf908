//! The composite noise model a navigation filter needs: quantisation, white noise, a sum of
//! first-order Gauss-Markov terms, random walk and rate ramp, with an optional AR(p) part for
//! the sensor's short-term colouring, fitted to the Allan variance and checked against it at
//! every averaging time.
//!
//! The components are independent, so the Allan variance of the sum is the sum of theirs, and
//! each is linear in its variance parameter ([`component`] gives the exact discrete-time
//! curves). A model is therefore fitted by non-negative least squares ([`nnls`]) on the octave
//! Allan variances ([`Octaves`]), each row weighted by the inverse variance of its estimate,
//! over a fixed log-spaced grid of Gauss-Markov correlation times; the terms are then reduced
//! to the caller's budget of Kalman states. See [`NoiseModel::fit`] for the procedure and
//! [`NoiseModel::kalman`] for the hand-off.
//!
//! Units: `u` is the sensor's unit (deg/s, rad/s, g, m/s^2). `Q` is in u s, `N` in u/sqrt(Hz)
//! (u s^(1/2)), `K` in u/s/sqrt(Hz) (u s^(-1/2)), `R` in u/s, Gauss-Markov `sigma` in u and
//! correlation times in s. For a gyro in deg/s, `N` in deg/sqrt(h) is `60 N`.
//!
//! Everything here runs in `f64`, on the host and on the device alike, allocation-free: the fit
//! is not per-sample work. On the emulated Cortex-M4F one fit from a 20-octave
//! [`AllanStream`](crate::allan::AllanStream) with a budget of three Gauss-Markov states takes
//! about 70 million instructions (82 million with an AR(8) part) and 34 KiB of stack; the
//! identified fit with the intervals of its parameters about 620 million and 122 KiB
//! (`cargo qemu bench`, [Performance](crate::guide::performance)).

use core::fmt;

use crate::model::ModelError;

mod columns;
pub mod component;
mod fit;
mod identify;
mod model;
pub mod nnls;
mod octaves;
mod parts;
mod uncertainty;

pub use fit::{FitConfig, Identified, OSCILLATOR_CYCLES, OSCILLATOR_MIN_HZ, RECORD_OCTAVES};
pub use model::{
    AllanRow, Check, GmState, GmTerm, Ieee952, KalmanForm, NoiseModel, Oscillator, OscillatorState,
    QuantizationStates,
};
pub use nnls::NnlsError;
pub use octaves::{DRIFT_OCTAVES, Estimator, NoiseType, Octaves, PARTS};
pub use parts::Coefficients;
pub use uncertainty::{
    Interval, MAX_PARAMETERS, OscillatorUncertainty, TermUncertainty, Uncertainty,
};

/// Why a noise model could not be fitted or used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NoiseError {
    /// The sample interval (or the filter's step) is not positive and finite, or so small or
    /// large that `1 / tau^2` or `tau^2` overflows.
    Interval,
    /// A sample or an Allan variance at this index is NaN, infinite or negative.
    NonFinite {
        /// Index into the input.
        index: usize,
    },
    /// Fewer octaves than the fit needs (2).
    TooFewOctaves {
        /// The octaves given.
        given: usize,
    },
    /// More octaves than the capacity `L`.
    TooManyOctaves {
        /// The capacity.
        capacity: usize,
    },
    /// Every Allan variance is zero: a constant (or stuck) input has no noise to model.
    Constant,
    /// More Gauss-Markov states asked for than the model's capacity `G`.
    Budget {
        /// States asked for.
        requested: usize,
        /// The capacity.
        capacity: usize,
    },
    /// The grid spacing is not in [0.5, 8] octaves.
    Spacing,
    /// The octave capacity `L` is too small for the fixed columns of the fit (quantisation,
    /// white noise, random walk, ramp, AR part: at most `2 L` columns in all).
    Capacity,
    /// A fitted parameter overflows `f64` (Allan variances near the top of its range).
    Overflow,
    /// The fit gives no noise at all for Allan variances that have some: they span too many
    /// decades (about 1e300) for their weights, or they rise as a rate ramp's do (`tau^2`)
    /// and the model has no ramp.
    Range,
    /// A model's parameter is out of range ([`NoiseModel::new`]): a coefficient or `sigma`
    /// negative or not finite, a correlation time, decay time or frequency not positive and
    /// finite, or Gauss-Markov terms not by non-decreasing correlation time.
    Parameter,
    /// The AR part is not a stationary model.
    Ar(ModelError),
    /// The least-squares solve failed.
    Nnls(NnlsError),
}

impl fmt::Display for NoiseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Interval => f.write_str(
                "sample interval must be positive and finite, and tau^2 and 1/tau^2 finite at \
                 every octave",
            ),
            Self::NonFinite { index } => write!(f, "value {index} is NaN, infinite or negative"),
            Self::TooFewOctaves { given } => write!(
                f,
                "{given} Allan octave(s), at least 2 needed (a record of at least 4 samples)"
            ),
            Self::TooManyOctaves { capacity } => {
                write!(f, "more than {capacity} Allan octaves")
            }
            Self::Constant => f.write_str("the input is constant: every Allan variance is zero"),
            Self::Budget {
                requested,
                capacity,
            } => write!(
                f,
                "{requested} Gauss-Markov states asked for, at most {capacity} held"
            ),
            Self::Spacing => f.write_str("grid spacing must be in [0.5, 8] octaves"),
            Self::Capacity => f.write_str(
                "the octave capacity is too small for the model's columns (at most 2 per octave)",
            ),
            Self::Overflow => f.write_str(
                "a fitted parameter overflows f64: the Allan variances are too large; rescale \
                 the data",
            ),
            Self::Range => f.write_str(
                "no term of the model fits these Allan variances: they span more decades than \
                 f64 can weigh (about 300), or they rise as a rate ramp's (tau^2) and the \
                 model has no ramp",
            ),
            Self::Parameter => f.write_str(
                "a noise model parameter is out of range (a negative or non-finite coefficient \
                 or sigma, a time or frequency not positive, or Gauss-Markov terms out of order)",
            ),
            Self::Ar(e) => write!(f, "AR part: {e}"),
            Self::Nnls(e) => write!(f, "least squares: {e:?}"),
        }
    }
}

impl core::error::Error for NoiseError {}

/// `iter.enumerate()` without its counter's overflow check (the index is bounded by the
/// range), so that the fit has no panic path with overflow checks on.
pub(crate) fn indexed<I: Iterator>(iter: I) -> impl Iterator<Item = (usize, I::Item)> {
    (0..usize::MAX).zip(iter)
}

/// `1 << j` as a column mask bit, 0 from `j = 64` on.
pub(crate) fn bit(j: usize) -> u64 {
    u32::try_from(j)
        .ok()
        .and_then(|j| 1u64.checked_shl(j))
        .unwrap_or(0)
}

impl From<NnlsError> for NoiseError {
    fn from(e: NnlsError) -> Self {
        Self::Nnls(e)
    }
}
