//! `imu-ar thermal`, and the autopilots' logs as every command reads them: simulated warm-up records with
//! parameters parsed from the files and applied through each autopilot's correction, written
//! again here from the autopilots' sources (PX4 `TemperatureCompensation::calc_thermal_offsets_3D`,
//! ArduPilot `AP_InertialSensor::TCal::correct_sensor`), against the simulated truth.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::common::{assert_one_line_failure, imu_ar, json, stdout, temp_file, temp_path};

#[path = "../../../recordings/tests/writers/mod.rs"]
mod writers;

use writers::{ACCEL_FIFO, Df, GYRO_FIFO, SENSOR_ACCEL, SENSOR_GYRO, ULog, fifo, sensor};

/// The true biases, about 30 deg C: gyros in rad/s, accelerometers in m/s^2.
const TRUTH: [[f64; 4]; 6] = [
    [0.004, 2e-4, -8e-6, 1e-7],
    [-0.01, -1e-4, 3e-6, 0.0],
    [0.002, 5e-5, 0.0, -2e-8],
    [0.1, 2e-3, -1e-5, 1e-7],
    [-0.2, -1e-3, 2e-5, 0.0],
    [9.81, 3e-3, 0.0, -1e-7],
];

fn bias(axis: usize, celsius: f64) -> f64 {
    let d = celsius - 30.0;
    let c = TRUTH[axis];
    c[0] + d * (c[1] + d * (c[2] + d * c[3]))
}

/// A warm-up of `n` samples from 20 to 60 deg C, fast at first and slow at the end, white
/// noise on every axis (SI units): `(temperature, axes)`. `bump` adds a bump of that many
/// rad/s at 45 deg C to gx.
fn samples(n: usize, bump: f64) -> Vec<(f64, [f64; 6])> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut normal = move || {
        let (u, v) = (uniform().max(1e-300), uniform());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    (0..n)
        .map(|i| {
            let s = i as f64 / n as f64;
            let celsius = 20.0 + 40.0 * (1.0 - (-4.0 * s).exp()) / (1.0 - (-4.0f64).exp());
            let axes = std::array::from_fn(|axis| {
                let mut v = bias(axis, celsius);
                if axis == 0 {
                    v += bump * (-((celsius - 45.0) / 2.5).powi(2)).exp();
                }
                v + if axis < 3 { 2e-3 } else { 2e-2 } * normal()
            });
            (celsius, axes)
        })
        .collect()
}

/// [`samples`] as a CSV record, the temperature in whole degrees, gyros in deg/s and
/// accelerometers in g (the tool converts).
fn warm_up(name: &str, bump: f64) -> PathBuf {
    let mut text =
        String::from("t,gx [deg/s],gy [deg/s],gz [deg/s],ax [g],ay [g],az [g],temperature\n");
    for (i, (celsius, axes)) in samples(120_000, bump).into_iter().enumerate() {
        text += &format!("{:.3}", i as f64 * 0.01);
        for (axis, v) in axes.iter().enumerate() {
            let to_unit = if axis < 3 {
                180.0 / std::f64::consts::PI
            } else {
                1.0 / 9.80665
            };
            text += &format!(",{:.9e}", v * to_unit);
        }
        text += &format!(",{:.0}\n", celsius.round());
    }
    temp_file(name, text)
}

/// The `NAME -> value` of a parameter file: QGroundControl's tab-separated rows or
/// ArduPilot's `NAME,VALUE` lines; comments left out.
fn params(path: &Path) -> HashMap<String, f32> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .filter_map(|l| {
            let cells: Vec<&str> = if l.contains('\t') {
                l.split('\t').skip(2).take(2).collect()
            } else {
                l.split(',').collect()
            };
            Some((cells[0].to_string(), cells.get(1)?.parse().ok()?))
        })
        .collect()
}

/// PX4's offset (src/modules/temperature_compensation/TemperatureCompensation.cpp,
/// `calc_thermal_offsets_3D`, in float): `p` the parameters, `s` "G" or "A".
fn px4_offset(p: &HashMap<String, f32>, s: &str, slot: usize, axis: usize, celsius: f32) -> f32 {
    let get = |name: &str| p[&format!("TC_{s}{slot}_{name}")];
    let (tref, tmin, tmax) = (get("TREF"), get("TMIN"), get("TMAX"));
    let delta = if celsius > tmax {
        tmax - tref
    } else if celsius < tmin {
        tmin - tref
    } else {
        celsius - tref
    };
    let (d2, d3) = (delta * delta, delta * delta * delta);
    let x = |k: usize| get(&format!("X{k}_{axis}"));
    x(0) + x(1) * delta + x(2) * d2 + x(3) * d3
}

/// ArduPilot's correction (libraries/AP_InertialSensor/AP_InertialSensor_tempcal.cpp,
/// `correct_sensor`, in float): what is subtracted at `celsius`, the offsets taken at
/// `caltemp`; `s` "ACC" or "GYR".
fn ardupilot_correction(
    p: &HashMap<String, f32>,
    s: &str,
    imu: usize,
    axis: usize,
    celsius: f32,
    caltemp: f32,
) -> f32 {
    let xyz = ["X", "Y", "Z"][axis];
    let c = |k: usize| p[&format!("INS_TCAL{imu}_{s}{k}_{xyz}")];
    let eval = |t: f32| (c(1) + (c(2) + c(3) * t) * t) * t * 1e-6;
    let (tmin, tmax) = (
        p[&format!("INS_TCAL{imu}_TMIN")],
        p[&format!("INS_TCAL{imu}_TMAX")],
    );
    let t = celsius.clamp(tmin, tmax);
    let tc = caltemp.clamp(tmin, tmax);
    eval(t - 35.0) - eval(tc - 35.0)
}

/// The written parameters, applied through each autopilot's formula, cancel the simulated
/// bias across the range: gyros to 1e-4 rad/s, accelerometers to 1e-3 m/s^2 (an
/// accelerometer's constant, and ArduPilot's, left to the offsets the autopilot calibrates at
/// its reference); the table and the JSON say every fit generalises.
#[test]
fn the_written_parameters_cancel_a_simulated_bias() {
    let record = warm_up("warm.csv", 0.0);
    let out = temp_path("thermal-out");
    let run = imu_ar(&[
        "thermal",
        record.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--device-id",
        "2359330,2359331",
        "--json",
    ]);
    let j = json(&run);
    assert_eq!(j["generalises"], true, "{j}");
    assert_eq!(
        j["ranges_c"],
        serde_json::json!([[20.0, 60.0], [20.0, 60.0]])
    );
    let px4 = params(&out.join("px4_thermal.params"));
    let ap = params(&out.join("ardupilot_tcal.parm"));
    assert_eq!(px4["TC_G0_ID"], 2359330.0);
    assert_eq!(px4["TC_A0_ID"], 2359331.0);
    assert_eq!((px4["TC_G_ENABLE"], px4["TC_A_ENABLE"]), (1.0, 1.0));
    assert_eq!(px4["TC_G0_TREF"], 40.0);
    assert_eq!(ap["INS_TCAL1_ENABLE"], 1.0);
    assert_eq!((ap["INS_TCAL1_TMIN"], ap["INS_TCAL1_TMAX"]), (20.0, 60.0));
    assert_cancelled(&px4, &ap, 0, 1);
}

/// A thermal run that cannot write one of its files writes none: with a folder in the way of
/// the plot, the JSON or the ArduPilot file (the files before it were left, exit 2, before),
/// and of a noise file; a run that writes them all lists them all in its JSON.
#[test]
fn a_thermal_run_writes_every_file_or_none() {
    let record = warm_up("all-or-none.csv", 0.0);
    let ids = [
        "--device-id",
        "2359330,2359331",
        "--noise-format",
        "kalibr",
        "--rate",
        "100",
    ];
    for blocked in [
        "thermal.png",
        "thermal.json",
        "ardupilot_tcal.parm",
        "imu.yaml",
    ] {
        let out = temp_path("thermal-blocked");
        std::fs::create_dir_all(out.join(blocked)).unwrap();
        let run = imu_ar(
            &[
                &[
                    "thermal",
                    record.to_str().unwrap(),
                    "--out",
                    out.to_str().unwrap(),
                ][..],
                &ids[..],
            ]
            .concat(),
        );
        assert_one_line_failure(&run);
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(
            err.contains(blocked) && err.contains("is a directory; no file was written"),
            "{blocked}: {err}"
        );
        assert_eq!(crate::common::names_in(&out), [blocked], "{blocked}");
    }
    let out = temp_path("thermal-all").join("new");
    let o = out.to_str().unwrap();
    let run = imu_ar(
        &[
            &["thermal", record.to_str().unwrap(), "--out", o, "--json"][..],
            &ids[..],
        ]
        .concat(),
    );
    let files = json(&run)["files"].clone();
    let names = [
        "imu.yaml",
        "px4_thermal.params",
        "ardupilot_tcal.parm",
        "thermal.json",
        "thermal.png",
    ];
    let want: Vec<String> = names
        .iter()
        .map(|n| out.join(n).display().to_string())
        .collect();
    assert_eq!(files, serde_json::json!(want));
    for name in names {
        assert!(out.join(name).is_file(), "{name}");
    }
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("thermal.json")).unwrap()).unwrap();
    assert_eq!(written["files"], files);
}

