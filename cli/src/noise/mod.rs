//! `imu-ar noise`: the composite noise model of one axis, fitted to the record's overlapping
//! Allan variance (`imu_ar::noise`): white noise, quantisation, first-order Gauss-Markov terms
//! (and, with `--oscillators`, second-order ones), random walk, rate ramp and an AR part for
//! the sensor's short-term colouring; checked at every averaging time and handed to a Kalman
//! filter as `Phi`, `Q` and `P0`.

pub(crate) mod plot;
pub(crate) mod units;

use std::path::PathBuf;

use imu_ar::ArModel;
use imu_ar::batch::criteria::Criterion;
use imu_ar::batch::{BatchConfig, burg};
use imu_ar::noise::{
    Check, FitConfig, Ieee952, Interval, KalmanForm, NoiseError, NoiseModel, Octaves, PARTS,
    Uncertainty,
};
use serde::Serialize;

use crate::chart;
use crate::error::Fail;
use crate::export::{AxisModel, StateSpace};
use crate::input::timing::TimingSummary;
use crate::input::{Input, check_decimate, check_order, check_rate, check_span, decimated, number};
use crate::kalman::{AllanRow, allan_text};
use crate::method::with_order;
use crate::output::{Output, json};
use units::Units;

/// The most Kalman states the tool gives the Gauss-Markov terms (`--gm-states`).
pub const MAX_GM_STATES: usize = 8;

/// The highest AR order that the automatic choice (BIC) considers.
pub const AUTO_AR_ORDER: usize = 8;

/// Octaves held: `m = 1 .. 2^31` samples.
pub(crate) const OCTAVES: usize = 32;

/// The arguments of `imu-ar noise`.
#[derive(clap::Args)]
pub struct Args {
    /// The column.
    #[command(flatten)]
    input: Input,
    /// Sample rate in Hz of the raw record [default: from the timestamps].
    #[arg(long, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// The composite's settings.
    #[command(flatten)]
    model: ModelArgs,
    /// Order of the AR part (the sensor's short-term colouring), 1 to 32, or 0 for none
    /// [default: the order 0 to 8 that BIC selects].
    #[arg(long, allow_negative_numbers = true)]
    ar_order: Option<usize>,
    /// Average blocks of M samples first; the model's rate becomes rate / M.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    decimate: usize,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Draw the decomposition plot (data with standard errors, model, components) into this
    /// PNG file.
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// The composite's settings that `noise` and `characterise` share.
#[derive(clap::Args)]
pub struct ModelArgs {
    /// The Kalman states the Gauss-Markov terms may take, 0 to 8 (an oscillator takes two).
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    gm_states: usize,
    /// Allow second-order Gauss-Markov terms (damped oscillators, two states each) for a
    /// spectral line between 0.1 Hz and an eighth of the rate.
    #[arg(long)]
    oscillators: bool,
    /// Fit a rate ramp too (in a static record, usually a temperature drift).
    #[arg(long)]
    ramp: bool,
    /// Fit the curve with every state the budget allows instead of identifying the terms (the
    /// identification adds each term only when it lowers an information criterion, refines
    /// correlation times off the grid and takes a term the record cannot tell from a random
    /// walk as one: `NoiseModel::identify`).
    #[arg(long)]
    curve_fit: bool,
    /// The filter's rate in Hz for `phi`, `q` and `p0` [default: the model's rate], and the
    /// step PX4 EKF2 is asked for (the nearest it takes; default 100 Hz, `EKF2_PREDICT_US`
    /// 10000). ArduPilot EKF3's step is its own (`--loop-rate`).
    #[arg(long, allow_negative_numbers = true)]
    pub filter_rate: Option<f64>,
}

impl ModelArgs {
    /// The fit's settings, once the flags are checked.
    pub fn config(&self) -> Result<FitConfig, Fail> {
        if self.gm_states > MAX_GM_STATES {
            return Err(Fail(format!(
                "--gm-states {}: at most {MAX_GM_STATES}",
                self.gm_states
            )));
        }
        if let Some(f) = self.filter_rate {
            check_rate(f).map_err(|_| {
                Fail(format!(
                    "--filter-rate {}: must be a positive number of Hz",
                    number(f)
                ))
            })?;
        }
        Ok(FitConfig::new(self.gm_states)
            .with_oscillators(self.oscillators)
            .with_ramp(self.ramp)
            .with_identification(!self.curve_fit))
    }
}

/// Bias instability: the minimum Allan deviation of the data over 0.664, and where it is.
#[derive(Serialize)]
pub struct BiasInstability {
    /// `B`, in the column's unit.
    pub value: f64,
    /// The `tau` of the minimum, s.
    pub tau_s: f64,
}

/// A Gauss-Markov term. A second-order term (an oscillator) has a frequency too.
#[derive(Serialize)]
pub struct GmEntry {
    /// Stationary standard deviation, in the column's unit.
    pub sigma: f64,
    /// Correlation time (an oscillator's decay time), s.
    pub correlation_time_s: f64,
    /// An oscillator's centre frequency, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<f64>,
}

/// The AR part: coefficients from the batch (Burg) fit, innovation variance scaled by the
/// noise fit.
#[derive(Serialize)]
pub struct ArPart {
    /// `p`.
    pub order: usize,
    /// `a_1..a_p`.
    pub a: Vec<f64>,
    /// Innovation variance in the model (the Burg fit's times `scale`).
    pub noise_variance: f64,
    /// The factor the noise fit put on the Burg fit's innovation variance.
    pub scale: f64,
}

/// A value with its 95 % interval.
#[derive(Clone, Copy, Serialize)]
pub struct Bounds {
    /// The value.
    pub value: f64,
    /// The interval's lower end.
    pub low: f64,
    /// The interval's upper end (infinite when the data do not bound it: `null` in JSON).
    pub high: f64,
}

impl Bounds {
    /// (A lower end below the smallest normal number is 0: a search that ran to the floor.)
    fn of(value: f64, i: Interval) -> Self {
        Self {
            value,
            low: if i.low.abs() < f64::MIN_POSITIVE {
                0.0
            } else {
                i.low
            },
            high: i.high,
        }
    }

