//! The measured Allan variances at `tau = 2^j dt` that a noise model is fitted to, with the
//! equivalent degrees of freedom of each.

use crate::Scalar;
use crate::allan::{self, AllanStream, overlapping_avar};

use super::{NoiseError, indexed};

/// Which estimator measured the Allan variances: it sets their equivalent degrees of freedom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Estimator {
    /// The overlapping estimator over `n` samples ([`overlapping_avar`], the host).
    Overlapping {
        /// Samples in the record.
        n: u64,
    },
    /// The non-overlapping estimator ([`AllanStream`], the device) over `n` samples (a
    /// forgetting stream: its effective number of differences per octave instead, see
    /// [`Octaves::from_stream`]).
    NonOverlapping {
        /// Samples taken.
        n: u64,
    },
}

/// The noise type that dominates an Allan estimate, which decides its degrees of freedom.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NoiseType {
    /// White phase noise: quantisation, `AVAR ~ tau^-2`.
    WhitePhase,
    /// White frequency noise: angle or velocity random walk, `AVAR ~ tau^-1`.
    WhiteFrequency,
    /// Flicker frequency noise: bias instability, flat `AVAR`.
    FlickerFrequency,
    /// Random-walk frequency noise: rate random walk, `AVAR ~ tau`.
    RandomWalkFrequency,
}

impl Estimator {
    /// Samples in the record.
    pub fn samples(&self) -> u64 {
        match *self {
            Self::Overlapping { n } | Self::NonOverlapping { n } => n,
        }
    }

    /// Equivalent degrees of freedom `nu` of the Allan variance at `m` samples per cluster
    /// when `noise` dominates: the estimate is distributed as `AVAR chi^2_nu / nu`, so its
    /// relative standard error is `sqrt(2 / nu)` (and the deviation's `1 / sqrt(2 nu)`).
    ///
    /// - Non-overlapping, `K = floor(n/m) - 1` differences of consecutive cluster means:
    ///   `2 K^2 / (3 K - 1)`, whatever the noise. Neighbouring differences share a cluster
    ///   (correlation -1/2 for white frequency noise), so `sum d^2` has the variance
    ///   `sigma^4 (12 K - 4)`, and this is exact for white frequency noise (about `2 K / 3`).
    /// - Overlapping: the simple formulas of W. J. Riley, *Handbook of Frequency Stability
    ///   Analysis*, NIST SP 1065 (2008), table 5 (after Howe, Allan and Barnes 1981), with
    ///   `N = n + 1` phase points, at most the `n - 2m + 1` differences there are.
    ///
    /// At least 1; 0 when fewer than two clusters fit (no estimate).
    pub fn edf(&self, m: u64, noise: NoiseType) -> f64 {
        let n = self.samples();
        if m == 0 || n / m < 2 {
            return 0.0;
        }
        match *self {
            Self::NonOverlapping { .. } => non_overlapping_edf((n / m - 1) as f64),
            Self::Overlapping { .. } => {
                let differences = n.saturating_sub(m.saturating_mul(2)).saturating_add(1) as f64;
                let riley = overlapping_edf(n as f64 + 1.0, m as f64, noise);
                riley.min(differences).max(1.0)
            }
        }
    }
}

impl Estimator {
    /// The correlation between the logarithms of the Allan variances of two neighbouring
    /// octaves (`m` and `2 m`) when `noise` dominates them. Neighbouring estimates share their
    /// data, so they are far from independent: a fit that counted every octave as a separate
    /// measurement would be too sure of itself, most of all of a random walk.
    ///
    /// Measured by simulation (1000 records of `2^15` samples per noise type, octaves
    /// `m = 4 .. 256`, where the values no longer depend on `m`):
    ///
    /// | noise | overlapping | non-overlapping |
    /// |---|---|---|
    /// | white phase (quantisation) | 0.37 | 0.28 |
    /// | white frequency (white noise) | 0.54 | 0.37 |
    /// | flicker frequency (bias instability) | 0.69 | 0.55 |
    /// | random-walk frequency (random walk) | 0.89 (0.75 used) | 0.86 (0.72 used) |
    ///
    /// Octaves further apart are taken as a Markov chain over the octaves (the product of the
    /// neighbours' correlations), which keeps the correlation matrix positive definite and its
    /// inverse tridiagonal. For the random walk the chain overstates the correlation two
    /// octaves apart (0.79 for 0.69 measured, overlapping), and whitened by it, the misfit
    /// `chi^2` of the true model was 1.45 times its number of octaves (48 white + random-walk
    /// records, 1 h at 100 and 400 Hz): it makes a bend of the curve look significant. With
    /// the neighbour correlation 0.75 the true model's `chi^2` matches its octaves, so that
    /// value is used (0.72 for the non-overlapping estimator, scaled alike).
    pub fn octave_correlation(&self, noise: NoiseType) -> f64 {
        let overlapping = matches!(self, Self::Overlapping { .. });
        match (noise, overlapping) {
            (NoiseType::WhitePhase, true) => 0.37,
            (NoiseType::WhitePhase, false) => 0.28,
            (NoiseType::WhiteFrequency, true) => 0.54,
            (NoiseType::WhiteFrequency, false) => 0.37,
            (NoiseType::FlickerFrequency, true) => 0.69,
            (NoiseType::FlickerFrequency, false) => 0.55,
            (NoiseType::RandomWalkFrequency, true) => 0.75,
            (NoiseType::RandomWalkFrequency, false) => 0.72,
        }
    }
}

