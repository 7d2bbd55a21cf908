//! Thermal calibration for the autopilots: the bias of each gyro and accelerometer axis
//! against the die temperature, fitted offline from a warm-up record, written in PX4's and
//! ArduPilot's conventions and checked through their own correction formulas.
//!
//! - [`bins`]: the samples grouped by temperature, each bin reduced to its median, so that
//!   the heating rate (minutes at one temperature, seconds at another) does not weight the fit
//!   and a knock does not move it;
//! - [`cubic`]: the bias as a polynomial in temperature, fitted to the bins with a robust
//!   (Huber) loss, on all bins or on a chosen subset for a held-out check;
//! - [`axis`]: one axis's fit with its checks;
//! - [`autopilot`]: the written parameters (PX4 `TC_*`, ArduPilot `INS_TCALn_*`) and their
//!   corrections, re-implemented from the autopilots' sources.

pub mod autopilot;
pub mod axis;
pub mod bins;
pub mod cubic;

use std::path::PathBuf;

use serde::Serialize;

use crate::characterise::{axis_unit, parse_unit};
use crate::error::{Fail, escaped, with_file};
use crate::input::source::{self, AXES, Request};
use crate::output::Output;
use autopilot::{ArduPilot, Px4, Sensor, Value};
use axis::{AxisFit, fit_axis};

/// The arguments of `imu-ar thermal`.
#[derive(clap::Args)]
pub struct Args {
    /// The warm-up record: CSV files read as one record (`-` is standard input), with the six
    /// axes and the die temperature (deg C) in every row.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// The six CSV columns: gyro x, y, z, then accelerometer x, y, z [default: gx .. az].
    #[arg(long, value_delimiter = ',')]
    columns: Option<Vec<String>>,
    /// The CSV column of the die temperature, deg C.
    #[arg(long, default_value = "temperature")]
    temperature_column: String,
    /// The gyro columns' unit when their header does not say: rad/s, deg/s or deg/h.
    #[arg(long)]
    gyro_unit: Option<String>,
    /// The accelerometer columns' unit when their header does not say: m/s^2, g or mg.
    #[arg(long)]
    accel_unit: Option<String>,
    /// The width of a temperature bin, deg C.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    bin_width: f64,
    /// The fewest samples a bin needs to take part.
    #[arg(long, default_value_t = 10)]
    min_bin: usize,
    /// Directory for the parameter files (created if needed).
    #[arg(long)]
    out: PathBuf,
    /// The files to write: px4, ardupilot, json, comma-separated, or all.
    #[arg(long, default_value = "all")]
    format: String,
    /// PX4: the device id of the gyro and of the accelerometer (TC_Gj_ID, TC_Aj_ID), which
    /// PX4 matches the calibration to; needed for px4 from a CSV record.
    #[arg(long, value_delimiter = ',')]
    device_id: Option<Vec<u32>>,
    /// PX4: the calibration slot j of TC_Gj_* and TC_Aj_* (0 to 3).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=3))]
    px4_slot: u8,
    /// ArduPilot: the IMU n of INS_TCALn_* (1 to 5).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u8).range(1..=5))]
    imu: u8,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// A parameter file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Px4,
    ArduPilot,
    Json,
}

impl Format {
    fn list(text: &str) -> Result<Vec<Format>, Fail> {
        let mut out = Vec::new();
        for name in text.split(',').map(str::trim) {
            let f: &[Format] = match name {
                "px4" => &[Format::Px4],
                "ardupilot" => &[Format::ArduPilot],
                "json" => &[Format::Json],
                "all" => &[Format::Px4, Format::ArduPilot, Format::Json],
                other => {
                    return Err(Fail(format!(
                        "--format {}: px4, ardupilot, json, or all",
                        escaped(other)
                    )));
                }
            };
            for f in f {
                if !out.contains(f) {
                    out.push(*f);
                }
            }
        }
        Ok(out)
    }

    fn file_name(self) -> &'static str {
        match self {
            Format::Px4 => "px4_thermal.params",
            Format::ArduPilot => "ardupilot_tcal.parm",
            Format::Json => "thermal.json",
        }
    }
}

/// The calibration and its checks.
#[derive(Serialize)]
pub struct Thermal {
    /// Samples read.
    pub n: usize,
    /// The temperature range of the bins, deg C: TMIN and TMAX of the files.
    pub range_c: (f64, f64),
    /// Per axis (gx .. az), in rad/s or m/s^2.
    pub axes: Vec<AxisResult>,
    /// Every axis's fit generalises: its held-out residual is at most
    /// [`HELD_OUT_FRACTION`] of its bias change, or the held-out bins' standardised residuals
    /// have a root mean square of at most [`HELD_OUT_Z`] (the fit explains them to their
    /// noise).
    pub generalises: bool,
    /// The files written.
    pub files: Vec<String>,
}

