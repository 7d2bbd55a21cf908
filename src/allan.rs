//! Allan variance of data: the overlapping estimator over a slice, and a streaming
//! fixed-memory estimator for the device.
//!
//! For averaging factor `m` (`tau = m dt`) and the prefix sums `S_k = sum_{i<k} x_i`, the
//! overlapping Allan variance (IEEE Std 952-1997, Annex C) is
//!
//! ```text
//! AVAR(m) = sum_{j=0}^{N-2m} (S_{j+2m} - 2 S_{j+m} + S_j)^2 / (2 m^2 (N - 2m + 1))
//! ```
//!
//! [`ArModel::allan_variance`](crate::ArModel::allan_variance) gives its expectation for a model.

use core::fmt;

use crate::Scalar;

/// Why an Allan variance could not be computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AllanError {
    /// The averaging factor `m` is zero.
    ZeroAveraging,
    /// Fewer than `2m` samples.
    TooShort {
        /// `2m`.
        needed: usize,
        /// The samples given.
        given: usize,
    },
    /// The sample at this index is NaN or infinite.
    NonFinite {
        /// Index into the input slice.
        index: usize,
    },
    /// A forgetting horizon below one sample, or not finite.
    Horizon,
}

impl fmt::Display for AllanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ZeroAveraging => f.write_str("averaging factor must be at least 1"),
            Self::TooShort { needed, given } => {
                write!(f, "{given} samples given, at least {needed} needed")
            }
            Self::NonFinite { index } => write!(f, "sample {index} is NaN or infinite"),
            Self::Horizon => f.write_str("forgetting horizon must be at least 1 sample"),
        }
    }
}

impl core::error::Error for AllanError {}

/// The overlapping Allan variance of `x` at averaging factor `m`, in units^2.
///
/// `O(N)` operations with two sliding window sums over the mean-removed data, in `f64`.
///
/// # Errors
///
/// [`AllanError`] for `m = 0`, fewer than `2m` samples or a non-finite sample.
///
/// ```
/// use imu_ar::allan::overlapping_avar;
///
/// // Alternating +-1: every pair average is 0, so AVAR(2) = 0, and AVAR(1) = 2.
/// let x = [1.0f64, -1.0, 1.0, -1.0, 1.0, -1.0];
/// assert_eq!(overlapping_avar(&x, 1).unwrap(), 2.0);
/// assert_eq!(overlapping_avar(&x, 2).unwrap(), 0.0);
/// ```
pub fn overlapping_avar<T: Scalar>(x: &[T], m: usize) -> Result<T, AllanError> {
    if m == 0 {
        return Err(AllanError::ZeroAveraging);
    }
    let n = x.len();
    if n / 2 < m {
        return Err(AllanError::TooShort {
            needed: 2 * m,
            given: n,
        });
    }
    if let Some(index) = x.iter().position(|v| !v.is_finite()) {
        return Err(AllanError::NonFinite { index });
    }
    Ok(centred_avar(x, m, mean(x)))
}

/// The mean of `x`, in f64, as [`overlapping_avar`] removes it.
pub(crate) fn mean<T: Scalar>(x: &[T]) -> f64 {
    x.iter().map(|v| v.to_f64()).sum::<f64>() / x.len() as f64
}

/// [`overlapping_avar`] of checked input (`1 <= m`, `2m <= n`, every sample finite) with its
/// `mean` given: the same operations, so that a caller that takes many factors of one record
/// removes the mean once and gets the same bits.
pub(crate) fn centred_avar<T: Scalar>(x: &[T], m: usize, mean: f64) -> T {
    let n = x.len();
    let y = |i: usize| x[i].to_f64() - mean;
    let mut w1: f64 = (0..m).map(y).sum();
    let mut w2: f64 = (m..2 * m).map(y).sum();
    let mut acc = (w2 - w1) * (w2 - w1);
    for j in 1..=n - 2 * m {
        w1 += y(j + m - 1) - y(j - 1);
        w2 += y(j + 2 * m - 1) - y(j + m - 1);
        acc += (w2 - w1) * (w2 - w1);
    }
    let mf = m as f64;
    T::from_f64(acc / (2.0 * mf * mf * (n - 2 * m + 1) as f64))
}

/// Overlapping Allan variances at `m = 1, 2, 4, ...` (while `2m <= N`) into `out`; returns how
/// many were written (at most `out.len()`). `out[j]` is `AVAR(2^j)`.
///
/// # Errors
///
/// [`AllanError`] for fewer than 2 samples or a non-finite sample.
pub fn octave_avar<T: Scalar>(x: &[T], out: &mut [T]) -> Result<usize, AllanError> {
    if x.len() < 2 {
        return Err(AllanError::TooShort {
            needed: 2,
            given: x.len(),
        });
    }
    let mut written = 0;
    for (j, slot) in out.iter_mut().enumerate() {
        let Some(m) = 1usize.checked_shl(j as u32).filter(|m| x.len() / 2 >= *m) else {
            break;
        };
        *slot = overlapping_avar(x, m)?;
        written += 1;
    }
    Ok(written)
}

/// One octave of [`AllanStream`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
struct Octave {
    /// Sum of the first of two blocks waiting for its partner.
    pending: Option<f64>,
    /// Average of the previous block.
    previous: Option<f64>,
    /// Weighted sum of squared differences of consecutive block averages.
    acc: f64,
    /// Sum of the weights of the differences in `acc` (their number without forgetting).
    weight: f64,
    /// Sum of the squared weights (for the effective number of differences).
    weight2: f64,
}

