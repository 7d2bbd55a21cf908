//! The `imu-ar` tool: outputs, the published ADIS16405 Allan table, and every bad input.

use std::path::{Path, PathBuf};

use imu_ar_host::fixtures::data_dir;
use std::process::{Command, Output};

fn imu_ar(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-ar"))
        .args(args)
        .output()
        .expect("run imu-ar")
}

/// A file in the temp directory with the given contents.
fn temp_file(name: &str, contents: &str) -> PathBuf {
    let path = std::env::temp_dir().join(format!("imu-ar-cli-{}-{name}", std::process::id()));
    std::fs::write(&path, contents).unwrap();
    path
}

fn json(out: &Output) -> serde_json::Value {
    assert!(
        out.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// A temp file `name` holding `n` samples (column `x`, 100 Hz) of an AR(2) whose a_1 drifts
/// linearly from 1.5 to 1.0 (a_2 = -0.7, unit innovation variance): a batch model fitted on
/// the first half is stale on the second.
fn drift_record(name: &str, n: &str) -> PathBuf {
    let out = imu_ar(&[
        "simulate", "--a", "1.5,-0.7", "--a-end", "1.0,-0.7", "--sigma", "1", "--n", n, "--seed",
        "4", "--rate", "100",
    ]);
    assert!(out.status.success());
    temp_file(name, &String::from_utf8(out.stdout).unwrap())
}

/// `imu-ar fit FILE --column x --method M --order P --json EXTRA..`, parsed.
fn fit_json(file: &Path, method: &str, order: &str, extra: &[&str]) -> serde_json::Value {
    let file = file.to_str().unwrap();
    let mut args = vec![
        "fit", file, "--column", "x", "--method", method, "--order", order,
    ];
    args.extend_from_slice(extra);
    args.push("--json");
    json(&imu_ar(&args))
}

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn adev_reproduces_the_published_adis16405_table() {
    let dir = data_dir().expect("the real records: ../shared/data/imu or IMU_AR_DATA (see README)");
    let part1 = dir.join("adis16405_imu1_part1.csv");
    let part2 = dir.join("adis16405_imu1_part2.csv");
    let reference =
        std::fs::read_to_string(dir.join("adis16405_imu1_allan_reference.csv")).unwrap();
    let mut worst = 0.0f64;
    for channel in ["gx", "gy", "gz", "ax", "ay", "az"] {
        let out = imu_ar(&[
            "adev",
            part1.to_str().unwrap(),
            part2.to_str().unwrap(),
            "--column",
            channel,
            "--rate",
            "100",
            "--json",
        ]);
        let v = json(&out);
        assert_eq!(v["n"], 1_000_000);
        let tau = v["tau_s"].as_array().unwrap();
        let avar = v["avar"].as_array().unwrap();
        let rows: Vec<Vec<&str>> = reference
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|r| r[0] == channel)
            .collect();
        assert_eq!(rows.len(), 18, "{channel}");
        for row in rows {
            let level: usize = row[1].parse().unwrap();
            let want_tau: f64 = row[2].parse().unwrap();
            let want: f64 = row[7].parse().unwrap();
            let got_tau = tau[level - 1].as_f64().unwrap();
            let got = avar[level - 1].as_f64().unwrap();
            assert!(
                (got_tau - want_tau).abs() < 1e-12,
                "{channel} level {level}: tau {got_tau}"
            );
            let rel = (got - want).abs() / want;
            worst = worst.max(rel);
            assert!(
                rel < 1e-6,
                "{channel} tau {want_tau}: {got:e} vs {want:e} ({rel:e})"
            );
        }
    }
    println!("largest relative difference to the published table: {worst:e}");
}

#[test]
fn fit_reports_the_documented_keys_and_convention() {
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "0.5", "--n", "20000", "--seed", "7", "--rate", "100",
    ]);
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    assert!(csv.starts_with("t_s,x\n0,"));
    assert_eq!(csv.lines().count(), 20_001);
    let file = temp_file("ar1.csv", &csv);
    for method in ["ls", "yule-walker", "burg"] {
        let v = fit_json(&file, method, "1", &["--rate", "100"]);
        assert_eq!(v["method"], method);
        assert_eq!(v["scalar"], "f64");
        assert_eq!(
            (v["order"].as_u64(), v["n"].as_u64()),
            (Some(1), Some(20_000))
        );
        // x[n] = a_1 x[n-1] + w: a_1 near +0.9, not -0.9.
        let a1 = v["a"][0].as_f64().unwrap();
        assert!((a1 - 0.9).abs() < 0.01, "{method}: a_1 = {a1}");
        let var = v["noise_variance"].as_f64().unwrap();
        assert!((var - 0.25).abs() < 0.01, "{method}: variance {var}");
        assert!(v["mean"].as_f64().unwrap().abs() < 0.1);
        assert_eq!(v["rate_hz"], 100.0);
        let tc = v["gauss_markov"]["correlation_time_s"].as_f64().unwrap();
        assert!(
            (tc - 0.01 / -(0.9f64.ln())).abs() < 0.01,
            "{method}: T_c {tc}"
        );
        assert_eq!(v.get("reflection").is_some(), method != "ls");
    }
    let v = json(&imu_ar(&[
        "order",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--max-order",
        "5",
        "--method",
        "burg",
        "--json",
    ]));
    for key in ["aic", "aicc", "bic", "fpe"] {
        assert_eq!(v["criteria"][key].as_array().unwrap().len(), 6, "{key}");
        assert_eq!(v["selected"][key], 1, "{key} should select the true order");
    }
    std::fs::remove_file(file).unwrap();
}

