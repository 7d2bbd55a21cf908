//! `imu-ar noise`: the composite model of both real records at every averaging time, its
//! hand-off to a filter, its keys, its plot and its refusals.

use std::path::{Path, PathBuf};
use std::process::Output;

use imu_ar_host::composite::Composite;
use imu_ar_host::fixtures::{AXES, real_records};
use serde_json::Value;

use crate::common;

use common::{column_file, imu_ar, json, misused, stdout, temp_file};

/// `imu-ar noise FILES --column C --rate HZ --json EXTRA..`, parsed.
fn noise(files: &[PathBuf], column: &str, rate: &str, extra: &[&str]) -> Value {
    let mut with_json = vec!["--json"];
    with_json.extend_from_slice(extra);
    json(&noise_run(files, column, rate, &with_json))
}

/// `imu-ar noise FILES --column C --rate HZ EXTRA..`.
fn noise_run(files: &[PathBuf], column: &str, rate: &str, extra: &[&str]) -> Output {
    let mut args: Vec<&str> = vec!["noise"];
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    args.extend(["--column", column, "--rate", rate]);
    args.extend_from_slice(extra);
    imu_ar(&args)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is not a number"))
}

/// The largest `tau` of the check: the whole record is explained when `explained_up_to_s`
/// reaches it.
fn longest_tau(v: &Value) -> f64 {
    f(&v["allan"].as_array().unwrap().last().unwrap()["tau_s"])
}

/// The data's Allan deviation at 1 s, read log-log between the octaves around it: the reading
/// of `N` of Kalibr and allan_variance_ros.
fn adev_at_1s(v: &Value) -> f64 {
    let rows = v["allan"].as_array().unwrap();
    let i = rows.iter().position(|r| f(&r["tau_s"]) >= 1.0).unwrap();
    let (t0, t1) = (f(&rows[i - 1]["tau_s"]), f(&rows[i]["tau_s"]));
    let (d0, d1) = (f(&rows[i - 1]["data_adev"]), f(&rows[i]["data_adev"]));
    let w = (1.0 / t0).ln() / (t1 / t0).ln();
    (d0.ln() * (1.0 - w) + d1.ln() * w).exp()
}

/// The share of the model's Allan variance that its white noise makes at the octave at or
/// above 1 s.
fn white_share_at_1s(v: &Value) -> f64 {
    let rows = v["allan"].as_array().unwrap();
    let r = rows.iter().find(|r| f(&r["tau_s"]) >= 1.0).unwrap();
    f(&v["white_noise"]).powi(2) / f(&r["tau_s"]) / f(&r["model_adev"]).powi(2)
}

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn both_real_records_are_explained_at_every_averaging_time() {
    let records = real_records().expect("the real records");
    println!("record axis ar_order gm_states N adev(1s) explained_up_to_s of longest_tau");
    for record in &records {
        for axis in AXES {
            let v = noise(&record.files, axis, "100", &[]);
            let (upto, longest) = (&v["explained_up_to_s"], longest_tau(&v));
            let order = v["ar"].get("order").map_or(0, |o| o.as_u64().unwrap());
            // The Gauss-Markov budget and the random walk; quantisation adds its two states.
            let quantization = if v["quantization"].is_null() { 0 } else { 2 };
            let states = v["phi"].as_array().unwrap().len() - quantization;
            let (n, at_1s) = (f(&v["white_noise"]), adev_at_1s(&v));
            println!(
                "{} {axis} {order} {} {n:.4e} {at_1s:.4e} {upto} {longest}",
                record.name,
                v["gauss_markov"].as_array().unwrap().len()
            );
            assert!(
                states <= 4,
                "{} {axis}: {states} filter states",
                record.name
            );
            // N against the classic reading at 1 s, where white noise dominates there and the
            // model explains the data up to there.
            if white_share_at_1s(&v) >= 0.5 && f(upto) >= 1.0 {
                assert!(
                    (n / at_1s - 1.0).abs() <= 0.1,
                    "{} {axis}: N {n} against ADEV(1 s) {at_1s}",
                    record.name
                );
            }
            let accel_line = record.name == "ADIS16405" && axis.starts_with('a');
            if !accel_line {
                assert_eq!(f(upto), longest, "{} {axis}: {v}", record.name);
                continue;
            }
            // The ADIS16405 accelerometers have a line near 0.58 Hz (an Allan bump at
            // 0.64 s): without oscillators the text names the failing range and the line...
            let mut args = vec!["noise"];
            args.extend(record.files.iter().map(|f| f.to_str().unwrap()));
            args.extend(["--column", axis, "--rate", "100"]);
            let text = stdout(&imu_ar(&args));
            let line = text
                .lines()
                .find(|l| l.starts_with("check fails at tau 0.64"))
                .unwrap_or_else(|| panic!("{axis}: no failure named:\n{text}"));
            assert!(line.contains("near 0.580 Hz"), "{axis}: {line}");
            // ...and one oscillator (two states) in a budget of five explains every octave.
            let v = noise(
                &record.files,
                axis,
                "100",
                &["--oscillators", "--gm-states", "5"],
            );
            let oscillator = v["gauss_markov"]
                .as_array()
                .unwrap()
                .iter()
                .find_map(|g| g.get("frequency_hz").map(f))
                .expect("an oscillator");
            println!(
                "  with --oscillators --gm-states 5: line at {oscillator:.3} Hz, {v:.0}",
                v = v["explained_up_to_s"]
            );
            assert!((0.5..0.7).contains(&oscillator), "{axis}: {oscillator} Hz");
            assert_eq!(f(&v["explained_up_to_s"]), longest_tau(&v), "{axis}: {v}");
        }
    }
}

