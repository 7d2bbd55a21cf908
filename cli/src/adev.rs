//! `imu-ar adev`: the overlapping Allan deviation at `m = 1, 2, 4, ...` samples.

use imu_ar::allan::AllanError;
use serde::Serialize;

use crate::error::Fail;
use crate::input::{Input, check_rate, check_span};
use crate::output::Output;

/// The arguments of `imu-ar adev`.
#[derive(clap::Args)]
pub struct Args {
    /// The column.
    #[command(flatten)]
    input: Input,
    /// Sample rate in Hz [default: from the timestamps].
    #[arg(long, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The Allan variance and deviation at `tau = m / rate` while `2m <= n`.
#[derive(Serialize)]
pub struct AdevResult {
    /// Sample rate in Hz.
    pub rate_hz: f64,
    /// Averaging times in s.
    pub tau_s: Vec<f64>,
    /// Overlapping Allan variance at each `tau`.
    pub avar: Vec<f64>,
    /// Its square root.
    pub adev: Vec<f64>,
    /// Samples in the record.
    pub n: usize,
}

impl Output for AdevResult {
    fn text(&self) -> String {
        let mut s = format!(
            "# n = {}, rate = {} Hz\n# tau_s avar adev\n",
            self.n, self.rate_hz
        );
        for ((t, v), d) in self.tau_s.iter().zip(&self.avar).zip(&self.adev) {
            s += &format!("{t} {v:e} {d:e}\n");
        }
        s
    }
}

/// Checks the rate, reads the record and computes its Allan deviation.
pub fn run(args: &Args) -> Result<AdevResult, Fail> {
    if let Some(r) = args.rate {
        check_rate(r)?;
    }
    let series = args.input.series(args.rate.is_none())?;
    let x = &series.x;
    if x.len() < 2 {
        let e = format!("{} sample(s), at least 2 needed", x.len());
        return Err(args.input.fail(e));
    }
    let rate = series.rate(args.rate, &args.input)?;
    check_span("--rate", rate, x.len())?;
    let mut ms = Vec::new();
    let mut m = 1usize;
    while x.len() / 2 >= m {
        ms.push(m);
        m *= 2;
    }
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let avar = octaves(x, &ms, threads)?;
    if let Some((m, _)) = ms.iter().zip(&avar).find(|(_, v)| !v.is_finite()) {
        return Err(args.input.fail(format!(
            "the Allan variance at m = {m} overflows: the samples' differences are too large \
             for f64 (scale the data, --unit)"
        )));
    }
    // All zero: the samples are all equal (a stuck sensor), or their differences underflow.
    if avar.iter().all(|&v| v == 0.0) {
        return Err(args.input.fail(if x.iter().all(|v| *v == x[0]) {
            "the record is constant (a stuck sensor?): every Allan variance is zero"
        } else {
            "the Allan variance underflows f64 (differences of about 1e-160 or less); rescale \
             the record"
        }));
    }
    let tau = ms.iter().map(|&m| m as f64 / rate).collect();
    Ok(AdevResult {
        rate_hz: rate,
        tau_s: tau,
        adev: avar.iter().map(|v| v.sqrt()).collect(),
        avar,
        n: x.len(),
    })
}

/// The overlapping Allan variances of `x` at the averaging factors `ms` (each `1 <= m` and
/// `2m <= n`), on up to `threads` threads: the estimator of
/// [`overlapping_avar`](imu_ar::allan::overlapping_avar) (the mean removed, SP 1065 eq. 11),
/// computed from the phase (the cumulative sum of `x` less its mean) as the mean square of its
/// second differences `p[i + 2m] - 2 p[i + m] + p[i]`. All factors are summed in one sweep over
/// the phase, block by block (the blocks at the factors' offsets stay in the cache from one
/// factor to the next), the record split between the threads. The same values as
/// `allantools.oadev(x, data_type="freq")` to about 1e-13, several times faster than a pass of
/// running sums per factor.
///
/// # Errors
///
/// [`AllanError`] for a factor of 0 or above `n / 2`, or a sample that is not finite.
pub fn octaves(x: &[f64], ms: &[usize], threads: usize) -> Result<Vec<f64>, AllanError> {
    let n = x.len();
    if let Some(&m) = ms.iter().find(|&&m| m == 0 || n / 2 < m) {
        return match m {
            0 => Err(AllanError::ZeroAveraging),
            m => Err(AllanError::TooShort {
                needed: 2 * m,
                given: n,
            }),
        };
    }
    let sum = x.iter().sum::<f64>();
    if !sum.is_finite()
        && let Some(index) = x.iter().position(|v| !v.is_finite())
    {
        return Err(AllanError::NonFinite { index });
    }
    let mean = sum / n as f64;
    let mut phase = Vec::with_capacity(n + 1);
    let mut p = 0.0;
    phase.push(p);
    for v in x {
        p += v - mean;
        phase.push(p);
    }
    let phase = &phase[..];
    // The second differences of the smallest factor reach furthest.
    let reach = ms.iter().map(|&m| n + 1 - 2 * m).max().unwrap_or(0);
    let threads = threads.clamp(1, reach.div_ceil(BLOCK).max(1));
    let part = reach.div_ceil(threads).next_multiple_of(BLOCK);
    let mut sums = vec![0.0; ms.len()];
    std::thread::scope(|s| {
        let work: Vec<_> = (0..threads)
            .map(|t| s.spawn(move || sweep(phase, ms, t * part, ((t + 1) * part).min(reach))))
            .collect();
        for h in work {
            // A sweep is arithmetic on slices of checked lengths: it does not panic.
            for (total, v) in sums.iter_mut().zip(h.join().unwrap_or_default()) {
                *total += v;
            }
        }
    });
    Ok(ms
        .iter()
        .zip(sums)
        .map(|(&m, sum)| {
            let mf = m as f64;
            sum / (2.0 * mf * mf * (n + 1 - 2 * m) as f64)
        })
        .collect())
}

/// The phase's samples per block of a sweep.
const BLOCK: usize = 1024;

/// For each factor of `ms`, the sum of the squared second differences of the phase `p` that
/// start at `from..to` (and exist).
fn sweep(p: &[f64], ms: &[usize], from: usize, to: usize) -> Vec<f64> {
    let mut sums = vec![0.0; ms.len()];
    let mut start = from;
    while start < to {
        let end = (start + BLOCK).min(to);
        for (sum, &m) in sums.iter_mut().zip(ms) {
            // The differences of factor m start at 0..=n - 2m.
            let last = (p.len() - 2 * m).min(end);
            if start < last {
                *sum += block(
                    &p[start..last],
                    &p[start + m..last + m],
                    &p[start + 2 * m..last + 2 * m],
                );
            }
        }
        start = end;
    }
    sums
}

/// The sum of `(c - 2 b + a)^2` over equal-length slices.
fn block(a: &[f64], b: &[f64], c: &[f64]) -> f64 {
    // Eight sums, so that the loop vectorises.
    const W: usize = 8;
    let mut acc = [0.0f64; W];
    let (ac, bc, cc) = (a.chunks_exact(W), b.chunks_exact(W), c.chunks_exact(W));
    let (ar, br, cr) = (ac.remainder(), bc.remainder(), cc.remainder());
    for ((a, b), c) in ac.zip(bc).zip(cc) {
        for j in 0..W {
            let d = c[j] - 2.0 * b[j] + a[j];
            acc[j] += d * d;
        }
    }
    let mut sum: f64 = acc.iter().sum();
    for ((a, b), c) in ar.iter().zip(br).zip(cr) {
        let d = c - 2.0 * b + a;
        sum += d * d;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use imu_ar::allan::overlapping_avar;

    #[test]
    fn the_phase_passes_agree_with_the_library() {
        let mut s = 3u32;
        let mut walk = 0.0;
        let x: Vec<f64> = (0..50_000)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let u = f64::from(s >> 8) / 16_777_216.0 - 0.5;
                walk += 1e-3 * u;
                5.0 + u + walk
            })
            .collect();
        let ms: Vec<usize> = (0..15).map(|k| 1 << k).collect();
        let fast = octaves(&x, &ms, 3).unwrap_or_default();
        assert_eq!(fast.len(), ms.len());
        for (&m, v) in ms.iter().zip(&fast) {
            let slow = overlapping_avar(&x, m).unwrap_or(f64::NAN);
            assert!((v / slow - 1.0).abs() < 1e-11, "m = {m}: {v} {slow}");
        }
        assert!(octaves(&x, &[25_001], 2).is_err());
        assert!(octaves(&[1.0, f64::NAN, 2.0, 3.0], &[1], 2).is_err());
        assert!(octaves(&[1.0, f64::INFINITY, 2.0, 3.0], &[1], 2).is_err());
        // Threads and blocks change nothing but the order of the sums.
        let one = octaves(&x, &ms, 1).unwrap_or_default();
        for (a, b) in one.iter().zip(&fast) {
            assert!((a / b - 1.0).abs() < 1e-13);
        }
    }
}