/// Six input files for a misuse case, named after it: good, text cell, NaN cell, empty,
/// header only, constant. Removed when dropped.
struct Inputs([PathBuf; 6]);

impl Inputs {
    fn new(case: &str) -> Self {
        let contents = [
            "# a comment\nt_s,x\n0,1\n0.01,2\n0.02,1.5\n0.03,0.5\n".to_string(),
            "t_s,x\n0,1\n0.01,abc\n".to_string(),
            "t_s,x\n0,1\n0.01,2\n0.02,NaN\n".to_string(),
            String::new(),
            "t_s,x\n".to_string(),
            format!("x\n{}", "3\n".repeat(50)),
        ];
        let names = ["good", "text", "nan", "empty", "header", "constant"];
        Self(core::array::from_fn(|i| {
            temp_file(&format!("{case}-{}.csv", names[i]), &contents[i])
        }))
    }

    fn paths(&self) -> [&str; 6] {
        core::array::from_fn(|i| self.0[i].to_str().unwrap())
    }
}

impl Drop for Inputs {
    fn drop(&mut self) {
        for f in &self.0 {
            let _ = std::fs::remove_file(f);
        }
    }
}

/// `imu-ar ARGS` exits with status 2, prints nothing on stdout and one line on stderr that
/// contains `expected`.
fn misused(args: &[&str], expected: &str) {
    let out = imu_ar(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{args:?}: status {:?}, stderr {stderr}",
        out.status
    );
    assert!(out.stdout.is_empty(), "{args:?}: wrote to stdout");
    assert_eq!(
        stderr.lines().count(),
        1,
        "{args:?}: stderr is not one line: {stderr}"
    );
    assert!(stderr.starts_with("imu-ar: "), "{args:?}: {stderr}");
    assert!(
        stderr.contains(expected),
        "{args:?}: {stderr:?} does not contain {expected:?}"
    );
}

/// One test per misuse: `name: |[good, text, nan, empty, header, constant]| (args, expected)`.
macro_rules! misuse {
    ($($name:ident: $case:expr;)*) => {
        $(
            #[test]
            fn $name() {
                let inputs = Inputs::new(stringify!($name));
                #[allow(unused_variables)]
                let case: fn([&str; 6]) -> (Vec<&str>, String) = $case;
                let (args, expected) = case(inputs.paths());
                misused(&args, &expected);
            }
        )*
    };
}

misuse! {
    missing_file: |[g, t, n, e, h, c]| (
        vec!["fit", "/nonexistent/log.csv", "--column", "x", "--method", "ls", "--order", "1"],
        "/nonexistent/log.csv: cannot open".into(),
    );
    missing_column: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "gq", "--method", "ls", "--order", "1"],
        format!("{g}: no column 'gq' (columns: t_s, x)"),
    );
    non_numeric_cell: |[g, t, n, e, h, c]| (
        vec!["fit", t, "--column", "x", "--method", "ls", "--order", "1"],
        format!("{t}:3: column 'x': 'abc' is not a number"),
    );
    nan_cell: |[g, t, n, e, h, c]| (
        vec!["fit", n, "--column", "x", "--method", "ls", "--order", "1"],
        format!("{n}:4: column 'x': 'NaN' is not a finite number"),
    );
    empty_file: |[g, t, n, e, h, c]| (
        vec!["adev", e, "--column", "x", "--rate", "100"],
        format!("{e}: empty file"),
    );
    header_only: |[g, t, n, e, h, c]| (
        vec!["adev", h, "--column", "x", "--rate", "100"],
        format!("{h}: no data rows"),
    );
    too_few_samples_for_the_order: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "3"],
        format!("{g}: 4 samples given, at least 8 needed"),
    );
    order_above_32: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "33"],
        "--order 33: the order must be 1 to 32".into(),
    );
    order_zero: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "0"],
        "--order 0: the order must be 1 to 32".into(),
    );
    max_order_above_32: |[g, t, n, e, h, c]| (
        vec!["order", g, "--column", "x", "--method", "ls", "--max-order", "40"],
        "--max-order 40: the order must be 1 to 32".into(),
    );
    constant_data: |[g, t, n, e, h, c]| (
        vec!["fit", c, "--column", "x", "--method", "burg", "--order", "1"],
        format!("{c}: data have zero variance"),
    );
    negative_rate: |[g, t, n, e, h, c]| (
        vec!["adev", g, "--column", "x", "--rate", "-5"],
        "--rate -5: must be a positive number".into(),
    );
    zero_rate: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "1", "--rate", "0"],
        "--rate 0: must be a positive number".into(),
    );
    unknown_method: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "kalman", "--order", "1"],
        "invalid value 'kalman' for '--method".into(),
    );
    order_not_a_number: |[g, t, n, e, h, c]| (
        vec!["fit", g, "--column", "x", "--method", "ls", "--order", "two"],
        "invalid value 'two' for '--order".into(),
    );
    non_stationary_simulation: |[g, t, n, e, h, c]| (
        vec!["simulate", "--a", "1.0", "--sigma", "1", "--n", "10", "--seed", "1"],
        "the model is not stationary".into(),
    );
    nan_sigma: |[g, t, n, e, h, c]| (
        vec!["simulate", "--a", "0.5", "--sigma", "nan", "--n", "10", "--seed", "1"],
        "--sigma NaN: must be finite".into(),
    );
    missing_argument: |[g, t, n, e, h, c]| (
        vec!["adev", g, "--rate", "100"],
        "the following required arguments were not provided".into(),
    );
}

