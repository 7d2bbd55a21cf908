//! Parameter files that navigation filters read, from the composite noise model of the six
//! axes of an IMU (`imu_ar::noise`): Kalibr's `imu.yaml`, the OpenVINS IMU chain, VINS-Mono,
//! ORB-SLAM3, PX4 EKF2 and ArduPilot EKF3 parameters, and the full composite as a state space
//! (`state_space.json`).
//!
//! Each target's convention (units, continuous or discrete, per axis or one number for all,
//! how its filter uses the number) is cited from its own source where its file is written
//! ([`files`] and [`params`]). Six of the formats take white noise `N` and random walk `K`
//! alone, one number per sensor, for the three axes together. None of them has a
//! bias-instability (Gauss-Markov) term: they carry the smallest pair `(N_H, K_H)`, `N_H >= N`
//! and `K_H >= K` of the worst axis, whose curve `sqrt(N_H^2/tau + K_H^2 tau/3)` overbounds the
//! model's Allan deviation of every axis at every octave in `[1 s, H]` (`log N_H/N + log K_H/K`
//! minimal, [`bound`]), `H` the horizon asked for or else the model's longest octave; never a
//! zero. The files state it with the fitted `N` and `K`. The state-space file always carries
//! the full composite.

pub mod bound;
pub mod files;
pub mod params;
mod state;

use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use imu_ar::noise::NoiseModel;
use serde_json::json;

use crate::error::Fail;
pub use state::StateSpace;

/// The most octaves of the model's Allan variance an axis carries.
pub const MAX_OCTAVES: usize = 63;

/// One axis's model in SI units (rad/s for a gyro, m/s^2 for an accelerometer).
#[derive(Clone, Debug, PartialEq)]
pub struct AxisModel {
    /// `N`, the continuous-time white-noise density, SI/sqrt(Hz) (the white term and the AR
    /// part's white equivalent).
    pub white_noise: f64,
    /// `K`, the continuous-time rate/acceleration random-walk density, SI/s/sqrt(Hz); 0 for
    /// none.
    pub random_walk: f64,
    /// Bias instability `B` (SI) and its `tau` (s), the IEEE 952 reading (minimum Allan
    /// deviation over 0.664) of the model's Allan deviation, for comments.
    pub bias_instability: (f64, f64),
    /// The model's sample interval `dt`, s: `model_avar[j]` is at `tau = 2^j dt`.
    pub dt: f64,
    /// The model's Allan variance (SI^2) at `tau_j = 2^j dt`, `j = 0..`.
    pub model_avar: Vec<f64>,
    /// The full composite at the filter's rate.
    pub state_space: StateSpace,
    /// The 95 % interval of `N` (SI), when the fit gave one.
    pub white_noise_interval: Option<(f64, f64)>,
    /// The 95 % interval of `K` (SI), when the fit gave one; from 0 for a model without `K`.
    pub random_walk_interval: Option<(f64, f64)>,
}

impl AxisModel {
    /// The axis of `model` (in its unit `u`) in SI units: `to_si` converts `u` to SI (e.g.
    /// `pi / 180` for deg/s, 9.80665 for g); its state space at the filter's step `filter_dt`
    /// with the random-walk state's initial variance `rw_p0` (in `u^2`); its Allan variance at
    /// `octaves` octaves (at least 21 for a statement up to `2^20 dt`).
    ///
    /// # Errors
    ///
    /// A [`Fail`] for a `to_si`, `filter_dt` or `rw_p0` that is not finite and positive (`rw_p0`
    /// may be 0), `octaves` outside `1..=63`, a model with no filter form at that step, or a
    /// number that overflows in SI.
    pub fn from_noise<const P: usize, const G: usize>(
        model: &NoiseModel<P, G>,
        to_si: f64,
        filter_dt: f64,
        rw_p0: f64,
        octaves: usize,
    ) -> Result<Self, Fail> {
        if !(to_si.is_finite() && to_si > 0.0) {
            return Err(Fail(format!(
                "unit factor {to_si}: must be positive and finite"
            )));
        }
        if !(1..=MAX_OCTAVES).contains(&octaves) {
            return Err(Fail(format!(
                "{octaves} octaves: 1 to {MAX_OCTAVES} (21 or more to reach 2^20 samples)"
            )));
        }
        let form = model
            .kalman(filter_dt, rw_p0)
            .map_err(|e| Fail(format!("filter step {filter_dt} s: {e}")))?;
        let mut avar = vec![0.0; octaves];
        model.avar_octaves(&mut avar)?;
        let s2 = to_si * to_si;
        avar.iter_mut().for_each(|v| *v *= s2);
        let lowest = avar
            .iter()
            .enumerate()
            .min_by(|p, q| p.1.total_cmp(q.1))
            .map_or((0.0, 0.0), |(j, v)| {
                (v.sqrt() / 0.664, model.dt() * 2f64.powi(j as i32))
            });
        let axis = Self {
            white_noise: model.white_noise() * to_si,
            random_walk: model.random_walk() * to_si,
            bias_instability: lowest,
            dt: model.dt(),
            model_avar: avar,
            state_space: StateSpace::of(&form, s2),
            white_noise_interval: None,
            random_walk_interval: None,
        };
        axis.check("the model")?;
        Ok(axis)
    }