/// White noise, one Gauss-Markov term and a random walk at 100 Hz, as a CSV file.
fn composite_record(name: &str) -> (Composite, PathBuf) {
    let truth = Composite {
        dt: 0.01,
        white: 0.01,
        quantization: 0.0,
        gm: vec![(0.004, 5.0)],
        random_walk: 2e-4,
    };
    let x = truth.simulate(1 << 19, 11);
    let path = column_file(name, x.iter().map(|v| v.to_string()));
    (truth, path)
}

#[test]
fn identifies_a_simulated_composite_with_intervals_around_the_truth() {
    let (truth, path) = composite_record("noise-identify.csv");
    let files = [path];
    let v = noise(&files, "x", "100", &["--ar-order", "0"]);
    let within = |b: &Value, want: f64| f(&b["low"]) <= want && want <= f(&b["high"]);
    let i = &v["intervals"];
    assert!(
        (f(&v["white_noise"]) / truth.white - 1.0).abs() < 0.03,
        "{v}"
    );
    assert!(within(&i["white_noise"], truth.white), "{i}");
    let k = f(&v["random_walk"]);
    assert!((k / truth.random_walk - 1.0).abs() < 0.3, "K {k}: {v}");
    assert!(within(&i["random_walk"], truth.random_walk), "{i}");
    let terms = v["gauss_markov"].as_array().unwrap();
    assert_eq!(terms.len(), 1, "{v}");
    let t = &i["gauss_markov"][0]["correlation_time_s"];
    assert!(within(t, truth.gm[0].1), "{t}");
    assert_eq!(v["budget_limited"], Value::Bool(false));
    assert_eq!(v["curve_fit"], Value::Bool(false));
    // Each octave is checked at two standard errors, a 95 % test of its own: the true model
    // failed one somewhere on a quarter of the records of the identification campaign.
    let failing = v["allan"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["agrees"] == Value::Bool(false))
        .count();
    assert!(failing <= 1, "{v}");
}

