//! The recursive fits of `imu-ar fit`: RLS, the lattice and the SFTF in `f64` or `f32`, and
//! the fixed-point lattice; each reports the model after the last sample.

use imu_ar::recursive::{
    Channel, Config, ConfigError, Estimator, FixedChannel, FixedConfig, FixedLattice, FloatArith,
    Gate, Lattice, Rls, Sftf, Start,
};

use super::FitResult;
use crate::error::Fail;
use crate::method::{Method, ScalarKind};

/// The settings of a recursive fit.
pub(super) struct Recursive {
    pub method: Method,
    pub scalar: ScalarKind,
    pub lambda: f64,
    pub delta: f64,
    pub demean: bool,
    pub dt: f64,
    pub rate: Option<f64>,
    /// Whether `delta` is the default (not given).
    pub default_delta: bool,
    /// `--prior-a`: the model the estimator starts from.
    pub prior: Option<Vec<f64>>,
    /// `--settle N`: samples held for a settled start.
    pub settle: Option<usize>,
    /// `--gate K`.
    pub gate: Option<Gate>,
}

/// An estimator made by `make` (from the prior, if any), run over `x` less `offset`, with a
/// settled start on the first `--settle` samples if asked; its model and health.
fn run<T: FloatArith, const P: usize, E: Start<T, P>>(
    x: &[f64],
    offset: f64,
    r: &Recursive,
    config: &Config<T>,
    make: impl FnOnce(&[T; P]) -> Result<E, ConfigError>,
) -> Result<E, Fail> {
    let prior: [T; P] = match &r.prior {
        Some(a) => core::array::from_fn(|k| T::from_f64(a.get(k).copied().unwrap_or(0.0))),
        None => [T::ZERO; P],
    };
    let mut estimator = make(&prior).map_err(|e| Fail(format!("--prior-a: {e}")))?;
    let samples = x.iter().map(|&v| T::from_f64(v - offset));
    let held = match r.settle {
        Some(n) => {
            // The accepted samples among the first n (the rejected ones are counted).
            let head: Vec<T> = samples
                .clone()
                .take(n)
                .filter_map(|v| estimator.screen(v))
                .collect();
            estimator.settle(config, &head);
            n
        }
        None => 0,
    };
    for v in samples.skip(held) {
        estimator.update(config, v);
    }
    Ok(estimator)
}

/// The scale of `--scalar fixed`: given, or the default `8 / max |x|`.
#[derive(Clone, Copy)]
pub(super) enum Scale {
    Given(f64),
    Default(f64),
}

/// The configuration in `T`, with an error that says which setting `T` cannot carry.
fn config_in<T: FloatArith>(r: &Recursive) -> Result<(Config<T>, Channel<T>), Fail> {
    let config = Config::new(T::from_f64(r.lambda), T::from_f64(r.dt))
        .map(|c| r.gate.map_or(c, |g| c.with_gate(g)));
    // Checked in the order lambda, delta, interval.
    match (config, Channel::new(T::from_f64(r.delta))) {
        (Ok(config), Ok(channel)) => Ok((config, channel)),
        (Err(ConfigError::Lambda), _) => Err(ConfigError::Lambda),
        (_, Err(e)) | (Err(e), _) => Err(e),
    }
    .map_err(|e| {
        if r.default_delta {
            Fail(format!(
                "{e}: the default --delta (0.1 x the variance of the first 1000 samples) is {}, \
                 which --scalar {} cannot carry; give --delta",
                r.delta,
                r.scalar.name()
            ))
        } else {
            Fail(e.to_string())
        }
    })
}