    /// `[low, high]`, an upper end the data do not bound `unbounded`.
    fn text(&self) -> String {
        let high = if self.high.is_infinite() {
            "unbounded".to_string()
        } else {
            json(&self.high)
        };
        format!("[{}, {high}]", json(&self.low))
    }
}

/// A Gauss-Markov term's intervals.
#[derive(Serialize)]
pub struct TermBounds {
    /// `sigma`.
    pub sigma: Bounds,
    /// Correlation time (an oscillator's decay time), s.
    pub correlation_time_s: Bounds,
    /// An oscillator's frequency, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frequency_hz: Option<Bounds>,
}

/// The 95 % intervals of the parameters (`NoiseModel::uncertainty`): from the sampling
/// distribution of the octave Allan variances, the terms a model lacks from 0.
#[derive(Serialize)]
pub struct Intervals {
    /// `N`.
    pub white_noise: Bounds,
    /// `Q`.
    pub quantization: Bounds,
    /// `K`.
    pub random_walk: Bounds,
    /// `R`.
    pub rate_ramp: Bounds,
    /// `B`.
    pub bias_instability: Bounds,
    /// The Gauss-Markov terms, in the order of `gauss_markov`.
    pub gauss_markov: Vec<TermBounds>,
    /// Where the record's eighths show its short-term level moving more than sampling explains
    /// (`Octaves::drift`): the largest such movement, which `white_noise`'s interval counts.
    pub level_drift: Option<LevelDrift>,
}

/// How much the record's short-term level moves between its eighths.
#[derive(Serialize)]
pub struct LevelDrift {
    /// The averaging time where it moves most, s.
    pub tau_s: f64,
    /// The standard deviation of the eighths' Allan deviation beyond their sampling spread,
    /// relative.
    pub spread: f64,
}

impl LevelDrift {
    fn of<const P: usize>(
        model: &NoiseModel<P, MAX_GM_STATES>,
        octaves: &Octaves<OCTAVES>,
    ) -> Option<Self> {
        let (j, d) = model.level_drift(octaves).ok().flatten()?;
        Some(Self {
            tau_s: octaves.tau(j),
            // The eighths' relative variance of their Allan variance is PARTS times the
            // drift; the deviation's is a quarter of that.
            spread: (PARTS as f64 * d).sqrt() / 2.0,
        })
    }
}

impl Intervals {
    fn of<const P: usize>(
        model: &NoiseModel<P, MAX_GM_STATES>,
        u: &Uncertainty<MAX_GM_STATES, OCTAVES>,
        b: f64,
        octaves: &Octaves<OCTAVES>,
    ) -> Self {
        let mut gauss_markov: Vec<TermBounds> = model
            .gauss_markov()
            .iter()
            .zip(u.gauss_markov())
            .map(|(t, i)| TermBounds {
                sigma: Bounds::of(t.sigma, i.sigma),
                correlation_time_s: Bounds::of(t.correlation_time, i.correlation_time),
                frequency_hz: None,
            })
            .collect();
        gauss_markov.extend(
            model
                .oscillators()
                .iter()
                .zip(u.oscillators())
                .map(|(o, i)| TermBounds {
                    sigma: Bounds::of(o.sigma, i.sigma),
                    correlation_time_s: Bounds::of(o.decay_time, i.decay_time),
                    frequency_hz: Some(Bounds::of(o.frequency, i.frequency)),
                }),
        );
        Self {
            white_noise: Bounds::of(model.white_noise(), u.white_noise),
            quantization: Bounds::of(model.quantization(), u.quantization),
            random_walk: Bounds::of(model.random_walk(), u.random_walk),
            rate_ramp: Bounds::of(model.ramp(), u.ramp),
            bias_instability: Bounds::of(b, u.bias_instability),
            gauss_markov,
            level_drift: LevelDrift::of(model, octaves),
        }
    }
}

/// What the text output adds to the JSON object.
#[derive(Default)]
pub struct Details {
    unit: String,
    filter_rate_hz: f64,
    states: Vec<String>,
    h: Vec<f64>,
    white_term: f64,
    white_noise_at_1s: Option<f64>,
    measurement_variance: f64,
}

/// The composite model of one axis, its filter form and its Allan check.
#[derive(Serialize)]
pub struct NoiseResult {
    /// The model's rate in Hz (after `--decimate`).
    pub rate_hz: f64,
    /// Samples fitted.
    pub n: usize,
    /// `N` of the whole model (white term and the AR part's white equivalent), u/sqrt(Hz).
    pub white_noise: Option<f64>,
    /// `Q`, u s.
    pub quantization: Option<f64>,
    /// `K`, u/s/sqrt(Hz).
    pub random_walk: Option<f64>,
    /// `R`, u/s.
    pub rate_ramp: Option<f64>,
    /// `B` and its `tau`.
    pub bias_instability: BiasInstability,
    /// The Gauss-Markov terms: first order by correlation time, then the oscillators.
    pub gauss_markov: Vec<GmEntry>,
    /// Whether a term the data call for was left out for want of states (`--gm-states`): the
    /// budget, not the data, limited the model.
    pub budget_limited: bool,
    /// Whether the model is the curve fit that fills the budget (`--curve-fit`, or where the
    /// identified terms fail the whole-curve check and the curve fit passes it): its
    /// parameters describe the curve, and may not be the sensor's.
    pub curve_fit: bool,
    /// The 95 % intervals of the parameters, when the model has few enough for them.
    pub intervals: Option<Intervals>,
    /// The AR part, or `None`.
    pub ar: Option<ArPart>,
    /// The filter's transition over one step: the Gauss-Markov states, the oscillators' state
    /// pairs, the random-walk state, in that order.
    pub phi: Vec<Vec<f64>>,
    /// The process noise of one step.
    pub q: Vec<Vec<f64>>,
    /// The stationary covariance (for the random walk: its variance over the record).
    pub p0: Vec<Vec<f64>>,
    /// The Allan check at every octave.
    pub allan: Vec<AllanRow>,
    /// The largest `tau` (s) up to which every row agrees.
    pub explained_up_to_s: Option<f64>,
    /// The normal deviate of each row's test, so that the check is one 95 % test of the whole
    /// curve (`NoiseModel::check_whole`).
    pub check_z: f64,
    /// What the timestamps show, when the rate came from them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timing: Option<TimingSummary>,
    /// For the text output.
    #[serde(skip)]
    pub details: Details,
}

/// Checks the settings, reads the record, fits and checks the model and draws its plot.
pub fn run(args: &Args) -> Result<NoiseResult, Fail> {
    run_with(args, None)
}

/// [`run`] on the samples `given` (the Python package's arrays) in place of the files': the
/// same checks, fit and result; the rate is `--rate`.
pub fn run_with(args: &Args, given: Option<&[f64]>) -> Result<NoiseResult, Fail> {
    if let Some(r) = args.rate {
        check_rate(r)?;
    }
    check_decimate(args.decimate)?;
    let config = args.model.config()?;
    if let Some(p) = args.ar_order.filter(|p| *p > 0) {
        check_order("--ar-order", p)?;
    }
    if let Some(path) = &args.plot {
        plot::check_path(path)?;
    }
    let series = match given {
        Some(x) => {
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(args.input.fail(format!("sample {i} is NaN or infinite")));
            }
            args.input.given(x)
        }
        None => args.input.series(args.rate.is_none())?,
    };
    let rate = series.rate(args.rate, &args.input)?;
    crate::input::check_gaps(series.timing.as_ref(), series.x.len())
        .and_then(|()| crate::input::check_subsampled(&args.input.files, series.timing.as_ref()))
        .map_err(|e| args.input.fail(e))?;
    let x = decimated(&args.input.files, &series.x, args.decimate)?;
    check_span("--rate", rate, x.len())?;
    let rate = rate / args.decimate as f64;
    let fit = Fitting {
        n: x.len(),
        rate,
        filter_rate: args.model.filter_rate.unwrap_or(rate),
        config,
        units: Units::of(&series.unit),
        export: false,
    };
    let octaves = Octaves::<OCTAVES>::overlapping(&x, 1.0 / rate).map_err(|e| match e {
        NoiseError::Overflow => args.input.fail(
            "the Allan variance overflows f64 (values of about 1e152 or more); rescale the record",
        ),
        e => args.input.fail(e),
    })?;
    if octaves.avar().len() < 2 {
        return Err(args.input.fail(NoiseError::TooFewOctaves {
            given: octaves.avar().len(),
        }));
    }
    if x.iter().all(|v| *v == x[0]) {
        return Err(args.input.fail(
            "the record is constant (a stuck sensor?): every Allan variance is zero, there is \
             no noise to model",
        ));
    }
    // A record that no AR model describes (a Burg fit fails on perfectly predictable data)
    // gets no AR part.
    let order = match args.ar_order {
        Some(p) => p,
        None => bic_order(&x, rate).unwrap_or(0),
    };
    let fitted = match order {
        0 => fit.model::<1>(&octaves, None),
        p => with_order!(p, ar_part(&fit, &x, &octaves)),
    };
    // The same when the order was chosen here and its model does not describe the record
    // (a trend or a pure tone: not stationary).
    let fitted = match fitted {
        Err(_) if args.ar_order.is_none() && order > 0 => fit.model::<1>(&octaves, None),
        fitted => fitted,
    };
    let Fitted {
        mut result, paint, ..
    } = fitted.map_err(|Fail(e)| {
        // Every Allan variance underflowed, though the samples differ.
        if e == NoiseError::Constant.to_string() {
            args.input.fail(
                "the Allan variance underflows f64 (differences of about 1e-160 or less); \
                 rescale the record",
            )
        } else {
            args.input.fail(e)
        }
    })?;
    if let Some(path) = &args.plot {
        plot::png(path, chart::SIZE, &[(&paint, String::new())])
            .map_err(|e| Fail(format!("--plot {}: cannot draw: {e}", path.display())))?;
    }
    result.timing = series.timing;
    Ok(result)
}

