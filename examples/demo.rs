//! The main job on the emulated Cortex-M4F: learn the error model of every axis of an IMU.
//!
//! ```text
//! cargo qemu demo
//! ```
//!
//! Inside the firmware, a simulated MPU-6050 answers the register protocol on a simulated I2C
//! bus (`examples/common/sim_imu.rs`) and produces six axes at 100 Hz, each with a constant
//! bias, a first-order Gauss-Markov drift whose sigma and correlation time change with a
//! simulated temperature ramp (25 to 45 deg C), white noise, and quantisation to counts. The
//! firmware reads it through `imu_ar::sensor::Mpu6050` (FIFO batches of 100 ms) and estimates
//! each axis with an f32 lattice of order 4 (`lambda = 0.9995`, a 20 s memory, shared by the six
//! axes; `delta` and the saturation limit per channel, in deg/s or g) plus a BIC order selector. Every 10 s of sensor time it logs, per axis: `a_1..a_4`, the innovation sigma, the
//! selected order, the Gauss-Markov correlation time and sigma of the order-1 model, and the
//! one-step prediction MSE of the lattice and of a batch LS model fitted on the previous 10 s.
//!
//! After 120 s it checks each axis against the simulated truth and exits 0 when all hold. The
//! truth of an AR(4) fit to `bias + Gauss-Markov + white` (an ARMA(1,1)) is its best AR(4)
//! approximation: Levinson-Durbin on the exact autocovariances, at the temperature of the
//! centre of mass of the estimator's memory (`lambda / (1 - lambda)` samples before the end).
//! - the running mean is within 4 standard deviations (of an exponentially weighted mean of
//!   this process) of the true mean;
//! - every coefficient is within 0.1 of the true AR(4) coefficients (about 6 standard
//!   deviations with 4000 effective samples);
//! - the innovation variance is within 10 % of the true AR(4) innovation variance;
//! - the lattice's prediction MSE over the last 10 s is within 25 % of that same variance.
//!
//! Then it fits the composite noise model of every axis (`imu_ar::noise`: white noise,
//! quantisation, up to two Gauss-Markov terms, random walk) from the octave Allan variances its
//! `AllanStream` kept over the whole run (13 octaves, to 41 s), and checks it against the truth
//! over the run (the mean of the truth's Allan variance over the temperature ramp):
//! - `N` within 5 % of the truth's, on the axes where white noise makes at least half of the
//!   Allan variance at 0.01 s (all but gz, whose drift makes over 90 % of it);
//! - the model's Allan deviation within the Allan check's tolerance of the truth's at every
//!   octave (two standard errors of the run's estimate, or 10 %).
//!
//! The Allan check of the model against the run's own data is logged as well, with every octave
//! where it fails. Its last octaves rest on 4 and 1 differences: on gz, the five 20 s block
//! means of this seed agree to within 0.007 deg/s where the truth's spread is 0.06, and the
//! check against the data fails there while the model agrees with the truth.
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

    struct NoDelay;
    impl DelayNs for NoDelay {
        fn delay_ns(&mut self, _: u32) {}
    }

    /// One axis: its estimator and order selector, and the bookkeeping of the current 10 s
    /// window (its samples, and the squared one-step errors of the lattice and of the batch
    /// model fitted on the window before).
    struct Axis {
        name: &'static str,
        unit: &'static str,
        lattice: Lattice<f32, P>,
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
        fn new(index: usize, config: &Config<f32>, channel: &Channel<f32>) -> Self {
            Self {
                name: NAMES[index],
                unit: if index < 3 { "deg/s" } else { "g" },
                lattice: Lattice::new(config, channel),
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

        /// One sample: the batch model's prediction error (on in-window history), the
        /// lattice's update and error, the selector.
        fn push(&mut self, config: &Config<f32>, x: f32) {
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
            self.batch_model = covariance::<f32, P>(&self.samples, batch)
                .ok()
                .map(|f| f.model);
            self.report(t, config, (self.counted > 0).then_some(mse));
            self.len = 0;
            self.lattice_se = 0.0;
            self.batch_se = 0.0;
            self.counted = 0;
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

        /// The truth check of the module docs; logs it and returns whether it holds.
        fn check(&self, config: &Config<f32>, truth: &AxisTruth) -> bool {
            let (Some(model), Some((a_true, e_true))) =
                (self.lattice.model(config), truth.ar_projection::<P>())
            else {
                defmt::error!("{=str}: no model", self.name);
                return false;
            };
            let mean_sd = truth.ew_mean_sd(f64::from(config.lambda()));
            let mean_err = (f64::from(model.mean()) - truth.mean).abs();
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
                "check {=str}: mean {=f32} vs {=f32} (|err| {=f32} <= {=f32}) {=bool}; max|a - a_true| {=f32} <= {=f32} {=bool}; innovation variance / truth {=f32} in [0.9, 1.1] {=bool}; lattice MSE / truth {=f32} in [0.75, 1.25] {=bool}",
                self.name,
                model.mean(),
                truth.mean as f32,
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
            // The run's expected Allan variance: the mean over the run of the truth's.
            let truth_avar = |m: u64| {
                let sum: f64 = truth
                    .iter()
                    .map(|t| {
                        let (w, g) = (&t[axis], t[axis].gm_sigma * t[axis].gm_sigma);
                        w.white * w.white * dt * component::white(dt, m)
                            + g * component::gauss_markov(dt, w.tc, m)
                    })
                    .sum();
                sum / TRUTH_POINTS as f64
            };
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
        let mut axes: [Axis; AXES] =
            core::array::from_fn(|i| Axis::new(i, &config, if i < 3 { &gyro } else { &accel }));

        let mut batch = [RawSample::default(); 32];
        let mut n = 0usize;
        while n < DURATION_S as usize * RATE as usize {
            let got = match imu.read_fifo(&mut batch) {
                Ok(k) => k,
                Err(e) => {
                    defmt::warn!("demo: FIFO: {}", defmt::Debug2Format(&e));
                    continue;
                }
            };
            for s in &batch[..got] {
                let gyro = scale.gyro(s.gyro, GyroUnit::DegPerSec);
                let accel = scale.accel(s.accel, AccelUnit::G);
                for (axis, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
                    axis.push(&config, x);
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
        // The composite noise model of every axis, against the truth over the whole run.
        let over_run: [[AxisTruth; AXES]; TRUTH_POINTS] = core::array::from_fn(|k| {
            sim.truth_at((k as f64 + 0.5) * f64::from(DURATION_S) / TRUTH_POINTS as f64)
        });
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