/// The degrees of freedom of `k` (effective) consecutive differences of cluster means:
/// `2 k^2 / (3 k - 1)` (see [`Estimator::edf`]).
pub(super) fn non_overlapping_edf(k: f64) -> f64 {
    if k <= 0.0 {
        return 0.0;
    }
    2.0 * k * k / (3.0 * k - 1.0)
}

/// Riley's table 5 for `big` phase points and `m` samples per cluster.
fn overlapping_edf(big: f64, m: f64, noise: NoiseType) -> f64 {
    match noise {
        NoiseType::WhitePhase => (big + 1.0) * (big - 2.0 * m) / (2.0 * (big - m)),
        NoiseType::WhiteFrequency => {
            (3.0 * (big - 1.0) / (2.0 * m) - 2.0 * (big - 2.0) / big) * 4.0 * m * m
                / (4.0 * m * m + 5.0)
        }
        NoiseType::FlickerFrequency if m < 2.0 => {
            2.0 * (big - 2.0) * (big - 2.0) / (2.3 * big - 4.9)
        }
        NoiseType::FlickerFrequency => 5.0 * big * big / (4.0 * m * (big + 3.0 * m)),
        NoiseType::RandomWalkFrequency => {
            let b1 = big - 1.0;
            (big - 2.0) / m * (b1 * b1 - 3.0 * m * b1 + 4.0 * m * m) / ((big - 3.0) * (big - 3.0))
        }
    }
}

/// Parts a record is cut into to see whether its short-term level moves
/// ([`Octaves::with_parts`]).
pub const PARTS: usize = 8;

/// The first octaves whose level is compared between the parts of a record: `tau` up to
/// eight samples, where a change of the white level shows in full and a slow change of the
/// mean (a warm-up, a ramp: Allan variance growing as `tau^2`) does not.
pub const DRIFT_OCTAVES: usize = 4;

/// The fewest clusters of `2^j` samples a part needs for its octave `j` to be compared.
const PART_CLUSTERS: u64 = 64;

/// Allan variances at `tau = 2^j dt`, `j = 0..len`, with the estimator that measured them.
///
/// `L` is the capacity in octaves.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Octaves<const L: usize> {
    dt: f64,
    avar: [f64; L],
    /// A stream's effective number of differences per octave; empty otherwise.
    differences: Option<[f64; L]>,
    len: usize,
    estimator: Estimator,
    /// The relative variance the movement of the level between parts of the record adds to
    /// the Allan variance of each of the first octaves ([`Octaves::with_parts`]); 0 where it is
    /// not measured or not significant.
    drift: [f64; DRIFT_OCTAVES],
}

impl<const L: usize> Octaves<L> {
    /// The octaves of a streaming estimator sampled every `dt` seconds: every level with at
    /// least one difference, each with the stream's effective number of differences as its
    /// degrees of freedom (for a forgetting stream, fewer than `floor(n/m) - 1`).
    ///
    /// # Errors
    ///
    /// [`NoiseError::Interval`] for a `dt` that is not positive and finite.
    pub fn from_stream(stream: &AllanStream<L>, dt: f64) -> Result<Self, NoiseError> {
        check_dt(dt)?;
        let mut avar = [0.0; L];
        let mut differences = [0.0; L];
        let mut len = 0;
        for (j, (a, d)) in indexed(avar.iter_mut().zip(differences.iter_mut())) {
            let Some(v) = stream.avar(j) else { break };
            (*a, *d) = (v, stream.differences(j));
            len = j.saturating_add(1);
        }
        Ok(Self {
            dt,
            avar,
            differences: Some(differences),
            len,
            estimator: Estimator::NonOverlapping {
                n: stream.samples(),
            },
            drift: [0.0; DRIFT_OCTAVES],
        })
    }