    /// Refuses an axis with a number that is not finite, or negative where it must not be.
    fn check(&self, name: &str) -> Result<(), Fail> {
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        let ok = nonneg(self.white_noise)
            && nonneg(self.random_walk)
            && nonneg(self.bias_instability.0)
            && nonneg(self.bias_instability.1)
            && self.dt.is_finite()
            && self.dt > 0.0
            && !self.model_avar.is_empty()
            && self.model_avar.iter().all(|v| nonneg(*v))
            && self.state_space.is_finite();
        if ok {
            Ok(())
        } else {
            Err(Fail(format!(
                "{name}: a value is NaN, infinite or negative (or no Allan variance): nothing \
                 to export"
            )))
        }
    }
}

/// Six axes: gyro x, y, z then accelerometer x, y, z.
#[derive(Clone, Debug, PartialEq)]
pub struct ImuModel {
    /// The axes, in SI units.
    pub axes: [AxisModel; 6],
    /// The IMU's sample rate, Hz (the rate of the models: `1 / dt`).
    pub rate_hz: f64,
    /// The IMU's ROS topic (Kalibr, OpenVINS) [default: `/imu0`].
    pub topic: Option<String>,
    /// The rate of the state-space filter and of PX4 EKF2's prediction, Hz, with which EKF2
    /// uses its noise parameters [default: EKF2's 100 Hz (`EKF2_PREDICT_US` 10000)].
    pub filter_rate_hz: Option<f64>,
    /// ArduPilot's main loop rate (`SCHED_LOOP_RATE`), Hz, which sets EKF3's step
    /// ([`params::ekf3_step`]) [default: 400, 12.5 ms].
    pub loop_rate_hz: Option<f64>,
    /// The vehicle ID of PX4's parameter file (`MAV_SYS_ID`) [default: 1].
    pub sysid: Option<u8>,
    /// PX4's `IMU_INTEG_RATE`, Hz: the rate of the messages EKF2 steps a whole number of
    /// ([`params::ekf2_step`]) [default: 200].
    pub imu_integ_rate_hz: Option<f64>,
    /// What part of the record the models come from, when not the whole of it (a comment
    /// line of every file).
    pub origin: Option<String>,
}

/// The names of the six axes.
pub const AXIS_NAMES: [&str; 6] = [
    "gyro x", "gyro y", "gyro z", "accel x", "accel y", "accel z",
];

impl ImuModel {
    /// Refuses a model with a value that is not finite, or axes at another rate.
    fn check(&self) -> Result<(), Fail> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return Err(Fail(format!(
                "rate {} Hz: must be positive and finite",
                self.rate_hz
            )));
        }
        for (a, name) in self.axes.iter().zip(AXIS_NAMES) {
            a.check(name)?;
            if (a.dt * self.rate_hz - 1.0).abs() > 1e-9 {
                return Err(Fail(format!(
                    "{name}: sampled every {} s, not at the IMU's {} Hz",
                    a.dt, self.rate_hz
                )));
            }
        }
        if let Some(f) = self.filter_rate_hz.filter(|f| !(f.is_finite() && *f > 0.0)) {
            return Err(Fail(format!(
                "filter rate {f} Hz: must be positive and finite"
            )));
        }
        Ok(())
    }
}

/// A parameter file's format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// Kalibr's `imu.yaml`.
    Kalibr,
    /// OpenVINS's `kalibr_imu_chain.yaml`.
    OpenVins,
    /// VINS-Mono / VINS-Fusion's IMU keys (OpenCV YAML).
    Vins,
    /// ORB-SLAM3's IMU keys (OpenCV YAML).
    OrbSlam3,
    /// PX4 EKF2 parameters (QGroundControl parameter file).
    Px4,
    /// ArduPilot EKF3 parameters (Mission Planner / MAVProxy parameter file).
    ArduPilot,
    /// The full composite per axis as JSON.
    StateSpace,
}