/// Checks that the model's Allan deviation stays within the record's at every `tau` of 1 s
/// or more (and 32 samples) that the record holds 16 times or more (past that, the few
/// differences a row averages may fall far under their mean), give or take three of the
/// row's tolerances: each of its terms
/// only adds to it, so a model past the data there claims noise the record does not hold. A
/// hump none of its terms takes (a spectral line) drives a white level or a short
/// Gauss-Markov term over the whole curve: refused, naming the line and `--oscillators`.
fn within_the_data(result: &NoiseResult) -> Result<(), Fail> {
    let from = (32.0 / result.rate_hz).max(1.0);
    let to = result.n as f64 / result.rate_hz / 16.0;
    let worst = result
        .allan
        .iter()
        .filter(|row| (from..=to).contains(&row.tau_s) && row.data_adev > 0.0)
        .map(|row| (row.model_adev / row.data_adev, row))
        .filter(|(over, row)| *over > 1.0 + 3.0 * row.tolerance)
        .max_by(|a, b| a.0.total_cmp(&b.0));
    match worst {
        None => Ok(()),
        Some((over, row)) => Err(Fail(format!(
            "the model's Allan deviation is {over:.2} times the record's at {} s ({} against \
             {}): it claims noise the record does not hold, to cover a hump at shorter times \
             that none of its terms takes (a spectral line: a vibration, a fan; \
             --oscillators models one)",
            number(row.tau_s),
            number(row.model_adev),
            number(row.data_adev)
        ))),
    }
}