    /// The overlapping Allan variances of `x`, sampled every `dt` seconds, at every octave
    /// with at least two clusters (`2m <= n`), up to `L`. `O(n L)` operations.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Interval`] for a bad `dt`; [`NoiseError::NonFinite`] for a NaN or
    /// infinite sample.
    pub fn overlapping<T: Scalar>(x: &[T], dt: f64) -> Result<Self, NoiseError> {
        check_dt(dt)?;
        if let Some(index) = x.iter().position(|v| !v.is_finite()) {
            return Err(NoiseError::NonFinite { index });
        }
        let mut avar = [0.0; L];
        let mut len = 0usize;
        // The mean once for every octave (the same bits as `overlapping_avar`'s).
        let mean = if x.is_empty() { 0.0 } else { allan::mean(x) };
        for (j, slot) in indexed(avar.iter_mut()) {
            let m = 1usize << j.min(63);
            if j >= 63 || x.len() / 2 < m {
                break;
            }
            // m >= 1, 2m <= n and every sample finite: the estimate exists.
            let v = allan::centred_avar(x, m, mean);
            // Sums of m samples of about 1e152 or more overflow.
            if !v.to_f64().is_finite() {
                return Err(NoiseError::Overflow);
            }
            *slot = v.to_f64();
            len = len.saturating_add(1);
        }
        let whole = Self {
            dt,
            avar,
            differences: None,
            len,
            estimator: Estimator::Overlapping { n: x.len() as u64 },
            drift: [0.0; DRIFT_OCTAVES],
        };
        // The same estimator over each of PARTS consecutive parts, at the first octaves: part
        // k's second differences are those that end in it (as a stream sums them), so that
        // the parts share the whole record's differences.
        let part = x.len() / PARTS;
        let mut parts = [(0u64, [0.0; DRIFT_OCTAVES]); PARTS];
        for (k, (samples, avar)) in indexed(parts.iter_mut()) {
            *samples = part as u64;
            let end = k.saturating_add(1).saturating_mul(part);
            for (j, slot) in indexed(avar.iter_mut()) {
                let m = 1usize << j;
                if (part as u64) < PART_CLUSTERS.saturating_mul(m as u64) {
                    break;
                }
                let start = k.saturating_mul(part).saturating_sub(2 * m);
                let Some(slice) = x.get(start..end) else {
                    return Ok(whole);
                };
                let Ok(v) = overlapping_avar(slice, m) else {
                    break;
                };
                *slot = v.to_f64();
            }
        }
        let rows = parts.each_ref().map(|(n, a)| (*n, &a[..]));
        Ok(whole.with_parts(&rows))
    }

    /// The octaves with what consecutive parts of the same record say of its stationarity:
    /// `parts[k]` holds part `k`'s samples and its Allan variances at the first octaves, as
    /// the whole record's were measured (what it holds at octaves its samples are too few for
    /// is not read).
    ///
    /// At each of the first [`DRIFT_OCTAVES`] octaves where every part has at least 64
    /// clusters, the parts' spread is tested against their sampling spread (Cochran's `Q`,
    /// `(k - 1) s^2 / (2 / nu)` against `chi^2_(k-1)`, at 5 % over the octaves together). Where
    /// the level moves more than sampling explains, the excess between-part variance over
    /// `k` is what that movement adds to the whole record's estimate (the random-effects
    /// model of meta-analysis, DerSimonian and Laird 1986): [`NoiseModel::uncertainty`] adds
    /// it to `N`'s. Fewer than four parts change nothing.
    ///
    /// [`NoiseModel::uncertainty`]: super::NoiseModel::uncertainty
    #[must_use]
    pub fn with_parts(mut self, parts: &[(u64, &[f64])]) -> Self {
        self.drift = [0.0; DRIFT_OCTAVES];
        let k = parts.len();
        if k < 4 {
            return self;
        }
        let kf = k as f64;
        // Bonferroni over the octaves: chi^2_(k-1) at 1 - 0.05 / DRIFT_OCTAVES (z = 2.241).
        let critical = (kf - 1.0) * chi2_quantile_over_nu(kf - 1.0, 2.241);
        for (j, slot) in indexed(self.drift.iter_mut()) {
            let m = 1u64 << j;
            // The parts' mean, summed in shares so that it cannot overflow.
            let mut sum = 0.0;
            let mut within = 0.0;
            let mut usable = true;
            for (n, avar) in parts {
                let a = avar.get(j).copied().unwrap_or(f64::NAN);
                // A part of zero variance (a stuck sensor) is the level's largest move.
                usable &= *n >= PART_CLUSTERS.saturating_mul(m) && a.is_finite() && a >= 0.0;
                sum += a / kf;
                within += 2.0
                    / Estimator::Overlapping { n: *n }
                        .edf(m, NoiseType::WhiteFrequency)
                        .max(1.0);
            }
            if !(usable && sum > 0.0 && sum.is_finite()) {
                break;
            }
            let mean = sum;
            within /= kf;
            let spread = parts
                .iter()
                .map(|(_, a)| {
                    let r = a.get(j).copied().unwrap_or(0.0) / mean - 1.0;
                    r * r
                })
                .sum::<f64>()
                / (kf - 1.0);
            if (kf - 1.0) * spread / within > critical {
                *slot = (spread - within) / kf;
            }
        }
        self
    }

