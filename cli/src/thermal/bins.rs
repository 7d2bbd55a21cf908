//! Samples grouped by temperature.
//!
//! A warm-up record spends most of its time where the temperature moves slowly (near the end
//! of the warm-up, or at a temperature a sensor reports in 1 deg C steps), and a plain fit to
//! the raw samples is pulled towards those temperatures. Bins of equal width, each reduced to
//! its median and fitted with equal weight, give every temperature the same say; the median
//! keeps a knock or a bump out of a bin's value.

use crate::input::number;

/// The most bins a record may span.
pub const MAX_BINS: usize = 100_000;

/// One bin of samples: where it lies and what it holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bin {
    /// The mean temperature of its samples, deg C (with 1 deg C steps, the step's value).
    pub celsius: f64,
    /// The median of its samples.
    pub value: f64,
    /// Its samples.
    pub count: usize,
    /// The median absolute deviation of its samples from `value`, times 1.4826 (the standard
    /// deviation, for normal noise).
    pub spread: f64,
    /// The lowest and the highest temperature of its samples, deg C.
    pub span: (f64, f64),
}

/// The bins `[k width, (k + 1) width)` deg C of the samples `x` taken at
/// `celsius`, lowest first, those with fewer than `min_count` samples left out. Samples with a
/// temperature or a value that is not finite are left out. An error when the temperatures span
/// more than [`MAX_BINS`] bins, or the width is not a positive number.
pub fn bins(celsius: &[f64], x: &[f64], width: f64, min_count: usize) -> Result<Vec<Bin>, String> {
    along(celsius, x, width, min_count, None)
}

/// [`bins`] with each sample first moved along `curve` to its bin's mean temperature:
/// `x - (curve(T) - curve(T_bin))`. Within a bin the samples are seldom spread evenly (a
/// warm-up slows down as it ends), so that the median of the raw values belongs to another
/// temperature than the mean; moved along a first fit, they belong to the bin's mean
/// temperature to the curve's accuracy.
pub fn along(
    celsius: &[f64],
    x: &[f64],
    width: f64,
    min_count: usize,
    curve: Option<&dyn Fn(f64) -> f64>,
) -> Result<Vec<Bin>, String> {
    let pairs = || {
        celsius
            .iter()
            .zip(x)
            .filter(|(t, v)| t.is_finite() && v.is_finite())
    };
    if !(width.is_finite() && width > 0.0) {
        return Err(format!(
            "a bin width of {} deg C: it must be a positive number",
            number(width)
        ));
    }
    let (Some(low), Some(top)) = (
        pairs().map(|(t, _)| *t).reduce(f64::min),
        pairs().map(|(t, _)| *t).reduce(f64::max),
    ) else {
        return Ok(Vec::new());
    };
    // A count that overflows to infinity (or NaN) is too many too.
    let count = (top / width).floor() - (low / width).floor();
    if count.is_nan() || count >= MAX_BINS as f64 {
        return Err(format!(
            "temperatures from {} to {} deg C: more than {MAX_BINS} bins of {} deg C \
             (not a die temperature in deg C, or --bin-width too small?)",
            number(low),
            number(top),
            number(width)
        ));
    }
    // Bins at whole multiples of the width: a sensor that reports whole degrees has each step
    // in one bin of 1 deg C.
    let first = (low / width).floor();
    let index = |t: f64| ((t / width).floor() - first) as usize;
    let high = pairs().map(|(t, _)| index(*t)).max().unwrap_or(0);
    let mut groups: Vec<(f64, Vec<(f64, f64)>)> = vec![(0.0, Vec::new()); high + 1];
    for (&t, &v) in pairs() {
        let g = &mut groups[index(t)];
        g.0 += t;
        g.1.push((t, v));
    }
    Ok(groups
        .into_iter()
        .filter(|(_, samples)| !samples.is_empty() && samples.len() >= min_count)
        .map(|(sum, samples)| {
            let count = samples.len();
            let mean = sum / count as f64;
            let mut values: Vec<f64> = match curve {
                Some(c) => {
                    let at = c(mean);
                    samples.iter().map(|&(t, v)| v - (c(t) - at)).collect()
                }
                None => samples.iter().map(|&(_, v)| v).collect(),
            };
            let value = median(&mut values);
            let mut deviations: Vec<f64> = values.iter().map(|v| (v - value).abs()).collect();
            let spread = 1.4826 * median(&mut deviations);
            let span = samples
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &(t, _)| {
                    (l.min(t), h.max(t))
                });
            Bin {
                celsius: mean,
                value,
                count,
                spread,
                span,
            }
        })
        .collect())
}

/// The median of `values` (not empty), which it reorders.
pub fn median(values: &mut [f64]) -> f64 {
    let n = values.len();
    let mid = n / 2;
    let (below, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    let m = *m;
    if n % 2 == 1 {
        m
    } else {
        let lower = below.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut [7.0]), 7.0);
    }

    /// Ten times as many samples at 20 deg C as at 30: each bin is one value, its median; a
    /// knock (one sample far off) does not move it; a NaN is left out.
    #[test]
    fn a_bin_is_its_median_whatever_the_time_spent_in_it() {
        let mut t = vec![20.2; 1000];
        let mut x = vec![1.0; 1000];
        t.extend([30.1; 100]);
        x.extend([2.0; 100]);
        t.push(30.3);
        x.push(1e6);
        t.push(f64::NAN);
        x.push(5.0);
        let b = bins(&t, &x, 1.0, 10).unwrap();
        assert_eq!(b.len(), 2);
        assert_eq!((b[0].value, b[0].count), (1.0, 1000));
        assert_eq!((b[1].value, b[1].count), (2.0, 101));
        assert!((b[1].celsius - (30.1 * 100.0 + 30.3) / 101.0).abs() < 1e-12);
        assert_eq!(b[1].spread, 0.0);
        // Too few samples: left out.
        assert_eq!(bins(&t, &x, 1.0, 200).unwrap().len(), 1);
        assert_eq!(bins(&[], &[], 1.0, 1), Ok(Vec::new()));
        assert!(bins(&t, &x, 0.0, 1).is_err());
        // A garbage temperature would ask for 1e300 bins.
        t.push(1e300);
        x.push(0.0);
        assert!(
            bins(&t, &x, 1.0, 1)
                .unwrap_err()
                .contains("more than 100000 bins")
        );
    }
}
