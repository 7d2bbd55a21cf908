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

use imu_ar::noise::{DRIFT_OCTAVES, Estimator, NoiseError, Octaves, PARTS};

/// Octaves computed from every phase point: `m` up to `2^EXACT`.
const EXACT: usize = 12;

/// Ring length of a level: the phase points of two windows of `2^EXACT`, rounded up to a
/// power of two.
const RING: usize = 1 << (EXACT + 2);

/// Autocovariance lags kept (the AR part's highest order).
pub const LAGS: usize = 8;

/// Phase points of level 0 kept: two windows of the longest octave it serves.
const KEEP: usize = 2 << EXACT;

/// Samples between marks at first (eight blocks make the shortest record the library cuts in
/// parts: 64 samples a part); doubled whenever the marks reach [`MARKS`].
const BLOCK: u64 = 1 << 6;

/// The most marks kept.
const MARKS: usize = 1 << 10;

/// The sums of the first octaves over one block of samples (the second differences that end
/// in it): the record's parts are runs of blocks ([`Octaves::with_parts`]). Each block is
/// summed on its own, so that a huge sample in one part leaves the others' sums exact.
#[derive(Clone, Copy, Default)]
struct Mark {
    /// Samples in the block.
    n: u64,
    sums: [f64; DRIFT_OCTAVES],
    counts: [u64; DRIFT_OCTAVES],
}

/// Phase points every `2^level` samples (`level` from 1), in a ring.
struct Level {
    ring: Vec<f64>,
    /// Points taken.
    len: u64,
}

