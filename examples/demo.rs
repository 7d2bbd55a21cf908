//! The main job on the emulated Cortex-M4F: learn the error model of every axis of an IMU.
//!
//! ```text
//! cargo qemu demo
//! ```
//!
//! Inside the firmware, a simulated MPU-6050 answers the register protocol on a simulated I2C
//! bus (`examples/common/sim_imu.rs`) and produces six axes at 100 Hz while its die
//! temperature ramps from 25 to 45 deg C, each axis with a bias that is a cubic in the
//! temperature (0.27 to 0.32 deg/s, 24 to 28 mg over the 20 K), a first-order Gauss-Markov
//! drift whose sigma and correlation time change with the temperature, white noise, and
//! quantisation to counts. The firmware reads it through `imu_ar::sensor::Mpu6050` (FIFO
//! batches of 100 ms, the die temperature from the data registers after each batch, in deg C
//! by `ImuReader::die_temperature`). Each axis's sample goes through a thermal stage
//! (`imu_ar::thermal::ThermalBias`, a cubic in the temperature, `lambda = 0.99999`, range 20 to
//! 50 deg C), and its residual is estimated with an f32 lattice of order 4 (`lambda = 0.9995`,
//! a 20 s memory, shared by the six axes; `delta` and the saturation limit per channel, in
//! deg/s or g) plus a BIC order selector. Every 10 s of sensor time it logs, per axis:
//! `a_1..a_4`, the innovation sigma, the selected order, the Gauss-Markov correlation time and
//! sigma of the order-1 model, and the one-step prediction MSE of the lattice and of a batch LS
//! model fitted on the previous 10 s.
//!
//! After 120 s it checks each axis against the simulated truth and exits 0 when all hold. The
//! truth of an AR(4) fit to `Gauss-Markov + white` (an ARMA(1,1)) is its best AR(4)
//! approximation: Levinson-Durbin on the exact autocovariances, at the temperature of the
//! centre of mass of the estimator's memory (`lambda / (1 - lambda)` samples before the end).
//! - the running mean of the residual is within 4 standard deviations (of an exponentially
//!   weighted mean of this process) of 0, the residual's true mean;
//! - every coefficient is within 0.1 of the true AR(4) coefficients (about 6 standard
//!   deviations with 4000 effective samples);
//! - the innovation variance is within 10 % of the true AR(4) innovation variance;
//! - the lattice's prediction MSE over the last 10 s is within 25 % of that same variance.
//!
//! The same lattice runs on the samples as read, without the thermal stage, for comparison:
//! per axis the demo logs the thermal stage's bias at the last temperature against the true
//! bias, and the innovation variance, the prediction MSE of the last 10 s and the Allan
//! deviation at 20.48 s of both paths against the truth; and then how far off the truth the
//! innovation variance is on the worst axis, with and without the stage. With the stage it
//! must be within 10 % on every axis.
//!
//! Then it fits the composite noise model of every axis (`imu_ar::noise`: white noise,
//! quantisation, up to two Gauss-Markov terms, random walk) from the octave Allan variances its
//! `AllanStream` kept of the residual over the whole run (13 octaves, to 41 s), and checks it
//! against the truth over the run (the mean of the truth's Allan variance over the temperature
//! ramp):
//! - `N` within 5 % of the truth's, on the axes where white noise makes at least half of the
//!   Allan variance at 0.01 s (all but gz, whose drift makes over 90 % of it);
//! - the model's Allan deviation within the Allan check's tolerance of the truth's at every
//!   octave (two standard errors of the run's estimate, or 10 %).
//!
//! The Allan check of the model against the run's own data is logged as well, with every octave
//! where it fails. Its last octaves rest on 4 and 1 differences, and so do the Allan
//! deviations of the comparison: over one monotone ramp the temperature is a function of time,
//! so the cubic also takes up some of the drift's slowest content, and those octaves of the
//! residual can fall below the truth's.
//!
//! The Gauss-Markov correlation time and sigma (from the order-1 model) are logged where an
//! AR(1) fits, i.e. where the selector chose order 1; `NaN` elsewhere.
//!
//! Build with `IMU_AR_DEMO_FAULT=lambda` (forgetting factor 0.5: a 3-sample memory) or
//! `IMU_AR_DEMO_FAULT=corrupt` (every 20th sample spiked by 2000 counts) to see the checks
//! fail and the firmware exit 1.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/mod.rs"]
mod common;

#[cfg(target_os = "none")]
#[path = "common/sim_imu.rs"]
mod sim_imu;

