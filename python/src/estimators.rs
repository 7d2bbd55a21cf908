//! The device's recursive estimators as one Python class, `_native.Estimator`: RLS, the
//! lattice and the SFTF in f64 or f32, and the fixed-point lattice, of order 1 to 32. Each
//! runs the library's code, the code the firmware runs, sample by sample; its model after the
//! last sample is reported as `imu-ar fit --method ... --json` reports it, so that a record
//! replayed from Python gives the tool's model bit for bit.

use std::sync::Mutex;

use imu_ar::recursive::{
    Channel, Config, Estimator as _, FixedChannel, FixedConfig, FixedLattice, FloatArith, Lattice,
    Rls, Sftf,
};
use imu_ar_cli::error::Fail;
use imu_ar_cli::fit::{FitResult, centre};
use imu_ar_cli::input::{
    check_delta, check_lambda, check_order, check_rate, default_delta, number,
};
use imu_ar_cli::method::GaussMarkov;
use imu_ar_cli::output::json_line;
use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;

use crate::errors::{guarded, to_py_checked};

/// Which estimator.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Conventional RLS (Bierman U-D).
    Rls,
    /// The EF-LSL lattice.
    Lattice,
    /// The stabilised fast transversal filter.
    Sftf,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Rls => "rls",
            Method::Lattice => "lattice",
            Method::Sftf => "sftf",
        }
    }
}

/// Its arithmetic.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Scalar {
    /// f64.
    F64,
    /// f32, as on a Cortex-M4F.
    F32,
    /// The fixed-point lattice.
    Fixed,
}

impl Scalar {
    fn name(self) -> &'static str {
        match self {
            Scalar::F64 => "f64",
            Scalar::F32 => "f32",
            Scalar::Fixed => "fixed",
        }
    }
}

/// The settings of an estimator, those left to the first samples resolved then.
#[derive(Clone, Copy)]
pub struct Settings {
    /// The estimator.
    pub method: Method,
    /// Its arithmetic.
    pub scalar: Scalar,
    /// The order.
    pub order: usize,
    /// The forgetting factor.
    pub lambda: f64,
    /// The initial regularisation [default: the tool's, from the first 1000 samples].
    pub delta: Option<f64>,
    /// The sample rate, Hz (the model's time scale).
    pub rate: Option<f64>,
    /// Whether the running mean is removed.
    pub demean: bool,
    /// The offset removed in f64 before the estimator [default: the tool's: 0 in f64, the
    /// first samples' mean in f32 and fixed point].
    pub offset: Option<f64>,
    /// Internal units per sensor unit of the fixed-point lattice [default: the tool's,
    /// `8 / max |x - offset|` of the first samples].
    pub scale: Option<f64>,
}

impl Settings {
    /// The checks `imu-ar fit` makes of the same flags.
    pub fn check(&self) -> Result<(), Fail> {
        check_order("order", self.order)?;
        if self.scalar == Scalar::Fixed && self.method != Method::Lattice {
            return Err(Fail(format!(
                "scalar fixed: only the lattice runs in fixed point, not {}",
                self.method.name()
            )));
        }
        check_lambda(self.lambda).map_err(|Fail(e)| Fail(e.replace("--lambda", "lam")))?;
        if let Some(d) = self.delta {
            check_delta(d).map_err(|Fail(e)| Fail(e.replace("--delta", "delta")))?;
        }
        if let Some(r) = self.rate {
            check_rate(r).map_err(|Fail(e)| Fail(e.replace("--rate", "rate")))?;
        }
        if self.scale.is_some() && self.scalar != Scalar::Fixed {
            return Err(Fail(format!(
                "scale: only the fixed-point lattice takes a scale, not {} in {}",
                self.method.name(),
                self.scalar.name()
            )));
        }
        if let Some(s) = self.scale.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Fail(format!(
                "scale {}: must be positive and finite",
                number(s)
            )));
        }
        if let Some(o) = self.offset.filter(|o| !o.is_finite()) {
            return Err(Fail(format!("offset {}: must be finite", number(o))));
        }
        if let Some(o) = self.offset.filter(|o| o.abs() > f64::from(f32::MAX))
            && self.scalar != Scalar::F64
        {
            return Err(Fail(format!(
                "offset {}: beyond f32's range, in which the samples less the offset reach the \
                 estimator",
                number(o)
            )));
        }
        Ok(())
    }

    /// The sample interval, s (1 without a rate, as the tool).
    fn dt(&self) -> f64 {
        self.rate.map_or(1.0, |r| 1.0 / r)
    }
}