#[test]
fn hands_a_simulated_composite_to_a_filter_at_its_rate() {
    let (truth, path) = composite_record("noise-composite.csv");
    let files = [path];
    let v = noise(
        &files,
        "x",
        "100",
        &["--ar-order", "0", "--filter-rate", "10"],
    );
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    let mut documented = [
        "rate_hz",
        "n",
        "white_noise",
        "quantization",
        "random_walk",
        "rate_ramp",
        "bias_instability",
        "gauss_markov",
        "budget_limited",
        "curve_fit",
        "intervals",
        "ar",
        "phi",
        "q",
        "p0",
        "allan",
        "explained_up_to_s",
        "check_z",
    ];
    documented.sort_unstable();
    assert_eq!(keys, documented);
    assert_eq!(v["ar"], Value::Null);
    assert_eq!(v["rate_ramp"], Value::Null);
    assert_eq!(v["n"], 1 << 19);
    assert!(
        (f(&v["white_noise"]) / truth.white - 1.0).abs() < 0.03,
        "{v}"
    );
    assert_eq!(f(&v["explained_up_to_s"]), longest_tau(&v));

    // The filter's states: one per Gauss-Markov term, the random walk, then the quantisation
    // pair `[q_k/Dt, q_(k-1)/Dt]` where the fit gives quantisation; each block is the exact
    // discretisation at the filter's step of 0.1 s.
    let dt = 0.1;
    let gm = v["gauss_markov"].as_array().unwrap();
    let (phi, q, p0) = (&v["phi"], &v["q"], &v["p0"]);
    let n = gm.len() + 1;
    let pair = v["quantization"]
        .as_f64()
        .map(|quantization| (n, quantization));
    let states = n + pair.map_or(0, |_| 2);
    assert_eq!(phi.as_array().unwrap().len(), states);
    for i in 0..states {
        for k in (0..states).filter(|k| *k != i) {
            // Within the pair, q_(k-1) takes q_k's value.
            let within = pair.is_some_and(|(at, _)| i == at + 1 && k == at);
            assert_eq!(f(&phi[i][k]), if within { 1.0 } else { 0.0 });
            assert_eq!(f(&q[i][k]), 0.0);
            assert_eq!(f(&p0[i][k]), 0.0);
        }
    }
    if let Some((at, quantization)) = pair {
        let variance = (quantization / dt).powi(2);
        assert_eq!(f(&phi[at][at]), 0.0);
        assert_eq!(f(&phi[at + 1][at + 1]), 0.0);
        assert!((f(&q[at][at]) / variance - 1.0).abs() < 1e-12);
        assert_eq!(f(&q[at + 1][at + 1]), 0.0);
        assert!((f(&p0[at][at]) / variance - 1.0).abs() < 1e-12);
        assert!((f(&p0[at + 1][at + 1]) / variance - 1.0).abs() < 1e-12);
    }
    for (i, g) in gm.iter().enumerate() {
        let (s, t) = (f(&g["sigma"]), f(&g["correlation_time_s"]));
        assert!((f(&phi[i][i]) - (-dt / t).exp()).abs() < 1e-12);
        assert!((f(&q[i][i]) / (s * s * (1.0 - (-2.0 * dt / t).exp())) - 1.0).abs() < 1e-9);
        assert!((f(&p0[i][i]) / (s * s) - 1.0).abs() < 1e-12);
    }
    let k = f(&v["random_walk"]);
    let last = n - 1;
    assert_eq!(f(&phi[last][last]), 1.0);
    assert!((f(&q[last][last]) / (k * k * dt) - 1.0).abs() < 1e-12);
    // The random walk starts with the variance it reaches over the record.
    let span = (1 << 19) as f64 * 0.01;
    assert!((f(&p0[last][last]) / (k * k * span) - 1.0).abs() < 1e-12);
}