#[cfg(target_os = "none")]
mod firmware {
    use embedded_hal::delay::DelayNs;
    use imu_ar::ArModel;
    use imu_ar::allan::AllanStream;
    use imu_ar::batch::{BatchConfig, covariance};
    use imu_ar::noise::{FitConfig, NoiseModel, Octaves, component};
    use imu_ar::recursive::{Channel, Config, Estimator, Lattice, OrderRule, OrderSelector};
    use imu_ar::sensor::{AccelUnit, GyroUnit, ImuReader, Mpu6050, Mpu6050Config, RawSample};
    use imu_ar::thermal::{ThermalBias, ThermalConfig};

    use super::common;
    use super::sim_imu::{AXES, AxisTruth, SimImu};

    const P: usize = 4;
    const RATE: f32 = 100.0;
    const WINDOW: usize = 1000; // 10 s
    const DURATION_S: u32 = 120;
    /// Octaves of the Allan stream: up to 2^13 samples (82 s).
    const OCTAVES: usize = 14;
    /// Times over the run at which the truth's Allan variance is averaged.
    const TRUTH_POINTS: usize = 24;
    const NAMES: [&str; AXES] = ["gx", "gy", "gz", "ax", "ay", "az"];
    /// Largest accepted coefficient error: about 6 standard deviations of an estimate with
    /// `(1 + lambda)/(1 - lambda) = 4000` effective samples.
    const A_TOLERANCE: f64 = 0.1;
    /// The octave of the Allan comparison of the thermal stage: `m = 2^11` (20.48 s), the
    /// longest with four differences in the run.
    const ALLAN_LEVEL: usize = 11;
    /// Coefficients of the bias's temperature polynomial: degree 3, as PX4's.
    const THERMAL_COEFFS: usize = 4;
    /// The thermal stage's forgetting factor: a memory of 10^5 samples (1000 s).
    const THERMAL_LAMBDA: f32 = 0.99999;
    /// The temperatures the thermal stage learns from, deg C: the ramp's, with 5 K to spare.
    const THERMAL_RANGE: (f32, f32) = (20.0, 50.0);

    struct NoDelay;
    impl DelayNs for NoDelay {
        fn delay_ns(&mut self, _: u32) {}
    }

    /// One axis: its thermal stage, whose residual feeds the estimator, the order selector
    /// and the Allan stream; the bookkeeping of the current 10 s window (its samples, and the
    /// squared one-step errors of the lattice and of the batch model fitted on the window
    /// before); and, for comparison, the same lattice on the uncompensated samples.
    struct Axis {
        name: &'static str,
        unit: &'static str,
        thermal: ThermalBias<f32, THERMAL_COEFFS>,
        lattice: Lattice<f32, P>,
        /// The lattice on the samples as read, without the thermal stage.
        raw: Lattice<f32, P>,
        /// The squared one-step errors of `raw` over the window, and how many.
        raw_se: f64,
        raw_counted: usize,
        /// `raw`'s prediction MSE over the last window that had a batch model.
        raw_mse: f64,
        /// The octave Allan variances of the samples as read.
        raw_allan: AllanStream<OCTAVES>,
        selector: OrderSelector<f32, P>,
        samples: [f32; WINDOW],
        len: usize,
        lattice_se: f64,
        batch_se: f64,
        counted: usize,
        batch_model: Option<ArModel<f32, P>>,
        /// `(lattice, batch)` prediction MSE of the last window that had a batch model.
        last_mse: (f64, f64),
        /// The octave Allan variances of the whole run, for the composite noise model.
        allan: AllanStream<OCTAVES>,
    }

    impl Axis {
        fn new(
            index: usize,
            config: &Config<f32>,
            channel: &Channel<f32>,
            thermal: ThermalBias<f32, THERMAL_COEFFS>,
        ) -> Self {
            Self {
                name: NAMES[index],
                unit: if index < 3 { "deg/s" } else { "g" },
                thermal,
                lattice: Lattice::new(config, channel),
                raw: Lattice::new(config, channel),
                raw_se: 0.0,
                raw_counted: 0,
                raw_mse: 0.0,
                raw_allan: AllanStream::new(),
                selector: OrderSelector::new(OrderRule::Bic, 500, 3),
                samples: [0.0; WINDOW],
                len: 0,
                lattice_se: 0.0,
                batch_se: 0.0,
                counted: 0,
                batch_model: None,
                last_mse: (0.0, 0.0),
                allan: AllanStream::new(),
            }
        }

