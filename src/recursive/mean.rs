//! Exponentially weighted running mean.

use super::shell::WeightSum;
use crate::Scalar;

/// The exponentially weighted mean `m_n = sum lambda^(n-i) x_i / sum lambda^(n-i)`, updated as
/// `m_n = m_{n-1} + (x_n - m_{n-1}) / W_n`, `W_n = lambda W_{n-1} + 1`.
///
/// The recursive cores remove it with the same `lambda` as the estimator: a residual turn-on
/// bias otherwise drives `a_1` towards 1 (numerics.md section 2.4). The sample is centred with
/// the mean *before* it (`y_n = x_n - m_{n-1}`, `m_0 = x_1`), so the a-priori prediction error of
/// `y` is that of `x` and the prediction `xhat_n = m_{n-1} + yhat_n` is causal.
///
/// The mean is held as `x_1 + c`, and `c` tracks the mean of `x - x_1`: a sensor's offset is
/// usually much larger than its noise (an accelerometer axis at -1 g with 4 mg of noise), and
/// in `f32` the increments `y_n / W_n` of a mean held directly would be rounded to the grid of
/// the offset (ulp(1) = 1.2e-7 against increments of 4e-7 at `lambda = 0.9999`). Measured on
/// the ADIS16405 `az` record, order 8, `lambda = 0.9999`: the held-directly mean cost 7.4e-4 in
/// the coefficients, this form 1.5e-6.
///
/// The origin is re-centred on the mean (`x_1 + c` becomes the origin, `c` becomes 0) whenever
/// `|c|` exceeds `|x_1 + c|`, the mean itself: the offset is then no more precise than the
/// mean held directly, so the move costs no more than `c`'s own rounding, and it leaves `c`
/// small against the spread again. Without it a large first sample pins the grid of `c` for
/// good (a first sample of `1e6` puts `c` on a grid of 0.0625 in `f32`, coarser than any
/// increment `y_n / W_n`); with it, any start is forgotten as `lambda` says.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunningMean<T> {
    /// `x_1`, or the mean at the last re-centring.
    origin: T,
    /// Weighted mean of `x - origin`.
    offset: T,
    weight: WeightSum<T>,
    started: bool,
}

impl<T: Scalar> RunningMean<T> {
    /// No samples yet; the mean is 0 until the first.
    pub fn new() -> Self {
        Self {
            origin: T::ZERO,
            offset: T::ZERO,
            weight: WeightSum(T::ZERO),
            started: false,
        }
    }

    /// A mean already settled: `mean` with the weight `weight` of the samples behind it
    /// (`sum lambda^(n-i)`), as if they had been taken one by one.
    pub fn settled(mean: T, weight: T) -> Self {
        Self {
            origin: mean,
            offset: T::ZERO,
            weight: WeightSum(weight),
            started: true,
        }
    }

    /// The current mean.
    pub fn mean(&self) -> T {
        self.origin + self.offset
    }

    /// What [`center`](Self::center) would return for `x`, without taking `x` into the mean.
    pub fn peek(&self, x: T) -> T {
        if self.started {
            (x - self.origin) - self.offset
        } else {
            T::ZERO
        }
    }

    /// Centres `x` with the mean before it and then takes `x` into the mean.
    ///
    /// ```
    /// use imu_ar::recursive::RunningMean;
    ///
    /// let mut m = RunningMean::new();
    /// assert_eq!(m.center(0.5f32, 4.0), 0.0); // the first sample starts the mean
    /// assert_eq!(m.center(0.5, 1.0), -3.0);
    /// assert_eq!(m.mean(), 2.0); // (0.5 * 4 + 1) / 1.5
    /// ```
    pub fn center(&mut self, lambda: T, x: T) -> T {
        if !self.started {
            self.origin = x;
            self.started = true;
        }
        let y = (x - self.origin) - self.offset;
        self.weight.push(lambda);
        self.offset += y / self.weight.0;
        if self.offset.abs() > (self.origin + self.offset).abs() {
            self.origin += self.offset;
            self.offset = T::ZERO;
        }
        y
    }
}
