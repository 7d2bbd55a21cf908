//! The autopilots' thermal-calibration parameters and their corrections, re-implemented from
//! their sources so that what is written can be applied back to the data it was fitted on.
//!
//! PX4 (`src/modules/temperature_compensation/TemperatureCompensation.cpp`,
//! `calc_thermal_offsets_3D`, in `float`):
//!
//! ```text
//! dT = clamp(T, TMIN, TMAX) - TREF
//! offset[i] = X0[i] + X1[i] dT + X2[i] dT^2 + X3[i] dT^3,   corrected = raw - offset
//! ```
//!
//! per sensor `TC_Gj_*` (gyro, rad/s) or `TC_Aj_*` (accelerometer, m/s^2), matched to the
//! sensor by `TC_xj_ID` = its device id; TREF is the middle of the range, as PX4's
//! `Tools/process_sensor_caldata.py` sets it. A gyro's X0 is its bias at TREF; an
//! accelerometer's is 0 (its constant is the accelerometer calibration's, `CAL_ACCn_OFF`, which
//! PX4 asks to redo after a thermal calibration), as PX4's on-board calibration writes it.
//!
//! ArduPilot (`libraries/AP_InertialSensor/AP_InertialSensor_tempcal.cpp`, `correct_sensor`,
//! in `float`):
//!
//! ```text
//! P(t) = (c1 + (c2 + c3 t) t) t * 1e-6,   t = T - 35
//! v -= P(clamp(T, TMIN, TMAX) - 35);  v += P(clamp(CALTEMP, TMIN, TMAX) - 35)
//! ```
//!
//! with `c_k` the vectors `INS_TCALn_ACCk` and `INS_TCALn_GYRk` (n = 1..3; `INS4_TCAL_*` and
//! `INS5_TCAL_*` for the fourth and fifth IMU), applied when `INS_TCALn_ENABLE` is 1. The
//! polynomial has no constant: the offsets (`INS_ACCOFFS`, `INS_GYROFFS`) hold it, at the
//! temperature `INS_ACCn_CALTEMP` / `INS_GYRn_CALTEMP` they were measured at.

use super::cubic::Poly;

/// ArduPilot's fixed reference temperature, deg C.
pub const ARDUPILOT_REFERENCE: f64 = 35.0;

/// ArduPilot's scale of the stored coefficients.
pub const ARDUPILOT_SCALE: f64 = 1e6;

/// Which sensor of an IMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sensor {
    /// The gyro (rad/s).
    Gyro,
    /// The accelerometer (m/s^2).
    Accel,
}

/// PX4's thermal calibration of one sensor: the `TC_Gj_*` or `TC_Aj_*` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Px4 {
    /// Gyro or accelerometer.
    pub sensor: Sensor,
    /// `TC_xj_ID`: the sensor's device id.
    pub device_id: u32,
    /// `TC_xj_X0_i .. X3_i`: `x[k][i]`, the coefficient of `dT^k` of axis `i`.
    pub x: [[f32; 3]; 4],
    /// `TC_xj_TREF`, deg C.
    pub tref: f32,
    /// `TC_xj_TMIN`, deg C.
    pub tmin: f32,
    /// `TC_xj_TMAX`, deg C.
    pub tmax: f32,
}

impl Px4 {
    /// The parameters of the fitted biases `axes` (x, y, z) over `tmin ..= tmax` deg C.
    pub fn new(sensor: Sensor, device_id: u32, axes: &[Poly; 3], tmin: f64, tmax: f64) -> Self {
        let tref = 0.5 * (tmin + tmax);
        let mut x = [[0.0f32; 3]; 4];
        for (i, axis) in axes.iter().enumerate() {
            let c = axis.about(tref).coefficients;
            for k in 0..4 {
                x[k][i] = c[k] as f32;
            }
            if sensor == Sensor::Accel {
                x[0][i] = 0.0;
            }
        }
        Px4 {
            sensor,
            device_id,
            x,
            tref: tref as f32,
            tmin: tmin as f32,
            tmax: tmax as f32,
        }
    }

    /// The offset PX4 subtracts from axis `i` at `celsius`, as PX4 computes it (in `f32`).
    pub fn offset(&self, i: usize, celsius: f32) -> f32 {
        let dt = if celsius > self.tmax {
            self.tmax - self.tref
        } else if celsius < self.tmin {
            self.tmin - self.tref
        } else {
            celsius - self.tref
        };
        let dt2 = dt * dt;
        let dt3 = dt2 * dt;
        self.x[0][i] + self.x[1][i] * dt + self.x[2][i] * dt2 + self.x[3][i] * dt3
    }

