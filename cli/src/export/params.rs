//! The autopilot parameter files: PX4 EKF2 (a QGroundControl parameter file) and ArduPilot
//! EKF3 (a Mission Planner / MAVProxy parameter file). Both filters use their noise
//! parameters as continuous-looking rates that they multiply by their own prediction step, so
//! the values depend on the filter's rate, which the caller may set
//! ([`super::ImuModel::filter_rate_hz`]).

use super::ImuModel;
use super::files::{ACCEL, GYRO, Written, comments, document, finite, num, short, written};
use crate::error::Fail;

/// PX4's default `EKF2_PREDICT_US`, us.
pub const PX4_PREDICT_US: f64 = 10_000.0;

/// ArduPilot EKF3's `EKF_TARGET_DT`, s.
pub const ARDUPILOT_TARGET_DT: f64 = 0.012;

/// ArduPilot's default main loop rate (`SCHED_LOOP_RATE` of a copter), Hz.
pub const ARDUPILOT_LOOP_HZ: f64 = 400.0;

/// PX4's default vehicle ID (`MAV_SYS_ID`).
pub const PX4_SYSID: u8 = 1;

/// PX4's default `IMU_INTEG_RATE`, Hz: the rate of the `vehicle_imu` messages EKF2 steps on.
pub const PX4_IMU_INTEG_RATE: f64 = 200.0;

/// EKF2's prediction step, us, for an `EKF2_PREDICT_US` of `asked` us, IMU samples at
/// `sample_hz` and an `IMU_INTEG_RATE` of `integ_hz`: `vehicle_imu` integrates the whole
/// number of samples nearest its interval (`VehicleIMU`, one at least), and EKF2's down-sampler
/// the whole number of those nearest `asked` (`ImuDownSampler::update`, `required_samples`,
/// one at least). With the step, the `vehicle_imu` interval.
pub fn ekf2_step(asked: f64, sample_hz: f64, integ_hz: f64) -> (f64, f64) {
    let sample = 1e6 / sample_hz;
    let imu = (1e6 / integ_hz / sample).round().max(1.0) * sample;
    ((asked / imu).round().max(1.0) * imu, imu)
}

/// EKF3's prediction step at a main loop of `loop_hz`: it sums IMU samples (one per loop,
/// `dtIMUavg = 1 / loop_hz`) until `n dtIMUavg >= EKF_TARGET_DT - dtIMUavg / 2`
/// (`AP_NavEKF3_core.cpp`, `readIMUData`), so `dt` is the smallest such `n` times the loop
/// period: 12.5 ms at 400 Hz, 12 ms at 500 Hz, 20 ms at 50 Hz.
pub fn ekf3_step(loop_hz: f64) -> f64 {
    let period = 1.0 / loop_hz;
    let n = (ARDUPILOT_TARGET_DT / period - 0.5 - 1e-9).ceil().max(1.0);
    n * period
}

/// The discrete value `x / sqrt(dt)` of a continuous density `x` for a filter that adds
/// `(dt * value)^2` per step (so that the variance grows by `x^2 dt`).
fn per_step(what: &str, x: f64, dt: f64) -> Result<f64, Fail> {
    finite(what, x / dt.sqrt())
}