        /// One sample `x` at `celsius`: the uncompensated lattice's update; the thermal
        /// stage's residual, and for it the batch model's prediction error (on in-window
        /// history), the lattice's update and error, the selector.
        fn push(
            &mut self,
            config: &Config<f32>,
            thermal: &ThermalConfig<f32, THERMAL_COEFFS>,
            x: f32,
            celsius: f32,
        ) {
            let raw = self.raw.update(config, x);
            self.raw_allan.push(x);
            let Some(x) = self.thermal.update(thermal, x, celsius) else {
                return;
            };
            let comparing = self.len >= P && self.batch_model.is_some();
            if let (Some(e), true) = (raw, comparing) {
                self.raw_se += f64::from(e) * f64::from(e);
                self.raw_counted += 1;
            }
            if let (Some(m), true) = (&self.batch_model, self.len >= P) {
                let past: [f32; P] = core::array::from_fn(|k| self.samples[self.len - 1 - k]);
                let e = f64::from(x - m.predict(&past));
                self.batch_se += e * e;
            }
            if let Some(e) = self.lattice.update(config, x) {
                self.selector.update(config, &self.lattice);
                if self.len >= P && self.batch_model.is_some() {
                    self.lattice_se += f64::from(e) * f64::from(e);
                    self.counted += 1;
                }
            }
            self.samples[self.len] = x;
            self.len += 1;
            self.allan.push(x);
        }

        /// The end of a window at `t` s: report, fit the batch model of the next window, and
        /// start it.
        fn end_window(&mut self, t: f32, config: &Config<f32>, batch: &BatchConfig<f32>) {
            let counted = self.counted.max(1) as f64;
            let mse = (self.lattice_se / counted, self.batch_se / counted);
            if self.counted > 0 {
                self.last_mse = mse;
            }
            if self.raw_counted > 0 {
                self.raw_mse = self.raw_se / self.raw_counted as f64;
            }
            self.batch_model = covariance::<f32, P>(&self.samples, batch)
                .ok()
                .map(|f| f.model);
            self.report(t, config, (self.counted > 0).then_some(mse));
            self.len = 0;
            self.lattice_se = 0.0;
            self.batch_se = 0.0;
            self.counted = 0;
            self.raw_se = 0.0;
            self.raw_counted = 0;
        }

        /// Logs the model, the selected order, the Gauss-Markov parameters where an AR(1)
        /// fits, and the window's `(lattice, batch)` prediction MSE when there was a batch
        /// model to compare with.
        fn report(&self, t: f32, config: &Config<f32>, mse: Option<(f64, f64)>) {
            let Some(model) = self.lattice.model(config) else {
                return;
            };
            let sigma = libm::sqrtf(model.noise_variance());
            let gm = self
                .lattice
                .coefficients(1)
                .zip(self.lattice.innovation_variance(1))
                .and_then(|(a, v)| ArModel::new([a[0]], v, model.mean(), config.dt()).ok())
                .and_then(|m| m.to_gauss_markov().ok());
            let order = self.selector.order();
            // Only where an AR(1) fits: the selected order is 1.
            let (tc, gm_sigma) = match (gm, order) {
                (Some(g), 1) => (g.correlation_time(), g.sigma()),
                _ => (f32::NAN, f32::NAN),
            };
            let a = model.a().as_slice();
            if let Some((lattice_mse, batch_mse)) = mse {
                defmt::info!(
                    "t={=f32}s {=str}: a={=[?]} sigma={=f32} {=str} order={=usize} gm(tc={=f32}s sigma={=f32}) mse lattice={=f32} batch={=f32}",
                    t,
                    self.name,
                    a,
                    sigma,
                    self.unit,
                    order,
                    tc,
                    gm_sigma,
                    lattice_mse as f32,
                    batch_mse as f32
                );
            } else {
                defmt::info!(
                    "t={=f32}s {=str}: a={=[?]} sigma={=f32} {=str} order={=usize} gm(tc={=f32}s sigma={=f32})",
                    t,
                    self.name,
                    a,
                    sigma,
                    self.unit,
                    order,
                    tc,
                    gm_sigma
                );
            }
        }

