//! `imu-ar kalman`: a batch fit handed to a navigation Kalman filter (numerics.md 6).

use imu_ar::ArModel;
use imu_ar::allan::overlapping_avar;
use imu_ar::batch::BatchConfig;
use imu_ar::model::Matrix;
use serde_json::{Value, json};

use crate::{Fail, Method, batch_fit};

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
pub fn handoff<const P: usize>(
    method: Method,
    x: &[f64],
    rate: f64,
    filter_rate: f64,
) -> Result<Value, Fail> {
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
                "--filter-rate {filter_rate}: one filter step would be {ratio:e} model steps, \
                 more than the {} supported",
                u32::MAX
            )));
        }
        None if steps >= 1.0 && (ratio - steps).abs() <= 1e-9 * ratio => {
            let (phi, q) = model.discretize(steps as u32);
            (rows(&phi), rows(&q), Some(steps as u32))
        }
        None => {
            return Err(Fail(format!(
                "--filter-rate {filter_rate}: the model's rate ({rate} Hz) is not an integer \
                 multiple of it, and only an AR(1) with 0 < a_1 < 1 (a Gauss-Markov process) \
                 can be sampled at any rate"
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
        allan.push(json!({
            "tau_s": tau,
            "data_adev": data,
            "model_adev": fitted,
            "data_over_model": data_over_model,
            "tolerance": tol,
            "agrees": agrees,
        }));
        m *= 2;
    }
    let mut v = json!({
        "method": method.name(),
        "order": P,
        "n": n,
        "rate_hz": rate,
        "filter_rate_hz": filter_rate,
        "steps": steps,
        "mean": model.mean(),
        "a": model.a().to_vec(),
        "noise_variance": model.noise_variance(),
        "phi": phi,
        "q": q,
        "p0": rows(&p0),
        "allan": allan,
        "explained_up_to_s": explained_up_to,
    });
    if let Some(gm) = gm {
        v["gauss_markov"] = json!({
            "correlation_time_s": gm.correlation_time(),
            "sigma": gm.sigma(),
            "driving_psd": gm.driving_psd(),
        });
    }
    Ok(v)
}

/// The hand-off as text.
pub fn text(v: &Value) -> String {
    let mut s = format!(
        "{} AR({}) of {} samples at {} Hz; filter at {} Hz\na {}\nnoise_variance {}\n",
        v["method"].as_str().unwrap_or(""),
        v["order"],
        v["n"],
        v["rate_hz"],
        v["filter_rate_hz"],
        v["a"],
        v["noise_variance"]
    );
    if let Some(gm) = v.get("gauss_markov") {
        s += &format!(
            "gauss_markov correlation_time_s {} sigma {}\n",
            gm["correlation_time_s"], gm["sigma"]
        );
    }
    s += &format!("phi {}\nq {}\np0 {}\n", v["phi"], v["q"], v["p0"]);
    s += "# tau_s data_adev model_adev data/model tolerance\n";
    for row in v["allan"].as_array().into_iter().flatten() {
        s += &format!(
            "{} {:e} {:e} {:.3} {:.3}\n",
            row["tau_s"],
            row["data_adev"].as_f64().unwrap_or(f64::NAN),
            row["model_adev"].as_f64().unwrap_or(f64::NAN),
            row["data_over_model"].as_f64().unwrap_or(f64::NAN),
            row["tolerance"].as_f64().unwrap_or(f64::NAN)
        );
    }
    s += &format!("explained_up_to_s {}\n", v["explained_up_to_s"]);
    s
}