/// An autopilot's four parameters (gyro noise, accelerometer noise, gyro bias noise,
/// accelerometer bias noise), each with its documented range and the most its filter takes
/// at run time (a larger value is constrained to it).
type Names = [(&'static str, (f64, f64), f64); 4];

/// A parameter, its value, its documented range and the most its filter takes.
type Value = (&'static str, f64, (f64, f64), f64);

/// PX4's, from `src/modules/ekf2/module.yaml`; EKF2 constrains each to [0, 1]
/// (`Ekf::updateParameters`).
const PX4_NAMES: Names = [
    ("EKF2_GYR_NOISE", (1e-4, 0.1), 1.0),
    ("EKF2_ACC_NOISE", (0.01, 1.0), 1.0),
    ("EKF2_GYR_B_NOISE", (0.0, 0.01), 1.0),
    ("EKF2_ACC_B_NOISE", (0.0, 0.01), 1.0),
];

/// PX4's filter, as its notes name it.
const PX4_FILTER: &str = "EKF2 (Ekf::updateParameters)";

/// ArduPilot's, from the `@Range` of `libraries/AP_NavEKF3/AP_NavEKF3.cpp` (master:
/// `EK3_ABIAS_P_NSE` to 0.02); EKF3 constrains the gyro noise and both bias noises to
/// [0, 1] and the accelerometer noise to [0, 5] (`BAD_IMU_DATA_ACC_P_NSE`) in
/// `NavEKF3_core::CovariancePrediction`.
const ARDUPILOT_NAMES: Names = [
    ("EK3_GYRO_P_NSE", (1e-4, 0.1), 1.0),
    ("EK3_ACC_P_NSE", (0.01, 1.0), 5.0),
    ("EK3_GBIAS_P_NSE", (1e-5, 1e-3), 1.0),
    ("EK3_ABIAS_P_NSE", (1e-5, 0.02), 1.0),
];

/// ArduPilot's filter, as its notes name it.
const ARDUPILOT_FILTER: &str = "EKF3 (NavEKF3_core::CovariancePrediction)";

/// The values `N / sqrt(dt)`, `K / sqrt(dt)` of `names` for a filter stepping `dt`, and the
/// two sensors written.
fn autopilot(
    model: &ImuModel,
    horizon: Option<f64>,
    dt: f64,
    names: &Names,
) -> Result<(Vec<Value>, [Written; 2]), Fail> {
    let sensors = [
        written(model, &GYRO, horizon)?,
        written(model, &ACCEL, horizon)?,
    ];
    let [g, a] = &sensors;
    let mut values = Vec::new();
    for (&(name, range, most), x) in names.iter().zip([g.n, a.n, g.k, a.k]) {
        values.push((name, per_step(name, x, dt)?, range, most));
    }
    Ok((values, sensors))
}

/// A note for each value outside the target's documented range, and what `filter` takes
/// of one past the most it takes.
fn range_notes(values: &[Value], filter: &str) -> Vec<String> {
    values
        .iter()
        .filter(|(_, v, (low, high), _)| v < low || v > high)
        .map(|&(name, v, (low, high), most)| {
            let run = if v > most {
                format!(
                    "; {filter} takes {most} at run time whatever is set, a variance {:.3} \
                     times the model's",
                    (most / v).powi(2)
                )
            } else {
                String::new()
            };
            format!(
                "note: {name} = {} is outside its documented range [{low}, {high}]; the ground \
                 station may refuse or clamp it{run}.",
                short(v)
            )
        })
        .collect()
}

/// PX4 EKF2 parameters as a QGroundControl parameter file (tab-separated `Vehicle-Id
/// Component-Id Name Value Type`, type 9 `MAV_PARAM_TYPE_REAL32`, 6 `INT32`; `#` comments:
/// <https://docs.qgroundcontrol.com/master/en/qgc-dev-guide/file_formats/parameters.html>).
/// This is the file PX4 users load (QGroundControl, Parameters > Tools > Load from file); a
/// list of `param set` lines would need the MAVLink shell or an SD-card start script.
///
/// Convention (PX4/PX4-Autopilot): `src/modules/ekf2/EKF/covariance.cpp`,
/// `Ekf::predictCovariance` (at 765f2844e93fef99f3b6ae77b102b41728f89ead), with `dt` the
/// prediction step (`EKF2_PREDICT_US`, default 10000 us in `src/modules/ekf2/module.yaml`):
/// `gyro_var = sq(EKF2_GYR_NOISE)` enters `sym::PredictCovariance`, whose derivation
/// (`EKF/python/ekf_derivation/derivation.py`, `predict_covariance`, at
/// 1263e1a15a0e0dbea210cdcc0864000f5ea8a96a) puts the noise on the rate times `dt`: the angle
/// variance grows by `EKF2_GYR_NOISE^2 dt^2` per step (the same for `EKF2_ACC_NOISE` and the
/// velocity); the bias variance by `(dt * EKF2_GYR_B_NOISE)^2` (`gyro_bias_process_noise`;
/// `EKF2_ACC_B_NOISE` alike). Matching `N^2 dt` and `K^2 dt`: `EKF2_GYR_NOISE = N / sqrt(dt)`,
/// `EKF2_GYR_B_NOISE = K / sqrt(dt)`; one number for the three axes. `EKF2_PREDICT_US` is
/// written too, so that the file holds the step its values assume.
///
/// # Errors
///
/// A [`Fail`] for a filter rate outside `EKF2_PREDICT_US`'s range (1000 to 20000 us: 50 to
/// 1000 Hz), a vehicle id of 0, or a value that is not finite.
pub fn px4(model: &ImuModel, horizon: Option<f64>) -> Result<String, Fail> {
    let asked = match model.filter_rate_hz {
        Some(f) => (1e6 / f).round(),
        None => PX4_PREDICT_US,
    };
    let integ = model.imu_integ_rate_hz.unwrap_or(PX4_IMU_INTEG_RATE);
    if !(100.0..=1000.0).contains(&integ) {
        return Err(Fail(format!(
            "PX4: IMU_INTEG_RATE {integ} Hz is outside its range, 100 to 1000 Hz"
        )));
    }
    if integ.fract() != 0.0 {
        return Err(Fail(format!(
            "PX4: IMU_INTEG_RATE {integ} Hz is not a whole number (an INT32 parameter)"
        )));
    }
    // (Whole us, as the parameter holds them.)
    let (step, imu) = ekf2_step(asked, model.rate_hz, integ);
    let predict_us = step.round();
    if !(1000.0..=20000.0).contains(&predict_us) {
        return Err(Fail(format!(
            "PX4: filter rate {} Hz gives EKF2_PREDICT_US {predict_us}, outside 1000 to 20000 \
             (50 to 1000 Hz)",
            model.filter_rate_hz.unwrap_or(1e6 / asked)
        )));
    }
    let dt = predict_us * 1e-6;
    let stepped = if predict_us == asked {
        format!(
            "(EKF2 steps whole vehicle_imu messages, {} us apart at IMU_INTEG_RATE {integ} Hz.)",
            short(imu)
        )
    } else {
        format!(
            "(EKF2 steps whole vehicle_imu messages, {} us apart at IMU_INTEG_RATE {integ} Hz: \
             {asked} us asked, {predict_us} us written.)",
            short(imu)
        )
    };
    let (values, sensors) = autopilot(model, horizon, dt, &PX4_NAMES)?;
    let sysid = model.sysid.unwrap_or(PX4_SYSID);
    if sysid == 0 {
        return Err(Fail(
            "PX4: vehicle id 0 is not a MAV_SYS_ID (1 to 255)".into(),
        ));
    }
    let mut lines = vec![
        format!("Onboard parameters for Vehicle {sysid}"),
        String::new(),
    ];
    lines.extend(document(
        model,
        "PX4 EKF2",
        &[
            "EKF2 adds (dt * EKF2_GYR_NOISE)^2 to the angle variance and (dt * EKF2_GYR_B_NOISE)^2",
            "to the bias variance every prediction step dt (PX4-Autopilot ekf2 covariance.cpp,",
            "predictCovariance; derivation.py); the accelerometer alike. Discrete at the filter's",
            &format!(
                "step dt = EKF2_PREDICT_US = {predict_us} us: value = N / sqrt(dt), K / sqrt(dt)."
            ),
            &stepped,
            &format!(
                "Vehicle-Id {sysid} (MAV_SYS_ID{}): QGroundControl loads the file only into the",
                if model.sysid.is_some() {
                    ""
                } else {
                    ", the default"
                }
            ),
            "vehicle of that id (imu-ar characterise --sysid sets it).",
        ],
        &[&sensors[0], &sensors[1]],
    ));
    lines.extend(range_notes(&values, PX4_FILTER));
    lines.push(String::new());
    lines.push("Vehicle-Id\tComponent-Id\tName\tValue\tType".into());
    let mut text = comments(&lines);
    text += &format!("{sysid}\t1\tEKF2_PREDICT_US\t{predict_us}\t6\n");
    for (name, v, ..) in values {
        text += &format!("{sysid}\t1\t{name}\t{}\t9\n", num(v));
    }
    Ok(text)
}

/// ArduPilot EKF3 parameters as a parameter file of `NAME,VALUE` lines with `#` comments, the
/// form Mission Planner saves and loads (Config > Full Parameter List > Load from file) and
/// MAVProxy's `param load` reads.
///
/// Convention (ArduPilot/ardupilot, `libraries/AP_NavEKF3/AP_NavEKF3_core.cpp`,
/// `NavEKF3_core::CovariancePrediction`, at 363e7e9eec9bdd54953b1bcc3e6bb71895c3c139): `dt`
/// is the EKF's step, set by its target `EKF_TARGET_DT` = 12 ms and the main loop rate
/// ([`ekf3_step`]; [`super::ImuModel::loop_rate_hz`], default 400 Hz: 12.5 ms), not by a
/// filter rate of the user's; per step, `daxVar = sq(dt*_gyrNoise)` (`EK3_GYRO_P_NSE`) and
/// `dvxVar = sq(dt*_accNoise)` (`EK3_ACC_P_NSE`); the delta-angle bias state (the rate bias
/// times `dt`) gets `sq(sq(dt) * _gyroBiasProcessNoise)` (`EK3_GBIAS_P_NSE`), the
/// delta-velocity bias `sq(sq(dt) * _accelBiasProcessNoise)` (`EK3_ABIAS_P_NSE`): the rate
/// bias variance grows by `(dt EK3_GBIAS_P_NSE)^2` per step. Matching `N^2 dt` and `K^2 dt`:
/// value = `N / sqrt(dt)`, `K / sqrt(dt)`; one number for the three axes.
///
/// # Errors
///
/// A [`Fail`] for a loop rate outside 50 to 2000 Hz, or a value that is not finite.
pub fn ardupilot(model: &ImuModel, horizon: Option<f64>) -> Result<String, Fail> {
    let loop_hz = model.loop_rate_hz.unwrap_or(ARDUPILOT_LOOP_HZ);
    if !(50.0..=2000.0).contains(&loop_hz) {
        return Err(Fail(format!(
            "ArduPilot: loop rate {loop_hz} Hz is outside SCHED_LOOP_RATE's 50 to 2000 Hz"
        )));
    }
    let dt = ekf3_step(loop_hz);
    let (values, sensors) = autopilot(model, horizon, dt, &ARDUPILOT_NAMES)?;
    let mut lines = document(
        model,
        "ArduPilot EKF3",
        &[
            "EKF3 adds (dt * EK3_GYRO_P_NSE)^2 to the delta-angle variance and (dt^2 *",
            "EK3_GBIAS_P_NSE)^2 to the delta-angle bias variance every step dt (ArduPilot",
            "AP_NavEKF3_core.cpp, CovariancePrediction); the accelerometer alike. Discrete at the",
            &format!(
                "EKF's step dt = {} s: value = N / sqrt(dt), K / sqrt(dt). EKF3 sums IMU samples",
                short(dt)
            ),
            &format!(
                "until their time reaches EKF_TARGET_DT (12 ms) less half a sample: {} samples of a",
                (dt * loop_hz).round()
            ),
            &format!(
                "{} Hz main loop (SCHED_LOOP_RATE{}; imu-ar characterise --loop-rate sets it).",
                short(loop_hz),
                if model.loop_rate_hz.is_some() {
                    ""
                } else {
                    ", a copter's default"
                }
            ),
        ],
        &[&sensors[0], &sensors[1]],
    );
    if let Some(f) = model.filter_rate_hz {
        lines.push(format!(
            "note: --filter-rate {f} Hz is not EKF3's step, which its loop rate sets."
        ));
    }
    lines.extend(range_notes(&values, ARDUPILOT_FILTER));
    let mut text = comments(&lines);
    for (name, v, ..) in values {
        text += &format!("{name},{}\n", num(v));
    }
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_past_what_the_filter_takes_says_what_it_takes() {
        // EKF2 constrains its noises to [0, 1] whatever the parameter holds: a value of 2
        // runs as 1, a quarter of the variance (the note said only that the ground station
        // may refuse or clamp it). One under its range, or over it but within what the
        // filter takes, has only the range's note.
        let notes = range_notes(
            &[
                ("EKF2_ACC_NOISE", 2.0, (0.01, 1.0), 1.0),
                ("EKF2_GYR_NOISE", 5e-5, (1e-4, 0.1), 1.0),
                ("EK3_ACC_P_NSE", 2.0, (0.01, 1.0), 5.0),
                ("EKF2_GYR_B_NOISE", 1e-3, (0.0, 0.01), 1.0),
            ],
            PX4_FILTER,
        );
        assert_eq!(notes.len(), 3, "{notes:?}");
        assert!(
            notes[0].ends_with(
                "; EKF2 (Ekf::updateParameters) takes 1 at run time whatever is set, a variance \
                 0.250 times the model's."
            ),
            "{}",
            notes[0]
        );
        for note in &notes[1..] {
            assert!(note.ends_with("may refuse or clamp it."), "{note}");
        }
    }
}
