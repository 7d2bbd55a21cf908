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
}

impl fmt::Display for AllanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ZeroAveraging => f.write_str("averaging factor must be at least 1"),
            Self::TooShort { needed, given } => {
                write!(f, "{given} samples given, at least {needed} needed")
            }
            Self::NonFinite { index } => write!(f, "sample {index} is NaN or infinite"),
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
    let mean = x.iter().map(|v| v.to_f64()).sum::<f64>() / n as f64;
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
    Ok(T::from_f64(acc / (2.0 * mf * mf * (n - 2 * m + 1) as f64)))
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
    /// Sum of squared differences of consecutive block averages.
    acc: f64,
    /// Number of differences in `acc`.
    count: u64,
}

/// Streaming Allan variance at `m = 1, 2, 4, .., 2^(L-1)` in fixed memory.
///
/// Each octave keeps the pending block sum, the previous block average, a sum of squares and a
/// count (40 bytes an octave: 800 bytes for `L = 20`), so one sample costs `O(1)` amortised
/// (two octave updates on average). The estimate is the **non-overlapping** Allan variance
/// `sum_k (ybar_{k+1} - ybar_k)^2 / (2 K)` over consecutive blocks of `m` samples: it has the same
/// expectation as [`overlapping_avar`] but uses `N/m - 1` differences instead of `N - 2m + 1`,
/// so its variance is larger (by up to about 2x at large `m`). Accumulates in `f64`.
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
    samples: u64,
    rejected: u64,
}

impl<const L: usize> Default for AllanStream<L> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const L: usize> AllanStream<L> {
    /// An empty estimator.
    pub const fn new() -> Self {
        Self {
            octaves: [Octave {
                pending: None,
                previous: None,
                acc: 0.0,
                count: 0,
            }; L],
            samples: 0,
            rejected: 0,
        }
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
        for o in self.octaves.iter_mut() {
            let avg = block / size;
            size *= 2.0;
            if let Some(prev) = o.previous {
                o.acc += (avg - prev) * (avg - prev);
                o.count = o.count.saturating_add(1);
            }
            o.previous = Some(avg);
            match o.pending.take() {
                Some(first) => block += first,
                None => {
                    o.pending = Some(block);
                    break;
                }
            }
        }
        true
    }

    /// Allan variance at `m = 2^level`, or `None` before two blocks of that size were seen.
    pub fn avar(&self, level: usize) -> Option<f64> {
        let o = self.octaves.get(level)?;
        (o.count > 0).then(|| o.acc / (2.0 * o.count as f64))
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