/// The offset removed in f64 before a fit in f32 or fixed point: the mean of the samples that
/// f32 can hold when the mean is removed (so that rounding to f32 does not erase a small
/// signal on a large offset), else 0.
pub fn centre(x: &[f64], demean: bool) -> f64 {
    if !demean {
        return 0.0;
    }
    let (sum, n) = x
        .iter()
        .filter(|v| v.abs() <= f64::from(f32::MAX))
        .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// Runs RLS, the lattice or the SFTF in `T` over `x` and reports the model after the last sample.
///
/// In f32 the mean (of the samples f32 can hold) is removed in f64 first and added back to
/// the reported mean, so that rounding to f32 does not erase a small signal on a large offset.
pub(super) fn recursive_fit<T: FloatArith, const P: usize>(
    x: &[f64],
    r: &Recursive,
) -> Result<FitResult, Fail> {
    let (config, channel) = config_in::<T>(r)?;
    let config = config.with_demean(r.demean);
    let offset = if core::mem::size_of::<T>() < 8 {
        centre(x, r.demean)
    } else {
        0.0
    };
    let (model, health, reflection) = match r.method {
        Method::Rls => {
            let rls = run(x, offset, r, &config, |a0| {
                Rls::<T, P>::with_prior(&config, &channel, a0)
            })?;
            (rls.model(&config), rls.health(), None)
        }
        Method::Sftf => {
            let sftf = run(x, offset, r, &config, |a0| {
                Sftf::<T, P>::with_prior(&config, &channel, a0)
            })?;
            (sftf.model(&config), sftf.health(), None)
        }
        _ => {
            let lattice = run(x, offset, r, &config, |a0| {
                Lattice::<T, P>::with_prior(&config, &channel, a0)
            })?;
            let model = lattice.model(&config);
            let k = model.and_then(|m| m.reflection().ok());
            (model, lattice.health(), k)
        }
    };
    let model = model.ok_or_else(|| Fail("no finite model".into()))?;
    let a: Vec<f64> = model.a().iter().map(|v| v.to_f64()).collect();
    let mean = model.mean().to_f64() + offset;
    let noise_variance = model.noise_variance().to_f64();
    Ok(FitResult {
        reflection: reflection.map(|k| k.iter().map(|v| v.to_f64()).collect()),
        lambda: Some(r.lambda),
        delta: Some(r.delta),
        restarts: Some(health.restarts),
        non_finite: Some(health.non_finite),
        outliers: Some(health.outliers),
        ..FitResult::new(
            r.method.name(),
            r.scalar.name(),
            x.len(),
            mean,
            a,
            noise_variance,
        )
    }
    .with_rate(r.rate, r.dt))
}

/// Runs the fixed-point lattice over `x` (in sensor units, scaled by `scale`); the mean is
/// removed in f64 first, as for f32.
pub(super) fn fixed_fit<const P: usize>(
    x: &[f64],
    r: &Recursive,
    scale: Scale,
) -> Result<FitResult, Fail> {
    let (config, channel) = config_in::<f32>(r)?;
    let config = config.with_demean(r.demean);
    let scale_value = match scale {
        Scale::Given(s) | Scale::Default(s) => s,
    };
    let settings = FixedChannel::new(&channel, scale_value as f32)
        .and_then(|channel| Ok((FixedConfig::new(&config)?, channel)));
    let (fixed, fixed_channel) = settings.map_err(|e| {
        let product = r.delta * scale_value * scale_value;
        if e == ConfigError::FixedLambda {
            return Fail(format!("--lambda {}: {e}", r.lambda));
        }
        match scale {
            Scale::Given(s) => Fail(format!(
                "--scale {s}: {e} (delta x scale^2 = {product:e} must be in [1e-9, 1e6))"
            )),
            Scale::Default(s) => Fail(format!(
                "{e}: the default --scale 8 / max |x - mean| = {s:e} and delta {} give \
                 delta x scale^2 = {product:e}, outside [1e-9, 1e6); give --scale or --delta",
                r.delta
            )),
        }
    })?;
    let offset = centre(x, r.demean);
    let prior: [f32; P] = match &r.prior {
        Some(a) => core::array::from_fn(|k| a.get(k).copied().unwrap_or(0.0) as f32),
        None => [0.0; P],
    };
    let mut lattice = FixedLattice::<P>::with_prior(&fixed, &fixed_channel, &prior)
        .map_err(|e| Fail(format!("--prior-a: {e}")))?;
    for &v in x {
        lattice.update(&fixed, (v - offset) as f32);
    }
    let health = lattice.health();
    let model = lattice
        .model(&fixed)
        .ok_or_else(|| Fail("no finite model".into()))?;
    let a: Vec<f64> = model.a().iter().map(|&v| f64::from(v)).collect();
    let mean = f64::from(model.mean()) + offset;
    let noise_variance = f64::from(model.noise_variance());
    Ok(FitResult {
        reflection: model
            .reflection()
            .ok()
            .map(|k| k.iter().map(|&v| f64::from(v)).collect()),
        lambda: Some(fixed.lambda()),
        delta: Some(r.delta),
        scale: Some(f64::from(fixed_channel.scale())),
        restarts: Some(health.restarts),
        saturated: Some(health.saturated),
        clipped: Some(health.clipped),
        non_finite: Some(health.non_finite),
        outliers: Some(health.outliers),
        ..FitResult::new("lattice", "fixed", x.len(), mean, a, noise_variance)
    }
    .with_rate(r.rate, r.dt))
}
