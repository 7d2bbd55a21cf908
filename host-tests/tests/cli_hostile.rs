//! Hostile inputs to the `imu-ar` tool (red team of issue 23's fixes). Each test is one
//! defect; it fails until the defect is fixed. The contract (architecture.md): bad input exits
//! with status 2 and ONE line on stderr naming file, line and problem, nothing on stdout; no
//! NaN or infinity in any output; no result that is wrong but looks fine.

use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

fn imu_ar(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_imu-ar"))
        .args(args)
        .output()
        .expect("run imu-ar")
}

fn temp_bytes(name: &str, contents: &[u8]) -> PathBuf {
    let path = std::env::temp_dir().join(format!("imu-ar-hostile-{}-{name}", std::process::id()));
    std::fs::write(&path, contents).unwrap();
    path
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Status 2, nothing on stdout, exactly one line on stderr.
fn assert_one_line_failure(out: &Output) {
    assert_eq!(out.status.code(), Some(2), "stderr: {}", stderr(out));
    assert!(out.stdout.is_empty(), "stdout: {}", stdout(out));
    assert_eq!(
        stderr(out).trim_end_matches('\n').lines().count(),
        1,
        "not one line: {:?}",
        stderr(out)
    );
}

fn no_nan_inf(text: &str) {
    let lower = text.to_ascii_lowercase();
    assert!(
        !lower.contains("nan") && !lower.contains("inf"),
        "NaN/inf in output: {text}"
    );
}

/// A 5000-sample AR(2) record (column `x`).
fn ar2(name: &str) -> PathBuf {
    let out = imu_ar(&[
        "simulate", "--a", "0.7,-0.2", "--sigma", "1", "--n", "5000", "--seed", "5",
    ]);
    assert!(out.status.success());
    temp_bytes(name, &out.stdout)
}

// Defect: `simulate --sigma 1e308` passes the `--sigma` check (finite) but every sample
// overflows; it prints `NaN` samples and exits 0. Expected: status 2 naming --sigma (or
// finite samples).
#[test]
fn simulate_huge_sigma_prints_nan() {
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "1e308", "--n", "5", "--seed", "1",
    ]);
    if out.status.success() {
        no_nan_inf(&stdout(&out));
    } else {
        assert_one_line_failure(&out);
    }
}

// Defect: `simulate --rate 1e-320` (subnormal) is accepted; `t_s` becomes `inf` from the second
// row on. Expected: status 2 naming --rate, or finite times.
#[test]
fn simulate_subnormal_rate_prints_inf() {
    let out = imu_ar(&[
        "simulate", "--a", "0.9", "--sigma", "1", "--n", "3", "--seed", "1", "--rate", "1e-320",
    ]);
    if out.status.success() {
        no_nan_inf(&stdout(&out));
    } else {
        assert_one_line_failure(&out);
    }
}