/// What a replay gives besides the errors: each sample's lattice internals.
#[derive(Default)]
pub struct Trace {
    /// Float lattices: per sample `e, f_1..f_P, kf_1..kf_P, kb_1..kb_P, F_0..F_P`.
    pub values: Vec<f64>,
    /// The fixed-point lattice: the same, as the numbers' bit patterns.
    pub bits: Vec<i64>,
}

/// One estimator of some order and arithmetic, run and reported.
pub trait Replay: Send + Sync {
    /// Takes `x` less `offset`, pushing each sample's a-priori error (NaN when rejected) and,
    /// with `trace`, its internals (zeros for a rejected sample).
    fn run(&mut self, x: &[f64], offset: f64, errors: &mut Vec<f64>, trace: Option<&mut Trace>);
    /// The model after the last sample, as `imu-ar fit` reports it (without `n`, the
    /// settings and the rate, which the caller adds).
    fn result(&self, offset: f64) -> Result<FitResult, Fail>;
    /// A copy, state and all.
    fn boxed(&self) -> Box<dyn Replay>;
}

/// The refusal of a model when there is none: what the estimator counted says why.
fn no_model(h: &imu_ar::recursive::Health) -> Fail {
    Fail(format!(
        "no finite model: none since the last restart (restarts {}, non-finite {}, saturated \
         {}, clipped {}, outliers {})",
        h.restarts, h.non_finite, h.saturated, h.clipped, h.outliers
    ))
}

/// A float estimator.
#[derive(Clone)]
enum Float<T: FloatArith, const P: usize> {
    Rls(Config<T>, Box<Rls<T, P>>),
    Lattice(Config<T>, Box<Lattice<T, P>>),
    Sftf(Config<T>, Box<Sftf<T, P>>),
}

/// The configuration in `T`, as `imu-ar fit` makes it.
fn config_in<T: FloatArith>(s: &Settings, delta: f64) -> Result<(Config<T>, Channel<T>), Fail> {
    let config = Config::new(T::from_f64(s.lambda), T::from_f64(s.dt()))
        .map_err(|e| Fail(e.to_string()))?
        .with_demean(s.demean);
    let channel = Channel::new(T::from_f64(delta)).map_err(|e| {
        Fail(format!(
            "delta {}: {e} in {}",
            number(delta),
            s.scalar.name()
        ))
    })?;
    Ok((config, channel))
}

impl<T: FloatArith + Send + Sync, const P: usize> Float<T, P> {
    fn new(s: &Settings, delta: f64) -> Result<Self, Fail> {
        let (config, channel) = config_in::<T>(s, delta)?;
        let prior = [T::ZERO; P];
        let e = |e: imu_ar::recursive::ConfigError| Fail(e.to_string());
        Ok(match s.method {
            Method::Rls => Float::Rls(
                config,
                Box::new(Rls::with_prior(&config, &channel, &prior).map_err(e)?),
            ),
            Method::Lattice => Float::Lattice(
                config,
                Box::new(Lattice::with_prior(&config, &channel, &prior).map_err(e)?),
            ),
            Method::Sftf => Float::Sftf(
                config,
                Box::new(Sftf::with_prior(&config, &channel, &prior).map_err(e)?),
            ),
        })
    }
}