/// What draws a fit's decomposition on an area, with a caption.
pub(crate) type Paint<'a> = Box<dyn Fn(&plot::Area, &str) -> Result<(), String> + Send + Sync + 'a>;

/// A fitted and checked model: its result, and what draws it.
pub(crate) struct Fitted<'a> {
    /// The result.
    pub result: NoiseResult,
    /// Draws the decomposition (the caption empty for the default one).
    pub paint: Paint<'a>,
    /// The model for the parameter files, when [`Fitting::export`] asks for it.
    pub axis: Option<AxisModel>,
}

/// The order `0..=8` (fewer for a short record) that BIC selects for a Burg fit.
fn bic_order(x: &[f64], rate: f64) -> Result<usize, Fail> {
    // Burg needs P + 2 samples with the mean removed.
    let top = AUTO_AR_ORDER.min(x.len().saturating_sub(2));
    if top == 0 {
        return Ok(0);
    }
    let fit = with_order!(top, burg_fit(x, rate))?;
    let variances = (0..=top).map(|m| fit.0.get(m).copied().unwrap_or(f64::NAN));
    Ok(Criterion::Bic.select(fit.1, variances))
}

/// The innovation variances of orders `0..=P` of a Burg fit, and its effective length.
fn burg_fit<const P: usize>(x: &[f64], rate: f64) -> Result<(Vec<f64>, usize), Fail> {
    let fit = burg::<f64, P>(x, &BatchConfig::new(1.0 / rate)?)?;
    let variances = (0..=P).filter_map(|m| fit.innovation_variance(m)).collect();
    Ok((variances, fit.n_effective))
}