#[test]
fn fits_equal_statsmodels() {
    // `imu-ar simulate --a 1.2,-0.5,0.1 --sigma 1 --n 3000 --seed 3`, fitted with statsmodels
    // 0.14: AutoReg(x - x.mean(), lags=3, trend='n'), yule_walker(x, 3, method='mle'),
    // burg(x, 3, demean=True). The numbers below are statsmodels' output.
    let out = imu_ar(&[
        "simulate",
        "--a",
        "1.2,-0.5,0.1",
        "--sigma",
        "1",
        "--n",
        "3000",
        "--seed",
        "3",
    ]);
    assert!(out.status.success());
    let file = temp_file("statsmodels.csv", &String::from_utf8(out.stdout).unwrap());
    let cases: [(&str, [f64; 3], Option<f64>); 3] = [
        (
            "ls",
            [
                1.1711062400129162,
                -0.48276460600773013,
                0.09581430632893939,
            ],
            Some(1.0158118582253695),
        ),
        (
            "yule-walker",
            [
                1.1708211421020744,
                -0.48229398124751366,
                0.09560095902769526,
            ],
            Some(1.0152353133129488),
        ),
        // statsmodels normalises Burg's sigma2 differently; the coefficients agree.
        (
            "burg",
            [
                1.1710606512565502,
                -0.48265469358722257,
                0.09579311373656321,
            ],
            None,
        ),
    ];
    for (method, a, variance) in cases {
        let v = fit_json(&file, method, "3", &[]);
        for k in 0..3 {
            let got = v["a"][k].as_f64().unwrap();
            assert!(
                (got - a[k]).abs() < 1e-10,
                "{method} a_{}: {got} vs {}",
                k + 1,
                a[k]
            );
        }
        if let Some(var) = variance {
            let got = v["noise_variance"].as_f64().unwrap();
            assert!(
                (got - var).abs() < 1e-10,
                "{method} variance: {got} vs {var}"
            );
        }
    }
    std::fs::remove_file(file).unwrap();
}