// Defect: `adev --rate 1e-320` is accepted and every `tau_s` is infinite, printed as `null`
// in JSON (and `kalman --rate 1e-308` prints `null` taus and a wrong Allan check). Expected:
// status 2 naming --rate, or finite taus.
#[test]
fn adev_subnormal_rate_gives_infinite_taus() {
    let file = ar2("adev-rate.csv");
    let out = imu_ar(&[
        "adev", file.to_str().unwrap(), "--column", "x", "--rate", "1e-320", "--json",
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

// Defect: CSV errors count only '\n'; with classic Mac '\r' line endings (which the csv
// reader accepts as record terminators) every error says line 1. 'abc' is on line 4.
#[test]
fn csv_error_line_with_cr_only_endings() {
    let file = temp_bytes("cr.csv", b"x\r1\r2\rabc\r5\r");
    let out = imu_ar(&[
        "fit", file.to_str().unwrap(), "--column", "x", "--method", "burg", "--order", "1",
    ]);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("cr.csv:4:"), "{}", stderr(&out));
}

// Defect: a line whose first non-blank character is '#' but that does not start with '#' is
// a record to the csv reader (only a leading '#' is a comment), but the line locator skips it
// as a comment and names the next line. '  #c' is on line 3; the error says line 4.
#[test]
fn csv_error_line_of_indented_hash_cell() {
    let file = temp_bytes("hash.csv", b"x\n1\n  #c\n3\n4\n5\n");
    let out = imu_ar(&[
        "fit", file.to_str().unwrap(), "--column", "x", "--method", "burg", "--order", "1",
    ]);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("hash.csv:3:"), "{}", stderr(&out));
}

// Defect: a quoted cell holding a newline is echoed verbatim, so the error is two lines.
// Expected: one line (escape or cut the cell).
#[test]
fn csv_error_quoted_newline_cell_is_multiline() {
    let file = temp_bytes("qnl.csv", b"x\n\"1\n2\"\n3\n");
    let out = imu_ar(&[
        "fit", file.to_str().unwrap(), "--column", "x", "--method", "burg", "--order", "1",
    ]);
    assert_one_line_failure(&out);
}

// Defect: "no column" lists the header's names verbatim; a quoted header name with a newline
// makes the error two lines. Expected: one line.
#[test]
fn csv_error_header_with_newline_is_multiline() {
    let file = temp_bytes("hnl.csv", b"a,\"x\ny\"\n1,2\n");
    let out = imu_ar(&[
        "fit", file.to_str().unwrap(), "--column", "z", "--method", "burg", "--order", "1",
    ]);
    assert_one_line_failure(&out);
}

// Defect: `compare --delta 1e-320`: RLS and the lattice give no MSE, and the text output says
// "lattice against batch: NaN % lower", exit 0. Expected: status 2 (as `fit` says "no finite
// model"), or no NaN in the output.
#[test]
fn compare_tiny_delta_prints_nan() {
    let file = ar2("cmp-delta.csv");
    let out = imu_ar(&[
        "compare", file.to_str().unwrap(), "--column", "x", "--order", "2", "--delta", "1e-320",
    ]);
    if out.status.success() {
        no_nan_inf(&stdout(&out));
    } else {
        assert_one_line_failure(&out);
    }
}

// Defect: `report --delta 1e-320` exits 0 claiming lattice_mse 0.0, rls_mse 0.0,
// reduction_percent 100 and lattice_a [-0.0] (a perfect lattice), where `fit` with the same
// delta says "no finite model". A wrong result that looks fine. Expected: status 2, or MSEs
// that are not better than the batch fit's on this stationary record.
#[test]
fn report_tiny_delta_claims_perfect_lattice() {
    let file = ar2("rep-delta.csv");
    let dir = std::env::temp_dir().join(format!("imu-ar-hostile-{}-rep", std::process::id()));
    let out = imu_ar(&[
        "report", file.to_str().unwrap(), "--column", "x", "--order", "1", "--rate", "100",
        "--out", dir.to_str().unwrap(), "--delta", "1e-320",
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

// Defect: `--decimate` larger than the record leaves 0 samples; the recursive methods then
// say "the variance of the first 1000 samples ... overflows f64 (values of about 1e154 or
// more)", which is false (the mean of no samples is NaN). Expected: an error about too few
// samples (as burg says "0 samples given").
#[test]
fn decimate_beyond_record_blames_overflow() {
    let file = ar2("dec.csv");
    let out = imu_ar(&[
        "fit", file.to_str().unwrap(), "--column", "x", "--method", "lattice", "--order", "1",
        "--decimate", "5001",
    ]);
    assert_one_line_failure(&out);
    assert!(
        !stderr(&out).contains("overflow"),
        "misleading: {}",
        stderr(&out)
    );
}

// Defect: a missing required argument prints only clap's first line, "the following required
// arguments were not provided:", dropping the names of the arguments. Expected: one line that
// names the missing argument (--method).
#[test]
fn missing_argument_error_names_nothing() {
    let file = ar2("miss.csv");
    let out = imu_ar(&["fit", file.to_str().unwrap(), "--column", "x", "--order", "1"]);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("--method"), "{}", stderr(&out));
}

// Defect: `simulate` into a pipe closed early (`| head -c 100`) exits with status 1, though
// the code means a closed pipe to end the run quietly (status 0): simulate swallows
// BrokenPipe, then main's flush of the leftover stdout buffer fails.
#[test]
fn simulate_closed_pipe_exits_nonzero() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_imu-ar"))
        .args([
            "simulate", "--a", "0.5", "--sigma", "1", "--n", "1000000", "--seed", "1",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut head = [0u8; 100];
    child.stdout.as_mut().unwrap().read_exact(&mut head).unwrap();
    drop(child.stdout.take());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0), "status {status:?} on a closed pipe");
}