impl<T: FloatArith + Send + Sync + 'static, const P: usize> Replay for Float<T, P> {
    fn boxed(&self) -> Box<dyn Replay> {
        Box::new(self.clone())
    }

    fn run(
        &mut self,
        x: &[f64],
        offset: f64,
        errors: &mut Vec<f64>,
        mut trace: Option<&mut Trace>,
    ) {
        for &v in x {
            let v = T::from_f64(v - offset);
            let e = match self {
                Float::Rls(c, r) => r.update(c, v),
                Float::Sftf(c, f) => f.update(c, v),
                Float::Lattice(c, l) => l.update(c, v),
            };
            errors.push(e.map_or(f64::NAN, |e| e.to_f64()));
            if let (Some(t), Float::Lattice(_, l)) = (trace.as_deref_mut(), &*self) {
                let row = &mut t.values;
                match e {
                    Some(e) => {
                        row.push(e.to_f64());
                        let k = l
                            .forward_reflection()
                            .into_iter()
                            .chain(l.backward_reflection());
                        row.extend(l.errors().into_iter().chain(k).map(|v| v.to_f64()));
                        row.extend((0..=P).map(|m| l.energy(m).map_or(f64::NAN, |v| v.to_f64())));
                    }
                    None => row.extend(std::iter::repeat_n(0.0, 4 * P + 2)),
                }
            }
        }
    }

    fn result(&self, offset: f64) -> Result<FitResult, Fail> {
        let (model, health, reflection) = match self {
            Float::Rls(c, r) => (r.model(c), r.health(), None),
            Float::Sftf(c, f) => (f.model(c), f.health(), None),
            Float::Lattice(c, l) => {
                let model = l.model(c);
                let k = model.and_then(|m| m.reflection().ok());
                (model, l.health(), k)
            }
        };
        let model = model.ok_or_else(|| no_model(&health))?;
        Ok(FitResult {
            reflection: reflection.map(|k| k.iter().map(|v| v.to_f64()).collect()),
            restarts: Some(health.restarts),
            non_finite: Some(health.non_finite),
            outliers: Some(health.outliers),
            ..FitResult::new(
                "",
                "",
                0,
                model.mean().to_f64() + offset,
                model.a().iter().map(|v| v.to_f64()).collect(),
                model.noise_variance().to_f64(),
            )
        })
    }
}

/// The fixed-point lattice.
#[derive(Clone)]
struct Fixed<const P: usize> {
    config: FixedConfig,
    channel: FixedChannel,
    lattice: Box<FixedLattice<P>>,
}

impl<const P: usize> Fixed<P> {
    fn new(s: &Settings, delta: f64, scale: f64) -> Result<Self, Fail> {
        let (config, channel) = config_in::<f32>(s, delta)?;
        let channel = FixedChannel::new(&channel, scale as f32).map_err(|e| {
            Fail(format!(
                "scale {}: {e} (delta x scale^2 = {:e} must be in [1e-9, 1e6))",
                number(scale),
                delta * scale * scale
            ))
        })?;
        let config = FixedConfig::new(&config)
            .map_err(|e| Fail(format!("lam {}: {e}", number(s.lambda))))?;
        let lattice = FixedLattice::with_prior(&config, &channel, &[0.0; P])
            .map_err(|e| Fail(e.to_string()))?;
        Ok(Self {
            config,
            channel,
            lattice: Box::new(lattice),
        })
    }
}

impl<const P: usize> Replay for Fixed<P> {
    fn boxed(&self) -> Box<dyn Replay> {
        Box::new(self.clone())
    }

    fn run(
        &mut self,
        x: &[f64],
        offset: f64,
        errors: &mut Vec<f64>,
        mut trace: Option<&mut Trace>,
    ) {
        let l = &mut self.lattice;
        for &v in x {
            let e = l.update(&self.config, (v - offset) as f32);
            errors.push(e.map_or(f64::NAN, f64::from));
            if let Some(t) = trace.as_deref_mut() {
                let row = &mut t.bits;
                match e {
                    Some(_) => {
                        let f = l.errors();
                        row.push(i64::from(f[P - 1].to_bits()));
                        row.extend(f.iter().map(|v| i64::from(v.to_bits())));
                        let k = l
                            .forward_reflection()
                            .into_iter()
                            .chain(l.backward_reflection());
                        row.extend(k.map(|v| i64::from(v.to_bits())));
                        row.extend((0..=P).map(|m| l.energy(m).map_or(0, |v| v.to_bits())));
                    }
                    None => row.extend(std::iter::repeat_n(0, 4 * P + 2)),
                }
            }
        }
    }