        /// The truth check of the module docs; logs it and returns whether it holds. The
        /// lattice runs on the thermal stage's residual, whose true mean is 0.
        fn check(&self, config: &Config<f32>, truth: &AxisTruth) -> bool {
            let (Some(model), Some((a_true, e_true))) =
                (self.lattice.model(config), truth.ar_projection::<P>())
            else {
                defmt::error!("{=str}: no model", self.name);
                return false;
            };
            let mean_sd = truth.ew_mean_sd(f64::from(config.lambda()));
            let mean_err = f64::from(model.mean()).abs();
            let a_err = model
                .a()
                .iter()
                .zip(&a_true)
                .fold(0.0f64, |m, (a, b)| m.max((f64::from(*a) - b).abs()));
            let var_ratio = f64::from(model.noise_variance()) / e_true;
            let mse_ratio = self.last_mse.0 / e_true;
            let pass_mean = mean_err <= 4.0 * mean_sd;
            let pass_a = a_err <= A_TOLERANCE;
            let pass_var = (0.9..=1.1).contains(&var_ratio);
            let pass_mse = (0.75..=1.25).contains(&mse_ratio);
            defmt::info!(
                "check {=str}: mean {=f32} vs 0 (|err| {=f32} <= {=f32}) {=bool}; max|a - a_true| {=f32} <= {=f32} {=bool}; innovation variance / truth {=f32} in [0.9, 1.1] {=bool}; lattice MSE / truth {=f32} in [0.75, 1.25] {=bool}",
                self.name,
                model.mean(),
                mean_err as f32,
                (4.0 * mean_sd) as f32,
                pass_mean,
                a_err as f32,
                A_TOLERANCE as f32,
                pass_a,
                var_ratio as f32,
                pass_var,
                mse_ratio as f32,
                pass_mse
            );
            pass_mean && pass_a && pass_var && pass_mse
        }

        /// The thermal stage at the end of the run: its bias at `end` (the last temperature)
        /// against the truth there; the innovation variance and prediction MSE of the lattice
        /// with and without it against the truth of the memory's centre; the Allan deviation
        /// at [`ALLAN_LEVEL`] with and without it against the truth's over the run,
        /// `truth_adev`. Logs them and returns `(compensated, uncompensated)` innovation
        /// variance / truth.
        fn thermal_check(
            &self,
            config: &Config<f32>,
            thermal: &ThermalConfig<f32, THERMAL_COEFFS>,
            truth: &AxisTruth,
            end: (f32, &AxisTruth),
            truth_adev: f64,
        ) -> (f64, f64) {
            let e_true = truth.ar_projection::<P>().map_or(f64::NAN, |(_, e)| e);
            let variance = |l: &Lattice<f32, P>| {
                l.model(config)
                    .map_or(f64::NAN, |m| f64::from(m.noise_variance()) / e_true)
            };
            let (compensated, uncompensated) = (variance(&self.lattice), variance(&self.raw));
            let bias = self.thermal.bias(thermal, end.0).unwrap_or(f32::NAN);
            let health = self.thermal.health();
            let adev = |s: &AllanStream<OCTAVES>| {
                s.avar(ALLAN_LEVEL)
                    .map_or(f64::NAN, |v| libm::sqrt(v) / truth_adev)
            };
            defmt::info!(
                "check {=str} thermal: bias at {=f32} C {=f32} vs {=f32} {=str} ({=u64} samples learned, {=u64} out of range); innovation variance / truth: compensated {=f32} in [0.9, 1.1] {=bool}, uncompensated {=f32} ({=f32} % off); lattice MSE / truth: compensated {=f32}, uncompensated {=f32}; ADEV at {=f32} s / truth: compensated {=f32}, uncompensated {=f32}",
                self.name,
                end.0,
                bias,
                end.1.mean as f32,
                self.unit,
                health.samples,
                health.out_of_range,
                compensated as f32,
                (0.9..=1.1).contains(&compensated),
                uncompensated as f32,
                (100.0 * libm::fabs(uncompensated - 1.0)) as f32,
                (self.last_mse.0 / e_true) as f32,
                (self.raw_mse / e_true) as f32,
                (1u32 << ALLAN_LEVEL) as f32 / RATE,
                adev(&self.allan) as f32,
                adev(&self.raw_allan) as f32
            );
            (compensated, uncompensated)
        }