/// The largest held-out residual, as a fraction of the bias change, that passes.
pub const HELD_OUT_FRACTION: f64 = 0.1;

/// The largest root mean square of the held-out bins' standardised residuals that passes.
pub const HELD_OUT_Z: f64 = 2.0;

/// One axis.
#[derive(Serialize)]
pub struct AxisResult {
    /// gx .. az.
    pub axis: &'static str,
    /// rad/s or m/s^2.
    pub unit: &'static str,
    /// The cubic's coefficients of `(T - reference)^0..3`, per kelvin to that power.
    pub coefficients: [f64; 4],
    /// The temperature the powers are about (the middle of the range), deg C.
    pub reference_c: f64,
    /// Bins fitted.
    pub bins: usize,
    /// The bias change over the range: the largest bin less the smallest.
    pub change: f64,
    /// The largest `|bin - fit|`.
    pub residual: f64,
    /// The largest `|bin - fit|` over bins held out of the fit.
    pub held_out: f64,
    /// The root mean square of the held-out bins' residuals over their standard errors.
    pub held_out_z: f64,
    /// The largest bias PX4's correction leaves in a bin, applied through its formula: for a
    /// gyro, whose X0 holds the bias, the corrected bin; for an accelerometer, whose constant
    /// the accelerometer calibration at TREF removes, the corrected bin less the fit at TREF.
    pub px4_left: f64,
    /// The largest bias ArduPilot's correction leaves in a bin, the offsets calibrated at
    /// CALTEMP (the middle of the range here): the corrected bin less the fit at CALTEMP.
    pub ardupilot_left: f64,
    /// The fit generalises (see [`Thermal::generalises`]).
    pub generalises: bool,
}

/// Reads the record, fits every axis, checks the fits through the autopilots' formulas and
/// writes the files.
pub fn run(args: &Args) -> Result<Thermal, Fail> {
    if !(args.bin_width.is_finite() && args.bin_width > 0.0) {
        return Err(Fail(format!(
            "--bin-width {}: a positive number of deg C",
            args.bin_width
        )));
    }
    let formats = Format::list(&args.format)?;
    let device = match (&args.device_id, formats.contains(&Format::Px4)) {
        (Some(ids), _) if ids.len() == 2 => Some([ids[0], ids[1]]),
        (Some(ids), _) => {
            return Err(Fail(format!(
                "--device-id: {} ids given; two are needed (the gyro's, then the \
                 accelerometer's)",
                ids.len()
            )));
        }
        (None, true) => {
            return Err(Fail(
                "px4: PX4 matches TC_Gj_ID and TC_Aj_ID to the sensors' device ids, which a CSV \
                 record does not hold: give --device-id GYRO,ACCEL (PX4's sensor_gyro and \
                 sensor_accel device_id), or leave px4 out of --format"
                    .into(),
            ));
        }
        (None, false) => None,
    };
    let (celsius, axes, units) = read(args)?;
    let n = celsius.len();
    let mut fits: Vec<AxisFit> = Vec::with_capacity(6);
    for (i, x) in axes.iter().enumerate() {
        let fit = fit_axis(&celsius, x, args.bin_width, args.min_bin)
            .map_err(|e| with_file(&args.files, format!("{}: {e}", AXES[i])))?;
        fits.push(fit);
    }
    let range = fits[0].range;
    let polys = |from: usize| [fits[from].poly, fits[from + 1].poly, fits[from + 2].poly];
    let (gyro, accel) = (polys(0), polys(3));
    let px4 = device.map(|[g, a]| {
        [
            Px4::new(Sensor::Gyro, g, &gyro, range.0, range.1),
            Px4::new(Sensor::Accel, a, &accel, range.0, range.1),
        ]
    });
    let ardupilot = ArduPilot::new(&accel, &gyro, range.0, range.1);
    let mut results = Vec::with_capacity(6);
    for (i, fit) in fits.iter().enumerate() {
        let sensor = if i < 3 { Sensor::Gyro } else { Sensor::Accel };
        let corrected = |correct: &dyn Fn(f32) -> f32| -> Vec<f64> {
            fit.bins
                .iter()
                .map(|b| b.value - f64::from(correct(b.celsius as f32)))
                .collect()
        };
        let largest =
            |v: Vec<f64>, offset: f64| v.iter().fold(0.0f64, |m, x| m.max((x - offset).abs()));
        // The middle of the range: PX4's TREF, and the CALTEMP of the check.
        let middle = 0.5 * (range.0 + range.1);
        let px4_left = px4.map_or(f64::NAN, |p| {
            let left = corrected(&|t| p[i / 3].offset(i % 3, t));
            match sensor {
                Sensor::Gyro => largest(left, 0.0),
                Sensor::Accel => largest(left, fit.poly.at(middle)),
            }
        });
        let ardupilot_left = largest(
            corrected(&|t| ardupilot.correction(sensor, i % 3, t, middle as f32)),
            fit.poly.at(middle),
        );
        let generalises =
            fit.held_out <= HELD_OUT_FRACTION * fit.change || fit.held_out_z <= HELD_OUT_Z;
        results.push(AxisResult {
            axis: AXES[i],
            unit: units[i],
            coefficients: fit.poly.coefficients,
            reference_c: fit.poly.reference,
            bins: fit.bins.len(),
            change: fit.change,
            residual: fit.residual,
            held_out: fit.held_out,
            held_out_z: fit.held_out_z,
            px4_left,
            ardupilot_left,
            generalises,
        });
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Fail(format!("--out {}: cannot create: {e}", args.out.display())))?;
    let mut thermal = Thermal {
        n,
        range_c: range,
        generalises: results.iter().all(|a| a.generalises),
        axes: results,
        files: Vec::new(),
    };
    for format in formats {
        let text = match format {
            Format::Px4 => match &px4 {
                Some(p) => px4_file(p, args.px4_slot.into(), &thermal),
                None => continue,
            },
            Format::ArduPilot => ardupilot_file(&ardupilot, args.imu.into(), &thermal),
            Format::Json => format!("{}\n", serde_json::to_value(&thermal)?),
        };
        let path = args.out.join(format.file_name());
        std::fs::write(&path, text).map_err(|e| Fail(format!("{}: {e}", path.display())))?;
        thermal.files.push(path.display().to_string());
    }
    Ok(thermal)
}