#[test]
fn recursive_fits_and_the_drifting_ar2_comparison() {
    let file = drift_record("drift.csv", "100000");
    let f = file.to_str().unwrap();
    for lambda in ["0.99", "0.999"] {
        let v = json(&imu_ar(&[
            "compare", f, "--column", "x", "--order", "2", "--lambda", lambda, "--json",
        ]));
        let (batch, rls, lattice) = (
            v["batch_mse"].as_f64().unwrap(),
            v["rls_mse"].as_f64().unwrap(),
            v["lattice_mse"].as_f64().unwrap(),
        );
        println!(
            "lambda {lambda}: batch {batch:.4}, RLS {rls:.4}, lattice {lattice:.4}, {:.1} % lower",
            v["reduction_percent"]
        );
        assert!(lattice < batch && rls < batch, "lambda {lambda}: {v}");
        assert!(
            (rls - lattice).abs() < 1e-9 * lattice,
            "RLS and lattice solve the same problem"
        );
        // So does the SFTF, which holds at p = 2 and these lambdas.
        assert_eq!(v["sftf_restarts"], 0, "lambda {lambda}: {v}");
        let sftf = v["sftf_mse"].as_f64().unwrap();
        assert!((sftf - lattice).abs() < 1e-9 * lattice, "{v}");
        assert_eq!(
            (v["n_train"].as_u64(), v["n_eval"].as_u64()),
            (Some(50_000), Some(50_000))
        );
    }
    // The recursive fits report the documented keys; f32 and f64 agree closely, and RLS and
    // the SFTF equal the lattice in f64.
    let f64_fit = fit_json(
        &file,
        "lattice",
        "2",
        &["--lambda", "0.999", "--delta", "0.5"],
    );
    let f32_fit = fit_json(
        &file,
        "lattice",
        "2",
        &["--lambda", "0.999", "--delta", "0.5", "--scalar", "f32"],
    );
    let rls_fit = fit_json(&file, "rls", "2", &["--lambda", "0.999", "--delta", "0.5"]);
    let sftf_fit = fit_json(&file, "sftf", "2", &["--lambda", "0.999", "--delta", "0.5"]);
    assert_eq!(
        (sftf_fit["method"].as_str(), sftf_fit["restarts"].as_u64()),
        (Some("sftf"), Some(0))
    );
    assert_eq!(f32_fit["scalar"], "f32");
    let fixed_fit = fit_json(
        &file,
        "lattice",
        "2",
        &["--lambda", "0.999", "--delta", "0.5", "--scalar", "fixed"],
    );
    assert_eq!(
        (fixed_fit["scalar"].as_str(), fixed_fit["clipped"].as_u64()),
        (Some("fixed"), Some(0))
    );
    for k in 0..2 {
        let (a, q) = (
            f64_fit["a"][k].as_f64().unwrap(),
            fixed_fit["a"][k].as_f64().unwrap(),
        );
        assert!((a - q).abs() < 1e-4, "fixed a_{}: {q} vs f64 {a}", k + 1);
    }
    assert_eq!(
        (f64_fit["lambda"].as_f64(), f64_fit["delta"].as_f64()),
        (Some(0.999), Some(0.5))
    );
    assert_eq!(f64_fit["restarts"], 0);
    for k in 0..2 {
        let (a, b, c) = (
            f64_fit["a"][k].as_f64().unwrap(),
            f32_fit["a"][k].as_f64().unwrap(),
            rls_fit["a"][k].as_f64().unwrap(),
        );
        let d = sftf_fit["a"][k].as_f64().unwrap();
        assert!(
            (a - b).abs() < 1e-4 && (a - c).abs() < 1e-9 && (a - d).abs() < 1e-9,
            "a_{}: {a} {b} {c} {d}",
            k + 1
        );
    }
    // At the end of the record a_1 is near 1.0, not the 1.25 of a whole-record batch fit.
    let a1 = f64_fit["a"][0].as_f64().unwrap();
    assert!((a1 - 1.0).abs() < 0.05, "a_1 = {a1}");
    std::fs::remove_file(file).unwrap();
}

#[test]
fn decimate_fits_the_block_averages() {
    // 1003 samples: 100 blocks of 10, and 3 left over that must be dropped.
    let raw: Vec<f64> = (0..1003)
        .map(|n| (n as f64 * 0.37).sin() + 0.1 * (n % 7) as f64)
        .collect();
    let averaged: Vec<f64> = (0..100)
        .map(|b| raw[10 * b..10 * b + 10].iter().sum::<f64>() / 10.0)
        .collect();
    let csv = |x: &[f64]| {
        x.iter()
            .fold("x\n".to_string(), |s, v| s + &format!("{v:e}\n"))
    };
    let raw_file = temp_file("decimate-raw.csv", &csv(&raw));
    let averaged_file = temp_file("decimate-averaged.csv", &csv(&averaged));
    for method in ["ls", "burg", "lattice"] {
        let decimated = fit_json(
            &raw_file,
            method,
            "2",
            &["--decimate", "10", "--rate", "50"],
        );
        let direct = fit_json(&averaged_file, method, "2", &["--rate", "5"]);
        assert_eq!(decimated["n"], 100, "{method}");
        assert_eq!(decimated["rate_hz"], 5.0, "{method}");
        for (d, a) in decimated["a"]
            .as_array()
            .unwrap()
            .iter()
            .zip(direct["a"].as_array().unwrap())
        {
            let (d, a) = (d.as_f64().unwrap(), a.as_f64().unwrap());
            assert!(
                (d - a).abs() <= 1e-12 * (1.0 + a.abs()),
                "{method}: {d} against {a}"
            );
        }
    }
    let compare = json(&imu_ar(&[
        "compare",
        raw_file.to_str().unwrap(),
        "--column",
        "x",
        "--order",
        "2",
        "--decimate",
        "10",
        "--json",
    ]));
    assert_eq!(
        (compare["n_train"].as_u64(), compare["n_eval"].as_u64()),
        (Some(50), Some(50))
    );
    assert_eq!(compare["decimate"], 10);
    let zero = imu_ar(&[
        "fit",
        raw_file.to_str().unwrap(),
        "--column",
        "x",
        "--method",
        "ls",
        "--order",
        "2",
        "--decimate",
        "0",
    ]);
    assert_eq!(zero.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&zero.stderr),
        "imu-ar: --decimate 0: must be at least 1\n"
    );
}