        /// The composite noise model of the whole run, fitted from the Allan stream, against
        /// the truth over the run (see the module docs); logs it and returns whether it holds.
        fn composite(&self, truth: &[[AxisTruth; AXES]; TRUTH_POINTS], axis: usize) -> bool {
            let dt = 1.0 / f64::from(RATE);
            let fitted = Octaves::from_stream(&self.allan, dt).and_then(|octaves| {
                let model = NoiseModel::<1, 2>::fit(&octaves, None, &FitConfig::new(2))?;
                Ok((model, model.check(&octaves)?))
            });
            let Ok((model, check)) = fitted else {
                defmt::error!("{=str}: no composite model", self.name);
                return false;
            };
            let truth_avar = |m: u64| truth_avar(truth, axis, m);
            let n_true = truth[0][axis].white * libm::sqrt(dt);
            let n_err = libm::fabs(model.white_noise() / n_true - 1.0);
            // N is resolved where the white noise makes at least half the first octave.
            let resolved = n_true * n_true / dt >= 0.5 * truth_avar(1);
            let pass_n = !resolved || n_err <= 0.05;
            let mut worst: f64 = 0.0;
            let pass_truth = check.rows().iter().enumerate().all(|(j, row)| {
                let err = libm::fabs(row.model_adev / libm::sqrt(truth_avar(1 << j)) - 1.0);
                worst = worst.max(err / row.tolerance);
                err <= row.tolerance
            });
            for row in check.rows().iter().filter(|r| !r.agrees) {
                defmt::warn!(
                    "noise {=str}: tau {=f32} s: data ADEV {=f32}, model {=f32}, tolerance {=f32}",
                    self.name,
                    row.tau as f32,
                    row.data_adev as f32,
                    row.model_adev as f32,
                    row.tolerance as f32
                );
            }
            let upto = check.explained_up_to().unwrap_or(0.0);
            defmt::info!(
                "noise {=str}: N {=f32} vs {=f32} {=str}/sqrt(Hz) (|err| {=f32}{=str}) {=bool}; {=usize} Gauss-Markov term(s); the check against the data holds to {=f32} s of {=f32} s; model ADEV against the truth's, worst |err|/tolerance {=f32} <= 1 {=bool}",
                self.name,
                model.white_noise() as f32,
                n_true as f32,
                self.unit,
                n_err as f32,
                if resolved {
                    " <= 0.05"
                } else {
                    ", not resolved: no limit"
                },
                pass_n,
                model.gauss_markov().len(),
                upto as f32,
                check.rows().last().map_or(0.0, |r| r.tau) as f32,
                worst as f32,
                pass_truth
            );
            pass_n && pass_truth
        }
    }

    /// The run's expected Allan variance of `axis` at `m` samples: the mean over the run of
    /// the truth's.
    fn truth_avar(truth: &[[AxisTruth; AXES]; TRUTH_POINTS], axis: usize, m: u64) -> f64 {
        let dt = 1.0 / f64::from(RATE);
        let sum: f64 = truth
            .iter()
            .map(|t| {
                let (w, g) = (&t[axis], t[axis].gm_sigma * t[axis].gm_sigma);
                w.white * w.white * dt * component::white(dt, m)
                    + g * component::gauss_markov(dt, w.tc, m)
            })
            .sum();
        sum / TRUTH_POINTS as f64
    }

