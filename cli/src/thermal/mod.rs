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
//! - [`bands`]: each axis's noise model per temperature band, and the worst band's for the
//!   noise parameter files;
//! - [`autopilot`]: the written parameters (PX4 `TC_*`, ArduPilot `INS_TCALn_*`) and their
//!   corrections, re-implemented from the autopilots' sources.

pub mod autopilot;
pub mod axis;
pub mod bands;
pub mod bins;
pub mod cubic;
pub mod plot;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::characterise::{axis_unit, parse_unit};
use crate::error::{Fail, escaped, with_file};
use crate::export::{self, ImuModel};
use crate::input::source::{self, AXES, Kind, Request};
use crate::input::{check_rate, resolve_rate};
use crate::noise::ModelArgs;
use crate::output::Output;
use autopilot::{ArduPilot, Px4, Sensor, Value};
use axis::{AxisFit, fit_axis};
use bands::AxisBands;
use imu_ar_recordings::{dataflash, ulog};

/// The arguments of `imu-ar thermal`.
#[derive(clap::Args)]
pub struct Args {
    /// The warm-up record: CSV files read as one record (`-` is standard input), with the six
    /// axes and the die temperature (deg C) in every row; or a PX4 ULog file (sensor_gyro and
    /// sensor_accel, or their FIFO topics); or an ArduPilot DataFlash log (IMU messages).
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
    /// The files to write: px4, ardupilot, json, png (thermal.png: per axis the bins, the fit
    /// and what it leaves), comma-separated, or all.
    #[arg(long, default_value = "all")]
    format: String,
    /// PX4: the device id of the gyro and of the accelerometer (TC_Gj_ID, TC_Aj_ID), which
    /// PX4 matches the calibration to; needed for px4 from a CSV record.
    #[arg(long, value_delimiter = ',')]
    device_id: Option<Vec<u32>>,
    /// PX4: the calibration slot j of TC_Gj_* and TC_Aj_* (0 to 3) [default: the instance read,
    /// as PX4's process_sensor_caldata.py numbers them, or 0].
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=3))]
    px4_slot: Option<u8>,
    /// ArduPilot: the IMU n of INS_TCALn_* (1 to 5) [default: the instance read plus 1, or 1].
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=5))]
    imu: Option<u8>,
    /// The IMU of a PX4 ULog file (the uORB instance of sensor_gyro and sensor_accel) or of an
    /// ArduPilot DataFlash log (the `I` of its IMU messages), when it holds several.
    #[arg(long)]
    instance: Option<u8>,
    /// The sample rate of a CSV record, Hz [default: from its time column]: the noise bands
    /// need it.
    #[arg(long, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// The temperature bands in which each axis's noise model is fitted (0: none).
    #[arg(long, default_value_t = 4)]
    bands: usize,
    /// The composite's settings, per band.
    #[command(flatten)]
    model: ModelArgs,
    /// Noise parameter files to write from each axis's worst band (the largest N), as
    /// `characterise --format` names them: kalibr, openvins, vins, orbslam3, px4, ardupilot,
    /// state-space, comma-separated, or all [default: none].
    #[arg(long)]
    noise_format: Option<String>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// The most temperature bands.
pub const MAX_BANDS: usize = 16;

/// A parameter file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Px4,
    ArduPilot,
    Json,
    Png,
}