#[test]
fn report_writes_four_pngs_and_a_summary() {
    let file = drift_record("report.csv", "20000");
    let out = std::env::temp_dir().join(format!("imu-ar-cli-{}-report", std::process::id()));
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    let report = |extra: &[&'static str]| {
        let mut args = vec!["report", f, "--column", "x", "--order", "2", "--out", o];
        args.extend_from_slice(extra);
        args
    };
    let v = json(&imu_ar(&report(&["--lambda", "0.99", "--rate", "100"])));
    for name in ["coefficients", "prediction_error", "psd", "adev"] {
        let png = std::fs::read(out.join(format!("{name}.png"))).unwrap();
        assert!(png.len() > 10_000, "{name}.png: {} bytes", png.len());
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{name}.png");
    }
    assert_eq!(
        (v["n"].as_u64(), v["n_train"].as_u64()),
        (Some(20000), Some(10000))
    );
    // The drift makes the batch model fitted on the first half worse on the second.
    let (batch, lattice) = (
        v["batch_mse"].as_f64().unwrap(),
        v["lattice_mse"].as_f64().unwrap(),
    );
    assert!(lattice < batch, "lattice {lattice}, batch {batch}");
    misused(
        &report(&["--rate", "0"]),
        "--rate 0: must be a positive number",
    );
    misused(
        &report(&["--rate", "100", "--decimate", "1000"]),
        "at least 64 samples (after --decimate), not 20",
    );
}

/// `report` summarises the comparison of `compare` on the record, the SFTF's included.
#[test]
fn report_and_compare_agree_on_the_sftf() {
    let file = drift_record("report-sftf.csv", "20000");
    let out = std::env::temp_dir().join(format!("imu-ar-cli-{}-sftf", std::process::id()));
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    let common = ["--column", "x", "--order", "2", "--lambda", "0.99"];
    let report = json(&imu_ar(
        &[&["report", f, "--rate", "100", "--out", o], &common[..]].concat(),
    ));
    let compare = json(&imu_ar(&[&["compare", f, "--json"], &common[..]].concat()));
    for key in [
        "batch_mse",
        "rls_mse",
        "lattice_mse",
        "sftf_mse",
        "sftf_restarts",
    ] {
        assert_eq!(report[key], compare[key], "{key}");
    }
    assert!(report["sftf_mse"].is_number(), "{report}");
    std::fs::remove_dir_all(out).unwrap();
    std::fs::remove_file(file).unwrap();
}

/// `imu-ar kalman FILE --column x ARGS.. --json`.
fn kalman(file: &Path, args: &[&str]) -> Output {
    let mut all = vec!["kalman", file.to_str().unwrap(), "--column", "x"];
    all.extend_from_slice(args);
    all.push("--json");
    imu_ar(&all)
}

fn matrix(v: &serde_json::Value) -> Vec<Vec<f64>> {
    let rows = v.as_array().unwrap().iter();
    rows.map(|r| {
        r.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    })
    .collect()
}

