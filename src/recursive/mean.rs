//! Exponentially weighted running mean.

use super::WeightSum;
use crate::Scalar;

/// The exponentially weighted mean `m_n = sum lambda^(n-i) x_i / sum lambda^(n-i)`, updated as
/// `m_n = m_{n-1} + (x_n - m_{n-1}) / W_n`, `W_n = lambda W_{n-1} + 1`.
///
/// The recursive cores remove it with the same `lambda` as the estimator: a residual turn-on
/// bias otherwise drives `a_1` towards 1 (numerics.md section 2.4). The sample is centred with
/// the mean *before* it (`y_n = x_n - m_{n-1}`, `m_0 = x_1`), so the a-priori prediction error of
/// `y` is that of `x` and the prediction `xhat_n = m_{n-1} + yhat_n` is causal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunningMean<T> {
    mean: T,
    weight: WeightSum<T>,
    started: bool,
}

impl<T: Scalar> RunningMean<T> {
    /// No samples yet; the mean is 0 until the first.
    pub fn new() -> Self {
        Self {
            mean: T::ZERO,
            weight: WeightSum(T::ZERO),
            started: false,
        }
    }

    /// The current mean.
    pub fn mean(&self) -> T {
        self.mean
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
            self.mean = x;
            self.started = true;
        }
        let y = x - self.mean;
        self.weight.push(lambda);
        self.mean += y / self.weight.0;
        y
    }
}
