//! Edge inputs to the `imu-ar` tool: extreme settings, unusual CSV line endings and cells. The
//! contract (architecture.md): bad input exits with status 2 and ONE line on stderr naming file,
//! line and problem, nothing on stdout; no NaN or infinity in any output; no result that is
//! wrong but looks fine.

use crate::common;

use common::{
    ar2, assert_one_line_failure, fit_burg, imu_ar, no_nan_inf, stderr, stdout, temp_file,
};

// Formerly: `simulate --sigma 1e308` passes the `--sigma` check (finite) but every sample
// overflows; it prints `NaN` samples and exits 0. Expected: status 2 naming --sigma (or
// finite samples).
#[test]
fn simulate_refuses_a_sigma_that_overflows() {
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "1e308", "--n", "5", "--seed", "1",
    ]);
    if out.status.success() {
        no_nan_inf(&stdout(&out));
    } else {
        assert_one_line_failure(&out);
    }
}

// Formerly: `simulate --rate 1e-320` (subnormal) is accepted; `t_s` becomes `inf` from the second
// row on. Expected: status 2 naming --rate, or finite times.
#[test]
fn simulate_refuses_a_subnormal_rate() {
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "1", "--n", "3", "--seed", "1", "--rate", "1e-320",
    ]);
    if out.status.success() {
        no_nan_inf(&stdout(&out));
    } else {
        assert_one_line_failure(&out);
    }
}

// Formerly: `adev --rate 1e-320` is accepted and every `tau_s` is infinite, printed as `null`
// in JSON (and `kalman --rate 1e-308` prints `null` taus and a wrong Allan check). Expected:
// status 2 naming --rate, or finite taus.
#[test]
fn adev_refuses_a_subnormal_rate() {
    let file = ar2("adev-rate.csv");
    let out = imu_ar(&[
        "adev",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--rate",
        "1e-320",
        "--json",
    ]);
    if out.status.success() {
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for t in v["tau_s"].as_array().unwrap() {
            assert!(t.is_number(), "tau_s not finite: {t}");
        }
    } else {
        assert_one_line_failure(&out);
    }
}

// Formerly: CSV errors count only '\n'; with classic Mac '\r' line endings (which the csv
// reader accepts as record terminators) every error says line 1. 'abc' is on line 4.
#[test]
fn csv_error_line_with_cr_only_endings_is_right() {
    let file = temp_file("cr.csv", b"x\r1\r2\rabc\r5\r");
    let out = fit_burg(&file);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("cr.csv:4:"), "{}", stderr(&out));
}

// Formerly: a line whose first non-blank character is '#' but that does not start with '#' is
// a record to the csv reader (only a leading '#' is a comment), but the line locator skips it
// as a comment and names the next line. '  #c' is on line 3; the error says line 4.
#[test]
fn csv_error_line_of_an_indented_hash_cell_is_right() {
    let file = temp_file("hash.csv", b"x\n1\n  #c\n3\n4\n5\n");
    let out = fit_burg(&file);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("hash.csv:3:"), "{}", stderr(&out));
}

// Formerly: a quoted cell holding a newline is echoed verbatim, so the error is two lines.
// Expected: one line (escape or cut the cell).
#[test]
fn csv_error_with_a_quoted_newline_is_one_line() {
    let file = temp_file("qnl.csv", b"x\n\"1\n2\"\n3\n");
    let out = fit_burg(&file);
    assert_one_line_failure(&out);
}

// Formerly: "no column" lists the header's names verbatim; a quoted header name with a newline
// makes the error two lines. Expected: one line.
#[test]
fn csv_error_with_a_newline_in_the_header_is_one_line() {
    let file = temp_file("hnl.csv", b"a,\"x\ny\"\n1,2\n");
    let out = imu_ar(&[
        "fit",
        file.to_str().unwrap(),
        "--column",
        "z",
        "--method",
        "burg",
        "--order",
        "1",
    ]);
    assert_one_line_failure(&out);
}