#[test]
fn kalman_hands_over_phi_q_and_the_allan_check() {
    // An AR(1) with phi = 0.9 at 10 Hz: a Gauss-Markov process with T_c = -0.1 / ln 0.9 s.
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "0.5", "--n", "200000", "--seed", "8", "--rate", "10",
    ]);
    assert!(out.status.success());
    let ar1 = temp_file("kalman-ar1.csv", &String::from_utf8(out.stdout).unwrap());
    let v = json(&kalman(
        &ar1,
        &["--order", "1", "--rate", "10", "--filter-rate", "100"],
    ));
    let a1 = v["a"][0].as_f64().unwrap();
    let s2 = v["noise_variance"].as_f64().unwrap();
    assert!((a1 - 0.9).abs() < 0.005, "a_1 {a1}");
    assert!((s2 - 0.25).abs() < 0.005, "sigma_w^2 {s2}");
    // Phi and Q of the 0.01 s filter step, from the fitted a_1 and sigma_w^2 by hand: the
    // Gauss-Markov process sampled at a tenth of the model's interval.
    let tc = -0.1 / a1.ln();
    let sigma2 = s2 / (1.0 - a1 * a1);
    let phi = (-0.01 / tc).exp();
    let gm = &v["gauss_markov"];
    assert!((gm["correlation_time_s"].as_f64().unwrap() - tc).abs() < 1e-12 * tc);
    assert!((gm["sigma"].as_f64().unwrap() - sigma2.sqrt()).abs() < 1e-12);
    assert!((matrix(&v["phi"])[0][0] - phi).abs() < 1e-12);
    assert!((matrix(&v["q"])[0][0] - sigma2 * (1.0 - phi * phi)).abs() < 1e-12 * sigma2);
    assert!((matrix(&v["p0"])[0][0] - sigma2).abs() < 1e-9 * sigma2);
    // The data are the model's process: the Allan check holds where the standard error is
    // below the 10 % floor (tau up to 100 s, 2000 clusters).
    let explained = v["explained_up_to_s"].as_f64().unwrap();
    assert!(explained >= 100.0, "explained up to {explained} s");

    // An AR(2) at 100 Hz for a 20 Hz filter: Phi^5 and Q_5 of the companion form, multiplied
    // out here step by step.
    let file = drift_record("kalman-ar2.csv", "20000");
    let v = json(&kalman(
        &file,
        &["--order", "2", "--rate", "100", "--filter-rate", "20"],
    ));
    assert_eq!(v["steps"].as_u64(), Some(5));
    let a: Vec<f64> = v["a"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    let s2 = v["noise_variance"].as_f64().unwrap();
    let step = [[a[0], a[1]], [1.0, 0.0]];
    let mul = |x: [[f64; 2]; 2], y: [[f64; 2]; 2]| -> [[f64; 2]; 2] {
        core::array::from_fn(|i| core::array::from_fn(|j| x[i][0] * y[0][j] + x[i][1] * y[1][j]))
    };
    let transpose = |x: [[f64; 2]; 2]| [[x[0][0], x[1][0]], [x[0][1], x[1][1]]];
    let (mut phi, mut q) = ([[1.0, 0.0], [0.0, 1.0]], [[0.0; 2]; 2]);
    for _ in 0..5 {
        q = mul(mul(step, q), transpose(step));
        q[0][0] += s2;
        phi = mul(step, phi);
    }
    for (got, want) in [(matrix(&v["phi"]), phi), (matrix(&v["q"]), q)] {
        for i in 0..2 {
            for j in 0..2 {
                assert!((got[i][j] - want[i][j]).abs() < 1e-12 * (1.0 + want[i][j].abs()));
            }
        }
    }
    // A drifting process is not stationary over the record: the check fails somewhere.
    assert_ne!(
        v["explained_up_to_s"],
        v["allan"].as_array().unwrap().last().unwrap()["tau_s"]
    );

    // Misuse: a rate that is no integer fraction of an AR(2)'s, a recursive method.
    let f = file.to_str().unwrap();
    for (extra, expected) in [
        (["--filter-rate", "30"], "is not an integer multiple of it"),
        (["--method", "lattice"], "the hand-off takes a batch fit"),
        (
            ["--filter-rate", "-1"],
            "--filter-rate -1: must be a positive number",
        ),
    ] {
        let mut args = vec![
            "kalman", f, "--column", "x", "--order", "2", "--rate", "100",
        ];
        args.extend_from_slice(&extra);
        misused(&args, expected);
    }
}

/// `imu-ar simulate --a A --sigma 1 --n N --seed K` as a temp file `name`.
fn simulated(name: &str, a: &str, n: &str, seed: &str) -> PathBuf {
    let out = imu_ar(&[
        "simulate", "--a", a, "--sigma", "1", "--n", n, "--seed", seed,
    ]);
    assert!(out.status.success());
    temp_file(name, &String::from_utf8(out.stdout).unwrap())
}

/// A temp file `name` with column `x` holding `values`.
fn column_file(name: &str, values: impl IntoIterator<Item = String>) -> PathBuf {
    let mut s = String::from("x\n");
    for v in values {
        s += &v;
        s.push('\n');
    }
    temp_file(name, &s)
}