/// The parameters of PX4 slot `slot` and ArduPilot IMU `imu`, applied through each
/// autopilot's formula, cancel the simulated bias across 20 to 60 deg C: gyros to 1e-4 rad/s,
/// accelerometers to 1e-3 m/s^2 (an accelerometer's constant, and ArduPilot's, left to the
/// offsets the autopilot calibrates at its reference).
fn assert_cancelled(
    px4: &HashMap<String, f32>,
    ap: &HashMap<String, f32>,
    slot: usize,
    imu: usize,
) {
    let caltemp = 33.0;
    for axis in 0..6 {
        let (s, a, tolerance) = if axis < 3 {
            ("G", "GYR", 1e-4)
        } else {
            ("A", "ACC", 1e-3)
        };
        let mut worst = [0.0f64; 2];
        for step in 0..=400 {
            let celsius = 20.0 + 0.1 * f64::from(step);
            let c = celsius as f32;
            // PX4: a gyro's X0 holds its bias; an accelerometer keeps its value at TREF.
            let kept = if axis < 3 { 0.0 } else { bias(axis, 40.0) };
            let px4_left =
                bias(axis, celsius) - f64::from(px4_offset(px4, s, slot, axis % 3, c)) - kept;
            // ArduPilot: the offsets keep the bias at CALTEMP.
            let ap_left = bias(axis, celsius)
                - f64::from(ardupilot_correction(
                    ap,
                    a,
                    imu,
                    axis % 3,
                    c,
                    caltemp as f32,
                ))
                - bias(axis, caltemp);
            worst[0] = worst[0].max(px4_left.abs());
            worst[1] = worst[1].max(ap_left.abs());
        }
        assert!(
            worst[0] < tolerance && worst[1] < tolerance,
            "axis {axis}: PX4 leaves {:.3e}, ArduPilot {:.3e} (tolerance {tolerance:e})",
            worst[0],
            worst[1]
        );
    }
}

/// A bump the cubic cannot follow: the held-out check fails, exit status 1, the files still
/// written, and the table says which axis.
#[test]
fn a_bump_fails_the_held_out_check_with_status_1() {
    let record = warm_up("bump.csv", 1.5e-3);
    let out = temp_path("thermal-bump");
    let run = imu_ar(&[
        "thermal",
        record.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--format",
        "ardupilot",
    ]);
    assert_eq!(run.status.code(), Some(1), "{}", stdout(&run));
    let text = stdout(&run);
    let gx = text.lines().find(|l| l.starts_with("gx ")).unwrap();
    assert!(gx.ends_with("false"), "{gx}");
    assert!(text.contains("does not generalise"), "{text}");
    assert!(out.join("ardupilot_tcal.parm").is_file());
}

/// One clear line each: a span under 10 deg C, PX4 from a CSV without device ids, a missing
/// temperature column.
#[test]
fn bad_warm_ups_are_refused_in_one_line() {
    let mut short = String::from("gx,gy,gz,ax,ay,az,temperature\n");
    for i in 0..2000 {
        short += &format!("0.1,0.2,0.3,0,0,1,{}\n", 30 + i % 8);
    }
    let short = temp_file("short.csv", short);
    let out = temp_path("thermal-short");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "thermal",
            short.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        a.extend(extra);
        imu_ar(&a)
    };
    let run = args(&[
        "--format",
        "ardupilot",
        "--gyro-unit",
        "rad/s",
        "--accel-unit",
        "g",
    ]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("at least 10 deg C"), "{e}");
    let run = args(&["--gyro-unit", "rad/s", "--accel-unit", "g"]);
    assert_one_line_failure(&run);
    assert!(String::from_utf8_lossy(&run.stderr).contains("--device-id"));
    let run = args(&["--format", "json", "--temperature-column", "temp"]);
    assert_one_line_failure(&run);
    assert!(String::from_utf8_lossy(&run.stderr).contains("temp"));
    // A width whose bin count overflows: named, in a short number.
    let run = args(&[
        "--format",
        "json",
        "--bin-width",
        "1e-310",
        "--gyro-unit",
        "rad/s",
        "--accel-unit",
        "g",
    ]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(
        e.contains("bins of 1e-310 deg C") && e.contains("too small"),
        "{e}"
    );
}