// Formerly: `compare --delta 1e-320`: RLS and the lattice give no MSE, and the text output says
// "lattice against batch: NaN % lower", exit 0. Expected: status 2 (as `fit` says "no finite
// model"), or no NaN in the output.
#[test]
fn compare_refuses_a_tiny_delta() {
    let file = ar2("cmp-delta.csv");
    let out = imu_ar(&[
        "compare",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--order",
        "2",
        "--delta",
        "1e-320",
    ]);
    if out.status.success() {
        no_nan_inf(&stdout(&out));
    } else {
        assert_one_line_failure(&out);
    }
}

// Formerly: `report --delta 1e-320` exits 0 claiming lattice_mse 0.0, rls_mse 0.0,
// reduction_percent 100 and lattice_a [-0.0] (a perfect lattice), where `fit` with the same
// delta says "no finite model". A wrong result that looks fine. Expected: status 2, or MSEs
// that are not better than the batch fit's on this stationary record.
#[test]
fn report_refuses_a_tiny_delta() {
    let file = ar2("rep-delta.csv");
    let dir = crate::common::temp_path("edges-rep");
    let out = imu_ar(&[
        "report",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--order",
        "1",
        "--rate",
        "100",
        "--out",
        dir.to_str().unwrap(),
        "--delta",
        "1e-320",
    ]);
    if out.status.success() {
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let batch = v["batch_mse"].as_f64().unwrap();
        let lattice = v["lattice_mse"].as_f64().unwrap_or(f64::NAN);
        assert!(
            lattice > 0.5 * batch,
            "lattice MSE {lattice} against batch {batch}: {v}"
        );
    } else {
        assert_one_line_failure(&out);
    }
}

// Formerly: `--decimate` larger than the record leaves 0 samples; the recursive methods then
// say "the variance of the first 1000 samples ... overflows f64 (values of about 1e154 or
// more)", which is false (the mean of no samples is NaN). Expected: an error about too few
// samples (as burg says "0 samples given").
#[test]
fn decimate_beyond_the_record_blames_no_overflow() {
    let file = ar2("dec.csv");
    let out = imu_ar(&[
        "fit",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--method",
        "lattice",
        "--order",
        "1",
        "--decimate",
        "5001",
    ]);
    assert_one_line_failure(&out);
    assert!(
        !stderr(&out).contains("overflow"),
        "misleading: {}",
        stderr(&out)
    );
}

/// The line of an error with mixed line endings (`\r\n`, lone `\r`, `\n`), comment and empty
/// lines between records.
#[test]
fn csv_error_line_with_mixed_endings() {
    // As for the CSV reader, a comment runs to the next '\n' (a lone '\r' in it ends a line
    // but not the comment).
    let cases: [(&str, &[u8], u64); 5] = [
        ("mixed", b"x\r\n1\r2\nabc\r\n", 4),
        ("mixed-blank", b"x\r1\r\r\n\n2\rabc\n", 6),
        ("mixed-comment", b"# c\nx\r\n1\n# d\n\r2\r\nabc\r", 7),
        ("cr-in-comment", b"x\n1\n# d\re\r\n2\nabc\n", 6),
        ("indented-comment", b"x\n1\n#c\n \t#d\n", 4),
    ];
    for (name, contents, line) in cases {
        let file = temp_file(&format!("{name}.csv"), contents);
        let out = fit_burg(&file);
        assert_one_line_failure(&out);
        let expected = format!("{name}.csv:{line}:");
        assert!(stderr(&out).contains(&expected), "{name}: {}", stderr(&out));
    }
}

/// Echoed control characters are escaped, so the error stays on one line and shows them.
#[test]
fn echoed_control_characters_are_escaped() {
    let file = temp_file("ctl.csv", b"a,\"x\ny\"\n1,\"2\r3\"\n");
    let f = file.to_str().unwrap();
    let out = imu_ar(&[
        "fit", f, "--column", "z", "--method", "burg", "--order", "1",
    ]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains(r"(columns: a, x\ny)"),
        "{}",
        stderr(&out)
    );
    let out = imu_ar(&[
        "fit", f, "--column", "x\ny", "--method", "burg", "--order", "1",
    ]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains(r"'2\r3' is not a number"),
        "{}",
        stderr(&out)
    );
}