impl Format {
    /// Every format.
    pub const ALL: [Format; 7] = [
        Self::Kalibr,
        Self::OpenVins,
        Self::Vins,
        Self::OrbSlam3,
        Self::Px4,
        Self::ArduPilot,
        Self::StateSpace,
    ];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Kalibr => "kalibr",
            Self::OpenVins => "openvins",
            Self::Vins => "vins",
            Self::OrbSlam3 => "orbslam3",
            Self::Px4 => "px4",
            Self::ArduPilot => "ardupilot",
            Self::StateSpace => "state-space",
        }
    }

    /// The file written.
    pub fn file_name(self) -> &'static str {
        match self {
            Self::Kalibr => "imu.yaml",
            Self::OpenVins => "kalibr_imu_chain.yaml",
            Self::Vins => "vins_imu.yaml",
            Self::OrbSlam3 => "orbslam3_imu.yaml",
            Self::Px4 => "px4.params",
            Self::ArduPilot => "ardupilot.param",
            Self::StateSpace => "state_space.json",
        }
    }

    /// A comma-separated list (`kalibr,px4`), or `all`; each format once.
    ///
    /// # Errors
    ///
    /// A [`Fail`] naming an unknown format, or for an empty list.
    pub fn list(text: &str) -> Result<Vec<Format>, Fail> {
        if text.trim() == "all" {
            return Ok(Self::ALL.to_vec());
        }
        let mut out = Vec::new();
        for f in text.split(',').map(|p| p.trim().parse::<Format>()) {
            let f = f?;
            if !out.contains(&f) {
                out.push(f);
            }
        }
        Ok(out)
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Format {
    type Err = Fail;

    fn from_str(s: &str) -> Result<Self, Fail> {
        Self::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|f| f.name()).collect();
                Fail(if s == "all" {
                    "format \"all\" stands alone: it is every format, not one of a list".into()
                } else {
                    format!(
                        "format {:?}: one of {} (or a comma-separated list, or all)",
                        crate::error::escaped(s),
                        names.join(", ")
                    )
                })
            })
    }
}

/// Writes the file of `format` into `dir` and returns its path. `horizon`: the time in
/// seconds the filter must coast; the six parameter formats carry the smallest white noise and
/// random walk `(N_H, K_H)` that overbound the model from 1 s up to it, or without it up to the
/// model's longest octave ([`bound`]).
///
/// # Errors
///
/// A [`Fail`] for a model with a value that is not finite, a horizon that is not finite or
/// below [`bound::FROM_TAU`], a topic with control characters, a filter rate PX4 cannot take, a
/// model that no white noise and random walk overbound, or a file that cannot be written.
pub fn write(
    format: Format,
    model: &ImuModel,
    horizon: Option<f64>,
    dir: &Path,
) -> Result<PathBuf, Fail> {
    model.check()?;
    if let Some(h) = horizon.filter(|h| !(h.is_finite() && *h >= bound::FROM_TAU)) {
        return Err(Fail(format!(
            "horizon {h} s: must be finite and at least {} s (the overbound runs from {} s)",
            bound::FROM_TAU,
            bound::FROM_TAU
        )));
    }
    let text = match format {
        Format::Kalibr => files::kalibr(model, horizon)?,
        Format::OpenVins => files::openvins(model, horizon)?,
        Format::Vins => files::vins(model, horizon)?,
        Format::OrbSlam3 => files::orbslam3(model, horizon)?,
        Format::Px4 => params::px4(model, horizon)?,
        Format::ArduPilot => params::ardupilot(model, horizon)?,
        Format::StateSpace => state_space_json(model),
    };
    let path = dir.join(format.file_name());
    std::fs::write(&path, text).map_err(|e| Fail(format!("{}: {e}", path.display())))?;
    Ok(path)
}

/// The full composite of every axis, in SI units.
fn state_space_json(model: &ImuModel) -> String {
    let axes: Vec<serde_json::Value> = model
        .axes
        .iter()
        .zip(AXIS_NAMES)
        .map(|(a, name)| {
            let adev: Vec<serde_json::Value> = a
                .model_avar
                .iter()
                .enumerate()
                .map(|(j, v)| json!({"tau_s": a.dt * 2f64.powi(j as i32), "adev": v.sqrt()}))
                .collect();
            json!({
                "axis": name,
                "unit": files::Sensor::of_axis(name).unit,
                "white_noise": a.white_noise,
                "random_walk": a.random_walk,
                "bias_instability": {"value": a.bias_instability.0, "tau_s": a.bias_instability.1},
                "states": a.state_space.states,
                "phi": a.state_space.phi,
                "q": a.state_space.q,
                "p0": a.state_space.p0,
                "h": a.state_space.h,
                "measurement_variance": a.state_space.measurement_variance,
                "quantization": a.state_space.quantization,
                "dt": a.state_space.dt,
                "model_adev": adev,
            })
        })
        .collect();
    let doc = json!({
        "written_by": files::TOOL,
        "units": "SI: a gyro in rad/s, an accelerometer in m/s^2; white_noise in unit/sqrt(Hz), \
                  random_walk in unit/s/sqrt(Hz), q, p0 and measurement_variance in unit^2, \
                  quantization.value in unit s",
        "form": "discrete time at the filter's step dt: x_{k+1} = phi x_k + w_k, Cov(w_k) = q, \
                 x_0 ~ (0, p0); the sensor averaged over a step is h x_k plus white noise of \
                 variance measurement_variance (N^2/dt); h is 1 on every state but an \
                 oscillator's (dx/dt), 0, and quantization (q_(k-1)/Dt), -1 (Dt is the step dt)",
        "rate_hz": model.rate_hz,
        "axes": axes,
    });
    let mut text = serde_json::to_string_pretty(&doc).unwrap_or_default();
    text.push('\n');
    text
}