    pub fn run() -> ! {
        let lambda = match option_env!("IMU_AR_DEMO_FAULT") {
            Some("lambda") => 0.5f32,
            _ => 0.9995,
        };
        let corrupt = option_env!("IMU_AR_DEMO_FAULT") == Some("corrupt");
        let mut imu = Mpu6050::new(SimImu::new(2010, corrupt), 0x68);
        if imu.init(&mut NoDelay, Mpu6050Config::default()).is_err() || imu.enable_fifo().is_err() {
            defmt::error!("demo: the simulated MPU-6050 did not initialise");
            common::exit(false)
        }
        let scale = imu.scale();
        // What the six axes share, and what belongs to each channel: gyro in deg/s and accel
        // in g, delta about 0.1 x each axis's variance, the saturation limit half a count
        // below the rail of its range.
        let settings = (
            Config::new(lambda, 1.0 / RATE),
            Channel::new(2.5e-4f32)
                .and_then(|c| c.with_saturation(scale.gyro_saturation(GyroUnit::DegPerSec))),
            Channel::new(1e-6f32)
                .and_then(|c| c.with_saturation(scale.accel_saturation(AccelUnit::G))),
            BatchConfig::new(1.0 / RATE),
        );
        let (Ok(config), Ok(gyro), Ok(accel), Ok(batch_config)) = settings else {
            common::exit(false)
        };
        // The thermal stage of every axis: the bias as a cubic in the die temperature, with
        // the axis's saturation limit.
        let Ok(thermal) = ThermalConfig::new(THERMAL_LAMBDA, THERMAL_RANGE.0, THERMAL_RANGE.1)
        else {
            common::exit(false)
        };
        let stage = |c: &Channel<f32>| {
            ThermalBias::new(&thermal).with_saturation(c.saturation().unwrap_or(f32::INFINITY))
        };
        let (Ok(gyro_stage), Ok(accel_stage)) = (stage(&gyro), stage(&accel)) else {
            common::exit(false)
        };
        let mut axes: [Axis; AXES] = core::array::from_fn(|i| {
            let (channel, stage) = if i < 3 {
                (&gyro, gyro_stage)
            } else {
                (&accel, accel_stage)
            };
            Axis::new(i, &config, channel, stage)
        });

        let mut batch = [RawSample::default(); 32];
        let mut n = 0usize;
        // The die temperature: the MPU-6050's FIFO packets carry none, so it is read from the
        // data registers after each batch (their latest sample, at most 100 ms and 0.02 K
        // after the batch's first). NaN until one is read: the thermal stage rejects those.
        let mut celsius = f32::NAN;
        while n < DURATION_S as usize * RATE as usize {
            let got = match imu.read_fifo(&mut batch) {
                Ok(k) => k,
                Err(e) => {
                    defmt::warn!("demo: FIFO: {}", defmt::Debug2Format(&e));
                    continue;
                }
            };
            if let Some(t) = imu.read().ok().and_then(|s| imu.die_temperature(&s)) {
                celsius = t;
            }
            for s in &batch[..got] {
                let gyro = scale.gyro(s.gyro, GyroUnit::DegPerSec);
                let accel = scale.accel(s.accel, AccelUnit::G);
                for (axis, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
                    axis.push(&config, &thermal, x, celsius);
                }
                n += 1;
                if n.is_multiple_of(WINDOW) {
                    for axis in &mut axes {
                        axis.end_window(n as f32 / RATE, &config, &batch_config);
                    }
                }
            }
        }

        // The truth check. An estimator with forgetting factor lambda sees the process averaged
        // over its memory, whose centre of mass lies lambda/(1 - lambda) samples back: compare
        // with the truth there (the parameters drift with the temperature ramp).
        let back = f64::from(lambda) / (1.0 - f64::from(lambda)) / f64::from(RATE);
        let sim = imu.destroy();
        let truth = sim.truth_at(f64::from(DURATION_S) - back);
        let ok = axes
            .iter()
            .zip(&truth)
            .fold(true, |ok, (axis, t)| axis.check(&config, t) & ok);
        // Over the run, for the Allan variances.
        let over_run: [[AxisTruth; AXES]; TRUTH_POINTS] = core::array::from_fn(|k| {
            sim.truth_at((k as f64 + 0.5) * f64::from(DURATION_S) / TRUTH_POINTS as f64)
        });
        // The thermal stage: the same lattice with and without it, against the same truth.
        let end = sim.truth_at(f64::from(DURATION_S));
        let (mut worst, mut worst_raw) = (0.0f64, 0.0f64);
        for (i, ((axis, t), e)) in axes.iter().zip(&truth).zip(&end).enumerate() {
            let adev = libm::sqrt(truth_avar(&over_run, i, 1 << ALLAN_LEVEL));
            let (c, u) = axis.thermal_check(&config, &thermal, t, (celsius, e), adev);
            worst = worst.max(libm::fabs(c - 1.0));
            worst_raw = worst_raw.max(libm::fabs(u - 1.0));
        }
        let thermal_ok = worst <= 0.1;
        defmt::info!(
            "demo: temperature ramp 25 to 45 C: innovation variance at most {=f32} % off the truth on every axis with the thermal stage (<= 10 % {=bool}), up to {=f32} % off without it",
            (100.0 * worst) as f32,
            thermal_ok,
            (100.0 * worst_raw) as f32
        );
        let ok = ok & thermal_ok;
        // The composite noise model of every axis, against the truth over the whole run.
        let ok = axes
            .iter()
            .enumerate()
            .fold(ok, |ok, (i, axis)| axis.composite(&over_run, i) & ok);
        if ok {
            defmt::info!(
                "demo: {=u32} s of six-axis data, every estimate within its tolerance of the simulated truth",
                DURATION_S
            );
        } else {
            defmt::error!("demo: estimates far from the simulated truth");
        }
        common::exit(ok)
    }
}

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    firmware::run()
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("demo is firmware for the Cortex-M4F: run it with `cargo qemu demo`");
}
