//! Estimators that see the whole record at once.
//!
//! | function | minimises | equals |
//! |---|---|---|
//! | [`covariance`] | `sum_{n=P}^{N-1} (y_n - a^T phi_n)^2` (conditional LS, no windowing) | statsmodels `AutoReg(x - x.mean(), lags=P, trend='n')` |
//! | [`yule_walker`] | the Yule-Walker equations of the biased autocovariance | statsmodels `yule_walker(x, order=P, method='mle', demean=True)` |
//! | [`burg`] | per stage, forward plus backward error energy (Burg 1967) | statsmodels `burg(x, order=P, demean=True)` (coefficients) |
//!
//! `y = x - mean(x)` unless [`BatchConfig::with_demean`] turns mean removal off. All three are
//! allocation-free, compute in `f64` whatever `T` is, and return a [`Fit`]: the order-`P`
//! [`ArModel`] and the innovation variances of every order `0..=P` for the order criteria of
//! [`criteria`]. [`levinson_durbin`] solves Toeplitz normal equations from given
//! autocovariances.

mod burg;
mod covariance;
pub mod criteria;
mod levinson;
mod yule_walker;

use core::fmt;

use crate::{ArModel, Scalar};

pub use burg::burg;
pub use covariance::covariance;
pub use levinson::{Levinson, LevinsonError, levinson_durbin};
pub use yule_walker::yule_walker;

/// Settings shared by the batch estimators, validated once.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BatchConfig<T> {
    dt: T,
    demean: bool,
}

impl<T: Scalar> BatchConfig<T> {
    /// Sample interval `dt` in seconds; the sample mean is removed before fitting.
    ///
    /// # Errors
    ///
    /// [`BatchError::Interval`] unless `dt` is positive and finite.
    pub fn new(dt: T) -> Result<Self, BatchError> {
        if !(dt.is_finite() && dt > T::ZERO) {
            return Err(BatchError::Interval);
        }
        Ok(Self { dt, demean: true })
    }

    /// Whether to remove the sample mean first (default `true`). Without it the model's mean
    /// is 0 and the data are fitted as they are.
    pub fn with_demean(self, demean: bool) -> Self {
        Self { demean, ..self }
    }

    /// The sample interval, in seconds.
    pub fn dt(&self) -> T {
        self.dt
    }

    /// Whether the sample mean is removed.
    pub fn demean(&self) -> bool {
        self.demean
    }
}

/// Why a batch fit could not be made. The input is never modified.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BatchError {
    /// The sample interval `dt` is not positive and finite.
    Interval,
    /// Too few samples for the order: every fit keeps at least one residual degree of
    /// freedom (see each estimator's bound), so that an exact fit with zero residual is never
    /// reported as a model.
    TooShort {
        /// The fewest samples that this estimator and order accept.
        needed: usize,
        /// The samples given.
        given: usize,
    },
    /// The sample at this index is NaN or infinite.
    NonFinite {
        /// Index into the input slice.
        index: usize,
    },
    /// The (mean-removed) data have zero energy, e.g. a constant input.
    ZeroVariance,
    /// The data's energy (the sum of the squared, mean-removed samples) overflows `f64`:
    /// values of about `1e154` and above. Rescale the record.
    Overflow,
    /// The normal equations are singular at this order: the data are exactly predictable by a
    /// model of lower order, e.g. a constant or a pure sinusoid.
    Singular {
        /// The order whose regressors are linearly dependent.
        order: usize,
    },
}

impl fmt::Display for BatchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Interval => f.write_str(crate::model::INTERVAL),
            Self::TooShort { needed, given } => {
                write!(
                    f,
                    "{given} samples given, at least {needed} needed for this order"
                )
            }
            Self::NonFinite { index } => write!(f, "sample {index} is NaN or infinite"),
            Self::ZeroVariance => f.write_str("data have zero variance (constant input?)"),
            Self::Overflow => f.write_str(
                "the data's energy overflows f64 (values of about 1e154 or more); rescale the record",
            ),
            Self::Singular { order } => {
                write!(f, "normal equations are singular at order {order}")
            }
        }
    }
}

impl core::error::Error for BatchError {}

/// The result of a batch fit: the order-`P` model and what the order criteria need.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fit<T, const P: usize> {
    /// The order-`P` model (coefficients, innovation variance, mean, `dt`).
    pub model: ArModel<T, P>,
    /// Innovation variance of the order-0 model.
    pub variance0: T,
    /// Innovation variance of the order-`m` model at index `m - 1`.
    pub variances: [T; P],
    /// Reflection coefficients `kappa_1..kappa_P` in the error-filter convention, for the
    /// estimators that produce them (Yule-Walker, Burg).
    pub reflection: Option<[T; P]>,
    /// The number of terms behind each variance, the `N` of the order criteria.
    pub n_effective: usize,
}

impl<T: Scalar, const P: usize> Fit<T, P> {
    /// Innovation variance of the order-`m` model, `m` in `0..=P`; `None` above `P`.
    pub fn innovation_variance(&self, m: usize) -> Option<T> {
        match m {
            0 => Some(self.variance0),
            _ => self.variances.get(m - 1).copied(),
        }
    }
}

/// Checks length, finiteness and magnitude, and returns the mean to remove (0 without
/// demeaning). `params` is the number of samples that the estimator's coefficients use up
/// (`P` for Burg and Yule-Walker, `2P` for the covariance method); the sample mean uses up one
/// more, and one residual degree of freedom must remain.
fn prepare<T: Scalar>(x: &[T], params: usize, config: &BatchConfig<T>) -> Result<f64, BatchError> {
    let needed = params + usize::from(config.demean) + 1;
    if x.len() < needed {
        return Err(BatchError::TooShort {
            needed,
            given: x.len(),
        });
    }
    if let Some(index) = x.iter().position(|v| !v.is_finite()) {
        return Err(BatchError::NonFinite { index });
    }
    let mean = if config.demean {
        x.iter().map(|v| v.to_f64()).sum::<f64>() / x.len() as f64
    } else {
        0.0
    };
    let energy: f64 = x
        .iter()
        .map(|v| (v.to_f64() - mean) * (v.to_f64() - mean))
        .sum();
    if !(mean.is_finite() && energy.is_finite()) {
        return Err(BatchError::Overflow);
    }
    Ok(mean)
}

/// Assembles a [`Fit`] from `f64` results.
fn finish<T: Scalar, const P: usize>(
    a: &[f64; P],
    variance0: f64,
    variances: &[f64; P],
    reflection: Option<&[f64; P]>,
    mean: f64,
    n_effective: usize,
    config: &BatchConfig<T>,
) -> Result<Fit<T, P>, BatchError> {
    let model = ArModel::new(
        a.map(T::from_f64),
        T::from_f64(variances[P - 1]),
        T::from_f64(mean),
        config.dt,
    )
    // Every input was finite and every pivot positive, so this holds; report it rather than
    // panic if rounding ever says otherwise.
    .map_err(|_| BatchError::ZeroVariance)?;
    Ok(Fit {
        model,
        variance0: T::from_f64(variance0),
        variances: variances.map(T::from_f64),
        reflection: reflection.map(|k| k.map(T::from_f64)),
        n_effective,
    })
}