#[test]
fn draws_the_decomposition_plot() {
    let (_, path) = composite_record("noise-plot.csv");
    let png = crate::common::temp_path("noise.png");
    let out = imu_ar(&[
        "noise",
        path.to_str().unwrap(),
        "--column",
        "x",
        "--rate",
        "100",
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert!(stdout(&out).contains("explained_up_to_s"));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert!(bytes.len() > 10_000);
}

/// `--plot PLOT` is refused before the input (a file that does not exist) is read.
fn plot_refused(plot: &Path, expected: &str) {
    misused(
        &[
            "noise",
            "/nonexistent/input.csv",
            "--column",
            "x",
            "--rate",
            "100",
            "--plot",
            plot.to_str().unwrap(),
        ],
        expected,
    );
}

#[test]
fn refuses_bad_input_with_one_line_and_nothing_on_stdout() {
    let constant = column_file("noise-constant.csv", (0..1000).map(|_| "1.5".to_string()));
    let constant = constant.to_str().unwrap();
    misused(
        &["noise", constant, "--column", "x", "--rate", "100"],
        "constant",
    );
    let short = column_file("noise-short.csv", ["1", "2", "4"].map(String::from));
    let short = short.to_str().unwrap();
    misused(
        &["noise", short, "--column", "x", "--rate", "100"],
        "1 Allan octave(s), at least 2",
    );
    let nan = temp_file("noise-nan.csv", "x\n1\n2\nNaN\n3\n5\n");
    let nan = nan.to_str().unwrap();
    misused(
        &["noise", nan, "--column", "x", "--rate", "100"],
        "'NaN' is not a finite number",
    );
    let good = column_file(
        "noise-good.csv",
        (0..400).map(|i| ((i * 37) % 11).to_string()),
    );
    let good = good.to_str().unwrap();
    let base = ["noise", good, "--column", "x", "--rate", "100"];
    let with = |extra: &[&str], expected: &str| {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        misused(&args, expected);
    };
    with(&["--gm-states", "9"], "--gm-states 9: at most 8");
    with(&["--ar-order", "33"], "--ar-order 33");
    with(&["--filter-rate", "0"], "--filter-rate 0");
    with(&["--decimate", "0"], "--decimate 0");
    with(&["--decimate", "200"], "1 Allan octave(s)");
    misused(
        &["noise", good, "--column", "x", "--rate", "-1"],
        "--rate -1",
    );
    plot_refused(Path::new("/tmp/plot.txt"), "must name a .png file");
    plot_refused(Path::new("/nonexistent/folder/plot.png"), "does not exist");
    // A folder in the way is named so ("must name a .png file", before).
    let folder = crate::common::temp_path("plot-folder.png");
    std::fs::create_dir_all(&folder).unwrap();
    plot_refused(&folder, "is a directory; name a .png file");
    // A plot that cannot be created is named with the system's reason (a plotting library's
    // nested error values, before).
    if Path::new("/proc/self").exists() {
        with(
            &["--plot", "/proc/x.png"],
            "--plot /proc/x.png: cannot draw: x.png: cannot be written: No such file or directory",
        );
    }
}

/// `column` of a temp file: a white-noise record of 4096 samples times `scale`.
fn scaled_white(name: &str, scale: f64) -> PathBuf {
    let mut seed = 77u64;
    let values = (0..4096).map(|_| {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        let u = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        format!("{:e}", u * scale)
    });
    column_file(name, values)
}

#[test]
fn fits_any_magnitude_alike() {
    let one = noise(
        &[scaled_white("noise-one.csv", 1.0)],
        "x",
        "100",
        &["--ar-order", "0"],
    );
    for scale in [1e-150, 1e-80, 1e100, 1e150] {
        let file = scaled_white(&format!("noise-scaled-{scale:e}.csv"), scale);
        let v = noise(&[file], "x", "100", &["--ar-order", "0"]);
        let ratio = f(&v["white_noise"]) / scale / f(&one["white_noise"]);
        assert!((ratio - 1.0).abs() < 1e-6, "scale {scale:e}: {v}");
        // The intervals too (before, past 1e82 their upper ends were null, and below 1e-74
        // they had no width).
        let intervals = v["intervals"].as_object().unwrap();
        for (key, b) in intervals.iter().filter(|(_, b)| b.get("high").is_some()) {
            for end in ["low", "high"] {
                let (got, want) = (f(&b[end]), f(&one["intervals"][key][end]) * scale);
                let close = got == want || (got / want - 1.0).abs() < 1e-6;
                assert!(close, "scale {scale:e}: {key} {end} {got:e}, want {want:e}");
            }
        }
        assert_eq!(
            v["explained_up_to_s"], one["explained_up_to_s"],
            "scale {scale:e}"
        );
    }
}

#[test]
fn refuses_rates_and_filter_steps_that_overflow() {
    let file = scaled_white("noise-rates.csv", 1.0);
    let file = file.to_str().unwrap();
    for rate in ["1e-300", "1e300"] {
        misused(&["noise", file, "--column", "x", "--rate", rate], "tau^2");
    }
    let quantised = column_file(
        "noise-quantised.csv",
        (0..4096).map(|i| ((i * 7919) % 5).to_string()),
    );
    misused(
        &[
            "noise",
            quantised.to_str().unwrap(),
            "--column",
            "x",
            "--rate",
            "100",
            "--filter-rate",
            "1e300",
        ],
        "no filter form at this step",
    );
}

#[test]
fn names_a_plot_it_cannot_write_and_refuses_control_characters() {
    let file = scaled_white("noise-unwritable.csv", 1.0);
    let file = file.to_str().unwrap();
    let base = ["noise", file, "--column", "x", "--rate", "100"];
    let mut args = base.to_vec();
    args.extend(["--plot", "/proc/imu-ar-noise.png"]);
    misused(&args, "--plot /proc/imu-ar-noise.png: cannot draw");
    let mut args = base.to_vec();
    args.extend(["--unit", "deg\n/s"]);
    misused(
        &args,
        "--unit \"deg\\n/s\": must not contain control characters",
    );
}

#[test]
fn a_record_no_ar_model_describes_gets_no_ar_part() {
    // Alternating +-1: perfectly predictable, so Burg cannot fit it; the tool fits the
    // composite without an AR part instead of failing.
    let file = column_file(
        "noise-alternating.csv",
        (0..1000).map(|i| if i % 2 == 0 { "1" } else { "-1" }.to_string()),
    );
    let out = imu_ar(&[
        "noise",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--rate",
        "100",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = stdout(&out);
    assert!(text.contains("ar null"), "{text}");
    common::no_nan_inf(&text);
}

#[test]
fn a_trend_gets_no_ar_part_and_out_of_range_magnitudes_are_named() {
    // A ramp: Burg fits it, but not with a stationary model; the automatic order falls back.
    let ramp = column_file(
        "noise-ramp.csv",
        (0..1000).map(|i| format!("{}", f64::from(i) * 0.01)),
    );
    let v = noise(&[ramp], "x", "100", &[]);
    assert_eq!(v["ar"], Value::Null);
    let huge = scaled_white("noise-huge.csv", 1e153);
    let huge = huge.to_str().unwrap();
    misused(
        &["noise", huge, "--column", "x", "--rate", "100"],
        "overflows f64",
    );
    let tiny = scaled_white("noise-tiny.csv", 1e-300);
    let tiny = tiny.to_str().unwrap();
    misused(
        &["noise", tiny, "--column", "x", "--rate", "100"],
        "underflows f64",
    );
}

#[test]
fn a_record_without_a_walk_names_the_bound_the_files_carry() {
    let file = scaled_white("noise-no-walk.csv", 1.0);
    let v = noise(
        std::slice::from_ref(&file),
        "x",
        "100",
        &["--ar-order", "0"],
    );
    assert!(v["random_walk"].is_null(), "{v}");
    let high = f(&v["intervals"]["random_walk"]["high"]);
    assert!(high > 0.0, "{v}");
    let files = std::slice::from_ref(&file);
    let text = stdout(&noise_run(files, "x", "100", &["--ar-order", "0"]));
    let line = text
        .lines()
        .find(|l| l.starts_with("random_walk "))
        .unwrap_or_else(|| panic!("{text}"));
    let said = line
        .split_once("the record shows no walk; at most ")
        .and_then(|(_, rest)| rest.split(' ').next())
        .and_then(|n| n.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("{line}"));
    assert_eq!(said, high, "{line}");
}

/// A random walk that dominates from the first octaves: BIC's AR part of the samples has a root
/// near 1 there. It is no short-term colouring, and the fit goes without it: before, its white
/// equivalent became `N` (up to five times the truth) and it took the walk, so that `K` went
/// missing.
#[test]
fn a_walk_that_dominates_is_not_taken_by_the_ar_part() {
    let truth = Composite {
        dt: 0.01,
        white: 1e-5,
        quantization: 0.0,
        gm: vec![],
        random_walk: 5e-4,
    };
    for seed in 0..4 {
        let x = truth.simulate(60_000, 1000 + seed);
        let file = column_file(
            &format!("noise-walk-dominates-{seed}.csv"),
            x.iter().map(|v| v.to_string()),
        );
        let v = noise(&[file], "x", "100", &[]);
        let n = f(&v["white_noise"]);
        let k = f(&v["random_walk"]);
        assert!(
            (n / truth.white - 1.0).abs() < 0.03,
            "seed {seed}: N {n}: {v}"
        );
        assert!(
            (k / truth.random_walk - 1.0).abs() < 0.3,
            "seed {seed}: K {k}: {v}"
        );
        let i = &v["intervals"];
        assert!(f(&i["white_noise"]["low"]) <= truth.white, "{i}");
        assert!(truth.white <= f(&i["white_noise"]["high"]), "{i}");
        for key in ["white_noise", "random_walk", "bias_instability"] {
            let b = &i[key];
            let inside = f(&b["low"]) <= f(&b["value"]) && f(&b["value"]) <= f(&b["high"]);
            assert!(inside, "seed {seed}: {key} {b}");
        }
    }
}

/// Uniform noise whose level steps up 10 % halfway: the record's eighths show it, the text and
/// the JSON name it, and `N`'s interval counts it; the same noise without the step shows none.
#[test]
fn a_level_that_moves_is_named_and_counted() {
    let n = 1usize << 16;
    let stepped = |name: &str, step: f64| {
        let mut seed = 91u64;
        let values = (0..n).map(move |i| {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            let u = (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            format!("{:e}", u * if i < n / 2 { 1.0 } else { step })
        });
        column_file(name, values)
    };
    let args = ["--ar-order", "0"];
    let still = noise(&[stepped("noise-level-still.csv", 1.0)], "x", "100", &args);
    assert!(still["intervals"]["level_drift"].is_null(), "{still}");
    let file = stepped("noise-level-moves.csv", 1.1);
    let moves = noise(std::slice::from_ref(&file), "x", "100", &args);
    let drift = &moves["intervals"]["level_drift"];
    // Eighths at 1.0 and 1.1 in the deviation: a spread of about 5 %.
    let spread = f(&drift["spread"]);
    assert!((0.03..0.07).contains(&spread), "{moves}");
    let width = |v: &Value| {
        let i = &v["intervals"]["white_noise"];
        f(&i["high"]) / f(&i["low"])
    };
    assert!(
        width(&moves) > 2.0 * width(&still) - 1.0,
        "{moves}\n{still}"
    );
    let text = stdout(&noise_run(&[file], "x", "100", &args));
    assert!(
        text.contains("the record's short-term level moves"),
        "{text}"
    );
}

#[test]
fn a_32_bit_counter_of_us_or_ms_is_read_on_past_its_wrap() {
    // 1 kHz stamped by a microcontroller's micros() (whole us, on 32 bits), begun 4.967 s
    // before it wraps (pass 46 F3: "not after the one before", and with --drop-backward
    // "dropped 15032 samples in a row"); the same samples stamped past 2^32 us are the
    // reference. And millis() at 100 Hz past its wrap.
    // (splitmix64 of k: white.)
    let value = |k: u64| {
        let mut z = k.wrapping_add(1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for (unit, per_second, start) in [("us", 1_000_000u64, 4_290_000_000u64), ("ms", 1000, 0)] {
        let rate = if unit == "us" { 1000 } else { 100 };
        let start = if unit == "ms" {
            (1u64 << 32) - 2000
        } else {
            start
        };
        let step = per_second / rate;
        let rows = |wrap: bool| {
            let mut s = format!("t_{unit},gx\n");
            for k in 0..20_000u64 {
                let t = start + k * step + (k % 3);
                let t = if wrap { t % (1u64 << 32) } else { t };
                s += &format!("{t},{}\n", value(k));
            }
            s
        };
        let wrapped = temp_file(&format!("wrapped-{unit}.csv"), rows(true));
        let straight = temp_file(&format!("straight-{unit}.csv"), rows(false));
        let run = imu_ar(&[
            "noise",
            wrapped.to_str().unwrap(),
            "--column",
            "gx",
            "--json",
        ]);
        let e = common::stderr(&run);
        assert!(run.status.success(), "{unit}: {e}");
        assert!(
            e.contains(&format!(
                "counts whole {unit} on 32 bits and wrapped 1 time"
            )),
            "{unit}: {e}"
        );
        let reference = imu_ar(&[
            "noise",
            straight.to_str().unwrap(),
            "--column",
            "gx",
            "--json",
        ]);
        assert!(common::stderr(&reference).is_empty());
        let (a, b) = (json(&run), json(&reference));
        assert_eq!(a["rate_hz"], b["rate_hz"], "{unit}");
        assert_eq!(a["n"], 20_000, "{unit}");
        assert_eq!(
            a["axes"][0]["model"]["white_noise"], b["axes"][0]["model"]["white_noise"],
            "{unit}"
        );
    }
    // A stamp that goes back from nowhere near the counter's top is no wrap: refused.
    let mut s = String::from("t_us,gx\n");
    for k in 0..20_000u64 {
        let t = 2_000_000_000 + k * 1000 - if k >= 10_000 { 1_999_990_000 } else { 0 };
        s += &format!("{t},{}\n", value(k));
    }
    let back = temp_file("back-not-wrapped.csv", s);
    let run = imu_ar(&["noise", back.to_str().unwrap(), "--column", "gx"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(common::stderr(&run).contains("is not after the one before"));
}
