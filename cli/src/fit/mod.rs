//! `imu-ar fit`: an AR(P) model of one column, by a batch or a recursive method.

mod recursive;

pub use recursive::centre;

use imu_ar::batch::{BatchConfig, BatchError};
use imu_ar::recursive::Gate;
use serde::Serialize;

use crate::error::Fail;
use crate::input::{
    Input, Prior, check_decimate, check_delta, check_lambda, check_order, check_rate, check_span,
    decimated, default_delta,
};
use crate::method::{DEFAULT_LAMBDA, GaussMarkov, Method, ScalarKind, batch_fit, with_order};
use crate::output::{Output, json};
use recursive::{Recursive, Scale, fixed_fit, recursive_fit};

/// The arguments of `imu-ar fit`.
#[derive(clap::Args)]
pub struct Args {
    /// The column.
    #[command(flatten)]
    input: Input,
    /// Estimator.
    #[arg(long, value_enum)]
    method: Method,
    /// Model order, 1 to 32.
    #[arg(long, allow_negative_numbers = true)]
    order: usize,
    /// Arithmetic of the recursive methods (the batch fits compute in f64).
    #[arg(long, value_enum, default_value = "f64")]
    scalar: ScalarKind,
    /// Forgetting factor of the recursive methods, in (0, 1].
    #[arg(long, default_value_t = DEFAULT_LAMBDA, allow_negative_numbers = true)]
    lambda: f64,
    /// Initial regularisation of the recursive methods [default: 0.1 x the variance of the
    /// first 1000 samples, or 1 when that is 0].
    #[arg(long, allow_negative_numbers = true)]
    delta: Option<f64>,
    /// The model the recursive methods start from.
    #[command(flatten)]
    prior: Prior,
    /// Settled start of the recursive methods (f64 and f32): hold the first N samples, then
    /// start from their batch fit as the prior, with the running mean settled and no
    /// prewindowed equation.
    #[arg(long, conflicts_with = "prior_a")]
    settle: Option<usize>,
    /// Innovation gate of the recursive methods: reject (and count) a sample whose a-priori
    /// error exceeds K (at least 1) innovation standard deviations; after 16 rejections in a
    /// row the gate opens until a sample passes.
    #[arg(long, allow_negative_numbers = true)]
    gate: Option<f64>,
    /// Internal units per sensor unit of `--scalar fixed` [default: 8 / max |x|, so that the
    /// record, offset included, uses half of the +-16 range].
    #[arg(long, allow_negative_numbers = true)]
    scale: Option<f64>,
    /// Fit the data as they are, without removing the (sample or running) mean.
    #[arg(long)]
    no_demean: bool,
    /// Average blocks of M samples first (the rate, if given, becomes rate / M).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    decimate: usize,
    /// Sample rate in Hz; gives the model its time scale.
    #[arg(long, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// A fitted model: `x[n] = mean + sum a_k (x[n-k] - mean) + w[n]`, with what qualifies it.
#[derive(Serialize)]
pub struct FitResult {
    /// The estimator.
    pub method: &'static str,
    /// Its arithmetic: `f64`, `f32` or `fixed`.
    pub scalar: &'static str,
    /// The model order `P`.
    pub order: usize,
    /// Samples fitted (after `--decimate`).
    pub n: usize,
    /// The mean of the data (for a recursive method, the running mean after the last sample).
    pub mean: f64,
    /// `a_1..a_P`.
    pub a: Vec<f64>,
    /// Variance of the innovation `w`.
    pub noise_variance: f64,
    /// Reflection coefficients (Yule-Walker, Burg and the lattice).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reflection: Option<Vec<f64>>,
    /// Forgetting factor (recursive methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lambda: Option<f64>,
    /// Initial regularisation (recursive methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub delta: Option<f64>,
    /// Internal units per sensor unit (fixed point).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// Restarts after a numerical breakdown (recursive methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub restarts: Option<u64>,
    /// Samples rejected as not finite (recursive methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub non_finite: Option<u64>,
    /// Samples rejected by `--gate` (recursive methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outliers: Option<u64>,
    /// Samples rejected as saturated (fixed point).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub saturated: Option<u64>,
    /// Internal values clipped to the number format (fixed point).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clipped: Option<u64>,
    /// The model's sample rate in Hz (with `--rate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rate_hz: Option<f64>,
    /// The Gauss-Markov form of an AR(1) with `0 < a_1 < 1` (with `--rate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gauss_markov: Option<GaussMarkov>,
}

impl FitResult {
    /// A fit of `n` samples with the keys every method reports; the others are absent.
    pub fn new(
        method: &'static str,
        scalar: &'static str,
        n: usize,
        mean: f64,
        a: Vec<f64>,
        noise_variance: f64,
    ) -> Self {
        Self {
            method,
            scalar,
            order: a.len(),
            n,
            mean,
            a,
            noise_variance,
            reflection: None,
            lambda: None,
            delta: None,
            scale: None,
            restarts: None,
            non_finite: None,
            outliers: None,
            saturated: None,
            clipped: None,
            rate_hz: None,
            gauss_markov: None,
        }
    }

