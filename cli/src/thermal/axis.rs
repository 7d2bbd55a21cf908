//! One axis's bias against temperature: binned, fitted, and checked on bins held out.

use super::bins::{self, Bin};
use super::cubic::{Poly, fit, prediction_variance};
use crate::input::number;

/// The smallest temperature span a calibration is fitted over, deg C (ArduPilot's
/// `TEMP_RANGE_MIN`).
pub const MIN_SPAN: f64 = 10.0;

/// The polynomial degree both autopilots use.
pub const DEGREE: usize = 3;

/// One axis's bias against temperature, with how well it is known.
#[derive(Clone, Debug, PartialEq)]
pub struct AxisFit {
    /// The fitted bias, about the middle of the range.
    pub poly: Poly,
    /// The bins it was fitted to.
    pub bins: Vec<Bin>,
    /// The lowest and the highest temperature of the samples, deg C.
    pub range: (f64, f64),
    /// The fitted bias's spread over the range, largest less smallest: the bias change to
    /// correct (the bins' own spread holds their noise, which a bin of a few samples at the
    /// range's end makes the whole of it on an axis without a thermal bias).
    pub change: f64,
    /// The largest `|bin - fit|` over the bins that tell it ([`AxisFit::telling`]).
    pub residual: f64,
    /// The bins whose median is known to within four times the typical bin's (their
    /// errors' median), or that lie more than four of their own errors off the fit: those
    /// the figures of what the fit leaves are taken over. A bin of a few samples at the
    /// range's end carries its noise, not the fit's error, unless the fit misses it.
    pub telling: Vec<bool>,
    /// The largest `|bin - fit|` over bins left out of the fit (those that tell it): fitted
    /// to the even bins and checked on the odd ones, and the other way round.
    pub held_out: f64,
    /// The root mean square of the held-out bins' `(bin - fit) / se`, `se` the standard error
    /// of a bin's median (`1.2533 spread / sqrt(count)`, normal noise): about 1 when the fit
    /// explains the bins to their noise.
    pub held_out_z: f64,
}

/// The robust cubic of `bins` about their middle, when they determine one.
fn first_fit(bins: &[Bin]) -> Option<Poly> {
    let (first, last) = (bins.first()?, bins.last()?);
    let points: Vec<(f64, f64)> = bins.iter().map(|b| (b.celsius, b.value)).collect();
    fit(&points, DEGREE, 0.5 * (first.celsius + last.celsius))
}

