//! Noise against temperature: each axis's composite noise model fitted per temperature band,
//! on its samples with the fitted thermal bias taken out (what a filter sees once the
//! calibration is applied), and the worst band's model for the noise parameter files.
//!
//! The bands split the sensor's calibrated range into equal widths; samples below or above it
//! join the first or the last band. A warm-up crosses each band once, in one stretch of the
//! record; a log that heats and cools crosses it twice, and the stretches cannot be joined (the
//! Allan variance of the joint would see the step between them as noise): the longest stretch
//! of the band is fitted, and the band says how many there were.

use serde::Serialize;

use crate::characterise::fit_axis;
use crate::characterise::stream::AxisStream;
use crate::error::Fail;
use crate::export::AxisModel;
use crate::noise::units::Units;
use crate::noise::{Fitting, OCTAVES};
use imu_ar::noise::FitConfig;

use super::axis::AxisFit;

/// The fewest samples a band's noise model is fitted to.
pub const MIN_BAND_SAMPLES: usize = 1000;

/// One band's model of one axis.
#[derive(Serialize)]
pub struct BandNoise {
    /// The band's lower edge, deg C.
    pub from_c: f64,
    /// Its upper edge, deg C.
    pub to_c: f64,
    /// Samples fitted: those of the band's longest stretch.
    pub n: usize,
    /// Samples in the band, in all its stretches.
    pub in_band: usize,
    /// The stretches of the record in the band (the times the temperature crossed it).
    pub stretches: usize,
    /// `N`, u/sqrt(Hz), when a model was fitted.
    pub white_noise: Option<f64>,
    /// Its 95 % interval, where the model gives one (the upper end infinite, `null`, when
    /// the data do not bound it).
    pub white_noise_95: Option<[f64; 2]>,
    /// `K`, u/s/sqrt(Hz), when the model has a random walk.
    pub random_walk: Option<f64>,
    /// Its 95 % interval.
    pub random_walk_95: Option<[f64; 2]>,
    /// `B`: the minimum Allan deviation of the band's data over 0.664.
    pub bias_instability: Option<f64>,
    /// The largest `tau` (s) up to which the model explains the band's Allan deviation.
    pub explained_up_to_s: Option<f64>,
    /// Why the band has no model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// One axis across the bands.
#[derive(Serialize)]
pub struct AxisBands {
    /// gx .. az.
    pub axis: &'static str,
    /// rad/s or m/s^2.
    pub unit: &'static str,
    /// The sample rate the models are at, Hz.
    pub rate_hz: f64,
    /// The bands, coldest first.
    pub bands: Vec<BandNoise>,
    /// The band with the largest `N`, whose model the worst-band parameter files carry.
    pub worst: Option<usize>,
}

/// One sensor of the record as the bands need it.
pub struct Sensor<'a> {
    /// The temperatures, deg C.
    pub celsius: &'a [f64],
    /// The three axes, SI units.
    pub axes: [&'a [f64]; 3],
    /// Their fits.
    pub fits: [&'a AxisFit; 3],
    /// The calibrated range, deg C.
    pub range: (f64, f64),
    /// The sample rate, Hz.
    pub rate: f64,
    /// rad/s or m/s^2.
    pub unit: &'static str,
}

/// The band of `celsius` among `count` bands of equal width over `range`.
pub fn band_of(celsius: f64, (low, high): (f64, f64), count: usize) -> usize {
    let at = (celsius - low) / (high - low) * count as f64;
    if at.is_nan() || at < 0.0 {
        0
    } else {
        (at as usize).min(count - 1)
    }
}

/// The models of `sensor`'s three axes in `count` bands (`names` naming the axes), with the
/// worst band's model of each for the files.
pub fn fit(
    sensor: &Sensor<'_>,
    names: [&'static str; 3],
    count: usize,
    config: &FitConfig,
    filter_rate: Option<f64>,
) -> Result<Vec<(AxisBands, Option<AxisModel>)>, Fail> {
    let (low, high) = sensor.range;
    let width = (high - low) / count as f64;
    let which: Vec<usize> = sensor
        .celsius
        .iter()
        .map(|&t| band_of(t, sensor.range, count))
        .collect();
    let mut out = Vec::with_capacity(3);
    for (k, (x, fit)) in sensor.axes.iter().zip(sensor.fits).enumerate() {
        let mut bands = Vec::with_capacity(count);
        let mut models: Vec<Option<AxisModel>> = Vec::with_capacity(count);
        for b in 0..count {
            // The runs of consecutive samples in the band, and the longest.
            let (mut stretches, mut in_band, mut longest, mut start) = (0, 0, 0..0, None);
            for i in 0..=which.len() {
                match (which.get(i) == Some(&b), start) {
                    (true, None) => start = Some(i),
                    (false, Some(s)) => {
                        stretches += 1;
                        in_band += i - s;
                        if i - s > longest.len() {
                            longest = s..i;
                        }
                        start = None;
                    }
                    _ => {}
                }
            }
            let kept: Vec<f64> = longest
                .map(|i| x[i] - fit.poly.at(sensor.celsius[i]))
                .collect();
            let mut band = BandNoise {
                from_c: low + width * b as f64,
                to_c: low + width * (b + 1) as f64,
                n: kept.len(),
                in_band,
                stretches,
                white_noise: None,
                white_noise_95: None,
                random_walk: None,
                random_walk_95: None,
                bias_instability: None,
                explained_up_to_s: None,
                note: None,
            };
            match band_model(&kept, sensor.rate, sensor.unit, config, filter_rate) {
                Ok((result, model)) => {
                    let interval = |b: &crate::noise::Bounds| [b.low, b.high];
                    band.white_noise = result.white_noise;
                    band.random_walk = result.random_walk;
                    band.white_noise_95 =
                        result.intervals.as_ref().map(|i| interval(&i.white_noise));
                    band.random_walk_95 = result
                        .intervals
                        .as_ref()
                        .filter(|_| result.random_walk.is_some())
                        .map(|i| interval(&i.random_walk));
                    band.bias_instability = Some(result.bias_instability.value);
                    band.explained_up_to_s = result.explained_up_to_s;
                    models.push(model);
                }
                Err(Fail(e)) => {
                    band.note = Some(e);
                    models.push(None);
                }
            }
            bands.push(band);
        }
        let worst = bands
            .iter()
            .enumerate()
            .filter(|(i, b)| b.white_noise.is_some() && models[*i].is_some())
            .max_by(|(_, a), (_, b)| {
                a.white_noise
                    .unwrap_or(0.0)
                    .total_cmp(&b.white_noise.unwrap_or(0.0))
            })
            .map(|(i, _)| i);
        let model = worst.and_then(|i| models[i].take());
        out.push((
            AxisBands {
                axis: names[k],
                unit: sensor.unit,
                rate_hz: sensor.rate,
                bands,
                worst,
            },
            model,
        ));
    }
    Ok(out)
}

/// The composite of one band's samples `x` at `rate`, as `characterise` fits an axis.
fn band_model(
    x: &[f64],
    rate: f64,
    unit: &'static str,
    config: &FitConfig,
    filter_rate: Option<f64>,
) -> Result<(crate::noise::NoiseResult, Option<AxisModel>), Fail> {
    if x.len() < MIN_BAND_SAMPLES {
        return Err(Fail(format!(
            "{} samples: at least {MIN_BAND_SAMPLES} are needed",
            x.len()
        )));
    }
    let mut stream = AxisStream::<OCTAVES>::new();
    stream.extend(x);
    if stream.is_constant() {
        return Err(Fail("constant: no noise to model".into()));
    }
    let fitting = Fitting {
        n: x.len(),
        rate,
        filter_rate: filter_rate.unwrap_or(rate),
        config: *config,
        units: Units::of(unit),
        export: true,
    };
    let octaves = stream
        .octaves(1.0 / rate, 1.0)
        .map_err(|e| Fail(e.to_string()))?;
    let fitted = fit_axis(&fitting, &stream, &octaves, 1.0)?;
    Ok((fitted.result, fitted.axis))
}