    /// Adds the rate and, for an AR(1) with `0 < a_1 < 1`, the Gauss-Markov form.
    fn with_rate(mut self, rate: Option<f64>, dt: f64) -> Self {
        if let Some(rate) = rate {
            self.rate_hz = Some(rate);
            self.gauss_markov = GaussMarkov::of(&self.a, self.noise_variance, dt);
        }
        self
    }

    /// A warning when most samples were rejected (saturated, non-finite).
    fn rejection_warning(&self) -> Option<String> {
        let n = self.n as u64;
        let rejected = self.saturated.unwrap_or(0) + self.non_finite.unwrap_or(0);
        (2 * rejected > n).then(|| {
            format!("{rejected} of {n} samples were rejected (saturated or non-finite); the model rests on the rest")
        })
    }
}

impl Output for FitResult {
    fn text(&self) -> String {
        let mut s = format!(
            "{} AR({}) fit of {} samples\nmean {}\na {}\nnoise_variance {}\n",
            self.method,
            self.order,
            self.n,
            json(&self.mean),
            json(&self.a),
            json(&self.noise_variance)
        );
        if let Some(k) = &self.reflection {
            s += &format!("reflection {}\n", json(k));
        }
        // Every count that qualifies the result.
        for (key, count) in [
            ("restarts", self.restarts),
            ("non_finite", self.non_finite),
            ("saturated", self.saturated),
            ("clipped", self.clipped),
        ] {
            if let Some(c) = count {
                s += &format!("{key} {c}\n");
            }
        }
        if let Some(gm) = &self.gauss_markov {
            s += &gm.text();
        }
        s
    }
}

/// Checks the settings, reads the record and fits it; warns on stderr when most samples were
/// rejected.
pub fn run(args: &Args) -> Result<FitResult, Fail> {
    run_with(args, None)
}

/// [`run`] on the samples `given` (the Python package's arrays) in place of the files': the
/// same checks, fit and result.
pub fn run_with(args: &Args, given: Option<&[f64]>) -> Result<FitResult, Fail> {
    let Args {
        ref input,
        method,
        order,
        scalar,
        lambda,
        delta,
        scale,
        ref prior,
        settle,
        gate,
        no_demean,
        decimate,
        rate,
        json: _,
    } = *args;
    let delta = delta.or(prior.prior_weight);
    let prior_a = prior.check(order)?;
    if prior_a.is_some() && !method.recursive() {
        return Err(Fail(format!(
            "--prior-a: only the recursive methods start from a prior, not {}",
            method.name()
        )));
    }
    if let Some(n) = settle {
        if !method.recursive() || matches!(scalar, ScalarKind::Fixed) {
            return Err(Fail(format!(
                "--settle: only --method rls, lattice or sftf in f64 or f32 take a settled \
                 start, not {} in {}",
                method.name(),
                scalar.name()
            )));
        }
        if n < 2 * order + 2 {
            return Err(Fail(format!(
                "--settle {n}: the batch fit of order {order} needs at least {} samples",
                2 * order + 2
            )));
        }
    }
    check_order("--order", order)?;
    check_decimate(decimate)?;
    let rate = rate.map(|r| r / decimate as f64);
    if matches!(scalar, ScalarKind::Fixed) && !matches!(method, Method::Lattice) {
        return Err(Fail(format!(
            "--scalar fixed: only --method lattice runs in fixed point, not {}",
            method.name()
        )));
    }
    if let Some(s) = scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
        return Err(Fail(format!("--scale {s}: must be positive and finite")));
    }
    let dt = match rate {
        Some(r) => 1.0 / check_rate(r)?,
        None => 1.0,
    };
    check_lambda(lambda)?;
    if let Some(d) = delta {
        check_delta(d)?;
    }
    let gate = match gate {
        Some(k) if !method.recursive() => {
            return Err(Fail(format!(
                "--gate {k}: only the recursive methods gate, not {}",
                method.name()
            )));
        }
        Some(k) => Some(Gate::new(k as f32, 16).map_err(|e| Fail(format!("--gate {k}: {e}")))?),
        None => None,
    };
    let x = match given {
        Some(x) => decimated(&input.files, x, decimate)?,
        None => input.load(decimate)?,
    };
    if let Some(n) = settle.filter(|&n| n >= x.len()) {
        return Err(input.fail(format!(
            "--settle {n}: the record has {} samples; the settled start needs more than it holds",
            x.len()
        )));
    }
    if let Some(r) = rate {
        check_span("--rate", r * decimate as f64, x.len() * decimate)?;
    }
    let fit = if method.recursive() {
        let default = delta.is_none();
        let delta = match delta {
            Some(d) => d,
            None => default_delta(&x).map_err(|e| input.fail(e))?,
        };
        let r = Recursive {
            method,
            scalar,
            lambda,
            delta,
            demean: !no_demean,
            dt,
            rate,
            default_delta: default,
            prior: prior_a.map(<[f64]>::to_vec),
            settle,
            gate,
        };
        match scalar {
            ScalarKind::F64 => with_order!(order, recursive_fit::<f64>(&x, &r)),
            ScalarKind::F32 => with_order!(order, recursive_fit::<f32>(&x, &r)),
            ScalarKind::Fixed => {
                // The default scale is taken from the samples the fit will see (centred
                // when the mean is removed).
                let offset = centre(&x, r.demean);
                let peak = x
                    .iter()
                    .map(|v| v - offset)
                    .filter(|v| v.abs() <= f64::from(f32::MAX))
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                let scale = match scale {
                    Some(s) => Scale::Given(s),
                    None => Scale::Default(if peak > 0.0 { 8.0 / peak } else { 1.0 }),
                };
                with_order!(order, fixed_fit(&x, &r, scale))
            }
        }
        .map_err(|Fail(e)| input.fail(e))?
    } else {
        let config = BatchConfig::new(dt)?.with_demean(!no_demean);
        with_order!(order, batch(method, &x, &config, rate)).map_err(|e| input.fail(e))?
    };
    if let Some(warning) = fit.rejection_warning() {
        eprintln!("imu-ar: warning: {}", input.fail(warning).0);
    }
    Ok(fit)
}

/// The batch fit of `x` by `method`.
fn batch<const P: usize>(
    method: Method,
    x: &[f64],
    config: &BatchConfig<f64>,
    rate: Option<f64>,
) -> Result<FitResult, BatchError> {
    let fit = batch_fit::<P>(method, x, config)?;
    let model = &fit.model;
    let a = model.a().to_vec();
    let (mean, noise_variance) = (model.mean(), model.noise_variance());
    Ok(FitResult {
        reflection: fit.reflection.map(|k| k.to_vec()),
        ..FitResult::new(method.name(), "f64", x.len(), mean, a, noise_variance)
    }
    .with_rate(rate, model.dt()))
}