    fn result(&self, offset: f64) -> Result<FitResult, Fail> {
        let health = self.lattice.health();
        let model = self
            .lattice
            .model(&self.config)
            .ok_or_else(|| no_model(&health))?;
        Ok(FitResult {
            reflection: model
                .reflection()
                .ok()
                .map(|k| k.iter().map(|&v| f64::from(v)).collect()),
            lambda: Some(self.config.lambda()),
            scale: Some(f64::from(self.channel.scale())),
            restarts: Some(health.restarts),
            saturated: Some(health.saturated),
            clipped: Some(health.clipped),
            non_finite: Some(health.non_finite),
            outliers: Some(health.outliers),
            ..FitResult::new(
                "",
                "",
                0,
                f64::from(model.mean()) + offset,
                model.a().iter().map(|&v| f64::from(v)).collect(),
                f64::from(model.noise_variance()),
            )
        })
    }
}

/// The estimator of `s` at order `P`, with `delta` and `scale` resolved.
fn make<const P: usize>(s: &Settings, delta: f64, scale: f64) -> Result<Box<dyn Replay>, Fail> {
    Ok(match s.scalar {
        Scalar::F64 => Box::new(Float::<f64, P>::new(s, delta)?),
        Scalar::F32 => Box::new(Float::<f32, P>::new(s, delta)?),
        Scalar::Fixed => Box::new(Fixed::<P>::new(s, delta, scale)?),
    })
}

/// [`make`] at the runtime order `s.order` (checked: 1 to 32).
fn build(s: &Settings, delta: f64, scale: f64) -> Result<Box<dyn Replay>, Fail> {
    macro_rules! orders {
        ($($p:literal)*) => {
            match s.order {
                $($p => make::<$p>(s, delta, scale),)*
                p => Err(Fail(format!("order {p}: the order must be 1 to 32"))),
            }
        };
    }
    orders!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32)
}

/// An estimator that starts with its first samples (its defaults are taken from them).
pub struct Replayer {
    /// The settings given.
    pub settings: Settings,
    /// The estimator and the offset and delta in use, once started.
    started: Option<(Box<dyn Replay>, f64, f64)>,
    /// Samples taken.
    pub n: usize,
}

impl Replayer {
    /// A replayer of `settings` (checked).
    pub fn new(settings: Settings) -> Result<Self, Fail> {
        settings.check()?;
        // Settings given in full are checked now: they make the estimator.
        let started = match (settings.delta, settings.offset, settings.scale) {
            (Some(d), Some(o), Some(sc)) => Some((build(&settings, d, sc)?, o, d)),
            (Some(d), Some(o), None) if settings.scalar != Scalar::Fixed => {
                Some((build(&settings, d, 1.0)?, o, d))
            }
            _ => None,
        };
        Ok(Self {
            settings,
            started,
            n: 0,
        })
    }