/// The Burg AR(`P`) fit of the record, and the composite with it as its AR part.
fn ar_part<'a, const P: usize>(
    fit: &'a Fitting,
    x: &[f64],
    octaves: &'a Octaves<OCTAVES>,
) -> Result<Fitted<'a>, Fail> {
    let ar = burg::<f64, P>(x, &BatchConfig::new(1.0 / fit.rate)?)
        .map_err(|e| Fail(format!("--ar-order {P}: {e}")))?
        .model;
    fit.model::<P>(octaves, Some(&ar))
}

/// One fit's inputs.
pub(crate) struct Fitting {
    /// Samples in the record.
    pub n: usize,
    /// The model's rate, Hz.
    pub rate: f64,
    /// The filter's rate, Hz.
    pub filter_rate: f64,
    /// The fit's settings.
    pub config: FitConfig,
    /// The record's unit.
    pub units: Units,
    /// Whether to give the model for the parameter files too (the record in SI units).
    pub export: bool,
}

impl Fitting {
    /// Fits the composite with the AR part `ar`, checks it, and hands it over; with the plot
    /// to draw, if one was asked for.
    pub(crate) fn model<'a, const P: usize>(
        &'a self,
        octaves: &'a Octaves<OCTAVES>,
        ar: Option<&ArModel<f64, P>>,
    ) -> Result<Fitted<'a>, Fail> {
        let fit = NoiseModel::<P, MAX_GM_STATES>::identify(octaves, ar, &self.config)?;
        let model = fit.model;
        let check = model.check_whole(octaves)?;
        let uncertainty = model.uncertainty(octaves).ok();
        let span = self.n as f64 / self.rate;
        // The random walk's state starts with the variance it reaches over the record.
        let rw_p0 = model.random_walk() * model.random_walk() * span;
        let form = model.kalman(1.0 / self.filter_rate, rw_p0).map_err(|e| {
            Fail(format!(
                "--filter-rate {}: no filter form at this step: {e}",
                number(self.filter_rate)
            ))
        })?;
        let mut result = self.result(&model, ar, &model.ieee952(octaves), &form, &check);
        within_the_data(&result)?;
        result.budget_limited = fit.budget_limited;
        result.curve_fit = fit.curve_fit;
        result.intervals = uncertainty
            .as_ref()
            .map(|u| Intervals::of(&model, u, result.bias_instability.value, octaves));
        let default = self.caption(&model);
        // The 95 % band of the model's Allan deviation, from its parameters' intervals.
        let band: Vec<(f64, f64)> = uncertainty.as_ref().map_or(Vec::new(), |u| {
            u.adev_band().iter().map(|i| (i.low, i.high)).collect()
        });
        let paint: Paint<'a> = Box::new(move |area, caption| {
            let caption = if caption.is_empty() {
                &default
            } else {
                caption
            };
            plot::decomposition(area, &model, octaves, &check, &band, caption)
        });
        // In SI units already (`export` is asked for with the record in SI); the bias
        // instability is the data's IEEE 952 reading, not the model's.
        let axis = match self.export {
            true => {
                let reach = octaves.avar().len();
                let mut axis =
                    AxisModel::from_noise(&model, 1.0, 1.0 / self.filter_rate, rw_p0, reach)?;
                axis.bias_instability =
                    (result.bias_instability.value, result.bias_instability.tau_s);
                if let Some(u) = &uncertainty {
                    axis.white_noise_interval = Some((u.white_noise.low, u.white_noise.high));
                    axis.random_walk_interval = Some((u.random_walk.low, u.random_walk.high));
                }
                Some(axis)
            }
            false => None,
        };
        Ok(Fitted {
            result,
            paint,
            axis,
        })
    }

    fn caption<const P: usize>(&self, model: &NoiseModel<P, MAX_GM_STATES>) -> String {
        let ar = model
            .ar()
            .map_or(String::new(), |_| format!(", AR({P}) part"));
        let unit = &self.units.name;
        let n = model.white_noise();
        let n = if n > 0.0 {
            format!(": N = {n:.4e} {unit}/sqrt(Hz)")
        } else {
            String::new()
        };
        format!(
            "Allan deviation in {unit} (n = {}, {} Hz{ar}){n}",
            self.n, self.rate
        )
    }

    fn result<const P: usize>(
        &self,
        model: &NoiseModel<P, MAX_GM_STATES>,
        ar: Option<&ArModel<f64, P>>,
        ieee: &Ieee952,
        form: &KalmanForm<MAX_GM_STATES>,
        check: &Check<OCTAVES>,
    ) -> NoiseResult {
        let positive = |v: f64| (v > 0.0).then_some(v);
        let mut gauss_markov: Vec<GmEntry> = model
            .gauss_markov()
            .iter()
            .map(|t| GmEntry {
                sigma: t.sigma,
                correlation_time_s: t.correlation_time,
                frequency_hz: None,
            })
            .collect();
        gauss_markov.extend(model.oscillators().iter().map(|o| GmEntry {
            sigma: o.sigma,
            correlation_time_s: o.decay_time,
            frequency_hz: Some(o.frequency),
        }));
        let ar_part = model.ar().zip(ar).map(|(used, fitted)| ArPart {
            order: P,
            a: used.a().to_vec(),
            noise_variance: used.noise_variance(),
            scale: used.noise_variance() / fitted.noise_variance(),
        });
        let space = StateSpace::of(form, 1.0);
        NoiseResult {
            rate_hz: self.rate,
            n: self.n,
            white_noise: positive(ieee.white_noise),
            quantization: positive(ieee.quantization),
            random_walk: positive(ieee.random_walk),
            rate_ramp: positive(ieee.ramp),
            bias_instability: BiasInstability {
                value: ieee.bias_instability.0,
                tau_s: ieee.bias_instability.1,
            },
            gauss_markov,
            budget_limited: false,
            curve_fit: false,
            intervals: None,
            ar: ar_part,
            phi: space.phi,
            q: space.q,
            p0: space.p0,
            allan: check
                .rows()
                .iter()
                .map(|r| AllanRow {
                    tau_s: r.tau,
                    data_adev: r.data_adev,
                    model_adev: r.model_adev,
                    data_over_model: r.data_adev / r.model_adev,
                    tolerance: r.tolerance,
                    agrees: r.agrees,
                })
                .collect(),
            explained_up_to_s: check.explained_up_to(),
            check_z: check.z(),
            timing: None,
            details: Details {
                unit: self.units.name.clone(),
                filter_rate_hz: self.filter_rate,
                states: space.states,
                h: space.h,
                white_term: model.white_term(),
                white_noise_at_1s: ieee.white_noise_at_1s,
                measurement_variance: form.measurement_variance,
            },
        }
    }
}