    /// The relative variance the movement of the record's level between its parts adds to
    /// its Allan variance at octave `j` ([`Octaves::with_parts`]); 0 where it is not
    /// significant or not measured.
    pub fn drift(&self, j: usize) -> f64 {
        self.drift.get(j).copied().unwrap_or(0.0)
    }

    /// Octaves given directly: `avar[j]` at `tau = 2^j dt`, measured by `estimator`.
    ///
    /// # Errors
    ///
    /// [`NoiseError::Interval`] for a bad `dt`, [`NoiseError::TooManyOctaves`] for more than `L`
    /// values or more octaves than the estimator's `n` samples give (octave `j` needs
    /// `2^(j+1)`), [`NoiseError::NonFinite`] for a NaN, infinite or negative value.
    pub fn new(dt: f64, avar: &[f64], estimator: Estimator) -> Result<Self, NoiseError> {
        check_dt(dt)?;
        if avar.len() > L {
            return Err(NoiseError::TooManyOctaves { capacity: L });
        }
        // Octave j needs two clusters of 2^j samples.
        let n = estimator.samples();
        let possible = (u64::BITS - n.leading_zeros()).saturating_sub(1) as usize;
        if avar.len() > possible {
            return Err(NoiseError::TooManyOctaves { capacity: possible });
        }
        if let Some(index) = avar.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(NoiseError::NonFinite { index });
        }
        let mut out = [0.0; L];
        out.iter_mut().zip(avar).for_each(|(o, v)| *o = *v);
        Ok(Self {
            dt,
            avar: out,
            differences: None,
            len: avar.len(),
            estimator,
            drift: [0.0; DRIFT_OCTAVES],
        })
    }

    /// The octaves with every Allan variance times `2^exponent`.
    pub(super) fn scaled(&self, exponent: i32) -> Self {
        let mut out = *self;
        out.avar
            .iter_mut()
            .for_each(|v| *v = libm::scalbn(*v, exponent));
        out
    }

    /// The sample interval, in seconds.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The Allan variances, `[j]` at `tau = 2^j dt`, in units^2.
    pub fn avar(&self) -> &[f64] {
        &self.avar[..self.len.min(L)]
    }

    /// The estimator that measured them.
    pub fn estimator(&self) -> Estimator {
        self.estimator
    }

    /// The degrees of freedom of octave `j` when `noise` dominates it: from a stream's
    /// effective number of differences `K`, `2 K^2 / (3 K - 1)` as for
    /// [`Estimator::NonOverlapping`] (at least 1), or [`Estimator::edf`].
    pub fn edf(&self, j: usize, noise: NoiseType) -> f64 {
        match &self.differences {
            Some(d) => d.get(j).map_or(0.0, |v| non_overlapping_edf(*v).max(1.0)),
            None => self.estimator.edf(1u64 << j.min(63), noise),
        }
    }

    /// `tau = 2^j dt`, in seconds.
    pub fn tau(&self, j: usize) -> f64 {
        self.dt * (1u64 << j.min(63)) as f64
    }
}

/// `chi^2_nu / nu` at `z` standard normal deviations (Wilson-Hilferty), at least 0.
pub(super) fn chi2_quantile_over_nu(nu: f64, z: f64) -> f64 {
    let c = 2.0 / (9.0 * nu);
    let b = 1.0 - c + z * libm::sqrt(c);
    if b > 0.0 { b * b * b } else { 0.0 }
}

fn check_dt(dt: f64) -> Result<(), NoiseError> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(NoiseError::Interval)
    }
}