impl Level {
    /// A level that starts at the phase point 0, as level 0 did.
    fn new() -> Self {
        Self {
            ring: vec![0.0; RING],
            len: 1,
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

/// `sum (p[i] - 2 p[i-m] + p[i-2m])^2` over `i` from `from` to the end of `p` (`from >= 2m`),
/// in four running sums: the loop the statistics spend their time in, vectorised.
fn second_differences(p: &[f64], m: usize, from: usize) -> f64 {
    let (a, b, c) = (
        &p[from..],
        &p[from - m..p.len() - m],
        &p[from - 2 * m..p.len() - 2 * m],
    );
    let mut sums = [0.0; 4];
    let mut quads = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .zip(c.chunks_exact(4));
    for ((a, b), c) in quads.by_ref() {
        for k in 0..4 {
            let d = a[k] - 2.0 * b[k] + c[k];
            sums[k] += d * d;
        }
    }
    let done = a.len() - a.len() % 4;
    let mut rest = 0.0;
    for i in done..a.len() {
        let d = a[i] - 2.0 * b[i] + c[i];
        rest += d * d;
    }
    (sums[0] + sums[1]) + (sums[2] + sums[3]) + rest
}

/// Adds `sum_t ys[t] ys[t-k]` over `t` from [`LAGS`] to the end to `lagged[k]`, for every `k`:
/// each sum term by term in the order of `t` from `-0.0` (as `Iterator::sum` adds), all lags
/// in one pass, so that the nine chains of additions overlap instead of running one after
/// another.
fn lagged_sums(lagged: &mut [f64; LAGS + 1], ys: &[f64]) {
    let mut sums = [-0.0f64; LAGS + 1];
    for window in ys.windows(LAGS + 1) {
        let y = window[LAGS];
        for (k, s) in sums.iter_mut().enumerate() {
            *s += y * window[LAGS - k];
        }
    }
    for (l, s) in lagged.iter_mut().zip(sums) {
        *l += s;
    }
}

/// One axis's streaming statistics.
pub struct AxisStream<const L: usize> {
    n: u64,
    /// The first sample, taken off every sample (so that the phase stays small).
    offset: f64,
    phase: f64,
    /// Level 0, every phase point: the newest (at least [`KEEP`]) in order, `points[0]` the
    /// point number `first`.
    points: Vec<f64>,
    first: u64,
    /// Levels 1 and up.
    levels: Vec<Level>,
    /// Sums of the squared second differences and their number, per octave.
    sums: [f64; L],
    counts: [u64; L],
    /// `sum_t y_t y_{t-k}` for `y = x - offset`.
    lagged: [f64; LAGS + 1],
    /// The first and the last `LAGS` values of `y` (the last in a ring: `y_t` at `t % LAGS`).
    head: [f64; LAGS],
    tail: [f64; LAGS],
    /// The values of `y` of one call of [`AxisStream::extend`], after the `LAGS` before them.
    ys: Vec<f64>,
    sum: f64,
    constant: bool,
    /// One mark per `block` samples, and the sums of the block under way.
    marks: Vec<Mark>,
    block: u64,
    open: Mark,
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
            points: Vec::new(),
            first: 0,
            levels: Vec::new(),
            sums: [0.0; L],
            counts: [0; L],
            lagged: [0.0; LAGS + 1],
            head: [0.0; LAGS],
            tail: [0.0; LAGS],
            ys: Vec::new(),
            sum: 0.0,
            constant: true,
            marks: Vec::new(),
            block: BLOCK,
            open: Mark::default(),
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
        self.extend(&[x]);
    }

    /// Takes the next (finite) samples, as [`AxisStream::push`] one by one would (to rounding:
    /// sums run in another order), in a fraction of its time for long runs.
    pub fn extend(&mut self, mut xs: &[f64]) {
        while !xs.is_empty() {
            let room = (self.block - self.n % self.block) as usize;
            let (now, rest) = xs.split_at(room.min(xs.len()));
            self.extend_within_block(now);
            if self.n.is_multiple_of(self.block) {
                self.mark();
            }
            xs = rest;
        }
    }

    /// Closes the block under way; when the marks are full, merges them in pairs and doubles
    /// the block.
    fn mark(&mut self) {
        self.open.n = self.block;
        self.marks.push(std::mem::take(&mut self.open));
        if self.marks.len() >= MARKS {
            let merged: Vec<Mark> = self
                .marks
                .chunks_exact(2)
                .map(|pair| {
                    let mut m = pair[0];
                    m.n += pair[1].n;
                    for j in 0..DRIFT_OCTAVES {
                        m.sums[j] += pair[1].sums[j];
                        m.counts[j] += pair[1].counts[j];
                    }
                    m
                })
                .collect();
            self.marks = merged;
            self.block *= 2;
        }
    }

    /// [`AxisStream::extend`] for samples that do not cross a block's end.
    fn extend_within_block(&mut self, xs: &[f64]) {
        let Some(&x0) = xs.first() else {
            return;
        };
        if self.n == 0 {
            self.offset = x0;
            self.points.push(0.0);
        }
        let before = self.n;
        // The LAGS values of y before these, oldest first.
        self.ys.clear();
        let lags = LAGS.min(before as usize);
        for i in (1..=lags).rev() {
            self.ys.push(self.tail[(before as usize - i) % LAGS]);
        }
        let new = self.points.len();
        for &x in xs {
            let y = x - self.offset;
            self.constant &= y == 0.0;
            let t = self.n as usize;
            if t < LAGS {
                self.head[t] = y;
            }
            self.tail[t % LAGS] = y;
            self.ys.push(y);
            self.sum += y;
            self.phase += y;
            self.points.push(self.phase);
            self.n += 1;
            // Level l takes every 2^l-th point.
            let mut level = 1;
            while level < L.saturating_sub(EXACT) && self.n.trailing_zeros() as usize >= level {
                if self.levels.len() < level {
                    self.levels.push(Level::new());
                }
                self.take_strided(level, self.phase);
                level += 1;
            }
        }
        // Autocovariance sums: each y against the LAGS values before it.
        if lags == LAGS {
            // All lags from the same y: their sums side by side, each in the order below.
            lagged_sums(&mut self.lagged, &self.ys);
        } else {
            for (k, lagged) in self.lagged.iter_mut().enumerate() {
                let ys = &self.ys;
                let from = lags.max(k);
                if from >= ys.len() {
                    continue;
                }
                *lagged += ys[from..]
                    .iter()
                    .zip(&ys[from - k..])
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
            }
        }
        // Level 0 serves octaves 0..=EXACT: point number q completes a second difference at
        // m = 2^j once q >= 2m.
        for j in 0..(EXACT + 1).min(L) {
            let m = 1usize << j;
            let from = new.max((2 * m).saturating_sub(self.first as usize));
            if from < self.points.len() {
                let (sum, count) = (
                    second_differences(&self.points, m, from),
                    (self.points.len() - from) as u64,
                );
                self.sums[j] += sum;
                self.counts[j] += count;
                if j < DRIFT_OCTAVES {
                    self.open.sums[j] += sum;
                    self.open.counts[j] += count;
                }
            }
        }
        if self.points.len() >= 2 * KEEP {
            let drop = self.points.len() - KEEP;
            self.points.drain(..drop);
            self.first += drop as u64;
        }
    }

    /// Adds point `p` to `level` (from 1), and the second difference it completes at octave
    /// `EXACT + level`, at `2^EXACT` of its points.
    fn take_strided(&mut self, level: usize, p: f64) {
        let lv = &mut self.levels[level - 1];
        lv.push(p);
        let j = EXACT + level;
        let m = 1u64 << EXACT;
        if j < L && lv.len > 2 * m {
            let d = lv.back(0) - 2.0 * lv.back(m) + lv.back(2 * m);
            self.sums[j] += d * d;
            self.counts[j] += 1;
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
        let octaves = Octaves::new(dt, &avar[..len], Estimator::Overlapping { n: self.n })?;
        // PARTS parts of whole blocks, as equal as the marks allow.
        let blocks = self.marks.len();
        if blocks < PARTS {
            return Ok(octaves);
        }
        let mut parts = [(0u64, [0.0; DRIFT_OCTAVES]); PARTS];
        for (k, (n, avar)) in parts.iter_mut().enumerate() {
            let run = &self.marks[k * blocks / PARTS..(k + 1) * blocks / PARTS];
            *n = run.iter().map(|b| b.n).sum();
            for (j, v) in avar.iter_mut().enumerate() {
                let count: u64 = run.iter().map(|b| b.counts[j]).sum();
                if count > 0 {
                    let sum: f64 = run.iter().map(|b| b.sums[j]).sum();
                    let mf = (1u64 << j) as f64;
                    *v = scale * sum / (2.0 * mf * mf * count as f64);
                }
            }
        }
        let rows = parts.each_ref().map(|(n, a)| (*n, &a[..]));
        Ok(octaves.with_parts(&rows))
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

    /// Gaussian noise of standard deviation `level(i)` at sample `i` (Box-Muller over a
    /// 64-bit linear congruential generator).
    fn noise(n: usize, level: impl Fn(usize) -> f64) -> Vec<f64> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|i| {
                let (u, v) = (uniform(), uniform());
                level(i) * (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
            })
            .collect()
    }

    #[test]
    fn parts_see_a_moving_level_as_the_library_does() {
        // 1.2 M samples: the marks are merged five times (one every 2048 samples).
        let n = 1_200_000;
        for (step, moves) in [(1.0, false), (1.1, true)] {
            let x = noise(n, |i| if i < n / 2 { 1.0 } else { step });
            let mut s = AxisStream::<20>::new();
            s.extend(&x);
            assert_eq!(s.block, BLOCK << 5);
            let o = s.octaves(0.01, 1.0).unwrap();
            let want = Octaves::<20>::overlapping(&x, 0.01).unwrap();
            for j in 0..DRIFT_OCTAVES {
                let (a, b) = (o.drift(j), want.drift(j));
                assert_eq!(a > 0.0, moves, "step {step} octave {j}: {a}");
                assert_eq!(b > 0.0, moves, "step {step} octave {j}: {b}");
                // Parts of whole blocks against exact eighths.
                assert!((a - b).abs() <= 0.05 * b, "octave {j}: {a} vs {b}");
            }
        }
    }

    /// The stream's parts against the library's exact eighths: a short record (its blocks not
    /// yet merged), a huge sample in the first part (each block summed on its own, so that the
    /// later parts are not lost to cancellation), a stuck eighth (zero variance: the largest
    /// move, not a part left out) and a record of exactly eight blocks.
    #[test]
    fn hostile_parts_agree_with_the_library() {
        let cases: [(&str, Vec<f64>); 4] = [
            (
                "short, stepped",
                noise(4000, |i| if i < 2000 { 1.0 } else { 3.0 }),
            ),
            ("outlier", {
                let mut x = noise(1 << 20, |_| 1.0);
                x[1000] = 1e11;
                x
            }),
            ("stuck eighth", {
                let n = 1 << 20;
                let mut x = noise(n, |_| 1.0);
                x[3 * n / 8..4 * n / 8].iter_mut().for_each(|v| *v = 5.0);
                x
            }),
            (
                "eight blocks",
                noise(8 * BLOCK as usize, |i| if i < 256 { 1.0 } else { 2.0 }),
            ),
        ];
        for (name, x) in cases {
            let mut s = AxisStream::<20>::new();
            s.extend(&x);
            let o = s.octaves(0.01, 1.0).unwrap();
            let want = Octaves::<20>::overlapping(&x, 0.01).unwrap();
            assert!(want.drift(0) > 0.0, "{name}: the library sees no move");
            for j in 0..DRIFT_OCTAVES {
                let (a, b) = (o.drift(j), want.drift(j));
                assert_eq!(a > 0.0, b > 0.0, "{name} octave {j}: {a} vs {b}");
                assert!((a - b).abs() <= 0.1 * b, "{name} octave {j}: {a} vs {b}");
            }
        }
    }

    /// The lags summed side by side give the bits of each lag summed on its own (the sums as
    /// they were formed, lag after lag), for ordinary, huge, tiny, signed-zero, infinite and
    /// NaN values, from a running sum of any value (NaN for NaN).
    #[test]
    fn lags_side_by_side_equal_each_lag_alone() {
        let special = [
            0.0,
            -0.0,
            1e300,
            -1e300,
            1e-300,
            f64::MIN_POSITIVE / 3.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            9.81,
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            state >> 11
        };
        for case in 0..20_000 {
            let len = LAGS + 1 + (next() % 80) as usize;
            let rare = next() % 4;
            let ys: Vec<f64> = (0..len)
                .map(|_| match next() % 64 {
                    k if k < rare => special[(next() % special.len() as u64) as usize],
                    _ if case % 7 == 0 => -0.0,
                    _ => {
                        (next() as f64 / (1u64 << 53) as f64 - 0.5)
                            * 10f64.powi((next() % 9) as i32 - 4)
                    }
                })
                .collect();
            let start: [f64; LAGS + 1] = std::array::from_fn(|k| match (case + k) % 5 {
                0 => 0.0,
                1 => -0.0,
                2 => special[(next() % special.len() as u64) as usize],
                _ => next() as f64 / 7.0,
            });
            let mut alone = start;
            for (k, lagged) in alone.iter_mut().enumerate() {
                *lagged += ys[LAGS..]
                    .iter()
                    .zip(&ys[LAGS - k..])
                    .map(|(a, b)| a * b)
                    .sum::<f64>();
            }
            let mut together = start;
            lagged_sums(&mut together, &ys);
            // (A NaN's sign and payload are not the arithmetic's to keep: any NaN is one.)
            let bits =
                |v: [f64; LAGS + 1]| v.map(|x| if x.is_nan() { None } else { Some(x.to_bits()) });
            assert_eq!(bits(together), bits(alone), "case {case}: {ys:?}");
        }
    }

    #[test]
    fn extending_in_pieces_equals_pushing_one_by_one() {
        let x = record(70_000);
        let mut one = AxisStream::<18>::new();
        x.iter().for_each(|v| one.push(*v));
        let mut pieces = AxisStream::<18>::new();
        let mut at = 0;
        for len in [1, 0, 7, 4096, 3, 20_000, 9000, 1].iter().cycle() {
            let end = (at + len).min(x.len());
            pieces.extend(&x[at..end]);
            at = end;
            if at == x.len() {
                break;
            }
        }
        assert_eq!(pieces.samples(), one.samples());
        assert_eq!(pieces.counts, one.counts);
        assert_eq!(pieces.marks.len(), one.marks.len());
        for (a, b) in pieces.marks.iter().zip(&one.marks) {
            assert_eq!((a.n, a.counts), (b.n, b.counts));
            for (p, q) in a.sums.iter().zip(&b.sums) {
                assert!((p - q).abs() <= 1e-12 * q, "mark at {}: {p} vs {q}", a.n);
            }
        }
        // Octaves 0 to 15 hold second differences (70,000 samples hold two windows of 2^15).
        assert!(pieces.counts[15] > 0 && pieces.counts[16] == 0);
        for j in 0..18 {
            let (a, b) = (pieces.sums[j], one.sums[j]);
            assert!((a - b).abs() <= 1e-12 * b, "octave {j}: {a} vs {b}");
        }
        for k in 0..=LAGS {
            let (a, b) = (pieces.lagged[k], one.lagged[k]);
            assert!((a - b).abs() <= 1e-12 * b.abs(), "lag {k}: {a} vs {b}");
        }
        assert_eq!(pieces.head, one.head);
        assert_eq!(pieces.tail, one.tail);
        assert_eq!(pieces.mean(), one.mean());
    }
}