impl Format {
    fn list(text: &str) -> Result<Vec<Format>, Fail> {
        let mut out = Vec::new();
        for name in text.split(',').map(str::trim) {
            let f: &[Format] = match name {
                "px4" => &[Format::Px4],
                "ardupilot" => &[Format::ArduPilot],
                "json" => &[Format::Json],
                "png" => &[Format::Png],
                "all" => &[Format::Px4, Format::ArduPilot, Format::Json, Format::Png],
                other => {
                    return Err(Fail(format!(
                        "--format {}: px4, ardupilot, json, png, or all",
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
            Format::Png => "thermal.png",
        }
    }
}

/// The calibration and its checks.
#[derive(Serialize)]
pub struct Thermal {
    /// Samples read.
    pub n: usize,
    /// The IMU's instance in the log, where it has one.
    pub instance: Option<u8>,
    /// The temperature range of the bins of the gyro and of the accelerometer, deg C: PX4's
    /// TMIN and TMAX of each, ArduPilot's of the accelerometer's.
    pub ranges_c: [(f64, f64); 2],
    /// The CALTEMP the ArduPilot check assumes: the middle of its range, deg C.
    pub caltemp_c: f64,
    /// Per axis (gx .. az), in rad/s or m/s^2.
    pub axes: Vec<AxisResult>,
    /// Every axis's fit generalises: its held-out residual is at most
    /// [`HELD_OUT_FRACTION`] of its bias change, or the held-out bins' standardised residuals
    /// have a root mean square of at most [`HELD_OUT_Z`] (the fit explains them to their
    /// noise).
    pub generalises: bool,
    /// The accelerometer's samples read (`n` is the gyro's).
    pub n_accel: usize,
    /// Samples of the gyro and of the accelerometer left out, by cause.
    pub dropped: [Dropped; 2],
    /// Per axis, the noise model in each temperature band (none with `--bands 0`).
    pub noise_bands: Vec<AxisBands>,
    /// Why there are no noise bands, when there are none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_bands_note: Option<String>,
    /// The files written.
    pub files: Vec<String>,
}

/// The largest held-out residual, as a fraction of the bias change, that passes.
pub const HELD_OUT_FRACTION: f64 = 0.1;

/// The largest root mean square of the held-out bins' standardised residuals that passes.
pub const HELD_OUT_Z: f64 = 2.5;

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
    /// The bias change over the range: the fitted bias's largest less its smallest.
    pub change: f64,
    /// The largest `|bin - fit|` over the bins whose median is known to within four times
    /// the typical bin's (not a few samples' noise at the range's end).
    pub residual: f64,
    /// The same over bins held out of the fit.
    pub held_out: f64,
    /// The root mean square of the held-out bins' residuals over their standard errors.
    pub held_out_z: f64,
    /// The largest bias PX4's correction leaves in a bin (of those of `residual`), applied
    /// through its formula: for a
    /// gyro, whose X0 holds the bias, the corrected bin; for an accelerometer, whose constant
    /// the accelerometer calibration at TREF removes, the corrected bin less the fit at TREF.
    pub px4_left: f64,
    /// The largest bias ArduPilot's correction leaves in a bin, the offsets calibrated at
    /// CALTEMP (the middle of the range here): the corrected bin less the fit at CALTEMP.
    pub ardupilot_left: f64,
    /// The fit generalises (see [`Thermal::generalises`]).
    pub generalises: bool,
}

/// One sensor of a warm-up record: its temperatures and its three axes, in SI units.
struct Record {
    celsius: Vec<f64>,
    axes: [Vec<f64>; 3],
    /// rad/s or m/s^2.
    unit: &'static str,
    /// The sample rate, Hz, or why the record gives none.
    rate: Result<f64, String>,
    /// Samples left out, by cause.
    dropped: Dropped,
}

/// Samples of one sensor left out of the calibration, by cause.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Dropped {
    /// A NaN or infinite value.
    pub non_finite: u64,
    /// No temperature (a FIFO sample without its sensor topic's, say).
    pub without_temperature: u64,
    /// A temperature outside -60 to 150 deg C: no die temperature in deg C.
    pub implausible_temperature: u64,
}

/// The die temperatures a sample may have, deg C (MEMS IMUs work from -40 to 105).
const PLAUSIBLE_C: core::ops::RangeInclusive<f64> = -60.0..=150.0;

/// A warm-up record: the gyro and the accelerometer of one IMU.
struct WarmUp {
    sensors: [Record; 2],
    /// Their PX4 device ids, where the record holds them.
    device_ids: Option<[u32; 2]>,
    /// The IMU's instance in the log (ULog multi_id, DataFlash `I`).
    instance: Option<u8>,
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
    let config = args.model.config()?;
    if args.bands > MAX_BANDS {
        return Err(Fail(format!("--bands {}: at most {MAX_BANDS}", args.bands)));
    }
    if let Some(r) = args.rate {
        check_rate(r)?;
    }
    let noise_formats = args
        .noise_format
        .as_deref()
        .map(export::Format::list)
        .transpose()?;
    if noise_formats.is_some() && args.bands == 0 {
        return Err(Fail(
            "--noise-format writes the worst band's models: --bands must be 1 or more".into(),
        ));
    }
    let given = match &args.device_id {
        Some(ids) if ids.len() == 2 => Some([ids[0], ids[1]]),
        Some(ids) => {
            return Err(Fail(format!(
                "--device-id: {} ids given; two are needed (the gyro's, then the \
                 accelerometer's)",
                ids.len()
            )));
        }
        None => None,
    };
    let warm = read(args)?;
    let device = given.or(warm.device_ids);
    if device.is_none() && formats.contains(&Format::Px4) {
        return Err(Fail(
            "px4: PX4 matches TC_Gj_ID and TC_Aj_ID to the sensors' device ids, which this \
             record does not hold: give --device-id GYRO,ACCEL (PX4's sensor_gyro and \
             sensor_accel device_id), or leave px4 out of --format"
                .into(),
        ));
    }
    let mut fits: Vec<AxisFit> = Vec::with_capacity(6);
    for (s, record) in warm.sensors.iter().enumerate() {
        for (k, x) in record.axes.iter().enumerate() {
            let fit = fit_axis(&record.celsius, x, args.bin_width, args.min_bin)
                .map_err(|e| with_file(&args.files, format!("{}: {e}", AXES[3 * s + k])))?;
            fits.push(fit);
        }
    }
    let ranges = [fits[0].range, fits[3].range];
    // ArduPilot documents INS_TCALn_TMAX from -70 to 80 deg C; MEMS dies run to 85.
    let top = ranges[0].1.max(ranges[1].1);
    if top > 80.0 {
        eprintln!(
            "imu-ar: warning: {}",
            with_file(
                &args.files,
                format!(
                    "the temperatures reach {top:.1} deg C, past ArduPilot's INS_TCALn_TMAX range \
                     (-70 to 80 deg C): a column in deg F (a cold soak from -20 to 30 deg C reads \
                     -4 to 86)? the temperature is read in deg C"
                )
            )
            .0
        );
    }
    let polys = |from: usize| [fits[from].poly, fits[from + 1].poly, fits[from + 2].poly];
    let (gyro, accel) = (polys(0), polys(3));
    let px4 = device.map(|[g, a]| {
        [
            Px4::new(Sensor::Gyro, g, &gyro, ranges[0].0, ranges[0].1),
            Px4::new(Sensor::Accel, a, &accel, ranges[1].0, ranges[1].1),
        ]
    });
    // ArduPilot has one range per IMU: its script takes the accelerometer's.
    let ardupilot = ArduPilot::new(&accel, &gyro, ranges[1].0, ranges[1].1);
    let caltemp = 0.5 * (ranges[1].0 + ranges[1].1);
    let mut results = Vec::with_capacity(6);
    for (i, fit) in fits.iter().enumerate() {
        let sensor = if i < 3 { Sensor::Gyro } else { Sensor::Accel };
        // Over the bins that tell what the fit leaves (not a few samples' noise).
        let corrected = |correct: &dyn Fn(f32) -> f32| -> Vec<f64> {
            fit.bins
                .iter()
                .zip(&fit.telling)
                .filter(|(_, t)| **t)
                .map(|(b, _)| b.value - f64::from(correct(b.celsius as f32)))
                .collect()
        };
        let largest =
            |v: Vec<f64>, offset: f64| v.iter().fold(0.0f64, |m, x| m.max((x - offset).abs()));
        // PX4's TREF: the middle of the sensor's range.
        let tref = 0.5 * (ranges[i / 3].0 + ranges[i / 3].1);
        let px4_left = px4.map_or(f64::NAN, |p| {
            let left = corrected(&|t| p[i / 3].offset(i % 3, t));
            match sensor {
                Sensor::Gyro => largest(left, 0.0),
                Sensor::Accel => largest(left, fit.poly.at(tref)),
            }
        });
        let ardupilot_left = largest(
            corrected(&|t| ardupilot.correction(sensor, i % 3, t, caltemp as f32)),
            fit.poly.at(caltemp),
        );
        let generalises =
            fit.held_out <= HELD_OUT_FRACTION * fit.change || fit.held_out_z <= HELD_OUT_Z;
        results.push(AxisResult {
            axis: AXES[i],
            unit: warm.sensors[i / 3].unit,
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
    let (noise_bands, worst, noise_bands_note) = noise_bands(args, &warm, &fits, ranges, &config)?;
    let mut thermal = Thermal {
        n: warm.sensors[0].celsius.len(),
        instance: warm.instance,
        ranges_c: ranges,
        caltemp_c: caltemp,
        generalises: results.iter().all(|a| a.generalises),
        axes: results,
        n_accel: warm.sensors[1].celsius.len(),
        dropped: [warm.sensors[0].dropped, warm.sensors[1].dropped],
        noise_bands,
        noise_bands_note,
        files: Vec::new(),
    };
    let px4_slot = match (args.px4_slot, warm.instance) {
        (Some(j), _) => j,
        (None, Some(i)) if i <= 3 => i,
        (None, None) => 0,
        (None, Some(i)) if formats.contains(&Format::Px4) => {
            return Err(Fail(format!(
                "px4: instance {i}: TC_Gj_* and TC_Aj_* have the slots 0 to 3; give --px4-slot"
            )));
        }
        (None, Some(_)) => 0,
    };
    let imu = match (args.imu, warm.instance) {
        (Some(n), _) => n,
        (None, Some(i)) if i <= 4 => i + 1,
        (None, None) => 1,
        (None, Some(i)) if formats.contains(&Format::ArduPilot) => {
            return Err(Fail(format!(
                "ardupilot: instance {i}: INS_TCALn numbers the IMUs 1 to 5; give --imu"
            )));
        }
        (None, Some(_)) => 1,
    };
    // A coefficient beyond f32 would be written as inf (a bias of 1e300, say).
    let written: Vec<f32> = px4
        .iter()
        .flatten()
        .flat_map(|p| p.x.iter().flatten().copied())
        .chain(
            ardupilot
                .accel
                .iter()
                .chain(&ardupilot.gyro)
                .flatten()
                .copied(),
        )
        .collect();
    if written.iter().any(|v| !v.is_finite()) {
        return Err(with_file(
            &args.files,
            "a fitted coefficient is beyond what a 32-bit float parameter holds: not a sensor's \
             bias (check the columns' units)",
        ));
    }
    let noise = match noise_formats {
        None => None,
        Some(noise_formats) => Some((noise_formats, noise_model(args, &thermal, worst)?)),
    };
    // The files of the set, all written or none (the noise files of the formats not asked
    // for, an earlier run's, set aside with them).
    let in_out = |name: &str| args.out.join(name).display().to_string();
    let noise_files = noise
        .iter()
        .flat_map(|(f, _)| f.iter().map(|f| f.file_name()));
    let own = formats
        .iter()
        .filter(|f| **f != Format::Px4 || px4.is_some())
        .map(|f| f.file_name());
    thermal.files = noise_files.chain(own).map(in_out).collect();
    let stale = noise
        .as_ref()
        .map_or(Vec::new(), |(f, _)| crate::characterise::stale(f));
    let units = [warm.sensors[0].unit, warm.sensors[1].unit];
    crate::characterise::write_staged(&args.out, &stale, &|folder| {
        let mut paths = Vec::new();
        if let Some((noise_formats, imu)) = &noise {
            for f in noise_formats {
                paths.push(export::write(*f, imu, None, folder)?);
            }
        }
        for format in &formats {
            let path = folder.join(format.file_name());
            let text = match format {
                Format::Px4 => match &px4 {
                    Some(p) => px4_file(p, px4_slot.into(), &thermal),
                    None => continue,
                },
                Format::ArduPilot => ardupilot_file(&ardupilot, imu.into(), &thermal),
                Format::Json => format!("{}\n", serde_json::to_value(&thermal)?),
                Format::Png => {
                    plot::png(&path, &fits, units)?;
                    paths.push(path);
                    continue;
                }
            };
            std::fs::write(&path, text).map_err(|e| Fail(format!("{}: {e}", path.display())))?;
            paths.push(path);
        }
        Ok(paths)
    })?;
    Ok(thermal)
}

/// The six axes' noise models from their worst temperature bands (`worst`, and the rate), for
/// `--noise-format`; an error saying why there are none.
fn noise_model(
    args: &Args,
    thermal: &Thermal,
    worst: Option<([export::AxisModel; 6], f64)>,
) -> Result<ImuModel, Fail> {
    let Some((axes, rate)) = worst else {
        let why = thermal.noise_bands_note.clone().unwrap_or_else(|| {
            let missing: Vec<String> = thermal
                .noise_bands
                .iter()
                .filter(|a| a.worst.is_none())
                .map(|a| {
                    let reason = a
                        .bands
                        .iter()
                        .find_map(|b| b.note.clone())
                        .unwrap_or_default();
                    format!("{} ({reason})", a.axis)
                })
                .collect();
            format!("no band of {} has a noise model", missing.join(", "))
        });
        return Err(with_file(&args.files, format!("--noise-format: {why}")));
    };
    let origin: Vec<String> = thermal
        .noise_bands
        .iter()
        .filter_map(|a| {
            let b = &a.bands[a.worst?];
            Some(format!("{} {:.1} to {:.1} deg C", a.axis, b.from_c, b.to_c))
        })
        .collect();
    Ok(ImuModel {
        axes,
        rate_hz: rate,
        topic: None,
        filter_rate_hz: args.model.filter_rate,
        loop_rate_hz: None,
        sysid: None,
        imu_integ_rate_hz: None,
        origin: Some(format!(
            "Each axis from its worst temperature band (the largest N), the thermal bias \
             taken out (imu-ar thermal): {}.",
            origin.join(", ")
        )),
    })
}

/// Each axis's noise model per temperature band ([`bands`]); with the worst band's models of
/// the six axes for the files and the gyro's rate, when every axis has one; or why there are
/// none.
#[allow(clippy::type_complexity)]
fn noise_bands(
    args: &Args,
    warm: &WarmUp,
    fits: &[AxisFit],
    ranges: [(f64, f64); 2],
    config: &imu_ar::noise::FitConfig,
) -> Result<
    (
        Vec<AxisBands>,
        Option<([export::AxisModel; 6], f64)>,
        Option<String>,
    ),
    Fail,
> {
    if args.bands == 0 {
        return Ok((Vec::new(), None, Some("--bands 0".into())));
    }
    let (gyro_rate, accel_rate) = match (&warm.sensors[0].rate, &warm.sensors[1].rate) {
        (Ok(g), Ok(a)) => (*g, *a),
        (Err(e), _) | (_, Err(e)) => return Ok((Vec::new(), None, Some(e.clone()))),
    };
    if args.noise_format.is_some() && (accel_rate / gyro_rate - 1.0).abs() > 0.01 {
        return Err(with_file(
            &args.files,
            format!(
                "--noise-format: the gyro is sampled at {gyro_rate:.6} Hz and the accelerometer \
                 at {accel_rate:.6} Hz; the noise parameter files take one IMU rate (leave \
                 --noise-format out: the bands are reported for each)"
            ),
        ));
    }
    let mut all = Vec::with_capacity(6);
    let mut models = Vec::with_capacity(6);
    for (s, rate) in [gyro_rate, accel_rate].into_iter().enumerate() {
        let r = &warm.sensors[s];
        let sensor = bands::Sensor {
            celsius: &r.celsius,
            axes: [&r.axes[0], &r.axes[1], &r.axes[2]],
            fits: [&fits[3 * s], &fits[3 * s + 1], &fits[3 * s + 2]],
            range: ranges[s],
            rate,
            unit: r.unit,
        };
        let names = [AXES[3 * s], AXES[3 * s + 1], AXES[3 * s + 2]];
        for (axis, model) in bands::fit(&sensor, names, args.bands, config, args.model.filter_rate)?
        {
            all.push(axis);
            models.push(model);
        }
    }
    let worst: Option<Vec<export::AxisModel>> = models.into_iter().collect();
    let worst = worst
        .and_then(|m| <[export::AxisModel; 6]>::try_from(m).ok())
        .map(|m| (m, gyro_rate));
    Ok((all, worst, None))
}

/// Says so on standard error when the log at `path` ends inside a message (`truncated`, its
/// offset).
fn warn_cut_short(path: &Path, truncated: Option<u64>) {
    if truncated.is_some() {
        let skipped = imu_ar_recordings::frame::Skipped {
            cut_short: 1,
            ..Default::default()
        };
        if let Some(w) = skipped.cut_short_warning() {
            eprintln!("imu-ar: warning: {}: {w}", path.display());
        }
    }
}

/// The sample rate of a log's sample times `us` (µs): one over their median interval; an
/// error when more than 1 % of the intervals are not positive (times that stand still or go
/// back: a FIFO message with dt 0, say), which no rate describes.
fn rate_of(us: &[f64]) -> Result<f64, String> {
    let mut d: Vec<f64> = us.windows(2).map(|w| w[1] - w[0]).collect();
    let bad = d.iter().filter(|d| d.is_nan() || **d <= 0.0).count();
    if d.is_empty() || bad * 100 > d.len() {
        return Err(format!(
            "the log's sample times do not move forward ({bad} of {} intervals zero, negative or \
             not a number): no sample rate for the noise bands",
            d.len()
        ));
    }
    d.retain(|d| *d > 0.0);
    let mid = d.len() / 2;
    let (_, median, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    Ok(1e6 / *median)
}

/// A log's sensor rate `rate` for the noise bands, or why its samples give none (the
/// logger's subsample: [`crate::input::subsampled`]); the calibration reads them all the same.
fn logged(kind: Kind, rate: f64) -> Result<f64, String> {
    crate::input::subsampled(kind, rate).map_or(Ok(rate), Err)
}

/// Keeps a sample of `record` at `celsius` with the values `xyz` (and its time `us` in
/// `times`), or counts why not.
fn keep(record: &mut Record, times: &mut Vec<f64>, us: f64, celsius: Option<f64>, xyz: [f64; 3]) {
    let Some(t) = celsius else {
        record.dropped.without_temperature += 1;
        return;
    };
    if !t.is_finite() || xyz.iter().any(|v| !v.is_finite()) {
        record.dropped.non_finite += 1;
        return;
    }
    if !PLAUSIBLE_C.contains(&t) {
        record.dropped.implausible_temperature += 1;
        return;
    }
    record.celsius.push(t);
    for (axis, x) in record.axes.iter_mut().zip(xyz) {
        axis.push(x);
    }
    times.push(us);
}

/// The highest median temperature of a warm-up read as deg C.
const HOTTEST_MEDIAN: f64 = 85.0;

/// The median of `v` (none when empty).
fn median_of(v: &[f64]) -> Option<f64> {
    let mut v = v.to_vec();
    let mid = v.len().checked_sub(1)? / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// An error when most of a sensor's temperatures are no die temperatures in deg C (a record in
/// kelvin or Fahrenheit), or when more than 1 % of its samples were given a temperature held
/// from the nearest one logged (`held`).
fn check_dropped(files: &[PathBuf], record: &Record, what: &str, held: u64) -> Result<(), Fail> {
    let d = record.dropped;
    let kept = record.celsius.len() as u64;
    if d.implausible_temperature > kept {
        return Err(with_file(
            files,
            format!(
                "{what}: {} of {} temperatures are outside -60 to 150 deg C: no die temperatures \
                 in deg C (kelvin or Fahrenheit?)",
                d.implausible_temperature,
                kept + d.implausible_temperature
            ),
        ));
    }
    // Dies run up to 85 deg C (105 or 125 for automotive parts) and a warm-up spends most of
    // its time below that: a median above it is a column in deg F (20 to 60 deg C read as
    // 68 to 140), whose calibration would clamp the vehicle's whole range to its TMIN.
    if let Some(median) = median_of(&record.celsius)
        && median > HOTTEST_MEDIAN
    {
        return Err(with_file(
            files,
            format!(
                "{what}: the temperatures' median is {median:.1} deg C, above the {HOTTEST_MEDIAN} \
                 deg C MEMS dies run at: a column in deg F (68 to 140 for 20 to 60 deg C)? give \
                 the temperature in deg C"
            ),
        ));
    }
    if held.saturating_mul(100) > kept {
        return Err(with_file(
            files,
            format!(
                "{what}: {held} of {kept} samples lie outside the times of the temperatures \
                 logged for them (more than 1 %), and would take a temperature held from the \
                 nearest: the temperature topic stopped early, or started late"
            ),
        ));
    }
    Ok(())
}

/// The warm-up record of `args.files`: a CSV record, a PX4 ULog file or an ArduPilot
/// DataFlash log.
fn read(args: &Args) -> Result<WarmUp, Fail> {
    let kind = Kind::of(&args.files[0]);
    if matches!(kind, Kind::Ulog | Kind::DataFlash) {
        if args.files.len() > 1 {
            return Err(with_file(
                &args.files,
                "one autopilot log at a time (a CSV record may span several files)",
            ));
        }
        if args.columns.is_some()
            || args.gyro_unit.is_some()
            || args.accel_unit.is_some()
            || args.rate.is_some()
        {
            return Err(with_file(
                &args.files,
                "--columns, --gyro-unit, --accel-unit and --rate are for CSV records: an \
                 autopilot log names its fields and units, and times its samples",
            ));
        }
        let path = &args.files[0];
        return if kind == Kind::Ulog {
            read_ulog(path, args.instance)
        } else {
            read_dataflash(path, args.instance)
        };
    }
    if args.instance.is_some() {
        return Err(with_file(
            &args.files,
            "--instance picks an IMU of a PX4 ULog file or an ArduPilot DataFlash log",
        ));
    }
    read_csv(args)
}

/// The samples of one sensor of a ULog file with their temperatures: of the sensor topic and
/// its FIFO topic, the one with more samples (the FIFO topic's temperatures interpolated from
/// the sensor topic's).
fn read_ulog(path: &Path, instance: Option<u8>) -> Result<WarmUp, Fail> {
    let fail = |e: String| with_file(std::slice::from_ref(&path.to_path_buf()), e);
    let survey = ulog::survey(path).map_err(|e| Fail(e.to_string()))?;
    warn_cut_short(path, survey.truncated);
    let mut sensors: Vec<Record> = Vec::with_capacity(2);
    let mut ids = [0u32; 2];
    let mut chosen = 0u8;
    for (s, (topic, fifo, unit)) in [
        (ulog::Topic::Gyro, ulog::Topic::GyroFifo, "rad/s"),
        (ulog::Topic::Accel, ulog::Topic::AccelFifo, "m/s^2"),
    ]
    .into_iter()
    .enumerate()
    {
        let mut instances: Vec<&ulog::TopicSurvey> = survey.instances(topic);
        for t in survey.instances(fifo) {
            if instances.iter().all(|s| s.instance != t.instance) {
                instances.push(t);
            }
        }
        instances.sort_by_key(|t| t.instance);
        if instances.is_empty() {
            return Err(fail(format!(
                "no {} or {} messages: a thermal calibration needs sensor_gyro and \
                 sensor_accel (PX4's SDLOG_PROFILE thermal calibration bit logs them)",
                topic.name(),
                fifo.name()
            )));
        }
        let which = match instance {
            Some(i) => i,
            None if instances.len() == 1 => instances[0].instance,
            None => {
                let list: Vec<String> = instances
                    .iter()
                    .map(|t| {
                        let ids: Vec<String> = t.device_ids.iter().map(|d| d.to_string()).collect();
                        format!("{} (device_id {})", t.instance, ids.join(", "))
                    })
                    .collect();
                return Err(fail(format!(
                    "{} instances of {}: {}; choose one with --instance",
                    instances.len(),
                    topic.name(),
                    list.join(", ")
                )));
            }
        };
        // Of the sensor topic and its FIFO topic, the one with more samples of this IMU.
        let topic = source::fuller(&survey, topic, fifo, Some(which));
        let mut record = Record {
            celsius: Vec::new(),
            axes: Default::default(),
            unit,
            rate: Err(String::new()),
            dropped: Dropped::default(),
        };
        let mut times = Vec::new();
        chosen = which;
        let select = ulog::Select {
            topic,
            which: ulog::Which::Instance(which),
        };
        let mut devices: Vec<u32> = Vec::new();
        let report = ulog::read_surveyed(path, &survey, &select, &mut |sample| {
            if !devices.contains(&sample.device_id) {
                devices.push(sample.device_id);
            }
            ids[s] = sample.device_id;
            keep(
                &mut record,
                &mut times,
                sample.time_us,
                sample.temperature,
                sample.xyz,
            );
        })
        .map_err(|e| Fail(e.to_string()))?;
        // The reader leaves out the samples that are not finite; they are counted here.
        record.dropped.non_finite += report.non_finite;
        record.rate = rate_of(&times).and_then(|r| logged(Kind::Ulog, r));
        let files = [path.to_path_buf()];
        check_dropped(&files, &record, topic.name(), report.held_temperature)?;
        if devices.len() > 1 {
            let list: Vec<String> = devices.iter().map(u32::to_string).collect();
            return Err(fail(format!(
                "{} instance {which} holds the samples of {} devices ({}): one calibration is \
                 one sensor's",
                topic.name(),
                devices.len(),
                list.join(", ")
            )));
        }
        if record.celsius.is_empty() {
            return Err(fail(format!(
                "{} has no temperature ({} samples without one{}): a thermal calibration needs \
                 the sensor's temperature",
                topic.name(),
                record.dropped.without_temperature,
                if topic.is_fifo() {
                    ", and no sensor topic of that device to take it from"
                } else {
                    ""
                }
            )));
        }
        sensors.push(record);
    }
    let [gyro, accel]: [Record; 2] = sensors
        .try_into()
        .map_err(|_| Fail("two sensors expected".into()))?;
    Ok(WarmUp {
        sensors: [gyro, accel],
        device_ids: Some(ids),
        instance: Some(chosen),
    })
}

/// The `IMU` messages of one instance of a DataFlash log: refused when ArduPilot had already
/// corrected them for temperature, or rotated them by AHRS_ORIENTATION (the calibration lives
/// in the sensor's frame before it).
fn read_dataflash(path: &Path, instance: Option<u8>) -> Result<WarmUp, Fail> {
    let fail = |e: String| with_file(std::slice::from_ref(&path.to_path_buf()), e);
    let survey = dataflash::survey(path).map_err(|e| Fail(e.to_string()))?;
    warn_cut_short(path, survey.truncated);
    let kind = dataflash::Kind::Imu;
    let instances = survey.instances(kind);
    if instances.is_empty() && !survey.unreadable.is_empty() {
        return Err(fail(format!(
            "its IMU messages cannot be read: {}",
            survey.unreadable.join("; ")
        )));
    }
    let chosen = match instance {
        Some(i) => i,
        None if instances.len() == 1 => instances[0].instance,
        None if instances.is_empty() => {
            return Err(fail(
                "no IMU messages (LOG_BITMASK's IMU bit logs them; a thermal calibration needs \
                 them with their temperature)"
                    .into(),
            ));
        }
        None => {
            let list: Vec<String> = instances.iter().map(|s| s.instance.to_string()).collect();
            return Err(fail(format!(
                "IMU messages of {} instances ({}): choose one with --instance",
                instances.len(),
                list.join(", ")
            )));
        }
    };
    let correction = survey.temperature_corrected(kind, chosen);
    if matches!(
        correction.corrected,
        dataflash::Corrected::Yes | dataflash::Corrected::Mixed
    ) {
        return Err(fail(format!(
            "the IMU samples of instance {chosen} were already temperature-corrected by \
             ArduPilot ({}): a thermal calibration is fitted on uncorrected data; log a warm-up \
             with {} 0",
            correction.reason,
            autopilot::ardupilot_prefix(usize::from(chosen) + 1) + "ENABLE"
        )));
    }
    if let Some(p) = survey.parameter("AHRS_ORIENTATION")
        && (p.value != 0.0 || p.changed())
    {
        return Err(fail(format!(
            "the IMU samples are rotated by AHRS_ORIENTATION {}: ArduPilot's thermal \
             calibration lives in the sensor's frame before that rotation; log a warm-up with \
             AHRS_ORIENTATION 0",
            p.value
        )));
    }
    let mut gyro = Record {
        celsius: Vec::new(),
        axes: Default::default(),
        unit: "rad/s",
        rate: Err(String::new()),
        dropped: Dropped::default(),
    };
    let mut accel = Record {
        celsius: Vec::new(),
        axes: Default::default(),
        unit: "m/s^2",
        rate: Err(String::new()),
        dropped: Dropped::default(),
    };
    let (mut times, mut accel_times) = (Vec::new(), Vec::new());
    let select = dataflash::Select {
        kind,
        instance: Some(chosen),
    };
    let report = dataflash::read_surveyed(path, &survey, &select, &mut |sample| {
        let t = sample.temperature;
        if let Some(xyz) = sample.gyro {
            keep(&mut gyro, &mut times, sample.time_us, t, xyz);
        }
        if let Some(xyz) = sample.accel {
            keep(&mut accel, &mut accel_times, sample.time_us, t, xyz);
        }
    })
    .map_err(|e| Fail(e.to_string()))?;
    // The reader leaves out the messages that are not finite; they are counted here.
    gyro.dropped.non_finite += report.non_finite;
    accel.dropped.non_finite += report.non_finite;
    if gyro.celsius.is_empty() || accel.celsius.is_empty() {
        return Err(fail(format!(
            "the IMU messages of instance {chosen} carry no usable temperature ({} without one, \
             {} outside -60 to 150 deg C): a thermal calibration needs it",
            gyro.dropped.without_temperature, gyro.dropped.implausible_temperature
        )));
    }
    let files = [path.to_path_buf()];
    check_dropped(&files, &gyro, "IMU gyro", report.held_temperature)?;
    check_dropped(&files, &accel, "IMU accelerometer", report.held_temperature)?;
    gyro.rate = rate_of(&times).and_then(|r| logged(Kind::DataFlash, r));
    accel.rate = rate_of(&accel_times).and_then(|r| logged(Kind::DataFlash, r));
    Ok(WarmUp {
        sensors: [gyro, accel],
        device_ids: None,
        instance: Some(chosen),
    })
}

/// The temperatures and the six axes in SI units of a CSV record.
fn read_csv(args: &Args) -> Result<WarmUp, Fail> {
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
        // Stamps are read where their unit is clear: the calibration needs none, the noise
        // bands a rate (from them or --rate).
        want_time: false,
        drop_backward: false,
        instance: None,
    };
    let mut celsius = Vec::new();
    let mut axes: [Vec<f64>; 6] = Default::default();
    let read = source::stream(&args.files, &request, &mut |v| {
        for (axis, x) in axes.iter_mut().zip(v) {
            axis.push(*x);
        }
        celsius.push(v[6]);
    })?;
    // The temperature column's unit bracket, where it has one, must say deg C.
    let bracket = match (read.units.get(6).copied().flatten(), read.unknown.get(6)) {
        (Some(u), _) => Some(u.name.to_string()),
        (None, Some(Some(b))) => Some(b.clone()),
        _ => None,
    };
    if let Some(b) = bracket {
        let plain: String = b.chars().filter(|c| !c.is_whitespace()).collect();
        if !["C", "degC", "°C", "deg_C", "celsius", "Celsius", "degreesC"].contains(&plain.as_str())
        {
            return Err(with_file(
                &args.files,
                format!(
                    "column '{}' is in [{}]: the temperature is read in deg C ([C], [degC] or \
                     no bracket)",
                    escaped(&args.temperature_column),
                    escaped(&b)
                ),
            ));
        }
    }
    let given = [
        args.gyro_unit.as_deref().map(parse_unit).transpose()?,
        args.accel_unit.as_deref().map(parse_unit).transpose()?,
    ];
    // The rate from --rate or the time column; without either, the noise bands say why not.
    let stamped = read.timing.as_ref().and_then(|(t, _)| t.kept_over_span());
    let (timing, unchecked) =
        crate::input::summary(read.timing, false).map_err(|e| with_file(&args.files, e))?;
    if let Some(w) = crate::input::unchecked(args.rate, unchecked.as_deref()) {
        eprintln!("imu-ar: warning: {}", with_file(&args.files, w).0);
    }
    // As noise reads a record: what its stamps show that would refuse them without --rate,
    // and gaps that miss more than a tenth of the samples, leave the bands out.
    let rate = match (args.rate, &timing, unchecked) {
        (None, _, Some(why)) => Err(format!("{why}: no sample rate for the noise bands")),
        (None, None, None) => Err(
            "the record gives no sample rate (no time column whose unit is clear): give --rate \
             for the noise bands"
                .to_string(),
        ),
        (r, t, _) => {
            let rate = resolve_rate(r, t.as_ref()).map_err(|e| with_file(&args.files, e.0))?;
            crate::input::check_packed(r, stamped).map_err(|e| with_file(&args.files, e))?;
            crate::input::check_gaps(t.as_ref(), celsius.len()).map(|()| rate)
        }
    };
    let mut names = [""; 6];
    for (i, axis) in axes.iter_mut().enumerate() {
        let unit = axis_unit(
            i,
            read.units.get(i).copied().flatten(),
            read.unknown.get(i).and_then(Option::as_deref),
            given[i / 3],
            &columns[i],
            Kind::of(&args.files[0]),
        )
        .map_err(|e| with_file(&args.files, e.0))?;
        for x in axis.iter_mut() {
            *x *= unit.to_si;
        }
        names[i] = unit.si().name;
    }
    let record = |unit| Record {
        celsius: Vec::new(),
        axes: Default::default(),
        unit,
        rate: rate.clone(),
        dropped: Dropped::default(),
    };
    let (mut gyro, mut accel) = (record(names[0]), record(names[3]));
    let mut times = Vec::new();
    for (k, &t) in celsius.iter().enumerate() {
        let xyz = |from: usize| [axes[from][k], axes[from + 1][k], axes[from + 2][k]];
        keep(&mut gyro, &mut times, 0.0, Some(t), xyz(0));
        keep(&mut accel, &mut times, 0.0, Some(t), xyz(3));
    }
    check_dropped(&args.files, &gyro, "the gyro", 0)?;
    check_dropped(&args.files, &accel, "the accelerometer", 0)?;
    Ok(WarmUp {
        sensors: [gyro, accel],
        device_ids: None,
        instance: None,
    })
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
            "imu-ar thermal: a cubic per axis over {} (gyro), {} (accelerometer),",
            span(thermal.ranges_c[0]),
            span(thermal.ranges_c[1])
        ),
        "fitted to temperature bins".into(),
        "(median per bin, Huber loss). Per axis: the bias change over the range, and what the"
            .into(),
        "correction below leaves of it, applied through the autopilot's formula to the bins;"
            .into(),
        "held out: the largest error on bins left out of the fit.".into(),
    ];
    for a in &thermal.axes {
        lines.push(format!(
            "{} ({}): change {:.3e}, PX4 leaves {}, ArduPilot leaves {}, held out {:.3e}{}",
            a.axis,
            a.unit,
            a.change,
            shown(a.px4_left),
            shown(a.ardupilot_left),
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
        "redo the gyro and the accelerometer calibrations after loading, or the old CAL_*_OFF"
            .into(),
    );
    lines.push(
        "offsets are subtracted on top (process_sensor_caldata.py; PX4's thermal guide).".into(),
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
    lines.push(format!("with CALTEMP at {:.1} deg C.", thermal.caltemp_c));
    let mut text = comments(&lines);
    for (name, v) in a.params(imu) {
        text += &format!("{name},{}\n", value(v));
    }
    text
}

impl Output for Thermal {
    fn text(&self) -> String {
        let mut s = format!(
            "{} samples{}; bins over {} (gyro), {} (accelerometer)\n",
            self.n,
            self.instance
                .map_or(String::new(), |i| format!(" of instance {i}")),
            span(self.ranges_c[0]),
            span(self.ranges_c[1])
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
        for (what, d) in ["gyro", "accelerometer"].iter().zip(&self.dropped) {
            let total = d.non_finite + d.without_temperature + d.implausible_temperature;
            if total > 0 {
                s += &format!(
                    "{what}: {total} samples left out ({} not finite, {} without a temperature, \
                     {} outside -60 to 150 deg C)\n",
                    d.non_finite, d.without_temperature, d.implausible_temperature
                );
            }
        }
        if !self.noise_bands.is_empty() {
            s += "noise against temperature, the thermal bias taken out (* the worst band, largest N):\n";
            s += "axis band (deg C)      samples  N (u/sqrt(Hz))  K (u/s/sqrt(Hz))  B (u)\n";
        }
        for a in &self.noise_bands {
            for (i, b) in a.bands.iter().enumerate() {
                let value = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{v:.3e}"));
                s += &format!(
                    "{:<4} {:>5.1} to {:<5.1}{} {:<8} {:<15} {:<17} {}{}\n",
                    a.axis,
                    b.from_c,
                    b.to_c,
                    if a.worst == Some(i) { "*" } else { " " },
                    b.n,
                    value(b.white_noise),
                    value(b.random_walk),
                    value(b.bias_instability),
                    match (&b.note, b.stretches) {
                        (Some(n), _) => format!(" ({n})"),
                        (None, k) if k > 1 => format!(
                            " (the longest of the {k} stretches the record spent in the band)"
                        ),
                        _ => String::new(),
                    }
                );
            }
        }
        if let Some(note) = &self.noise_bands_note
            && self.noise_bands.is_empty()
            && note != "--bands 0"
        {
            s += &format!("no noise bands: {note}\n");
        }
        for f in &self.files {
            s += &format!("wrote {f}\n");
        }
        if !self.generalises {
            s += "a fit does not generalise: its error on bins held out exceeds 10 % of its bias \
                  change and 2.5 times its expected error; the files are written, but check the record \
                  (a bump, a knock over many samples, too few bins)\n";
        }
        s
    }
}

/// A temperature range as the table and the files' comments give it.
fn span((low, high): (f64, f64)) -> String {
    format!("{low:.1} to {high:.1} deg C")
}

/// A value of the table: `-` where there is none (PX4's without its file).
fn shown(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        "-".into()
    }
}
