//! `imu-ar kalman`: a batch fit handed to a navigation Kalman filter (numerics.md 6): `Phi`,
//! `Q` and the stationary covariance at the filter's rate, the Gauss-Markov form of an AR(1),
//! and the Allan check that the model explains the data's Allan deviation.

use imu_ar::ArModel;
use imu_ar::allan::overlapping_avar;
use imu_ar::batch::BatchConfig;
use imu_ar::model::Matrix;
use serde::Serialize;

use crate::error::Fail;
use crate::input::{Record, check_rate, check_span, number};
use crate::method::{GaussMarkov, Method, batch_fit, with_order};
use crate::output::{Output, json};

/// The arguments of `imu-ar kalman`.
#[derive(clap::Args)]
pub struct Args {
    /// The record and the model order.
    #[command(flatten)]
    record: Record,
    /// Batch estimator.
    #[arg(long, value_enum, default_value = "burg")]
    method: Method,
    /// Sample rate in Hz of the raw record.
    #[arg(long, allow_negative_numbers = true)]
    rate: f64,
    /// Average blocks of M samples first; the model's rate becomes rate / M.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    decimate: usize,
    /// The filter's rate in Hz [default: the model's]. The model's rate must be an integer
    /// multiple of it, except for an AR(1) with a Gauss-Markov equivalent, which samples
    /// at any rate.
    #[arg(long, allow_negative_numbers = true)]
    filter_rate: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The model at the filter's rate, and the Allan check.
#[derive(Serialize)]
pub struct Handoff {
    /// The batch estimator.
    pub method: &'static str,
    /// The model order.
    pub order: usize,
    /// Samples fitted (after `--decimate`).
    pub n: usize,
    /// The model's rate in Hz.
    pub rate_hz: f64,
    /// The filter's rate in Hz.
    pub filter_rate_hz: f64,
    /// Model samples per filter step (`None`: an AR(1) sampled through its Gauss-Markov form).
    pub steps: Option<u32>,
    /// The mean of the data.
    pub mean: f64,
    /// `a_1..a_P`.
    pub a: Vec<f64>,
    /// Variance of the innovation.
    pub noise_variance: f64,
    /// The transition matrix of one filter step.
    pub phi: Vec<Vec<f64>>,
    /// The process noise of one filter step.
    pub q: Vec<Vec<f64>>,
    /// The stationary covariance.
    pub p0: Vec<Vec<f64>>,
    /// The Gauss-Markov form of an AR(1) with `0 < a_1 < 1`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gauss_markov: Option<GaussMarkov>,
    /// The Allan check at `m = 1, 2, 4, ...` model samples.
    pub allan: Vec<AllanRow>,
    /// The largest `tau` (s) up to which every row agrees.
    pub explained_up_to_s: Option<f64>,
}

/// The Allan deviation of the data against the model's at one averaging time.
#[derive(Serialize)]
pub struct AllanRow {
    /// The averaging time in s.
    pub tau_s: f64,
    /// The data's overlapping Allan deviation.
    pub data_adev: f64,
    /// The model's.
    pub model_adev: f64,
    /// Their ratio.
    pub data_over_model: f64,
    /// The relative difference accepted.
    pub tolerance: f64,
    /// Whether the ratio is within the tolerance of 1.
    pub agrees: bool,
}

/// Checks the settings, reads the record and hands its model over.
pub fn run(args: &Args) -> Result<Handoff, Fail> {
    let Args {
        ref record,
        method,
        rate,
        decimate,
        filter_rate,
        json: _,
    } = *args;
    if method.recursive() {
        return Err(Fail(format!(
            "--method {}: the hand-off takes a batch fit (ls, yule-walker, burg)",
            method.name()
        )));
    }
    let rate = check_rate(rate)? / decimate as f64;
    let filter_rate = match filter_rate {
        Some(f) => check_rate(f).map_err(|_| {
            Fail(format!(
                "--filter-rate {}: must be a positive number of Hz",
                number(f)
            ))
        })?,
        None => rate,
    };
    let x = record.load(decimate)?;
    check_span("--rate", rate * decimate as f64, x.len() * decimate)?;
    with_order!(record.order, handoff(method, &x, rate, filter_rate))
        .map_err(|Fail(e)| record.input.fail(e))
}

/// The Allan check as text, one row a line; as in the JSON, a number that is not finite is
/// `null`.
pub fn allan_text(rows: &[AllanRow]) -> String {
    let e = |v: f64| {
        if v.is_finite() {
            format!("{v:e}")
        } else {
            "null".into()
        }
    };
    let f = |v: f64| {
        if v.is_finite() {
            format!("{v:.3}")
        } else {
            "null".into()
        }
    };
    let mut s = String::from("# tau_s data_adev model_adev data/model tolerance agrees\n");
    for r in rows {
        s += &format!(
            "{} {} {} {} {} {}\n",
            json(&r.tau_s),
            e(r.data_adev),
            e(r.model_adev),
            f(r.data_over_model),
            f(r.tolerance),
            if r.agrees { "yes" } else { "NO" }
        );
    }
    s
}

/// Relative difference of a measured Allan deviation from a model's accepted at `m`
/// samples per cluster out of `n`: two standard errors of the measured value,
/// `1 / sqrt(2 (n/m - 1))` (IEEE Std 952-1997, Annex C), and never less than 10 %, the
/// accuracy a filter's noise tuning needs.
fn tolerance(n: usize, m: usize) -> f64 {
    let clusters = n as f64 / m as f64;
    (2.0 / (2.0 * (clusters - 1.0)).sqrt()).max(0.1)
}

fn rows<const P: usize>(m: &Matrix<f64, P>) -> Vec<Vec<f64>> {
    m.iter().map(|r| r.to_vec()).collect()
}

/// Fits `x` (sampled at `rate` Hz) with `method`, and returns the model at the filter's rate
/// with the Allan check.
fn handoff<const P: usize>(
    method: Method,
    x: &[f64],
    rate: f64,
    filter_rate: f64,
) -> Result<Handoff, Fail> {
    let fit = batch_fit::<P>(method, x, &BatchConfig::new(1.0 / rate)?)?;
    let model = fit.model;
    let p0 = model.stationary_covariance()?;
    let gm = if P == 1 {
        ArModel::new([model.a()[0]], model.noise_variance(), 0.0, model.dt())?
            .to_gauss_markov()
            .ok()
    } else {
        None
    };
    let ratio = rate / filter_rate;
    let steps = ratio.round();
    let (phi, q, steps) = match gm {
        // A Gauss-Markov process is sampled exactly at any interval.
        Some(gm) => {
            let ar1 = gm.to_ar1(1.0 / filter_rate, 0.0)?;
            let (phi, q) = (ar1.transition(), ar1.process_noise());
            (rows(&phi), rows(&q), None)
        }
        None if steps > f64::from(u32::MAX) => {
            return Err(Fail(format!(
                "--filter-rate {}: one filter step would be {ratio:e} model steps, more than \
                 the {} supported",
                number(filter_rate),
                u32::MAX
            )));
        }
        None if steps >= 1.0 && (ratio - steps).abs() <= 1e-9 * ratio => {
            let (phi, q) = model.discretize(steps as u32);
            (rows(&phi), rows(&q), Some(steps as u32))
        }
        None => {
            return Err(Fail(format!(
                "--filter-rate {}: the model's rate ({} Hz) is not an integer multiple of \
                 it, and only an AR(1) with 0 < a_1 < 1 (a Gauss-Markov process) can be \
                 sampled at any rate",
                number(filter_rate),
                number(rate)
            )));
        }
    };

    // The Allan check, on the data the model was fitted to.
    let n = x.len();
    let mut allan = Vec::new();
    let mut explained_up_to = None;
    let mut agreeing = true;
    let mut m = 1usize;
    while 2 * m <= n {
        let data = overlapping_avar(x, m)?.sqrt();
        let fitted = model
            .allan_variance(u32::try_from(m).map_err(|_| Fail("record too long".into()))?)?
            .sqrt();
        let tau = m as f64 / rate;
        // The measured value scatters about the model's, by the standard error.
        let (data_over_model, tol) = (data / fitted, tolerance(n, m));
        let agrees = (data_over_model - 1.0).abs() <= tol;
        agreeing &= agrees;
        if agreeing {
            explained_up_to = Some(tau);
        }
        allan.push(AllanRow {
            tau_s: tau,
            data_adev: data,
            model_adev: fitted,
            data_over_model,
            tolerance: tol,
            agrees,
        });
        m *= 2;
    }
    Ok(Handoff {
        method: method.name(),
        order: P,
        n,
        rate_hz: rate,
        filter_rate_hz: filter_rate,
        steps,
        mean: model.mean(),
        a: model.a().to_vec(),
        noise_variance: model.noise_variance(),
        phi,
        q,
        p0: rows(&p0),
        gauss_markov: gm.map(|gm| GaussMarkov {
            driving_psd: Some(gm.driving_psd()),
            ..GaussMarkov::from(&gm)
        }),
        allan,
        explained_up_to_s: explained_up_to,
    })
}

impl Output for Handoff {
    fn text(&self) -> String {
        let mut s = format!(
            "{} AR({}) of {} samples at {} Hz; filter at {} Hz\na {}\nnoise_variance {}\n",
            self.method,
            self.order,
            self.n,
            json(&self.rate_hz),
            json(&self.filter_rate_hz),
            json(&self.a),
            json(&self.noise_variance)
        );
        if let Some(gm) = &self.gauss_markov {
            s += &gm.text();
        }
        s += &format!(
            "phi {}\nq {}\np0 {}\n",
            json(&self.phi),
            json(&self.q),
            json(&self.p0)
        );
        s += &allan_text(&self.allan);
        s += &format!("explained_up_to_s {}\n", json(&self.explained_up_to_s));
        s
    }
}