/// The temperatures, the six axes in SI units, and the units' names, of a CSV record.
#[allow(clippy::type_complexity)]
fn read(args: &Args) -> Result<(Vec<f64>, [Vec<f64>; 6], [&'static str; 6]), Fail> {
    let mut columns = match &args.columns {
        Some(c) if c.len() == 6 => c.clone(),
        Some(c) => {
            return Err(Fail(format!(
                "--columns: {} names given; six are needed (gyro x, y, z, accelerometer x, y, z)",
                c.len()
            )));
        }
        None => AXES.map(String::from).to_vec(),
    };
    columns.push(args.temperature_column.clone());
    let request = Request {
        columns: &columns,
        topic: None,
        frame_id: None,
        time_column: None,
        want_time: false,
        drop_backward: false,
    };
    let mut celsius = Vec::new();
    let mut axes: [Vec<f64>; 6] = Default::default();
    let read = source::stream(&args.files, &request, &mut |v| {
        for (axis, x) in axes.iter_mut().zip(v) {
            axis.push(*x);
        }
        celsius.push(v[6]);
    })?;
    let given = [
        args.gyro_unit.as_deref().map(parse_unit).transpose()?,
        args.accel_unit.as_deref().map(parse_unit).transpose()?,
    ];
    let mut names = [""; 6];
    for (i, axis) in axes.iter_mut().enumerate() {
        let unit = axis_unit(
            i,
            read.units.get(i).copied().flatten(),
            read.unknown.get(i).and_then(Option::as_deref),
            given[i / 3],
            &columns[i],
            false,
        )
        .map_err(|e| with_file(&args.files, e.0))?;
        for x in axis.iter_mut() {
            *x *= unit.to_si;
        }
        names[i] = unit.si().name;
    }
    Ok((celsius, axes, names))
}

/// `#` comment lines of `lines`.
fn comments(lines: &[String]) -> String {
    lines.iter().map(|l| format!("# {l}\n")).collect()
}

/// A parameter's value as the files print it: floats to 9 significant digits (an `f32` read
/// back to the same bits).
fn value(v: Value) -> String {
    match v {
        Value::Int(i) => i.to_string(),
        Value::Float(f) => format!("{f:.8e}"),
    }
}

/// The check's lines for the files' comments.
fn summary(thermal: &Thermal) -> Vec<String> {
    let mut lines = vec![
        format!(
            "imu-ar thermal: a cubic per axis over {:.1} to {:.1} deg C, fitted to temperature bins",
            thermal.range_c.0, thermal.range_c.1
        ),
        "(median per bin, Huber loss). Per axis: the bias change over the range, and what the"
            .into(),
        "correction below leaves of it, applied through the autopilot's formula to the bins;"
            .into(),
        "held out: the largest error on bins left out of the fit.".into(),
    ];
    for a in &thermal.axes {
        lines.push(format!(
            "{} ({}): change {:.3e}, PX4 leaves {:.3e}, ArduPilot leaves {:.3e}, held out {:.3e}{}",
            a.axis,
            a.unit,
            a.change,
            a.px4_left,
            a.ardupilot_left,
            a.held_out,
            if a.generalises {
                ""
            } else {
                " (does NOT generalise)"
            }
        ));
    }
    lines
}

/// PX4's parameters as a QGroundControl parameter file (vehicle 1; type 6 INT32, 9 REAL32).
fn px4_file(p: &[Px4; 2], slot: usize, thermal: &Thermal) -> String {
    let mut lines = vec![
        "Onboard parameters for Vehicle 1".to_string(),
        String::new(),
    ];
    lines.extend(summary(thermal));
    lines.push(
        "PX4 subtracts X0 + X1 dT + X2 dT^2 + X3 dT^3, dT = clamp(T, TMIN, TMAX) - TREF".into(),
    );
    lines.push(
        "(temperature_compensation, calc_thermal_offsets_3D); X0 of the accelerometer is 0:".into(),
    );
    lines.push(
        "redo the accelerometer calibration after loading (PX4's thermal calibration guide)."
            .into(),
    );
    lines.push(String::new());
    lines.push("Vehicle-Id\tComponent-Id\tName\tValue\tType".into());
    let mut text = comments(&lines);
    let mut row = |name: &str, v: Value| {
        let kind = match v {
            Value::Int(_) => 6,
            Value::Float(_) => 9,
        };
        text += &format!("1\t1\t{name}\t{}\t{kind}\n", value(v));
    };
    row("TC_G_ENABLE", Value::Int(1));
    row("TC_A_ENABLE", Value::Int(1));
    for sensor in p {
        for (name, v) in sensor.params(slot) {
            row(&name, v);
        }
    }
    text
}

/// ArduPilot's parameters as `NAME,VALUE` lines (Mission Planner, MAVProxy `param load`).
fn ardupilot_file(a: &ArduPilot, imu: usize, thermal: &Thermal) -> String {
    let mut lines = summary(thermal);
    lines.push(
        "ArduPilot corrects v -= P(T' - 35) - P(CALTEMP' - 35), P(t) = (c1 + (c2 + c3 t) t) t 1e-6,".into(),
    );
    lines.push("T' and CALTEMP' clamped to TMIN..TMAX (AP_InertialSensor_tempcal.cpp,".into());
    lines.push(
        "correct_sensor): the offsets keep the bias at CALTEMP, the temperature of the last".into(),
    );
    lines.push(
        "accelerometer or gyro calibration (INS_ACCn_CALTEMP, INS_GYRn_CALTEMP). Checked above"
            .into(),
    );
    lines.push(format!(
        "with CALTEMP at {:.1} deg C.",
        0.5 * (thermal.range_c.0 + thermal.range_c.1)
    ));
    let mut text = comments(&lines);
    for (name, v) in a.params(imu) {
        text += &format!("{name},{}\n", value(v));
    }
    text
}

impl Output for Thermal {
    fn text(&self) -> String {
        let mut s = format!(
            "{} samples, bins from {:.1} to {:.1} deg C\n",
            self.n, self.range_c.0, self.range_c.1
        );
        s += "axis unit   bins change     residual   held_out   held_z PX4_left   AP_left    generalises\n";
        for a in &self.axes {
            s += &format!(
                "{:<4} {:<6} {:<4} {:<10.3e} {:<10.3e} {:<10.3e} {:<6.2} {:<10} {:<10} {}\n",
                a.axis,
                a.unit,
                a.bins,
                a.change,
                a.residual,
                a.held_out,
                a.held_out_z,
                shown(a.px4_left),
                shown(a.ardupilot_left),
                a.generalises
            );
        }
        for f in &self.files {
            s += &format!("wrote {f}\n");
        }
        if !self.generalises {
            s += "a fit does not generalise: its error on bins held out exceeds 10 % of its bias \
                  change and twice their noise; the files are written, but check the record \
                  (a bump, a knock over many samples, too few bins)\n";
        }
        s
    }
}

/// A value of the table: `-` where there is none (PX4's without its file).
fn shown(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        "-".into()
    }
}