/// The smallest difference between two of the finite values `x`: their resolution (0 for
/// fewer than two distinct values).
fn resolution(x: &[f64]) -> f64 {
    let mut v: Vec<f64> = x.iter().copied().filter(|v| v.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let step = v
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    if step.is_finite() { step } else { 0.0 }
}

/// The standard error of the median of a bin, for normal noise (1.2533 = sqrt(pi / 2)).
pub fn standard_error(bin: &Bin) -> f64 {
    1.2533 * bin.spread / (bin.count as f64).sqrt()
}

/// Fits the bias of one axis, the samples `x` at the temperatures `celsius` in bins of
/// `width` deg C (those with fewer than `min_count` samples left out): an error when fewer
/// than 8 bins hold samples, or the bins span less than [`MIN_SPAN`].
pub fn fit_axis(
    celsius: &[f64],
    x: &[f64],
    width: f64,
    min_count: usize,
) -> Result<AxisFit, String> {
    let first = bins::bins(celsius, x, width, min_count)?;
    // The samples moved along a first fit to their bins' mean temperatures, and binned again.
    let bins = match first_fit(&first) {
        Some(p) => bins::along(celsius, x, width, min_count, Some(&|t| p.at(t)))?,
        None => first,
    };
    let (Some(first), Some(last)) = (bins.first(), bins.last()) else {
        return Err(format!(
            "no temperature bin of {} deg C holds {min_count} samples (--min-bin)",
            number(width)
        ));
    };
    // The range of the samples in the bins fitted (a stray sample in a bin of its own, left
    // out, does not widen it): the autopilots hold the correction at its ends beyond it.
    let range = (first.span.0, last.span.1);
    if range.1 - range.0 < MIN_SPAN {
        return Err(format!(
            "the temperature spans {:.1} to {:.1} deg C: at least {MIN_SPAN} deg C are needed for a \
             thermal calibration",
            range.0, range.1
        ));
    }
    if bins.len() < 8 {
        return Err(format!(
            "{} temperature bins of {} deg C hold samples: at least 8 are needed",
            bins.len(),
            number(width)
        ));
    }
    let reference = 0.5 * (range.0 + range.1);
    let points: Vec<(f64, f64)> = bins.iter().map(|b| (b.celsius, b.value)).collect();
    let no_fit = || "the bins do not determine a cubic".to_string();
    let poly = fit(&points, DEGREE, reference).ok_or_else(no_fit)?;
    let worst = |p: &Poly, of: &mut dyn Iterator<Item = &(f64, f64)>| {
        of.map(|&(t, y)| (y - p.at(t)).abs()).fold(0.0, f64::max)
    };
    let mut held_out: f64 = 0.0;
    let mut z2 = 0.0;
    // A bin's error: its median's, and at least the values' resolution (a sensor quantised
    // coarser than its noise has bins of identical values, whose median is still only known to
    // within a step: a uniform error of the step over sqrt(12)).
    let step = resolution(x);
    let error = |b: &Bin| (standard_error(b).powi(2) + step * step / 12.0).sqrt();
    let mut errors: Vec<f64> = bins.iter().map(error).collect();
    let typical = {
        let mid = (errors.len() - 1) / 2;
        *errors.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    // (A bin off the fit by more than four of its own errors tells, however few its samples:
    // the bias beyond a knee at the range's end.)
    let telling: Vec<bool> = bins
        .iter()
        .map(|b| error(b) <= 4.0 * typical || (b.value - poly.at(b.celsius)).abs() > 4.0 * error(b))
        .collect();
    let residual = worst(
        &poly,
        &mut points
            .iter()
            .zip(&telling)
            .filter(|(_, t)| **t)
            .map(|(p, _)| p),
    );
    for parity in 0..2 {
        let kept: Vec<(f64, f64)> = points.iter().skip(parity).step_by(2).copied().collect();
        let p = fit(&kept, DEGREE, reference).ok_or_else(no_fit)?;
        let mut told = points.iter().zip(&telling).skip(1 - parity).step_by(2);
        held_out = held_out.max(worst(
            &p,
            &mut told.by_ref().filter(|(_, t)| **t).map(|(p, _)| p),
        ));
        // The error of a held-out bin's residual: its own, and the fit's from the other bins.
        let fitted: Vec<&Bin> = bins.iter().skip(parity).step_by(2).collect();
        let temperatures: Vec<f64> = fitted.iter().map(|b| b.celsius).collect();
        let errors: Vec<f64> = fitted.iter().map(|b| error(b)).collect();
        let variance =
            prediction_variance(&temperatures, &errors, DEGREE, reference).ok_or_else(no_fit)?;
        for b in bins.iter().skip(1 - parity).step_by(2) {
            // No error at all (identical values everywhere): a part in 1e12 of the value.
            let se = (error(b).powi(2) + variance(b.celsius))
                .sqrt()
                .max(1e-12 * b.value.abs())
                .max(f64::MIN_POSITIVE);
            z2 += ((b.value - p.at(b.celsius)) / se).powi(2);
        }
    }
    let held_out_z = (z2 / bins.len() as f64).sqrt();
    // The cubic over the range, at a thousand points and the bins' temperatures.
    let (low, high) = (0..=1000)
        .map(|k| range.0 + (range.1 - range.0) * f64::from(k) / 1000.0)
        .chain(points.iter().map(|p| p.0))
        .map(|t| poly.at(t))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    Ok(AxisFit {
        poly,
        bins,
        range,
        change: high - low,
        residual,
        telling,
        held_out,
        held_out_z,
    })
}

#[cfg(test)]
mod tests {
    use super::super::autopilot::{ArduPilot, Px4, Sensor};
    use super::*;
    use rand_chacha::ChaCha8Rng;
    use rand_core::{RngCore, SeedableRng};

    /// A simulated warm-up: 20 to 60 deg C, fast at first and slow at the end (an uneven
    /// heating rate), the temperature reported in whole degrees, a cubic gyro bias and white
    /// noise, with a few knocks.
    fn warm_up(seed: u64, bias: impl Fn(f64) -> f64, noise: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut normal = || {
            let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let v = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            (-2.0 * (u.max(1e-300)).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let n = 200_000;
        let (mut t, mut x) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for i in 0..n {
            let s = i as f64 / n as f64;
            // Temperature against time: a first-order rise, most of the time near the top.
            let celsius = 20.0 + 40.0 * (1.0 - (-4.0 * s).exp()) / (1.0 - (-4.0f64).exp());
            let mut v = bias(celsius) + noise * normal();
            if i % 40_000 == 17 {
                v += 50.0 * noise;
            }
            t.push(celsius.round());
            x.push(v);
        }
        (t, x)
    }

    fn gyro_bias(t: f64) -> f64 {
        0.004 + 2e-4 * (t - 30.0) - 8e-6 * (t - 30.0).powi(2) + 1e-7 * (t - 30.0).powi(3)
    }

    #[test]
    fn a_few_samples_at_the_ranges_end_do_not_make_what_the_fit_leaves() {
        // 2000 samples a degree from 20 to 59 deg C, then 19 at 60 deg C, their median 1e-3
        // off the bias (about one of its errors, known to 20 times the typical bin's): the
        // residual (and the autopilots' figures, over the same bins) was that bin's 1e-3,
        // several times what the fit leaves elsewhere, before.
        let (mut t, mut x) = warm_up(3, gyro_bias, 2e-3);
        t.retain(|c| *c < 60.0);
        x.truncate(t.len());
        let (t, x): (Vec<f64>, Vec<f64>) = t
            .iter()
            .zip(&x)
            .map(|(a, b)| (*a, *b))
            .chain((0..19).map(|k| {
                // The sensor's noise, spread evenly about the knocked bias.
                let spread = 2e-3 * (f64::from(k * 7 % 19) - 9.0) / 5.5;
                (60.0, gyro_bias(60.0) + 1e-3 + spread)
            }))
            .unzip();
        let f = fit_axis(&t, &x, 1.0, 10).unwrap();
        assert_eq!(
            f.telling.iter().filter(|t| !**t).count(),
            1,
            "{:?}",
            f.telling
        );
        assert!(!f.telling[f.bins.len() - 1]);
        assert!(
            f.residual < 5e-4 && f.held_out < 5e-4,
            "{} {}",
            f.residual,
            f.held_out
        );
        // The same bin of 200 samples off by 5e-2 (a knee past 59 deg C): 50 of its errors,
        // counted (left out, the figures said the fit left 1e-4 where it left 1e-2).
        let (mut t, mut x) = (t, x);
        t.truncate(t.len() - 19);
        x.truncate(t.len());
        for k in 0..200 {
            let spread = 2e-3 * (f64::from(k * 7 % 19) - 9.0) / 5.5;
            t.push(60.0);
            x.push(gyro_bias(60.0) + 5e-2 + spread);
        }
        let f = fit_axis(&t, &x, 1.0, 10).unwrap();
        assert!(f.telling[f.bins.len() - 1], "{:?}", f.telling);
        assert!(f.residual > 1e-2, "{}", f.residual);
    }

    /// The written parameters applied through each autopilot's formula leave at most 10 % of
    /// the bias change, on the bins fitted and on bins held out.
    #[test]
    fn a_warm_up_is_calibrated_for_both_autopilots() {
        let (t, x) = warm_up(1, gyro_bias, 2e-3);
        let f = fit_axis(&t, &x, 1.0, 20).unwrap();
        assert_eq!(f.range, (20.0, 60.0));
        assert!(
            f.residual < 0.1 * f.change,
            "{} of {}",
            f.residual,
            f.change
        );
        assert!(
            f.held_out < 0.1 * f.change,
            "{} of {}",
            f.held_out,
            f.change
        );
        let axes = [f.poly; 3];
        let px4 = Px4::new(Sensor::Gyro, 1, &axes, f.range.0, f.range.1);
        let ap = ArduPilot::new(&axes, &axes, f.range.0, f.range.1);
        for b in &f.bins {
            let px4_left = b.value - f64::from(px4.offset(0, b.celsius as f32));
            assert!(
                px4_left.abs() < 0.1 * f.change,
                "PX4 at {}: {px4_left}",
                b.celsius
            );
            let change = b.value - gyro_bias(35.0);
            let ap_left =
                change - f64::from(ap.correction(Sensor::Gyro, 0, b.celsius as f32, 35.0));
            assert!(
                ap_left.abs() < 0.1 * f.change,
                "ArduPilot at {}: {ap_left}",
                b.celsius
            );
        }
    }

    #[test]
    fn the_change_is_the_fits_not_a_few_samples_noise() {
        // No thermal bias, noise 0.02, 20 to 60 deg C evenly and 15 samples at 60 deg C: the
        // last bin's median is off by its noise (about 6e-3), which the bins' spread read as
        // the bias change (1e-2 where there is none). The fitted bias's spread is the change.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut normal = || {
            let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            let v = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            (-2.0 * (u.max(1e-300)).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let n = 240_000;
        let t: Vec<f64> = (0..n)
            .map(|i| 20.0 + 40.0 * i as f64 / n as f64)
            .chain([60.0; 15])
            .collect();
        let x: Vec<f64> = t.iter().map(|_| 0.02 * normal()).collect();
        let f = fit_axis(&t, &x, 1.0, 10).unwrap();
        let values = f.bins.iter().map(|b| b.value);
        let spread =
            values.clone().fold(f64::NEG_INFINITY, f64::max) - values.fold(f64::INFINITY, f64::min);
        assert!(f.change < 0.5 * spread, "{} of {spread}", f.change);
    }

    #[test]
    fn a_short_span_is_refused() {
        let t: Vec<f64> = (0..1000).map(|i| 30.0 + f64::from(i) * 0.008).collect();
        let x = vec![0.0; 1000];
        let e = fit_axis(&t, &x, 1.0, 1).unwrap_err();
        assert!(e.contains("at least 10 deg C"), "{e}");
    }
}