    /// Takes `x`: each sample's a-priori error, and with `trace` its internals.
    pub fn update(&mut self, x: &[f64], trace: Option<&mut Trace>) -> Result<Vec<f64>, Fail> {
        if self.started.is_none() {
            if x.is_empty() {
                return Ok(Vec::new());
            }
            let s = &self.settings;
            // The tool's defaults, from the samples the fit will see.
            let offset = s.offset.unwrap_or(match s.scalar {
                Scalar::F64 => 0.0,
                _ => centre(x, s.demean),
            });
            let delta = match s.delta {
                Some(d) => d,
                None => default_delta(x).map_err(Fail)?,
            };
            let scale = s.scale.unwrap_or_else(|| {
                let peak = x
                    .iter()
                    .map(|v| v - offset)
                    .filter(|v| v.abs() <= f64::from(f32::MAX))
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                if peak > 0.0 { 8.0 / peak } else { 1.0 }
            });
            let built = build(s, delta, scale).map_err(|Fail(e)| match s.scale {
                Some(_) => Fail(e),
                None if s.scalar == Scalar::Fixed => Fail(format!(
                    "{e}; that scale is the default, 8 / max |x - offset| of the first update \
                     (offset {})",
                    number(offset)
                )),
                None => Fail(e),
            })?;
            self.started = Some((built, offset, delta));
        }
        let mut errors = Vec::with_capacity(x.len());
        if let Some((e, offset, _)) = &mut self.started {
            e.run(x, *offset, &mut errors, trace);
        }
        self.n += x.len();
        Ok(errors)
    }

    /// A copy, state and all.
    pub fn copy(&self) -> Self {
        Self {
            settings: self.settings,
            started: self.started.as_ref().map(|(e, o, d)| (e.boxed(), *o, *d)),
            n: self.n,
        }
    }

    /// The model after the last sample, as `imu-ar fit --json` gives it.
    pub fn result(&self) -> Result<FitResult, Fail> {
        let Some((e, offset, delta)) = &self.started else {
            return Err(Fail("no samples yet: update() first".into()));
        };
        let s = &self.settings;
        let mut r = e.result(*offset)?;
        r.method = s.method.name();
        r.scalar = s.scalar.name();
        r.n = self.n;
        r.lambda = r.lambda.or(Some(s.lambda));
        r.delta = Some(*delta);
        if let Some(rate) = s.rate {
            r.rate_hz = Some(rate);
            r.gauss_markov = GaussMarkov::of(&r.a, r.noise_variance, s.dt());
        }
        Ok(r)
    }
}

/// What `update` returns: the errors and, when asked, the internals.
pub type Replayed<'py> = (Bound<'py, PyArray1<f64>>, Option<Bound<'py, PyAny>>);

/// `_native.Estimator(method, scalar, order, lam, delta, rate, demean, offset, scale)`: one of
/// the device's recursive estimators (the Python classes `Rls`, `Lattice`, `Sftf` and
/// `FixedLattice` hold one). Its calls from several threads take turns: each `update` takes
/// its samples in one piece, after or before another thread's.
#[pyclass(module = "imu_ar._native", frozen)]
pub struct Estimator {
    inner: Mutex<Replayer>,
}

impl Estimator {
    /// The estimator, once no other call holds it (without the GIL).
    fn with<T>(&self, f: impl FnOnce(&mut Replayer) -> Result<T, Fail>) -> Result<T, Fail> {
        let mut inner = self.inner.lock().map_err(|_| {
            Fail(
                "the estimator failed in an earlier call (an internal error); make a new one"
                    .into(),
            )
        })?;
        guarded(|| f(&mut inner))
    }
}