/// `--delta` outside the range f64 can carry is refused by `fit`, `compare` and `report` alike,
/// naming `--delta`.
#[test]
fn delta_out_of_range_is_refused_naming_delta() {
    let file = ar2("delta-range.csv");
    let f = file.to_str().unwrap();
    let dir = crate::common::temp_path("edges-delta");
    for delta in ["1e-320", "1e300", "0", "-1", "inf"] {
        for args in [
            vec![
                "fit", f, "--column", "x", "--method", "lattice", "--order", "1",
            ],
            vec!["compare", f, "--column", "x", "--order", "1"],
            vec![
                "report",
                f,
                "--column",
                "x",
                "--order",
                "1",
                "--rate",
                "100",
                "--out",
                dir.to_str().unwrap(),
            ],
        ] {
            let mut args = args.clone();
            args.extend(["--delta", delta]);
            let out = imu_ar(&args);
            assert_one_line_failure(&out);
            assert!(
                stderr(&out).contains("--delta"),
                "{args:?}: {}",
                stderr(&out)
            );
        }
    }
    assert!(!dir.exists(), "report created --out for bad input");
}

/// A rate whose times overflow is refused naming `--rate`, by every command that takes one.
#[test]
fn subnormal_rates_are_refused_naming_rate() {
    let file = ar2("rate-range.csv");
    let f = file.to_str().unwrap();
    let dir = crate::common::temp_path("edges-rate");
    let cases: [Vec<&str>; 6] = [
        vec![
            "kalman", f, "--column", "x", "--order", "1", "--rate", "1e-308",
        ],
        vec!["adev", f, "--column", "x", "--rate", "1e-308"],
        vec![
            "fit", f, "--column", "x", "--method", "burg", "--order", "1", "--rate", "1e-310",
        ],
        vec![
            "report",
            f,
            "--column",
            "x",
            "--order",
            "1",
            "--rate",
            "1e-308",
            "--out",
            dir.to_str().unwrap(),
        ],
        vec![
            "simulate", "--a", "0.5", "--sigma", "1", "--n", "10", "--seed", "1", "--rate",
            "1e-308",
        ],
        vec![
            "simulate", "--a", "0.5", "--sigma", "1", "--n", "2", "--seed", "1", "--rate", "5e-324",
        ],
    ];
    for args in cases {
        let out = imu_ar(&args);
        assert_one_line_failure(&out);
        assert!(
            stderr(&out).contains("--rate"),
            "{args:?}: {}",
            stderr(&out)
        );
    }
}

/// `simulate` refuses a sigma whose process overflows, naming `--sigma`, and still runs a
/// large one that does not.
#[test]
fn simulate_sigma_range() {
    for (a, sigma) in [("0.9", "1e308"), ("0.99", "1e305"), ("0.5,0.3", "1e307")] {
        let out = imu_ar(&[
            "simulate", "--a", a, "--sigma", sigma, "--n", "5", "--seed", "1",
        ]);
        assert_one_line_failure(&out);
        assert!(stderr(&out).contains("--sigma"), "{}", stderr(&out));
    }
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "1e200", "--n", "50", "--seed", "1",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    no_nan_inf(&stdout(&out));
}

/// Decimation that leaves no sample says so, for every command that decimates.
#[test]
fn decimate_beyond_record_says_no_sample_is_left() {
    let file = ar2("dec-all.csv");
    let f = file.to_str().unwrap();
    let dir = crate::common::temp_path("edges-dec");
    let cases: [Vec<&str>; 5] = [
        vec![
            "fit", f, "--column", "x", "--method", "burg", "--order", "1",
        ],
        vec!["fit", f, "--column", "x", "--method", "rls", "--order", "1"],
        vec!["compare", f, "--column", "x", "--order", "1"],
        vec![
            "kalman", f, "--column", "x", "--order", "1", "--rate", "100",
        ],
        vec![
            "report",
            f,
            "--column",
            "x",
            "--order",
            "1",
            "--rate",
            "100",
            "--out",
            dir.to_str().unwrap(),
        ],
    ];
    for args in cases {
        let mut args = args.clone();
        args.extend(["--decimate", "5001"]);
        let out = imu_ar(&args);
        assert_one_line_failure(&out);
        assert!(
            stderr(&out).contains("no sample is left"),
            "{args:?}: {}",
            stderr(&out)
        );
    }
}