/// Streaming Allan variance at `m = 1, 2, 4, .., 2^(L-1)` in fixed memory, optionally
/// forgetting.
///
/// Each octave keeps the pending block sum, the previous block average, a weighted sum of
/// squares and two weight sums (56 bytes an octave), so one sample costs `O(1)` amortised (two
/// octave updates on average). The estimate is the **non-overlapping** Allan variance
/// `sum_k (ybar_{k+1} - ybar_k)^2 / (2 K)` over consecutive blocks of `m` samples: it has the same
/// expectation as [`overlapping_avar`] but uses `N/m - 1` differences instead of `N - 2m + 1`,
/// so its variance is larger (by up to about 2x at large `m`). Accumulates in `f64`.
///
/// A stream made by [`AllanStream::forgetting`] weights each difference by `exp(-age / H)`,
/// its age in samples against the horizon `H`, so that it follows a sensor whose noise
/// changes; [`AllanStream::differences`] gives the effective number of differences
/// `(sum w)^2 / sum w^2` of each octave, which sets the estimate's standard error.
///
/// ```
/// use imu_ar::allan::AllanStream;
///
/// let mut s = AllanStream::<4>::new();
/// for x in [1.0f32, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0] {
///     s.push(x);
/// }
/// assert_eq!(s.avar(0), Some(2.0)); // m = 1
/// assert_eq!(s.avar(1), Some(0.0)); // m = 2
/// assert_eq!(s.avar(3), None); // m = 8 needs 16 samples
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AllanStream<const L: usize> {
    octaves: [Octave; L],
    /// Per-sample decay `exp(-1 / H)`; 1 without forgetting.
    decay: f64,
    samples: u64,
    rejected: u64,
}

impl<const L: usize> Default for AllanStream<L> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const L: usize> AllanStream<L> {
    /// An empty estimator that never forgets.
    pub const fn new() -> Self {
        Self {
            octaves: [Octave {
                pending: None,
                previous: None,
                acc: 0.0,
                weight: 0.0,
                weight2: 0.0,
            }; L],
            decay: 1.0,
            samples: 0,
            rejected: 0,
        }
    }

    /// An empty estimator that forgets with a horizon of `horizon` samples: a difference
    /// `k` samples old weighs `exp(-k / horizon)`. Octave `j` then has about
    /// `2 horizon / 2^j` effective differences, so the horizon should be many times the
    /// longest averaging time of interest. An octave follows a step change of the noise
    /// exponentially with time constant `horizon` samples, whatever its `m`.
    ///
    /// ```
    /// use imu_ar::allan::AllanStream;
    ///
    /// let mut s = AllanStream::<4>::forgetting(100.0).unwrap();
    /// for n in 0..2000 {
    ///     // Alternating +-1, then +-3 for the last 1,000 samples.
    ///     let level = if n < 1000 { 1.0 } else { 3.0 };
    ///     s.push(if n % 2 == 0 { level } else { -level });
    /// }
    /// // AVAR(1) = 2 level^2: the first 1,000 samples weigh exp(-10) by now.
    /// assert!((s.avar(0).unwrap() / 18.0 - 1.0).abs() < 1e-3);
    /// ```
    ///
    /// # Errors
    ///
    /// [`AllanError::Horizon`] unless `horizon` is at least 1 and finite.
    pub fn forgetting(horizon: f64) -> Result<Self, AllanError> {
        if !(horizon.is_finite() && horizon >= 1.0) {
            return Err(AllanError::Horizon);
        }
        Ok(Self {
            decay: libm::exp(-1.0 / horizon),
            ..Self::new()
        })
    }

    /// Adds one sample. A NaN or infinite sample is rejected, counted and changes nothing else;
    /// returns whether the sample was taken.
    pub fn push<T: Scalar>(&mut self, x: T) -> bool {
        if !x.is_finite() {
            self.rejected = self.rejected.saturating_add(1);
            return false;
        }
        self.samples = self.samples.saturating_add(1);
        let mut block = x.to_f64();
        let mut size = 1.0;
        // exp(-m / H): the decay between two differences of the octave of m.
        let mut decay = self.decay;
        for o in self.octaves.iter_mut() {
            let avg = block / size;
            size *= 2.0;
            if let Some(prev) = o.previous {
                o.acc = decay * o.acc + (avg - prev) * (avg - prev);
                o.weight = decay * o.weight + 1.0;
                o.weight2 = decay * decay * o.weight2 + 1.0;
            }
            o.previous = Some(avg);
            match o.pending.take() {
                Some(first) => block += first,
                None => {
                    o.pending = Some(block);
                    break;
                }
            }
            decay *= decay;
        }
        true
    }

    /// Allan variance at `m = 2^level`, or `None` before two blocks of that size were seen.
    pub fn avar(&self, level: usize) -> Option<f64> {
        let o = self.octaves.get(level)?;
        (o.weight > 0.0).then(|| o.acc / (2.0 * o.weight))
    }

    /// The effective number of differences behind [`AllanStream::avar`] at `level`,
    /// `(sum w)^2 / sum w^2`: without forgetting, their number `floor(N / m) - 1`. 0 before the
    /// first.
    pub fn differences(&self, level: usize) -> f64 {
        self.octaves
            .get(level)
            .filter(|o| o.weight2 > 0.0)
            .map_or(0.0, |o| o.weight * o.weight / o.weight2)
    }

    /// Samples taken.
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Samples rejected as NaN or infinite.
    pub fn rejected(&self) -> u64 {
        self.rejected
    }
}