    /// The parameters, by name: `TC_Gj_*` or `TC_Aj_*` for calibration slot `j` (0..=3).
    pub fn params(&self, j: usize) -> Vec<(String, Value)> {
        let s = match self.sensor {
            Sensor::Gyro => "G",
            Sensor::Accel => "A",
        };
        // PX4 stores the device id in an int32 parameter (it is a 24-bit bitfield).
        let mut out = vec![(format!("TC_{s}{j}_ID"), Value::Int(self.device_id as i32))];
        for k in (0..4).rev() {
            for i in 0..3 {
                out.push((format!("TC_{s}{j}_X{k}_{i}"), Value::Float(self.x[k][i])));
            }
        }
        out.push((format!("TC_{s}{j}_TREF"), Value::Float(self.tref)));
        out.push((format!("TC_{s}{j}_TMIN"), Value::Float(self.tmin)));
        out.push((format!("TC_{s}{j}_TMAX"), Value::Float(self.tmax)));
        out
    }
}

/// The prefix of IMU `n`'s thermal-calibration parameters: `INS_TCALn_` for IMUs 1 to 3,
/// `INSn_TCAL_` for the fourth and fifth (`AP_InertialSensor_Params.cpp`).
pub fn ardupilot_prefix(n: usize) -> String {
    if n <= 3 {
        format!("INS_TCAL{n}_")
    } else {
        format!("INS{n}_TCAL_")
    }
}

/// A parameter's value as an autopilot stores it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// A 32-bit integer parameter.
    Int(i32),
    /// A 32-bit float parameter.
    Float(f32),
}

/// ArduPilot's thermal calibration of one IMU: the `INS_TCALn_*` parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArduPilot {
    /// `INS_TCALn_ACCk_{X,Y,Z}`: `accel[k - 1][i]`, scaled by 1e6.
    pub accel: [[f32; 3]; 3],
    /// `INS_TCALn_GYRk_{X,Y,Z}`: `gyro[k - 1][i]`, scaled by 1e6.
    pub gyro: [[f32; 3]; 3],
    /// `INS_TCALn_TMIN`, deg C.
    pub tmin: f32,
    /// `INS_TCALn_TMAX`, deg C.
    pub tmax: f32,
}

impl ArduPilot {
    /// The parameters of the fitted biases (x, y, z of each sensor) over `tmin ..= tmax` deg C:
    /// each polynomial about 35 deg C, its constant dropped, scaled by 1e6.
    pub fn new(accel: &[Poly; 3], gyro: &[Poly; 3], tmin: f64, tmax: f64) -> Self {
        let scaled = |axes: &[Poly; 3]| {
            let mut c = [[0.0f32; 3]; 3];
            for (i, axis) in axes.iter().enumerate() {
                let q = axis.about(ARDUPILOT_REFERENCE).coefficients;
                for k in 1..4 {
                    c[k - 1][i] = (q[k] * ARDUPILOT_SCALE) as f32;
                }
            }
            c
        };
        ArduPilot {
            accel: scaled(accel),
            gyro: scaled(gyro),
            tmin: tmin as f32,
            tmax: tmax as f32,
        }
    }

    /// What ArduPilot subtracts from axis `i` of `sensor` at `celsius`, the offsets measured at
    /// `caltemp`, as ArduPilot computes it (in `f32`).
    pub fn correction(&self, sensor: Sensor, i: usize, celsius: f32, caltemp: f32) -> f32 {
        let c = match sensor {
            Sensor::Accel => &self.accel,
            Sensor::Gyro => &self.gyro,
        };
        let p =
            |t: f32| (c[0][i] + (c[1][i] + c[2][i] * t) * t) * t * (1.0 / ARDUPILOT_SCALE as f32);
        let reference = ARDUPILOT_REFERENCE as f32;
        let t = celsius.clamp(self.tmin, self.tmax);
        let tc = caltemp.clamp(self.tmin, self.tmax);
        p(t - reference) - p(tc - reference)
    }

