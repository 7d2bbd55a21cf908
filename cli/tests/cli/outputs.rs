//! The `imu-ar` tool's outputs: the documented keys and convention, fits against statsmodels,
//! the recursive and decimated fits, and `adev` against the published ADIS16405 Allan table.

use imu_ar_host::fixtures::data_dir;

use crate::common;

use common::{column_file, drift_record, fit_json, imu_ar, json, simulated, temp_file};

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn adev_reproduces_the_published_adis16405_table() {
    let dir = data_dir()
        .expect("the real records: ../shared/data/imu or IMU_AR_DATA (see docs/reliability.md)");
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
    let file = temp_file("statsmodels.csv", String::from_utf8(out.stdout).unwrap());
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
    let raw_file = temp_file("decimate-raw.csv", csv(&raw));
    let averaged_file = temp_file("decimate-averaged.csv", csv(&averaged));
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
