//! `imu-ar report`, `compare` and `kalman`: the plots and the summary, the comparison and the
//! Kalman hand-off, and what they refuse.

use std::path::Path;
use std::process::Output;

use crate::common;

use common::{drift_record, imu_ar, json, misused, simulated, temp_file};

#[test]
fn report_writes_four_pngs_and_a_summary() {
    let file = drift_record("report.csv", "20000");
    let out = crate::common::temp_path("cli-report");
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
    let out = crate::common::temp_path("cli-sftf");
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
    let ar1 = temp_file("kalman-ar1.csv", String::from_utf8(out.stdout).unwrap());
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
        "--filter-rate 1e-12: one filter step would be 1e14 model steps",
    );
    std::fs::remove_file(file).unwrap();
}

/// `report` writes every plot or none: with a folder in the way of one, the plots before it
/// were left (exit 2, "drawing failed: BackendError(...)" naming the input, before).
#[test]
fn report_writes_every_plot_or_none() {
    let file = drift_record("report-blocked.csv", "2000");
    for blocked in ["psd.png", "adev.png"] {
        let out = crate::common::temp_path("cli-report-blocked");
        std::fs::create_dir_all(out.join(blocked)).unwrap();
        let (f, o) = (file.to_str().unwrap(), out.to_str().unwrap());
        let run = imu_ar(&[
            "report", f, "--column", "x", "--order", "2", "--rate", "100", "--out", o,
        ]);
        common::assert_one_line_failure(&run);
        let err = common::stderr(&run);
        assert!(
            err.contains(&out.join(blocked).display().to_string())
                && err.contains("is a directory; no file was written"),
            "{blocked}: {err}"
        );
        assert_eq!(crate::common::names_in(&out), [blocked], "{blocked}");
    }
}

/// Issue 23 item 12: `report` creates `--out` only after its input passed every check.
#[test]
fn report_creates_out_only_for_good_input() {
    let file = simulated("report-short.csv", "0.5", "50", "3");
    let out = crate::common::temp_path("cli-never");
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