    /// The parameters, by name, of IMU `n` (1..=5): `INS_TCALn_*`, or `INSn_TCAL_*` for the
    /// fourth and fifth.
    pub fn params(&self, n: usize) -> Vec<(String, Value)> {
        let prefix = ardupilot_prefix(n);
        let mut out = vec![
            (format!("{prefix}ENABLE"), Value::Int(1)),
            (format!("{prefix}TMIN"), Value::Float(self.tmin)),
            (format!("{prefix}TMAX"), Value::Float(self.tmax)),
        ];
        for (name, c) in [("ACC", &self.accel), ("GYR", &self.gyro)] {
            for k in 1..4 {
                for (i, axis) in ["X", "Y", "Z"].iter().enumerate() {
                    out.push((
                        format!("{prefix}{name}{k}_{axis}"),
                        Value::Float(c[k - 1][i]),
                    ));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(c: [f64; 4], reference: f64) -> Poly {
        Poly {
            reference,
            coefficients: c,
        }
    }

    /// A gyro bias cubic about 27 deg C, written for PX4 (TREF the middle of 20..60) and
    /// applied through PX4's formula: the bias is gone to float rounding across the range, and
    /// held at the range's ends beyond it.
    #[test]
    fn px4_gyro_parameters_cancel_the_bias() {
        let axes = [
            poly([0.01, 2e-4, -3e-6, 5e-8], 27.0),
            poly([-0.02, -1e-4, 1e-6, 0.0], 27.0),
            poly([0.003, 0.0, 2e-6, -1e-8], 27.0),
        ];
        let px4 = Px4::new(Sensor::Gyro, 0x24_0021, &axes, 20.0, 60.0);
        assert_eq!(px4.tref, 40.0);
        for (i, axis) in axes.iter().enumerate() {
            for t in [20.0, 25.5, 40.0, 59.9, 60.0] {
                let left = axis.at(t) - f64::from(px4.offset(i, t as f32));
                assert!(left.abs() < 1e-7, "axis {i} at {t}: {left}");
            }
            assert_eq!(px4.offset(i, 80.0), px4.offset(i, 60.0));
            assert_eq!(px4.offset(i, -5.0), px4.offset(i, 20.0));
        }
        let params = px4.params(1);
        assert_eq!(params[0], ("TC_G1_ID".into(), Value::Int(0x24_0021)));
        assert_eq!(params.len(), 1 + 12 + 3);
        assert!(params.iter().any(|(n, _)| n == "TC_G1_X3_2"));
    }

    /// An accelerometer's X0 is 0: PX4 removes the change from TREF, not the constant.
    #[test]
    fn px4_accel_parameters_remove_the_change_from_the_reference() {
        let axes = [poly([9.81, 1e-3, 2e-5, 0.0], 20.0); 3];
        let px4 = Px4::new(Sensor::Accel, 7, &axes, 20.0, 50.0);
        for t in [20.0, 35.0, 50.0] {
            let left = axes[0].at(t) - f64::from(px4.offset(0, t as f32));
            let want = axes[0].at(35.0);
            assert!((left - want).abs() < 1e-5, "{left} vs {want}");
        }
    }

    /// ArduPilot: the bias change from CALTEMP is cancelled, the constant left to the offsets.
    #[test]
    fn ardupilot_parameters_cancel_the_change_from_caltemp() {
        let gyro = [poly([0.01, 2e-4, -3e-6, 5e-8], 27.0); 3];
        let accel = [poly([0.2, -2e-3, 1e-5, 1e-7], 30.0); 3];
        let ap = ArduPilot::new(&accel, &gyro, 18.0, 62.0);
        let caltemp = 31.0;
        for (sensor, axes) in [(Sensor::Gyro, &gyro), (Sensor::Accel, &accel)] {
            for t in [18.0, 30.0, 45.0, 62.0] {
                let change = axes[0].at(t) - axes[0].at(caltemp);
                let left = change - f64::from(ap.correction(sensor, 0, t as f32, caltemp as f32));
                assert!(left.abs() < 2e-6, "{sensor:?} at {t}: {left}");
            }
        }
        let names: Vec<String> = ap.params(2).into_iter().map(|(n, _)| n).collect();
        assert_eq!(names[0], "INS_TCAL2_ENABLE");
        assert!(names.contains(&"INS_TCAL2_GYR3_Z".to_string()));
        assert_eq!(ap.params(4)[0].0, "INS4_TCAL_ENABLE");
    }
}