/// Autopilot logs that cannot be read are named for what they are, in one line, by every
/// command: empty, cut inside the first message, IMU messages in units of their own; a log cut
/// short after its samples is read, with a warning.
#[test]
fn bad_autopilot_logs_are_named_in_one_line() {
    let mut wrong_units = Df::new();
    // The accelerometer's fields said to be in rad/s.
    wrong_units.fmtu(writers::IMU, "s#EEEEEE--O--zz", "F-000000-----00");
    for k in 0..100u64 {
        wrong_units.imu(1_000_000 + 10_000 * k, 0, [0.0; 3], [0.0, 0.0, 9.8], 30.0);
    }
    let cases: [(&str, Vec<u8>, &str); 5] = [
        (
            "empty.ulg",
            Vec::new(),
            "an empty file, not a PX4 ULog file",
        ),
        (
            "empty.bin",
            Vec::new(),
            "an empty file, not an ArduPilot DataFlash log",
        ),
        ("cut.ulg", b"ULo".to_vec(), "truncated ULog file"),
        (
            "cut.bin",
            vec![0xa3, 0x95],
            "it ends inside its first message",
        ),
        ("units.bin", wrong_units.bytes, "IMU"),
    ];
    for (name, bytes, want) in cases {
        let file = temp_file(name, bytes);
        let out = temp_path("bad-log");
        for args in [
            vec!["noise", file.to_str().unwrap(), "--column", "gx"],
            vec![
                "thermal",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        ] {
            let run = imu_ar(&args);
            assert_one_line_failure(&run);
            let e = String::from_utf8_lossy(&run.stderr);
            assert!(e.contains(want), "{name} {}: {e}", args[0]);
            assert!(
                !e.contains("CSV") && !e.contains("header row"),
                "{name}: {e}"
            );
        }
    }
    // Cut short after its samples (the power went): read, with a warning.
    let mut df = Df::new();
    for (k, (_, a)) in samples(4_000, 0.0).into_iter().enumerate() {
        let f = |i: usize| a[i] as f32;
        df.imu(
            1_000_000 + 10_000 * k as u64,
            0,
            [f(0), f(1), f(2)],
            [f(3), f(4), f(5)],
            30.0,
        );
    }
    let mut bytes = df.bytes;
    bytes.truncate(bytes.len() - 7);
    let file = temp_file("cut-short.bin", bytes);
    let run = imu_ar(&["noise", file.to_str().unwrap(), "--column", "gx", "--json"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert_eq!(json(&run)["n"], 3_999);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("warning") && e.contains("cut short"), "{e}");
    // Cut inside the first IMU message: no IMU messages, and why.
    let mut df = Df::new();
    let formats = df.bytes.len();
    df.imu(1_000_000, 0, [0.0; 3], [0.0; 3], 30.0);
    df.bytes.truncate(formats + 10);
    let file = temp_file("cut-first.bin", df.bytes);
    let run = imu_ar(&["noise", file.to_str().unwrap(), "--column", "gx"]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(
        e.contains("no IMU messages") && e.contains("cut short"),
        "{e}"
    );
}

/// A PX4 ULog warm-up: sensor_gyro and sensor_accel of the IMUs `instances` at 100 Hz
/// (instance i with device ids 2359330 + 2 i and 2359331 + 2 i), the same simulated biases on
/// each.
fn ulog_warm_up(name: &str, instances: std::ops::Range<u8>) -> PathBuf {
    let mut log = ULog::new(0);
    log.format(SENSOR_GYRO);
    log.format(SENSOR_ACCEL);
    for (k, i) in instances.clone().enumerate() {
        log.subscribe(i, 2 * k as u16, "sensor_gyro");
        log.subscribe(i, 2 * k as u16 + 1, "sensor_accel");
    }
    for (k, (celsius, axes)) in samples(60_000, 0.0).into_iter().enumerate() {
        let t = 1_000_000 + 10_000 * k as u64;
        for (m, i) in instances.clone().enumerate() {
            let device = 2_359_330 + 2 * u32::from(i);
            let f = |a: usize| axes[a] as f32;
            let msg = 2 * m as u16;
            log.data(
                msg,
                &sensor(t, t, device, [f(0), f(1), f(2)], celsius as f32),
            );
            log.data(
                msg + 1,
                &sensor(t, t, device + 1, [f(3), f(4), f(5)], celsius as f32),
            );
        }
    }
    temp_file(name, log.bytes)
}

/// A DataFlash warm-up: IMU messages of instance 0 at 100 Hz, with `params` first.
fn dataflash_warm_up(name: &str, params: &[(&str, f32)]) -> PathBuf {
    let mut log = Df::new();
    for (p, v) in params {
        log.parm(0, p, *v);
    }
    for (k, (celsius, axes)) in samples(60_000, 0.0).into_iter().enumerate() {
        let f = |a: usize| axes[a] as f32;
        let t = 1_000_000 + 10_000 * k as u64;
        log.imu(t, 0, [f(0), f(1), f(2)], [f(3), f(4), f(5)], celsius as f32);
    }
    temp_file(name, log.bytes)
}

/// `imu-ar thermal LOG --out DIR EXTRA..`, successful: its PX4 and ArduPilot parameters.
fn calibrated(log: &Path, extra: &[&str]) -> (HashMap<String, f32>, HashMap<String, f32>) {
    let out = temp_path("thermal-out");
    let mut args = vec![
        "thermal",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let run = imu_ar(&args);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{e}");
    (
        params(&out.join("px4_thermal.params")),
        params(&out.join("ardupilot_tcal.parm")),
    )
}

/// `imu-ar thermal` of a PX4 ULog file: the device ids from the log, no other flag; with two
/// IMUs, --instance picks one and numbers the PX4 slot and the ArduPilot IMU after it.
#[test]
fn a_ulog_warm_up_is_calibrated_with_its_device_ids() {
    let one = ulog_warm_up("one.ulg", 0..1);
    let out = temp_path("thermal-ulog");
    let j = json(&imu_ar(&[
        "thermal",
        one.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]));
    assert_eq!(j["generalises"], true, "{j}");
    let px4 = params(&out.join("px4_thermal.params"));
    let ap = params(&out.join("ardupilot_tcal.parm"));
    assert_eq!((px4["TC_G0_ID"], px4["TC_A0_ID"]), (2359330.0, 2359331.0));
    assert_cancelled(&px4, &ap, 0, 1);
    let two = ulog_warm_up("two.ulg", 0..2);
    let run = imu_ar(&[
        "thermal",
        two.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("--instance") && e.contains("2359332"), "{e}");
    let (px4, ap) = calibrated(&two, &["--instance", "1"]);
    assert_eq!((px4["TC_G1_ID"], px4["TC_A1_ID"]), (2359332.0, 2359333.0));
    assert_cancelled(&px4, &ap, 1, 2);
}

/// `imu-ar thermal` of an ArduPilot DataFlash log: calibrated from its IMU messages; refused
/// when ArduPilot had already corrected them (INS_TCAL1_ENABLE 1) or rotated them
/// (AHRS_ORIENTATION); an instance the log does not hold is refused by every command.
#[test]
fn a_dataflash_warm_up_is_calibrated_unless_already_corrected() {
    let log = dataflash_warm_up("warm.bin", &[("INS_TCAL1_ENABLE", 0.0)]);
    let (px4, ap) = calibrated(&log, &["--device-id", "1,2"]);
    assert_cancelled(&px4, &ap, 0, 1);
    let out = temp_path("thermal-bin");
    for (p, v, says) in [
        ("INS_TCAL1_ENABLE", 1.0, "already temperature-corrected"),
        ("AHRS_ORIENTATION", 2.0, "AHRS_ORIENTATION"),
    ] {
        let log = dataflash_warm_up("refused.bin", &[(p, v)]);
        let run = imu_ar(&[
            "thermal",
            log.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_one_line_failure(&run);
        let e = String::from_utf8_lossy(&run.stderr);
        assert!(e.contains(says), "{e}");
    }
    let run = imu_ar(&[
        "noise",
        log.to_str().unwrap(),
        "--column",
        "gx",
        "--instance",
        "3",
    ]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(
        e.contains("no IMU messages") && e.contains("of that instance"),
        "{e}"
    );
}

/// The same samples (f32, as the logs hold them, at 100 Hz) as an ArduPilot DataFlash log, a
/// PX4 ULog file and a CSV record: `imu-ar noise --json` gives the same model of every axis
/// from the log as from the CSV, bit for bit, and so does `characterise` (with no other flag;
/// the ULog file's two topics paired by their sample times).
#[test]
fn autopilot_logs_give_the_csvs_noise_model() {
    let rows: Vec<(u64, [f32; 6])> = samples(20_000, 0.0)
        .into_iter()
        .enumerate()
        .map(|(k, (_, axes))| (1_000_000 + 10_000 * k as u64, axes.map(|v| v as f32)))
        .collect();
    let mut df = Df::new();
    let mut ulog = ULog::new(0);
    ulog.format(SENSOR_GYRO);
    ulog.format(SENSOR_ACCEL);
    ulog.subscribe(0, 0, "sensor_gyro");
    ulog.subscribe(0, 1, "sensor_accel");
    let mut csv =
        String::from("t [us],gx [rad/s],gy [rad/s],gz [rad/s],ax [m/s^2],ay [m/s^2],az [m/s^2]\n");
    for (t, a) in &rows {
        df.imu(*t, 0, [a[0], a[1], a[2]], [a[3], a[4], a[5]], 30.0);
        ulog.data(0, &sensor(*t, *t, 7, [a[0], a[1], a[2]], 30.0));
        ulog.data(1, &sensor(*t, *t, 8, [a[3], a[4], a[5]], 30.0));
        csv += &format!("{t}");
        for v in a {
            csv += &format!(",{}", f64::from(*v));
        }
        csv += "\n";
    }
    let df = temp_file("same.bin", df.bytes);
    let ulog = temp_file("same.ulg", ulog.bytes);
    let csv = temp_file("same.csv", csv);
    // Everything but the unit the stamps were written in (the CSV's microseconds; the logs'
    // message stamps, in nanoseconds).
    let model = |file: &Path, column: &str| {
        let args = [
            "noise",
            file.to_str().unwrap(),
            "--column",
            column,
            "--json",
        ];
        let mut j = json(&imu_ar(&args));
        j["timing"]["unit"] = serde_json::Value::Null;
        j
    };
    for column in ["gx", "gy", "gz", "ax", "ay", "az"] {
        let want = model(&csv, column);
        assert_eq!(model(&df, column), want, "DataFlash {column}");
        assert_eq!(model(&ulog, column), want, "ULog {column}");
    }
    // characterise, with no other flag: the six axes of each, as of the CSV.
    let axes = |file: &Path| {
        let out = temp_path("characterise-log");
        let args = [
            "characterise",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        let j = json(&imu_ar(&[&args[..], &["--json"]].concat()));
        assert!(out.join("px4.params").is_file());
        let mut axes = j["axes"].clone();
        for a in axes.as_array_mut().unwrap() {
            a["column"] = serde_json::Value::Null;
            a["model"]["timing"]["unit"] = serde_json::Value::Null;
        }
        axes
    };
    let want = axes(&csv);
    assert_eq!(axes(&df), want, "DataFlash");
    assert_eq!(axes(&ulog), want, "ULog");
}

/// A ULog file whose accelerometer is published at times of its own (3 ms after the gyro):
/// `characterise` refuses to pair the two, saying so; one sensor's axes still read.
#[test]
fn a_ulog_file_with_unpaired_topics_is_refused_for_six_axes() {
    let mut ulog = ULog::new(0);
    ulog.format(SENSOR_GYRO);
    ulog.format(SENSOR_ACCEL);
    ulog.subscribe(0, 0, "sensor_gyro");
    ulog.subscribe(0, 1, "sensor_accel");
    for (k, (_, a)) in samples(5_000, 0.0).into_iter().enumerate() {
        let t = 1_000_000 + 10_000 * k as u64;
        let f = |i: usize| a[i] as f32;
        ulog.data(0, &sensor(t, t, 7, [f(0), f(1), f(2)], 30.0));
        ulog.data(
            1,
            &sensor(t + 3_000, t + 3_000, 8, [f(3), f(4), f(5)], 30.0),
        );
    }
    let file = temp_file("unpaired.ulg", ulog.bytes);
    let out = temp_path("unpaired");
    let run = imu_ar(&[
        "characterise",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("no partner"), "{e}");
    let run = imu_ar(&["noise", file.to_str().unwrap(), "--column", "az", "--json"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// A ULog file with the FIFO topics at the full rate and the sensor topics at 10 Hz, as PX4
/// logs them with the raw FIFO bits of SDLOG_PROFILE: the FIFO topics are read, every sample.
#[test]
fn a_ulog_files_fifo_topics_are_read_at_the_full_rate() {
    let mut ulog = ULog::new(0);
    for format in [GYRO_FIFO, ACCEL_FIFO, SENSOR_GYRO, SENSOR_ACCEL] {
        ulog.format(format);
    }
    for (id, name) in [
        "sensor_gyro_fifo",
        "sensor_accel_fifo",
        "sensor_gyro",
        "sensor_accel",
    ]
    .iter()
    .enumerate()
    {
        ulog.subscribe(0, id as u16, name);
    }
    let rows = samples(32 * 400, 0.0);
    for (k, block) in rows.chunks(32).enumerate() {
        // 1 kHz: the newest sample of each message at its timestamp_sample.
        let t = 1_000_000 + 1_000 * (32 * k as u64 + 31);
        for (s, scale) in [(0usize, 1e-4f32), (1, 1e-3)] {
            let mut xyz = [[0i16; 32]; 3];
            for (i, (_, a)) in block.iter().enumerate() {
                for (j, axis) in xyz.iter_mut().enumerate() {
                    axis[i] = (a[3 * s + j] / f64::from(scale)).round() as i16;
                }
            }
            ulog.data(s as u16, &fifo(t, 7 + s as u32, 1000.0, scale, 32, &xyz));
        }
        if k % 3 == 0 {
            ulog.data(2, &sensor(t, t, 7, [0.0; 3], 30.0));
            ulog.data(3, &sensor(t, t, 8, [0.0; 3], 30.0));
        }
    }
    let file = temp_file("fifo.ulg", ulog.bytes);
    let out = temp_path("fifo");
    let args = [
        "characterise",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--json",
    ];
    let j = json(&imu_ar(&args));
    assert_eq!(j["n"], 32 * 400);
    assert_eq!(j["rate_hz"], 1000.0);
}

/// Noise against temperature: a warm-up at 100 Hz whose white noise grows 50 % from 20 to
/// 60 deg C (on top of the cubic bias and the uneven heating of [`samples`]); each band's N
/// follows the truth of its samples (the root mean square of their standard deviations over
/// sqrt(rate)) within 5 %, and the worst band's model goes into the noise files.
#[test]
fn the_noise_of_each_temperature_band_follows_the_truth() {
    const RATE: f64 = 100.0;
    let rows = samples(240_000, 0.0);
    // The noise's growth: samples' white part scaled by 1 + 0.5 (T - 20) / 40 about the bias.
    let grow = |celsius: f64| 1.0 + 0.5 * (celsius - 20.0) / 40.0;
    let mut text = String::from(
        "t [s],gx [rad/s],gy [rad/s],gz [rad/s],ax [m/s^2],ay [m/s^2],az [m/s^2],temperature\n",
    );
    for (i, (celsius, axes)) in rows.iter().enumerate() {
        text += &format!("{:.2}", i as f64 / RATE);
        for (axis, v) in axes.iter().enumerate() {
            let b = bias(axis, *celsius);
            text += &format!(",{:.9e}", b + (v - b) * grow(*celsius));
        }
        text += &format!(",{celsius:.3}\n");
    }
    let file = temp_file("growing.csv", text);
    let out = temp_path("growing");
    let args = [
        "thermal",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--device-id",
        "1,2",
        "--noise-format",
        "kalibr",
        "--json",
    ];
    let j = json(&imu_ar(&args));
    let bands = j["noise_bands"].as_array().unwrap();
    assert_eq!(bands.len(), 6);
    let mut worst_gyro = 0.0f64;
    let mut largest = 0.0f64;
    for (axis, a) in bands.iter().enumerate() {
        assert_eq!(a["rate_hz"], RATE);
        let list = a["bands"].as_array().unwrap();
        assert_eq!(list.len(), 4);
        let low = list[0]["from_c"].as_f64().unwrap();
        let high = list[3]["to_c"].as_f64().unwrap();
        for (k, b) in list.iter().enumerate() {
            let (from, to) = (b["from_c"].as_f64().unwrap(), b["to_c"].as_f64().unwrap());
            // The truth: the mean variance of the band's samples, at the temperatures as
            // written; those outside the range join the first or the last band.
            let sigma = if axis < 3 { 2e-3 } else { 2e-2 };
            let inside: Vec<f64> = rows
                .iter()
                .map(|(t, _)| format!("{t:.3}").parse::<f64>().unwrap())
                .filter(|t| {
                    let at = ((t - low) / (high - low) * 4.0).floor().clamp(0.0, 3.0);
                    at as usize == k
                })
                .collect();
            assert_eq!(b["n"], inside.len(), "{axis} {from}");
            let variance = inside
                .iter()
                .map(|t| (sigma * grow(*t)).powi(2))
                .sum::<f64>()
                / inside.len() as f64;
            let truth = (variance / RATE).sqrt();
            let n = b["white_noise"].as_f64().unwrap();
            largest = largest.max((n / truth - 1.0).abs());
            assert!(
                (n / truth - 1.0).abs() < 0.05,
                "axis {axis}, {from:.1} to {to:.1} deg C: N {n:.4e}, truth {truth:.4e}"
            );
            if axis < 3 {
                worst_gyro = worst_gyro.max(n);
            }
        }
        // The hottest band is the noisiest.
        assert_eq!(a["worst"], 3, "axis {axis}");
    }
    eprintln!("the largest |N / truth - 1| of a band: {largest:.4}");
    // thermal.png: a PNG of the bins, fits and residuals, with the default --format all.
    let png = std::fs::read(out.join("thermal.png")).unwrap();
    assert!(
        png.starts_with(b"\x89PNG\r\n\x1a\n") && png.len() > 10_000,
        "{}",
        png.len()
    );
    let yaml = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
    assert!(yaml.contains("worst temperature band"), "{yaml}");
    let density: f64 = yaml
        .lines()
        .find_map(|l| l.trim().strip_prefix("gyroscope_noise_density:"))
        .and_then(|v| v.split('#').next())
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(
        density >= worst_gyro * 0.999 && density < worst_gyro * 1.05,
        "{density} against the worst band's {worst_gyro}"
    );
}

/// The sensors' full-rate samples, quantised as the autopilots log them (PX4's FIFO topics:
/// `x[i] * scale`; ArduPilot's batch sampler: `raw / mul`), give the noise model of the CSV of
/// the same values, bit for bit: one sensor's axes are read from the FIFO topic or the batches
/// when they hold more samples than the sensor topic or the `IMU` messages.
#[test]
fn fifo_topics_and_batches_give_the_csvs_noise_model() {
    const BLOCKS: usize = 400;
    let rows = samples(32 * BLOCKS, 0.0);
    // (FIFO scale, batch mul) of the gyro and the accelerometer.
    let quanta = [(1e-4f32, 10_000u16), (1e-3, 1_000)];
    let raw: Vec<[i16; 6]> = rows
        .iter()
        .map(|(_, a)| std::array::from_fn(|i| (a[i] / f64::from(quanta[i / 3].0)).round() as i16))
        .collect();
    let mut ulog = ULog::new(0);
    for format in [GYRO_FIFO, ACCEL_FIFO, SENSOR_GYRO, SENSOR_ACCEL] {
        ulog.format(format);
    }
    for (id, name) in [
        "sensor_gyro_fifo",
        "sensor_accel_fifo",
        "sensor_gyro",
        "sensor_accel",
    ]
    .iter()
    .enumerate()
    {
        ulog.subscribe(0, id as u16, name);
    }
    let mut df = Df::new();
    // One batch of each sensor, 1 kHz from 1 s; a few IMU messages at the loop's rate.
    for (n, ty) in [(0u16, 1u8), (1, 0)] {
        let mul = quanta[usize::from(ty == 0)].1;
        df.isbh(
            1_000_000,
            n,
            ty,
            0,
            mul,
            raw.len() as u16,
            1_000_000,
            1000.0,
        );
    }
    for (k, block) in raw.chunks(32).enumerate() {
        let t = 1_000_000 + 1_000 * (32 * k as u64 + 31);
        for s in 0..2 {
            let xyz: [[i16; 32]; 3] =
                std::array::from_fn(|j| std::array::from_fn(|i| block[i][3 * s + j]));
            ulog.data(
                s as u16,
                &fifo(t, 7 + s as u32, 1000.0, quanta[s].0, 32, &xyz),
            );
            // The batch's blocks carry the same raw values, scaled back by mul.
            let scaled: [[i16; 32]; 3] = std::array::from_fn(|j| {
                std::array::from_fn(|i| {
                    let v = f64::from(block[i][3 * s + j]) * f64::from(quanta[s].0);
                    (v * f64::from(quanta[s].1)).round() as i16
                })
            });
            df.isbd(t, if s == 0 { 0 } else { 1 }, k as u16, &scaled);
        }
        if k % 8 == 0 {
            ulog.data(2, &sensor(t, t, 7, [0.0; 3], 30.0));
            ulog.data(3, &sensor(t, t, 8, [0.0; 3], 30.0));
            df.imu(t, 0, [0.0; 3], [0.0; 3], 30.0);
        }
    }
    let mut csv =
        String::from("t [us],gx [rad/s],gy [rad/s],gz [rad/s],ax [m/s^2],ay [m/s^2],az [m/s^2]\n");
    for (k, r) in raw.iter().enumerate() {
        csv += &format!("{}", 1_000_000 + 1_000 * k as u64);
        for (i, v) in r.iter().enumerate() {
            csv += &format!(",{}", f64::from(*v) * f64::from(quanta[i / 3].0));
        }
        csv += "\n";
    }
    // The batch values: raw / mul, with raw = value * mul as written above.
    let mut batch_csv =
        String::from("t [us],gx [rad/s],gy [rad/s],gz [rad/s],ax [m/s^2],ay [m/s^2],az [m/s^2]\n");
    for (k, r) in raw.iter().enumerate() {
        batch_csv += &format!("{}", 1_000_000 + 1_000 * k as u64);
        for (i, v) in r.iter().enumerate() {
            let (scale, mul) = quanta[i / 3];
            let back = (f64::from(*v) * f64::from(scale) * f64::from(mul)).round();
            batch_csv += &format!(",{}", back / f64::from(mul));
        }
        batch_csv += "\n";
    }
    let ulog = temp_file("fifo-same.ulg", ulog.bytes);
    let df = temp_file("batch-same.bin", df.bytes);
    let csv = temp_file("fifo-same.csv", csv);
    let batch_csv = temp_file("batch-same.csv", batch_csv);
    let model = |file: &Path, column: &str| {
        let args = [
            "noise",
            file.to_str().unwrap(),
            "--column",
            column,
            "--json",
        ];
        let mut j = json(&imu_ar(&args));
        j["timing"]["unit"] = serde_json::Value::Null;
        j
    };
    for column in ["gx", "gy", "gz", "ax", "ay", "az"] {
        let fifo = model(&ulog, column);
        assert_eq!(fifo["n"], 32 * BLOCKS, "ULog FIFO {column}");
        assert_eq!(fifo, model(&csv, column), "ULog FIFO {column}");
        let batch = model(&df, column);
        assert_eq!(batch["n"], 32 * BLOCKS, "DataFlash batch {column}");
        assert_eq!(batch, model(&batch_csv, column), "DataFlash batch {column}");
        // Named as read from the batches (not the IMU messages characterise reads), which
        // nothing told before.
        let run = imu_ar(&["noise", df.to_str().unwrap(), "--column", column]);
        let e = crate::common::stderr(&run);
        let batches = if column.starts_with('g') {
            "gyro"
        } else {
            "accel"
        };
        assert!(
            e.contains("note: ")
                && e.contains(&format!(
                    "{column} read from the log's ISB {batches} batches of IMU 0"
                )),
            "{e}"
        );
    }
}

/// What a red-team pass found, each fixed: a stray temperature sample set TMAX (150 deg C from
/// one sample); a bias beyond f32 was written as `inf` with exit 0; a temperature column in
/// [K] was read as deg C; values quantised coarser than their noise failed the held-out check;
/// the one IMU of a ULog file at instance 3 was written as slot 0 and IMU 1.
#[test]
fn stray_temperatures_overflows_units_quantised_values_and_instances() {
    let record = warm_up("stray.csv", 0.0);
    let mut text = std::fs::read_to_string(&record).unwrap();
    text += "1200.0,0,0,0,0,0,1,150\n";
    let stray = temp_file("stray.csv", text);
    let (px4, ap) = calibrated(&stray, &["--device-id", "1,2"]);
    assert_eq!((px4["TC_G0_TMIN"], px4["TC_G0_TMAX"]), (20.0, 60.0));
    assert_eq!(ap["INS_TCAL1_TMAX"], 60.0);
    assert_cancelled(&px4, &ap, 0, 1);

    let rows = samples(20_000, 0.0);
    let csv = |name: &str, header: &str, value: &dyn Fn(f64, f64) -> f64| {
        let mut text = format!("gx,gy,gz,ax,ay,az,{header}\n");
        for (celsius, axes) in &rows {
            for v in axes {
                text += &format!("{},", value(*v, *celsius));
            }
            text += &format!("{celsius}\n");
        }
        temp_file(name, text)
    };
    let run = |file: &Path| {
        let out = temp_path("red");
        imu_ar(&[
            "thermal",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--format",
            "ardupilot",
            "--gyro-unit",
            "rad/s",
            "--accel-unit",
            "m/s^2",
        ])
    };
    let huge = csv("huge.csv", "temperature", &|_, t| 1e300 * (t - 40.0));
    let failed = run(&huge);
    assert_one_line_failure(&failed);
    assert!(String::from_utf8_lossy(&failed.stderr).contains("32-bit float"));
    let kelvin = csv("kelvin.csv", "temperature [K]", &|v, _| v);
    let failed = run(&kelvin);
    assert_one_line_failure(&failed);
    assert!(String::from_utf8_lossy(&failed.stderr).contains("[K]"));
    // Steps of 1e-3 on a noise of 2e-4: bins of identical values, known to a step.
    let quantised = csv("quantised.csv", "temperature", &|v, t| {
        let truth = v - 0.9 * (v - bias(0, t));
        (truth / 1e-3).round() * 1e-3
    });
    let passed = run(&quantised);
    assert!(passed.status.success(), "{}", stdout(&passed));

    let third = ulog_warm_up("third.ulg", 3..4);
    let (px4, ap) = calibrated(&third, &[]);
    assert_eq!(px4["TC_G3_ID"], 2359336.0);
    assert_eq!(ap["INS4_TCAL_ENABLE"], 1.0);
}

/// What a second red-team pass on the autopilot logs found, each fixed:
/// - a PX4 log with FIFO topics for IMU 0 only: IMU 1 could not be read (the FIFO topic was
///   chosen by the samples of all IMUs, not of the one asked for);
/// - the same for a DataFlash log's batches;
/// - FIFO messages with dt 0 gave noise bands at a wrong rate, exit 0;
/// - a log that heats and cools joined the two stretches of a band (a step taken for noise);
/// - NaN and implausible temperatures were dropped silently; Kelvin accepted;
/// - `--noise-format` with a gyro and an accelerometer at different rates failed with a message
///   naming neither;
/// - "PX4 leaves NaN" in the ArduPilot file's comments;
/// - NaN gyro samples of a ULog file were refused as unpaired;
/// - `noise` said nothing of samples it skipped.
#[test]
fn second_red_team_pass_on_logs() {
    let rows = samples(6_000, 0.0);
    let f = |a: f64| a as f32;
    // D1: sensor topics of IMUs 0 and 1 at 100 Hz, FIFO topics of IMU 0 only, at 1 kHz.
    let mut log = ULog::new(0);
    for format in [GYRO_FIFO, ACCEL_FIFO, SENSOR_GYRO, SENSOR_ACCEL] {
        log.format(format);
    }
    log.subscribe(0, 0, "sensor_gyro_fifo");
    log.subscribe(0, 1, "sensor_accel_fifo");
    for i in 0..2u8 {
        log.subscribe(i, 2 + 2 * u16::from(i), "sensor_gyro");
        log.subscribe(i, 3 + 2 * u16::from(i), "sensor_accel");
    }
    for (k, (celsius, a)) in rows.iter().enumerate() {
        let t = 1_000_000 + 10_000 * k as u64;
        for i in 0..2u16 {
            let device = 100 + 2 * u32::from(i);
            log.data(
                2 + 2 * i,
                &sensor(t, t, device, [f(a[0]), f(a[1]), f(a[2])], f(*celsius)),
            );
            log.data(
                3 + 2 * i,
                &sensor(t, t, device + 1, [f(a[3]), f(a[4]), f(a[5])], f(*celsius)),
            );
        }
        // (Counts of -9 to 9 scrambled: a pattern that repeats would hold no noise a model
        // of noise could take.)
        let xyz: [[i16; 32]; 3] = std::array::from_fn(|j| {
            std::array::from_fn(|i| {
                let mut z = (((k * 32 + i) * 3 + j) as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
                z = (z ^ (z >> 31)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
                ((z >> 40) % 19) as i16 - 9
            })
        });
        log.data(0, &fifo(t, 100, 1000.0, 1e-4, 10, &xyz));
        log.data(1, &fifo(t, 101, 1000.0, 1e-3, 10, &xyz));
    }
    let multi = temp_file("multi.ulg", log.bytes);
    let m = path_str(&multi);
    let j = json(&imu_ar(&[
        "noise",
        m,
        "--column",
        "gx",
        "--instance",
        "1",
        "--json",
    ]));
    assert_eq!(j["n"], 6_000, "IMU 1's sensor topic");
    let j = json(&imu_ar(&[
        "noise",
        m,
        "--column",
        "gx",
        "--instance",
        "0",
        "--json",
    ]));
    assert_eq!(j["n"], 60_000, "IMU 0's FIFO topic");
    let out = temp_path("multi");
    let args = [
        "thermal",
        m,
        "--out",
        path_str(&out),
        "--instance",
        "1",
        "--json",
    ];
    let j = json(&imu_ar(&args));
    assert_eq!(
        (j["n"].as_u64(), j["instance"].as_u64()),
        (Some(6_000), Some(1))
    );

    // D2: batches of IMU 0 only; IMU 1 is read from its IMU messages.
    let mut df = Df::new();
    df.isbh(1_000_000, 0, 1, 0, 1000, 2048, 1_000_000, 1000.0);
    for k in 0..64u64 {
        df.isbd(1_000_000 + k, 0, k as u16, &[[1i16; 32]; 3]);
    }
    for (k, (celsius, a)) in rows.iter().enumerate() {
        let t = 1_000_000 + 10_000 * k as u64;
        for i in 0..2 {
            df.imu(
                t,
                i,
                [f(a[0]), f(a[1]), f(a[2])],
                [f(a[3]), f(a[4]), f(a[5])],
                f(*celsius),
            );
        }
    }
    let bin = temp_file("batch-inst.bin", df.bytes);
    let b = path_str(&bin);
    let j = json(&imu_ar(&[
        "noise",
        b,
        "--column",
        "gx",
        "--instance",
        "1",
        "--json",
    ]));
    assert_eq!(j["n"], 6_000, "IMU 1's IMU messages");

    // D3: FIFO messages whose dt is 0 give no rate: no noise bands, and says why.
    let mut log = ULog::new(0);
    for format in [GYRO_FIFO, ACCEL_FIFO, SENSOR_GYRO, SENSOR_ACCEL] {
        log.format(format);
    }
    for (id, name) in [
        "sensor_gyro_fifo",
        "sensor_accel_fifo",
        "sensor_gyro",
        "sensor_accel",
    ]
    .iter()
    .enumerate()
    {
        log.subscribe(0, id as u16, name);
    }
    for (k, block) in rows.chunks(10).enumerate() {
        let t = 1_000_000 + 10_000 * k as u64;
        for (s, scale) in [(0usize, 1e-4f32), (1, 1e-3)] {
            let mut xyz = [[0i16; 32]; 3];
            for (i, (_, a)) in block.iter().enumerate() {
                for (j, axis) in xyz.iter_mut().enumerate() {
                    axis[i] = (a[3 * s + j] / f64::from(scale)).round() as i16;
                }
            }
            log.data(s as u16, &fifo(t, 7 + s as u32, 0.0, scale, 10, &xyz));
        }
        log.data(2, &sensor(t, t, 7, [0.0; 3], f(block[0].0)));
        log.data(3, &sensor(t, t, 8, [0.0; 3], f(block[0].0)));
    }
    let dt0 = temp_file("dt0.ulg", log.bytes);
    let out = temp_path("dt0");
    let j = json(&imu_ar(&[
        "thermal",
        path_str(&dt0),
        "--out",
        path_str(&out),
        "--json",
    ]));
    assert_eq!(j["noise_bands"].as_array().map(Vec::len), Some(0));
    assert!(
        j["noise_bands_note"]
            .as_str()
            .unwrap()
            .contains("do not move forward"),
        "{j}"
    );

    // D4, D5, D11: heat then cool, with an implausible temperature, as CSV.
    let mut text = String::from(
        "t [s],gx [rad/s],gy [rad/s],gz [rad/s],ax [m/s^2],ay [m/s^2],az [m/s^2],temperature\n",
    );
    let back: Vec<&(f64, [f64; 6])> = rows.iter().chain(rows.iter().rev()).collect();
    for (k, (celsius, a)) in back.iter().enumerate() {
        let t = match k {
            200 => "1e30".to_string(),
            _ => format!("{celsius:.3}"),
        };
        text += &format!(
            "{:.2},{},{},{},{},{},{},{t}\n",
            k as f64 / 100.0,
            a[0],
            a[1],
            a[2],
            a[3],
            a[4],
            a[5]
        );
    }
    let csv = temp_file("heat-cool.csv", text);
    let out = temp_path("heat-cool");
    let args = [
        "thermal",
        path_str(&csv),
        "--out",
        path_str(&out),
        "--device-id",
        "1,2",
    ];
    let run = imu_ar(&[&args[..], &["--json"]].concat());
    let j = json(&run);
    // (The CSV reader refuses a cell that is not a number, with its line.)
    assert_eq!(j["n"], 12_000 - 1);
    assert_eq!(j["dropped"][0]["implausible_temperature"], 1);
    // The bands below the peak are crossed twice: the longer stretch is fitted; the top one
    // holds the turn, one stretch.
    let bands = j["noise_bands"][0]["bands"].as_array().unwrap();
    for b in &bands[..3] {
        assert_eq!(b["stretches"], 2, "{b}");
        assert!(b["n"].as_u64() < b["in_band"].as_u64(), "{b}");
    }
    assert_eq!(bands[3]["stretches"], 1);
    // ArduPilot's file: no NaN where PX4's figure is missing.
    let run = imu_ar(&[
        "thermal",
        path_str(&csv),
        "--out",
        path_str(&out),
        "--format",
        "ardupilot",
    ]);
    assert!(run.status.success());
    let parm = std::fs::read_to_string(out.join("ardupilot_tcal.parm")).unwrap();
    assert!(!parm.contains("NaN") && !parm.contains("inf"), "{parm}");
    // Kelvin.
    let kelvin: String = std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(k, l)| match (k, l.rsplit_once(',')) {
            (0, _) | (_, None) => format!("{l}\n"),
            (_, Some((head, t))) => {
                format!(
                    "{head},{}\n",
                    t.parse::<f64>()
                        .map_or(t.to_string(), |c| format!("{:.3}", c + 273.15))
                )
            }
        })
        .collect();
    let kelvin = temp_file("kelvin.csv", kelvin);
    let run = imu_ar(&[
        "thermal",
        path_str(&kelvin),
        "--out",
        path_str(&out),
        "--device-id",
        "1,2",
    ]);
    assert_one_line_failure(&run);
    assert!(
        String::from_utf8_lossy(&run.stderr).contains("kelvin"),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );

    // D6: gyro at 100 Hz, accelerometer at 50 Hz, with --noise-format: one clear line.
    let mut log = ULog::new(0);
    log.format(SENSOR_GYRO);
    log.format(SENSOR_ACCEL);
    log.subscribe(0, 0, "sensor_gyro");
    log.subscribe(0, 1, "sensor_accel");
    for (k, (celsius, a)) in samples(40_000, 0.0).iter().enumerate() {
        let t = 1_000_000 + 10_000 * k as u64;
        log.data(
            0,
            &sensor(t, t, 7, [f(a[0]), f(a[1]), f(a[2])], f(*celsius)),
        );
        if k % 2 == 0 {
            log.data(
                1,
                &sensor(t, t, 8, [f(a[3]), f(a[4]), f(a[5])], f(*celsius)),
            );
        }
    }
    let rates = temp_file("rates.ulg", log.bytes);
    let out = temp_path("rates");
    let run = imu_ar(&[
        "thermal",
        path_str(&rates),
        "--out",
        path_str(&out),
        "--noise-format",
        "kalibr",
    ]);
    assert_one_line_failure(&run);
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("rates.ulg") && e.contains("one IMU rate"), "{e}");
    assert!(!out.join("px4_thermal.params").exists(), "nothing written");

    // D8, D9: NaN gyro samples in a ULog file are not finite, not unpaired; noise says so.
    let log = paired_log(&rows, 10_000, [7, 8], |k, g| {
        if k % 50 == 0 { [f32::NAN; 3] } else { g }
    });
    let nan = temp_file("nan-gyro.ulg", log);
    let out = temp_path("nan-gyro");
    let j = json(&imu_ar(&[
        "characterise",
        path_str(&nan),
        "--out",
        path_str(&out),
        "--json",
    ]));
    assert_eq!(
        (
            j["skipped"]["non_finite"].as_u64(),
            j["skipped"]["unpaired"].as_u64()
        ),
        (Some(120), Some(0))
    );
    let run = imu_ar(&["noise", path_str(&nan), "--column", "gx"]);
    assert!(run.status.success());
    let e = String::from_utf8_lossy(&run.stderr);
    assert!(e.contains("warning") && e.contains("120 not finite"), "{e}");
}

/// A PX4 ULog file of `sensor_gyro` and `sensor_accel` (device ids `devices`) holding `rows`
/// (temperature, six axes) `period_us` apart from 1 s, the `k`-th gyro values as `gyro` makes
/// them of the row's.
fn paired_log(
    rows: &[(f64, [f64; 6])],
    period_us: u64,
    devices: [u32; 2],
    gyro: impl Fn(usize, [f32; 3]) -> [f32; 3],
) -> Vec<u8> {
    let mut log = ULog::new(0);
    log.format(SENSOR_GYRO);
    log.format(SENSOR_ACCEL);
    log.subscribe(0, 0, "sensor_gyro");
    log.subscribe(0, 1, "sensor_accel");
    for (k, (celsius, a)) in rows.iter().enumerate() {
        let t = 1_000_000 + period_us * k as u64;
        let three = |i: usize| [a[i] as f32, a[i + 1] as f32, a[i + 2] as f32];
        let celsius = *celsius as f32;
        log.data(0, &sensor(t, t, devices[0], gyro(k, three(0)), celsius));
        log.data(1, &sensor(t, t, devices[1], three(3), celsius));
    }
    log.bytes
}

fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_px4_logs_subsampled_sensor_topics_give_no_noise_model() {
    // PX4's default logger profile writes sensor_gyro and sensor_accel once a second: single
    // readings of a faster stream, whose noise density read at 1 Hz is sqrt(rate) times the
    // sensor's (16 times for 250 Hz, exit 0, before). Refused by noise and characterise,
    // naming the profile; the thermal calibration, which needs only the bias, reads them.
    let log = paired_log(&samples(600, 0.0), 1_000_000, [100, 101], |_, g| g);
    let file = temp_file("one-hz.ulg", log);
    let m = path_str(&file);
    let out = temp_path("one-hz");
    for args in [
        vec!["noise", m, "--column", "gx"],
        vec!["characterise", m, "--out", path_str(&out)],
    ] {
        let run = imu_ar(&args);
        assert_eq!(
            run.status.code(),
            Some(2),
            "{args:?}: {}",
            crate::common::stderr(&run)
        );
        assert!(
            crate::common::stderr(&run).contains("the logger's subsample of its stream"),
            "{args:?}: {}",
            crate::common::stderr(&run)
        );
    }
    let j = json(&imu_ar(&["thermal", m, "--out", path_str(&out), "--json"]));
    assert_eq!(j["n"], 600, "{j}");
    // Nor do thermal's noise bands: the noise files were written from them, exit 0, before.
    let run = imu_ar(&[
        "thermal",
        m,
        "--out",
        path_str(&out),
        "--noise-format",
        "kalibr",
    ]);
    let e = crate::common::stderr(&run);
    assert_eq!(run.status.code(), Some(2), "{e}");
    assert!(e.contains("the logger's subsample of its stream"), "{e}");
    assert!(!out.join("imu.yaml").exists());
}

#[test]
fn ardupilot_imu_messages_logged_at_25_hz_give_no_noise_model() {
    // ArduCopter writes IMU at 25 Hz unless LOG_BITMASK's IMU_FAST bit is set: single filtered
    // readings of a 1 kHz stream (N 1.3 to 2.6 times the sensor's, exit 0, before). Refused by
    // noise, characterise and thermal's noise files; the calibration reads them.
    let rows = samples(1_500, 0.0);
    let mut df = Df::new();
    for (k, (celsius, a)) in rows.iter().enumerate() {
        let three = |i: usize| [a[i] as f32, a[i + 1] as f32, a[i + 2] as f32];
        df.imu(
            1_000_000 + 40_000 * k as u64,
            0,
            three(0),
            three(3),
            *celsius as f32,
        );
    }
    let file = temp_file("copter-25-hz.bin", df.bytes);
    let m = path_str(&file);
    let out = temp_path("copter-25-hz");
    for args in [
        vec!["noise", m, "--column", "gx"],
        vec!["characterise", m, "--out", path_str(&out)],
        vec![
            "thermal",
            m,
            "--out",
            path_str(&out),
            "--format",
            "ardupilot",
            "--noise-format",
            "px4",
        ],
    ] {
        let run = imu_ar(&args);
        let e = crate::common::stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {e}");
        assert!(
            e.contains("IMU messages at 25 Hz") && e.contains("IMU_FAST"),
            "{args:?}: {e}"
        );
    }
    let j = json(&imu_ar(&[
        "thermal",
        m,
        "--out",
        path_str(&out),
        "--format",
        "ardupilot",
        "--json",
    ]));
    assert_eq!(j["n"], 1_500, "{j}");
}

#[test]
fn a_px4_logs_sensor_topics_at_rates_apart_are_named_with_their_rates() {
    // sensor_gyro at 200 Hz, sensor_accel at 10 Hz (the thermal profile's subsample) on the
    // same clock: every accelerometer sample has a gyro partner, and the gyro samples alone
    // were named as topics "published at times of their own" before. Named now with both
    // rates and the subsample; the gyro read alone gives its model.
    let rows = samples(12_000, 0.0);
    let mut log = ULog::new(0);
    log.format(SENSOR_GYRO);
    log.format(SENSOR_ACCEL);
    log.subscribe(0, 0, "sensor_gyro");
    log.subscribe(0, 1, "sensor_accel");
    for (k, (celsius, a)) in rows.iter().enumerate() {
        let t = 1_000_000 + 5_000 * k as u64;
        let three = |i: usize| [a[i] as f32, a[i + 1] as f32, a[i + 2] as f32];
        log.data(0, &sensor(t, t, 100, three(0), *celsius as f32));
        if k % 20 == 0 {
            log.data(1, &sensor(t, t, 101, three(3), *celsius as f32));
        }
    }
    let file = temp_file("rates-apart.ulg", log.bytes);
    let m = path_str(&file);
    let out = temp_path("rates-apart");
    let run = imu_ar(&["characterise", m, "--out", path_str(&out)]);
    let e = crate::common::stderr(&run);
    assert_eq!(run.status.code(), Some(2), "{e}");
    assert!(
        e.contains("sensor_gyro is logged at 200 Hz and sensor_accel at 10 Hz")
            && e.contains("sensor_accel under 50 Hz is the logger's subsample")
            && !e.contains("times of their own"),
        "{e}"
    );
    assert!(!out.exists(), "{}", out.display());
    let j = json(&imu_ar(&["noise", m, "--column", "gx", "--json"]));
    assert_eq!(j["n"], 12_000, "{j}");
}

/// [`samples`] (100 Hz) as a CSV record in SI units, sample `k` stamped at `stamp(k)` s and
/// kept where `keep(k)`, the temperature `degrees(celsius)`.
fn stamped_warm_up(
    name: &str,
    stamp: impl Fn(usize) -> f64,
    keep: impl Fn(usize) -> bool,
    degrees: impl Fn(f64) -> f64,
) -> PathBuf {
    let mut text = String::from(
        "t [s],gx [rad/s],gy [rad/s],gz [rad/s],ax [m/s^2],ay [m/s^2],az [m/s^2],temperature\n",
    );
    for (k, (celsius, axes)) in samples(120_000, 0.0).into_iter().enumerate() {
        if !keep(k) {
            continue;
        }
        text += &format!("{:.6}", stamp(k));
        for v in axes {
            text += &format!(",{v:.9e}");
        }
        text += &format!(",{:.2}\n", degrees(celsius));
    }
    temp_file(name, text)
}

#[test]
fn thermal_noise_bands_take_the_rate_as_noise_does() {
    // A host stamping reads of 10 samples 2 ms apart (a 500 Hz "clock" among 100 Hz samples):
    // noise files written at 500 Hz, N sqrt(5) too low, exit 0, before. And a record whose
    // gaps miss half its samples (every other minute kept): noise refuses it, the bands read
    // it. The calibration reads both; the noise files are refused, naming why.
    let runs = stamped_warm_up(
        "reads-of-ten.csv",
        |k| (k / 10 + 1) as f64 * 0.1 - (9 - k % 10) as f64 * 0.002,
        |_| true,
        |c| c,
    );
    let halves = stamped_warm_up(
        "every-other-minute.csv",
        |k| k as f64 * 0.01,
        |k| (k / 6_000) % 2 == 0,
        |c| c,
    );
    for (file, why) in [(&runs, "runs of 10 samples"), (&halves, "gaps miss")] {
        let out = temp_path("bands-rate");
        let m = path_str(file);
        let args = [
            "thermal",
            m,
            "--out",
            path_str(&out),
            "--format",
            "ardupilot",
        ];
        let run = imu_ar(&[&args[..], &["--noise-format", "kalibr"]].concat());
        let e = crate::common::stderr(&run);
        assert_eq!(run.status.code(), Some(2), "{m}: {e}");
        assert!(e.contains("--noise-format") && e.contains(why), "{m}: {e}");
        // No folder left behind (an empty one was, before).
        assert!(!out.exists(), "{}", out.display());
        let run = imu_ar(&[&args[..], &["--json"]].concat());
        assert_eq!(
            run.status.code(),
            Some(0),
            "{m}: {}",
            crate::common::stderr(&run)
        );
    }
}

#[test]
fn a_warm_up_in_fahrenheit_is_refused() {
    // 20 to 60 deg C written in deg F (68 to 140): read as deg C, exit 0, and INS_TCAL1_TMAX
    // 140 written (the vehicle's whole range clamped to TMIN), before.
    let file = stamped_warm_up(
        "fahrenheit.csv",
        |k| k as f64 * 0.01,
        |_| true,
        |c| 1.8 * c + 32.0,
    );
    let out = temp_path("fahrenheit");
    let calibrate = |file: &Path| {
        imu_ar(&[
            "thermal",
            path_str(file),
            "--out",
            path_str(&out),
            "--format",
            "ardupilot",
        ])
    };
    let run = calibrate(&file);
    assert_one_line_failure(&run);
    let e = crate::common::stderr(&run);
    assert!(
        e.contains("above the 85 deg C MEMS dies run at: a column in deg F"),
        "{e}"
    );
    assert!(!out.exists());
    // A cold soak, -20 to 30 deg C, in deg F (-4 to 86, its median under 85): read, with a
    // warning naming ArduPilot's TMAX range (nothing was said, before).
    let file = stamped_warm_up(
        "cold-fahrenheit.csv",
        |k| k as f64 * 0.01,
        |_| true,
        |c| 1.8 * (1.25 * c - 45.0) + 32.0,
    );
    let run = calibrate(&file);
    let e = crate::common::stderr(&run);
    assert!(
        e.contains("warning") && e.contains("past ArduPilot's INS_TCALn_TMAX range"),
        "{e}"
    );
    // The same in deg C is read.
    let file = stamped_warm_up("celsius.csv", |k| k as f64 * 0.01, |_| true, |c| c);
    let run = calibrate(&file);
    assert_eq!(
        run.status.code(),
        Some(0),
        "{}",
        crate::common::stderr(&run)
    );
    assert!(!crate::common::stderr(&run).contains("warning"));
}

/// Gyro batches of a DataFlash log: each batch's samples are placed at its header's smp_rate
/// from its first, and the time between batches is the sampler's, so no stamp checks that
/// rate: it is read, with a warning that says so (not where --rate is given). Before, the
/// stamps were read as a clock's: a sensor at 1002 Hz under a header's 1000 Hz, batches 10
/// ms apart, read 1000.04 Hz with no warning; at 1000.5 Hz with a sample skipped between
/// batches, 1000 Hz with no warning; at 1001 Hz so, 1000.023 Hz as batches back to back;
/// back to back at 1000.5 Hz with one block lost, 999.52 Hz under a warning of "39898
/// pauses"; an exact 1000 Hz with a sample skipped, and 1000.5 Hz back to back, refused as a
/// FIFO's beat or two clocks. Batches whose headers give two rates are refused.
#[test]
fn batches_are_read_at_their_headers_rate_with_a_warning_that_no_stamp_checks_it() {
    let mut state = 7u32;
    let mut noise = move || {
        state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (state >> 20) as i16 - 2048
    };
    // The sensor's rate, the samples skipped between batches (or a pause, us), a block lost
    // (batch, block), and the second half's header rate.
    type Case = (f64, f64, f64, Option<(u16, u16)>, f32);
    let cases: [Case; 9] = [
        (1002.0, 0.0, 10_000.0, None, 1000.0),
        (1000.5, 1.0, 0.0, None, 1000.0),
        (1001.0, 1.0, 0.0, None, 1000.0),
        (1000.5, 0.0, 0.0, Some((5, 3)), 1000.0),
        (1000.0, 1.0, 0.0, None, 1000.0),
        (1000.5, 0.0, 0.0, None, 1000.0),
        (1000.0, 0.0, 10_000.0, None, 2000.0),
        // Headers a float's step apart, or 0.2 %, as ArduPilot's estimate of the rate moves
        // (refused as two rates, pass 50 F5): read at their mean.
        (1000.0, 0.0, 0.0, None, 1000.0001),
        (1001.0, 0.0, 10_000.0, None, 1002.0),
    ];
    for (case, (sensor, skipped, pause_us, lost, later)) in cases.into_iter().enumerate() {
        let mut df = Df::new();
        let mut start = 1_000_000.0f64;
        for n in 0..40u16 {
            let first = start.round() as u64;
            let rate = if n < 20 { 1000.0 } else { later };
            df.isbh(first, n, 1, 0, 1000, 1024, first, rate);
            for k in 0..32u16 {
                let xyz: [[i16; 32]; 3] = std::array::from_fn(|_| std::array::from_fn(|_| noise()));
                if lost != Some((n, k)) {
                    df.isbd(first + 32_000 * u64::from(k), n, k, &xyz);
                }
            }
            df.imu(first, 0, [0.0; 3], [0.0; 3], 30.0);
            start += (1024.0 + skipped) * 1e6 / sensor + pause_us;
        }
        let bin = temp_file(&format!("batches-{case}.bin"), df.bytes);
        let path = bin.to_str().unwrap();
        let run = imu_ar(&["noise", path, "--column", "gx"]);
        let (out, e) = (crate::common::stdout(&run), crate::common::stderr(&run));
        if later > 1000.0 && later < 1005.0 {
            // Half the samples at each header's rate.
            let mean = (1000.0 + f64::from(later)) / 2.0;
            assert!(run.status.success(), "case {case}: {e}");
            let read: f64 = out
                .split("timestamps (ns): rate ")
                .nth(1)
                .and_then(|r| r.split(' ').next())
                .and_then(|r| r.parse().ok())
                .unwrap_or_else(|| panic!("case {case}: {out}"));
            assert!(
                (read / mean - 1.0).abs() < 1e-9,
                "case {case}: {read} for {mean}"
            );
            assert!(e.contains("smp_rate, their mean"), "case {case}: {e}");
            continue;
        }
        if later != 1000.0 {
            assert_eq!(run.status.code(), Some(2), "case {case}: {out}{e}");
            assert!(e.contains("sample rates from 1000 to 2000 Hz"), "{e}");
            assert!(!e.contains("  "), "one line, no runs of spaces: {e}");
            continue;
        }
        assert!(run.status.success(), "case {case}: {e}");
        assert!(
            out.contains("timestamps (ns): rate 1000 Hz"),
            "case {case}: {out}"
        );
        assert!(
            e.contains("warning: ")
                && e.contains("placed at its header's smp_rate, 1000 Hz")
                && e.contains("--rate sets the sensor's own"),
            "case {case}: {e}"
        );
        let given = [
            "noise",
            path,
            "--column",
            "gx",
            "--rate",
            &sensor.to_string(),
        ];
        let run = imu_ar(&given);
        let e = crate::common::stderr(&run);
        assert!(run.status.success(), "case {case}: {e}");
        assert!(!e.contains("smp_rate"), "case {case}: {e}");
    }
}