impl NoiseResult {
    /// The variance of the white measurement noise in the filter, `N^2 / Dt`.
    pub fn measurement_variance(&self) -> f64 {
        self.details.measurement_variance
    }

    /// The filter's measurement row over its states: 1, but 0 on an oscillator's `dx/dt` and
    /// -1 on the earlier quantisation state.
    pub fn h(&self) -> &[f64] {
        &self.details.h
    }

    /// The filter's rate, Hz, of `phi`, `q` and `p0`.
    pub fn filter_rate(&self) -> f64 {
        self.details.filter_rate_hz
    }

    /// The names of the filter's states, in the order of `phi`.
    pub fn states(&self) -> &[String] {
        &self.details.states
    }

    /// The unit of the record.
    pub fn unit(&self) -> &str {
        &self.details.unit
    }

    /// `N` read as the Allan deviation at `tau = 1 s`, where the record has that octave pair.
    pub fn white_noise_at_1s(&self) -> Option<f64> {
        self.details.white_noise_at_1s
    }
}

impl Output for NoiseResult {
    fn text(&self) -> String {
        let d = &self.details;
        let u = Units::of(&d.unit);
        let mut s = format!(
            "composite noise model of {} samples at {} Hz, unit {}\n",
            self.n,
            json(&self.rate_hz),
            d.unit
        );
        if let Some(t) = &self.timing {
            s += &t.text();
            s += "\n";
        }
        let n = self.white_noise.unwrap_or(0.0);
        s += &format!("white_noise {}", json(&self.white_noise));
        if self.white_noise.is_some() {
            s += &format!(" {}{}", u.psd_root(), u.arw(n));
        }
        s += "\n";
        s += &format!(
            "  white term {}, AR part's white equivalent {}; Allan deviation at tau = 1 s: {}\n",
            json(&d.white_term),
            json(&(n * n - d.white_term * d.white_term).max(0.0).sqrt()),
            json(&d.white_noise_at_1s)
        );
        s += &format!(
            "quantization {}{}\n",
            json(&self.quantization),
            unit(self.quantization, &format!("{} s", u.name))
        );
        s += &format!("random_walk {}", json(&self.random_walk));
        match (self.random_walk, &self.intervals) {
            (Some(k), _) => s += &format!(" {}/s{}", u.psd_root(), u.rrw(k)),
            // Not identified: the bound the record sets is the walk a filter can take.
            (None, Some(i)) if i.random_walk.high > 0.0 => {
                s += &format!(
                    ": the record shows no walk; at most {} {}/s{} (95 %), the value the \
                     parameter files carry",
                    json(&i.random_walk.high),
                    u.psd_root(),
                    u.rrw(i.random_walk.high)
                )
            }
            (None, _) => {}
        }
        s += "\n";
        s += &format!(
            "rate_ramp {}{}\n",
            json(&self.rate_ramp),
            unit(self.rate_ramp, &format!("{}/s", u.name))
        );
        let b = &self.bias_instability;
        s += &format!(
            "bias_instability {} {}{} at tau_s {}\n",
            json(&b.value),
            u.name,
            u.bias(b.value),
            json(&b.tau_s)
        );
        for (i, t) in self.gauss_markov.iter().enumerate() {
            s += &format!(
                "gauss_markov[{i}] sigma {} correlation_time_s {}",
                json(&t.sigma),
                json(&t.correlation_time_s)
            );
            if let Some(f) = t.frequency_hz {
                s += &format!(" frequency_hz {} (second order: two states)", json(&f));
            }
            s += "\n";
        }
        if self.budget_limited {
            s += "budget_limited true: the data call for a term that --gm-states left no state \
                  for; the random walk and the other terms carry it\n";
        }
        if self.curve_fit {
            s += "curve_fit true: every state of the budget spent on the curve (--curve-fit, or \
                  the identified terms failed the whole-curve check); the parameters describe \
                  the curve, and may not be the sensor's\n";
        }
        if let Some(i) = &self.intervals {
            s += "95 % intervals (from the Allan variances' sampling distribution; a term the \
                  model lacks from 0):\n";
            s += &format!("  white_noise {}\n", i.white_noise.text());
            if let Some(d) = &i.level_drift {
                s += &format!(
                    "    the record's short-term level moves: its eighths' Allan deviation \
                     spreads {:.1} % beyond their sampling at {} s, which this interval counts\n",
                    100.0 * d.spread,
                    d.tau_s
                );
            }
            s += &format!("  quantization {}\n", i.quantization.text());
            s += &format!("  random_walk {}\n", i.random_walk.text());
            s += &format!("  rate_ramp {}\n", i.rate_ramp.text());
            s += &format!("  bias_instability {}\n", i.bias_instability.text());
            for (k, t) in i.gauss_markov.iter().enumerate() {
                s += &format!(
                    "  gauss_markov[{k}] sigma {} correlation_time_s {}",
                    t.sigma.text(),
                    t.correlation_time_s.text()
                );
                if let Some(f) = &t.frequency_hz {
                    s += &format!(" frequency_hz {}", f.text());
                }
                s += "\n";
            }
        }
        match &self.ar {
            Some(ar) => {
                s += &format!(
                    "ar order {} a {} noise_variance {} scale {}\n  \
                     in the filter as its white equivalent (in white_noise); for the \
                     short-term colouring, its companion form: imu-ar kalman --order {}\n",
                    ar.order,
                    json(&ar.a),
                    json(&ar.noise_variance),
                    json(&ar.scale),
                    ar.order
                )
            }
            None => s += "ar null\n",
        }
        s += &format!(
            "filter at {} Hz; states: {}\n",
            json(&d.filter_rate_hz),
            if d.states.is_empty() {
                "none".to_string()
            } else {
                d.states.join(", ")
            }
        );
        s += &format!(
            "phi {}\nq {}\np0 {}\nmeasurement_variance {} (N^2 / Dt, white; the sample \
             is h x plus it, h = 1 on each state but -1 on quantization (q_(k-1)/Dt) and 0 on \
             an oscillator's (dx/dt))\n",
            json(&self.phi),
            json(&self.q),
            json(&self.p0),
            json(&d.measurement_variance)
        );
        s += &format!(
            "Allan check: one 95 % test of the whole curve, each octave at z = {:.2} standard \
             errors\n",
            self.check_z
        );
        s += &allan_text(&self.allan);
        s += &format!("explained_up_to_s {}\n", json(&self.explained_up_to_s));
        for line in plot::failures(&self.allan) {
            s += &line;
            s += "\n";
        }
        s
    }
}

/// ` unit` after a value that is there.
fn unit(v: Option<f64>, unit: &str) -> String {
    v.map_or(String::new(), |_| format!(" {unit}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_interval_a_search_ran_to_the_floor_of_reads_from_zero_and_unbounded() {
        // A quantised record's correlation time printed [9.3289004e-316, null] (pass 47 F8).
        let b = Bounds::of(
            0.5,
            Interval {
                low: 9.3289004e-316,
                high: f64::INFINITY,
            },
        );
        assert_eq!(b.low, 0.0);
        assert_eq!(b.text(), "[0.0, unbounded]");
        let b = Bounds::of(
            0.5,
            Interval {
                low: 0.25,
                high: 2.0,
            },
        );
        assert_eq!(b.text(), "[0.25, 2.0]");
    }
}