#[pymethods]
impl Estimator {
    /// A new estimator; `ValueError` for settings the tool refuses.
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (method, scalar, order, lam, delta, rate, demean, offset, scale))]
    fn py_new(
        method: &str,
        scalar: &str,
        order: usize,
        lam: f64,
        delta: Option<f64>,
        rate: Option<f64>,
        demean: bool,
        offset: Option<f64>,
        scale: Option<f64>,
    ) -> PyResult<Self> {
        let method = match method {
            "rls" => Method::Rls,
            "lattice" => Method::Lattice,
            "sftf" => Method::Sftf,
            m => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "method {m:?}: rls, lattice or sftf"
                )));
            }
        };
        let scalar = match scalar {
            "f64" => Scalar::F64,
            "f32" => Scalar::F32,
            "fixed" => Scalar::Fixed,
            s => {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "scalar {s:?}: f64, f32 or fixed"
                )));
            }
        };
        let settings = Settings {
            method,
            scalar,
            order,
            lambda: lam,
            delta,
            rate,
            demean,
            offset,
            scale,
        };
        let inner = guarded(|| Replayer::new(settings)).map_err(to_py_checked)?;
        Ok(Self {
            inner: Mutex::new(inner),
        })
    }

    /// Takes the samples `x`; returns each one's a-priori prediction error (NaN for a rejected
    /// sample) and, with `trace`, the lattice's internals after each sample, one row each.
    /// Releases the GIL.
    #[pyo3(signature = (x, trace=false))]
    fn update<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray1<'py, f64>,
        trace: bool,
    ) -> PyResult<Replayed<'py>> {
        let x = x.as_slice()?;
        let (errors, t, settings) = py
            .detach(|| {
                self.with(|inner| {
                    if trace && inner.settings.method != Method::Lattice {
                        return Err(Fail(
                            "trace: only the lattices trace their internals".into(),
                        ));
                    }
                    let mut t = Trace::default();
                    let e = inner.update(x, trace.then_some(&mut t))?;
                    Ok((e, t, inner.settings))
                })
            })
            .map_err(to_py_checked)?;
        let width = 4 * settings.order + 2;
        let rows = errors.len();
        let traced = match (trace, settings.scalar) {
            (false, _) => None,
            (true, Scalar::Fixed) => Some(
                PyArray1::from_vec(py, t.bits)
                    .reshape([rows, width])?
                    .into_any(),
            ),
            (true, _) => Some(
                PyArray1::from_vec(py, t.values)
                    .reshape([rows, width])?
                    .into_any(),
            ),
        };
        Ok((errors.into_pyarray(py), traced))
    }

    /// The model after the last sample, as the JSON object of `imu-ar fit --json`.
    fn model_json(&self, py: Python<'_>) -> PyResult<String> {
        py.detach(|| self.with(|inner| json_line(&inner.result()?)))
            .map_err(to_py_checked)
    }

    /// A copy of the estimator, state and all (`copy.copy` and `copy.deepcopy`).
    fn copy(&self, py: Python<'_>) -> PyResult<Self> {
        let inner = py
            .detach(|| self.with(|inner| Ok(inner.copy())))
            .map_err(to_py_checked)?;
        Ok(Self {
            inner: Mutex::new(inner),
        })
    }

    /// Samples taken.
    #[getter]
    fn n(&self, py: Python<'_>) -> PyResult<usize> {
        py.detach(|| self.with(|inner| Ok(inner.n)))
            .map_err(to_py_checked)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(method: Method, scalar: Scalar) -> Settings {
        Settings {
            method,
            scalar,
            order: 2,
            lambda: 0.999,
            delta: None,
            rate: Some(100.0),
            demean: true,
            offset: None,
            scale: None,
        }
    }

    #[test]
    fn every_estimator_reports_a_model() {
        let mut s = 7u32;
        let x: Vec<f64> = (0..3000)
            .map(|_| {
                s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                f64::from(s >> 8) / 16_777_216.0
            })
            .collect();
        for (m, sc) in [
            (Method::Rls, Scalar::F64),
            (Method::Lattice, Scalar::F32),
            (Method::Sftf, Scalar::F64),
            (Method::Lattice, Scalar::Fixed),
        ] {
            let mut r = Replayer::new(settings(m, sc))
                .map_err(|f| f.0)
                .unwrap_or_else(|e| panic!("{e}"));
            let mut t = Trace::default();
            let e = r
                .update(&x, Some(&mut t))
                .map_err(|f| f.0)
                .unwrap_or_default();
            assert_eq!(e.len(), x.len());
            let model = r
                .result()
                .map_err(|f| f.0)
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(model.n, 3000);
            assert!((model.mean - 0.5).abs() < 0.05);
        }
    }

    #[test]
    fn bad_settings_are_refused() {
        let mut s = settings(Method::Rls, Scalar::Fixed);
        assert!(Replayer::new(s).is_err());
        s = settings(Method::Lattice, Scalar::F64);
        s.order = 33;
        assert!(Replayer::new(s).is_err());
        s.order = 2;
        s.lambda = 1.5;
        assert!(Replayer::new(s).is_err());
    }
}
