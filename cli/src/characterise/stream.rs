//! What `characterise` keeps of one axis while the record streams past: overlapping Allan
//! variances at every octave and the autocovariances for the AR part, in bounded memory
//! (about 2.6 MB per axis for any length), so that a 10-hour recording is never held.
//!
//! The Allan variance at `m` samples is that of the overlapping estimator,
//! `sum_i (P[i+2m] - 2 P[i+m] + P[i])^2 / (2 m^2 count)` over the phase `P` (the running sum of
//! the samples less the first), with every phase point `i` up to `m = 2^EXACT` (identical to
//! `imu_ar::allan::overlapping_avar`, to rounding) and, beyond, every `m / 2^EXACT`-th: there
//! are then still 4096 terms in every window of `m` samples, so the estimate keeps the
//! overlapping estimator's degrees of freedom to within a fraction of a percent.

use imu_ar::noise::{Estimator, NoiseError, Octaves};

/// Octaves computed from every phase point: `m` up to `2^EXACT`.
const EXACT: usize = 12;

/// Ring length of a level: the phase points of two windows of `2^EXACT`, rounded up to a
/// power of two.
const RING: usize = 1 << (EXACT + 2);

/// Autocovariance lags kept (the AR part's highest order).
pub const LAGS: usize = 8;

/// Phase points every `2^level` samples.
struct Level {
    ring: Vec<f64>,
    /// Points taken.
    len: u64,
}

impl Level {
    fn new() -> Self {
        Self {
            ring: vec![0.0; RING],
            len: 0,
        }
    }

    /// The point `back` places before the newest.
    fn back(&self, back: u64) -> f64 {
        let i = (self.len - 1 - back) as usize & (RING - 1);
        self.ring[i]
    }

    fn push(&mut self, p: f64) {
        let i = self.len as usize & (RING - 1);
        self.ring[i] = p;
        self.len += 1;
    }
}

/// One axis's streaming statistics.
pub struct AxisStream<const L: usize> {
    n: u64,
    /// The first sample, taken off every sample (so that the phase stays small).
    offset: f64,
    phase: f64,
    levels: Vec<Level>,
    /// Sums of the squared second differences and their number, per octave.
    sums: [f64; L],
    counts: [u64; L],
    /// `sum_t y_t y_{t-k}` for `y = x - offset`.
    lagged: [f64; LAGS + 1],
    /// The first and the last `LAGS` values of `y`.
    head: [f64; LAGS],
    tail: [f64; LAGS],
    sum: f64,
    constant: bool,
}

impl<const L: usize> Default for AxisStream<L> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const L: usize> AxisStream<L> {
    /// Nothing taken yet.
    pub fn new() -> Self {
        Self {
            n: 0,
            offset: 0.0,
            phase: 0.0,
            levels: Vec::new(),
            sums: [0.0; L],
            counts: [0; L],
            lagged: [0.0; LAGS + 1],
            head: [0.0; LAGS],
            tail: [0.0; LAGS],
            sum: 0.0,
            constant: true,
        }
    }

    /// Samples taken.
    pub fn samples(&self) -> u64 {
        self.n
    }

    /// Whether every sample so far equals the first.
    pub fn is_constant(&self) -> bool {
        self.constant
    }

    /// Takes the next (finite) sample.
    pub fn push(&mut self, x: f64) {
        if self.n == 0 {
            self.offset = x;
            self.levels.push(Level::new());
            self.levels[0].push(0.0);
        }
        let y = x - self.offset;
        self.constant &= y == 0.0;
        let n = self.n as usize;
        // Autocovariance sums: y against the LAGS values before it.
        self.lagged[0] += y * y;
        for k in 1..=LAGS.min(n) {
            self.lagged[k] += y * self.tail[(n - k) % LAGS];
        }
        if n < LAGS {
            self.head[n] = y;
        }
        self.tail[n % LAGS] = y;
        self.sum += y;
        self.n += 1;
        self.phase += y;
        self.take_point(0, self.phase);
        // Level l takes every 2^l-th point.
        let mut level = 1;
        while level < L.saturating_sub(EXACT) && self.n.trailing_zeros() as usize >= level {
            if self.levels.len() <= level {
                // The level starts at the phase point 0, as level 0 did.
                let mut fresh = Level::new();
                fresh.push(0.0);
                self.levels.push(fresh);
            }
            self.take_point(level, self.phase);
            level += 1;
        }
    }