/// Issue 23 item 3: the text output of a fixed-point fit shows the counts that qualify it,
/// and a fit that rejected most samples warns on stderr.
#[test]
fn fixed_fit_text_shows_every_count_and_warns() {
    let file = simulated("counts.csv", "0.7,-0.2", "5000", "5");
    let f = file.to_str().unwrap();
    let args = [
        "fit", f, "--column", "x", "--method", "lattice", "--scalar", "fixed", "--order", "2",
        "--scale", "30",
    ];
    let out = imu_ar(&args);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    let v = fit_json(
        &file,
        "lattice",
        "2",
        &["--scalar", "fixed", "--scale", "30"],
    );
    let saturated = v["saturated"].as_u64().unwrap();
    assert!(saturated > 2500, "{v}");
    for key in ["restarts", "saturated", "clipped", "non_finite"] {
        assert!(
            text.lines().any(|l| l == format!("{key} {}", v[key])),
            "{key} missing from:\n{text}"
        );
    }
    assert!(
        stderr.starts_with("imu-ar: warning: ")
            && stderr.contains(&format!("{saturated} of 5000 samples were rejected")),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1);
    // The default scale rejects nothing and warns about nothing.
    let out = imu_ar(&args[..10]);
    assert!(out.status.success() && out.stderr.is_empty());
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 5: an error names the record's own line, with CRLF line ends and after
/// blank lines and comments.
#[test]
fn csv_errors_name_the_records_own_line() {
    let cases = [
        ("crlf", "x\r\nabc\r\n2\r\n", 2),
        ("blank", "x\n1\n\n\nabc\n", 5),
        ("crlf-blank", "x\r\n1\r\n\r\n2\r\nabc\r\n", 5),
        ("comment", "# c\nx\n1\n# note\n\n2\nabc\n", 7),
    ];
    for (name, contents, line) in cases {
        let file = temp_file(&format!("line-{name}.csv"), contents);
        let f = file.to_str().unwrap();
        misused(
            &["fit", f, "--column", "x", "--method", "ls", "--order", "1"],
            &format!("{f}:{line}: column 'x': 'abc' is not a number"),
        );
        std::fs::remove_file(file).unwrap();
    }
}

/// Issue 23 item 6: a fit with zero residual degrees of freedom is refused.
#[test]
fn fits_without_residual_degrees_of_freedom_are_refused() {
    let two = temp_file("dof-two.csv", "x\n1\n2\n");
    let t = two.to_str().unwrap();
    for (method, needed) in [("ls", 4), ("burg", 3), ("yule-walker", 3)] {
        misused(
            &[
                "fit", t, "--column", "x", "--method", method, "--order", "1",
            ],
            &format!("{t}: 2 samples given, at least {needed} needed"),
        );
    }
    let file = simulated("dof-500.csv", "0.5", "500", "1");
    let f = file.to_str().unwrap();
    misused(
        &[
            "fit",
            f,
            "--column",
            "x",
            "--method",
            "ls",
            "--order",
            "1",
            "--decimate",
            "250",
        ],
        &format!("{f}: 2 samples given, at least 4 needed"),
    );
    std::fs::remove_file(two).unwrap();
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 7: `simulate` streams its output, so a huge `--n` starts writing at once
/// instead of aborting on an allocation.
#[test]
fn simulate_streams_any_length() {
    use std::io::{BufRead, BufReader};
    for n in ["1000000000000", "800000000000000000"] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_imu-ar"))
            .args([
                "simulate", "--a", "0.5", "--sigma", "1", "--n", n, "--seed", "1",
            ])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        assert_eq!(lines.next().unwrap().unwrap(), "t_s,x");
        for i in 0..1000 {
            let line = lines.next().expect("a row").unwrap();
            assert!(line.starts_with(&format!("{i},")), "{line}");
        }
        child.kill().unwrap();
        child.wait().unwrap();
    }
}

/// Issue 23 item 10: huge values are called an overflow, not zero variance, a singular
/// system or a bad `--delta` that was never given.
#[test]
fn huge_values_are_reported_as_an_overflow() {
    let file = column_file("huge.csv", (0..500).map(|i| format!("{}e160", 1 + i % 7)));
    let f = file.to_str().unwrap();
    for method in ["ls", "burg", "yule-walker", "rls", "lattice"] {
        misused(
            &[
                "fit", f, "--column", "x", "--method", method, "--order", "2",
            ],
            "overflows f64",
        );
    }
    misused(
        &["compare", f, "--column", "x", "--order", "2"],
        "overflows f64",
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 10: `compare` names the training part when it is too short.
#[test]
fn compare_names_the_training_part_when_too_short() {
    let file = simulated("compare-64.csv", "0.5", "64", "2");
    let f = file.to_str().unwrap();
    misused(
        &["compare", f, "--column", "x", "--order", "32"],
        "the training part (--train 0.5 of 64 samples) has 32 samples, at least 66 needed",
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 10: `order` on too few samples is an error, not "selected 0" over a table
/// of nulls.
#[test]
fn order_on_three_samples_is_refused() {
    let file = temp_file("order-3.csv", "x\n1\n2\n3\n");
    let f = file.to_str().unwrap();
    misused(
        &[
            "order",
            f,
            "--column",
            "x",
            "--method",
            "ls",
            "--max-order",
            "1",
        ],
        &format!("{f}: 3 samples given, at least 4 needed"),
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 10: a small AR(2) signal (sigma 1e-3) on an offset of 1e6 is fitted in f32
/// and in fixed point as in f64: the mean is removed in f64 before rounding.
#[test]
fn small_signal_on_a_large_offset_fits_in_f32_and_fixed() {
    let out = imu_ar(&[
        "simulate", "--a", "0.7,-0.2", "--sigma", "1", "--n", "5000", "--seed", "5",
    ]);
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    let values = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(1).unwrap().parse::<f64>().unwrap())
        .map(|v| format!("{}", 1e6 + 1e-3 * v));
    let file = column_file("offset.csv", values);
    for scalar in ["f32", "fixed"] {
        let v = fit_json(&file, "lattice", "2", &["--scalar", scalar]);
        let a: Vec<f64> = v["a"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        // 5000 samples: the standard error of each coefficient is about 0.014.
        assert!(
            (a[0] - 0.7).abs() < 0.1 && (a[1] + 0.2).abs() < 0.1,
            "{scalar}: a = {a:?}"
        );
        assert!((v["mean"].as_f64().unwrap() - 1e6).abs() < 1e-3, "{v}");
    }
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 11: a cell that f32 cannot hold (1e39) is rejected and counted.
#[test]
fn f32_counts_the_samples_it_cannot_hold() {
    let out = imu_ar(&[
        "simulate", "--a", "0.5", "--sigma", "1", "--n", "5000", "--seed", "6",
    ]);
    assert!(out.status.success());
    let csv = String::from_utf8(out.stdout).unwrap();
    let values = csv.lines().skip(1).enumerate().map(|(i, l)| {
        if i == 2500 {
            "1e39".to_string()
        } else {
            l.split(',').nth(1).unwrap().to_string()
        }
    });
    let file = column_file("f32-huge.csv", values);
    for method in ["rls", "lattice", "sftf"] {
        let v = fit_json(&file, method, "1", &["--scalar", "f32", "--delta", "0.1"]);
        assert_eq!(v["n"], 5000, "{method}");
        assert_eq!(v["non_finite"], 1, "{method}: {v}");
    }
    let v = fit_json(&file, "lattice", "1", &["--delta", "0.1"]);
    assert_eq!(v["non_finite"], 0);
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: `compare` says "higher" for a negative reduction.
#[test]
fn compare_says_higher_for_a_negative_reduction() {
    let file = simulated("compare-higher.csv", "0.7,-0.2", "5000", "5");
    let f = file.to_str().unwrap();
    // At order 32 the lattice (lambda 0.999) predicts this stationary record worse than LS.
    let args = ["compare", f, "--column", "x", "--order", "32"];
    let v = json(&imu_ar(&[&args[..], &["--json"]].concat()));
    let percent = v["reduction_percent"].as_f64().unwrap();
    assert!(
        percent < 0.0,
        "this record should favour the batch fit: {v}"
    );
    let out = imu_ar(&args);
    let text = String::from_utf8(out.stdout).unwrap();
    let line = text.lines().last().unwrap();
    assert_eq!(
        line,
        format!("lattice against batch: {:.1} % higher", -percent)
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: a filter step beyond `u32` model steps is an error, not 4294967295.
#[test]
fn kalman_refuses_a_filter_step_beyond_u32() {
    let file = simulated("kalman-slow.csv", "0.7,-0.2", "2000", "3");
    let f = file.to_str().unwrap();
    misused(
        &[
            "kalman",
            f,
            "--column",
            "x",
            "--order",
            "2",
            "--rate",
            "100",
            "--filter-rate",
            "1e-12",
        ],
        "--filter-rate 0.000000000001: one filter step would be 1e14 model steps",
    );
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: `report` creates `--out` only after its input passed every check.
#[test]
fn report_creates_out_only_for_good_input() {
    let file = simulated("report-short.csv", "0.5", "50", "3");
    let out = std::env::temp_dir().join(format!("imu-ar-cli-{}-never", std::process::id()));
    let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
    misused(
        &[
            "report", f, "--column", "x", "--order", "1", "--rate", "100", "--out", o,
        ],
        "report needs at least",
    );
    assert!(!out.exists(), "{o} was created");
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: an error shows a long cell cut short.
#[test]
fn an_error_shortens_a_long_cell() {
    let cell = "1".repeat(100_000);
    let file = column_file("long-cell.csv", [cell]);
    let f = file.to_str().unwrap();
    let args = ["fit", f, "--column", "x", "--method", "ls", "--order", "1"];
    misused(
        &args,
        &format!(
            "{f}:2: column 'x': '{}... (100000 bytes)' is not a finite number",
            "1".repeat(40)
        ),
    );
    assert!(imu_ar(&args).stderr.len() < 200 + f.len());
    std::fs::remove_file(file).unwrap();
}

/// Issue 23 item 12: a column named twice in the header is an error.
#[test]
fn a_duplicate_column_name_is_an_error() {
    let file = temp_file("dup.csv", "x,y,x\n1,2,3\n2,3,4\n1,5,2\n4,4,4\n");
    let f = file.to_str().unwrap();
    misused(
        &["fit", f, "--column", "x", "--method", "ls", "--order", "1"],
        &format!("{f}: the header names column 'x' 2 times"),
    );
    std::fs::remove_file(file).unwrap();
}

/// The fixed-point lattice's range of `lambda` is `[0.9, 1]`: below it, the error names
/// `--lambda`, not the scale.
#[test]
fn fixed_fit_refuses_a_lambda_below_its_range() {
    let file = simulated("fixed-lambda.csv", "0.7,-0.2", "2000", "5");
    let f = file.to_str().unwrap();
    misused(
        &[
            "fit", f, "--column", "x", "--method", "lattice", "--scalar", "fixed", "--order", "2",
            "--lambda", "0.5",
        ],
        "--lambda 0.5: the fixed-point lattice needs lambda in [0.9, 1]",
    );
}