    /// Adds point `p` to `level` and the second differences it completes.
    fn take_point(&mut self, level: usize, p: f64) {
        let lv = &mut self.levels[level];
        lv.push(p);
        let len = lv.len;
        // Level 0 serves octaves 0..=EXACT; level l > 0 octave EXACT + l, at 2^EXACT points.
        let octaves = if level == 0 {
            0..(EXACT + 1).min(L)
        } else {
            (EXACT + level)..(EXACT + level + 1).min(L)
        };
        for j in octaves {
            let m = 1u64 << (j - level);
            if len > 2 * m {
                let d = lv.back(0) - 2.0 * lv.back(m) + lv.back(2 * m);
                self.sums[j] += d * d;
                self.counts[j] += 1;
            }
        }
    }

    /// The Allan variances at every octave with at least two clusters, samples `dt` apart,
    /// times `scale` (the square of a unit conversion), measured by the overlapping estimator
    /// over the samples taken.
    pub fn octaves(&self, dt: f64, scale: f64) -> Result<Octaves<L>, NoiseError> {
        let mut avar = [0.0; L];
        let mut len = 0;
        for (j, v) in avar.iter_mut().enumerate() {
            let m = 1u64 << j;
            if self.n / 2 < m || self.counts[j] == 0 {
                break;
            }
            let mf = m as f64;
            *v = scale * self.sums[j] / (2.0 * mf * mf * self.counts[j] as f64);
            if !v.is_finite() {
                return Err(NoiseError::Overflow);
            }
            len = j + 1;
        }
        Octaves::new(dt, &avar[..len], Estimator::Overlapping { n: self.n })
    }

    /// The mean of the samples.
    pub fn mean(&self) -> f64 {
        self.offset + self.sum / self.n.max(1) as f64
    }

    /// The biased autocovariances `c_0..c_LAGS` about the mean (positive semi-definite, as
    /// Yule-Walker needs), `c_k = sum_{t>=k} (x_t - mean)(x_{t-k} - mean) / n`.
    pub fn autocovariances(&self) -> [f64; LAGS + 1] {
        let n = self.n as usize;
        let mu = self.sum / n.max(1) as f64;
        let mut c = [0.0; LAGS + 1];
        for (k, ck) in c.iter_mut().enumerate().take(n.min(LAGS + 1)) {
            // sum_{t>=k} y_t and sum_{t<n-k} y_t.
            let first: f64 = self.head[..k.min(LAGS)].iter().sum();
            let last: f64 = (1..=k).map(|i| self.tail[(n - i) % LAGS]).sum();
            let a = self.sum - first;
            let b = self.sum - last;
            *ck = (self.lagged[k] - mu * (a + b) + (n - k) as f64 * mu * mu) / n as f64;
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_ar::allan::overlapping_avar;

    fn record(n: usize) -> Vec<f64> {
        // A deterministic, coloured sequence with an offset.
        let mut s = 0.3f64;
        (0..n)
            .map(|i| {
                s = 0.9 * s + ((i * 7919 % 1013) as f64 / 1013.0 - 0.5);
                9.81 + s
            })
            .collect()
    }

    #[test]
    fn exact_octaves_equal_the_overlapping_estimator() {
        let x = record(20_000);
        let mut s = AxisStream::<16>::new();
        x.iter().for_each(|v| s.push(*v));
        let o = s.octaves(0.01, 1.0).unwrap();
        assert_eq!(o.avar().len(), 14);
        for (j, v) in o.avar().iter().enumerate().take(EXACT + 1) {
            let want = overlapping_avar(&x, 1 << j).unwrap();
            assert!((v / want - 1.0).abs() < 1e-9, "octave {j}: {v} vs {want}");
        }
    }

    #[test]
    fn strided_octaves_stay_close_to_the_overlapping_estimator() {
        let x = record(1 << 16);
        let mut s = AxisStream::<20>::new();
        x.iter().for_each(|v| s.push(*v));
        let o = s.octaves(0.01, 1.0).unwrap();
        assert_eq!(o.avar().len(), 16);
        for j in 13..16 {
            let want = overlapping_avar(&x, 1 << j).unwrap();
            // Every 2nd, 4th, 8th point: the same estimate to well within its standard error.
            assert!((o.avar()[j] / want - 1.0).abs() < 0.05, "octave {j}");
        }
    }

    #[test]
    fn autocovariances_equal_the_direct_sums() {
        for n in [1usize, 3, 9, 500] {
            let x = record(n);
            let mut s = AxisStream::<8>::new();
            x.iter().for_each(|v| s.push(*v));
            let mean = x.iter().sum::<f64>() / n as f64;
            let c = s.autocovariances();
            for k in 0..=LAGS.min(n - 1) {
                let want: f64 = (k..n)
                    .map(|t| (x[t] - mean) * (x[t - k] - mean))
                    .sum::<f64>()
                    / n as f64;
                assert!(
                    (c[k] - want).abs() < 1e-9 * want.abs().max(1e-3),
                    "n {n} lag {k}"
                );
            }
            assert!((s.mean() - mean).abs() < 1e-12);
        }
    }
}
