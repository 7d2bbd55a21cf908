//! The command line of `imu-ar`: a missing or bad argument is named on one line of stderr;
//! `-h`, `--help` and `--version` print to stdout.

use crate::common;

use common::{ar2, assert_one_line_failure, command, imu_ar, misused, stderr, stdout, temp_file};

// Formerly: a missing required argument prints only clap's first line, "the following required
// arguments were not provided:", dropping the names of the arguments. Expected: one line that
// names the missing argument (--method).
#[test]
fn missing_argument_error_names_the_argument() {
    let file = ar2("miss.csv");
    let out = imu_ar(&[
        "fit",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--order",
        "1",
    ]);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains("--method"), "{}", stderr(&out));
}

/// Every subcommand's missing argument is named on the one error line.
#[test]
fn missing_arguments_are_named_for_every_subcommand() {
    let file = ar2("miss-all.csv");
    let f = file.to_str().unwrap();
    // Without a time column, the rate must be given.
    let untimed = temp_file("miss-untimed.csv", "x\n1\n2\n3\n5\n");
    let u = untimed.to_str().unwrap();
    let cases: [(Vec<&str>, &str); 10] = [
        (
            vec!["fit", f, "--column", "x", "--method", "ls"],
            "--order <ORDER>",
        ),
        (vec!["compare", f, "--order", "1"], "--column <COLUMN>"),
        (
            vec!["report", f, "--column", "x", "--order", "1", "--rate", "1"],
            "--out <OUT>",
        ),
        (
            vec!["kalman", f, "--column", "x", "--order", "1"],
            "--rate <RATE>",
        ),
        (
            vec!["order", f, "--column", "x", "--method", "ls"],
            "--max-order <MAX_ORDER>",
        ),
        (vec!["adev", u, "--column", "x"], "--rate is required"),
        (vec!["noise", u, "--column", "x"], "--rate is required"),
        (vec!["characterise", f], "--out <OUT>"),
        (
            vec!["simulate", "--a", "0.5", "--n", "3", "--seed", "1"],
            "--sigma <SIGMA>",
        ),
        (vec!["adev", "--column", "x", "--rate", "1"], "<FILES>"),
    ];
    for (args, missing) in cases {
        let out = imu_ar(&args);
        assert_one_line_failure(&out);
        assert!(stderr(&out).contains(missing), "{args:?}: {}", stderr(&out));
    }
    // Other argument errors keep their detail on the one line.
    for (args, expected) in [
        (
            vec![
                "fit", f, "--column", "x", "--method", "ls", "--order", "1", "--bogus",
            ],
            "--bogus",
        ),
        (vec!["frobnicate"], "frobnicate"),
        (vec![], "subcommand"),
        (
            vec![
                "fit", f, "--column", "x", "--column", "y", "--method", "ls", "--order", "1",
            ],
            "--column",
        ),
    ] {
        let out = imu_ar(&args);
        assert_one_line_failure(&out);
        assert!(
            stderr(&out).contains(expected),
            "{args:?}: {}",
            stderr(&out)
        );
    }
}

/// `-h`, `--help` and `--version` still print to stdout with status 0.
#[test]
fn help_and_version_exit_zero() {
    for args in [
        vec!["--help"],
        vec!["-h"],
        vec!["fit", "--help"],
        vec!["simulate", "-h"],
        vec!["help", "kalman"],
    ] {
        let out = imu_ar(&args);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {}", stderr(&out));
        assert!(
            stdout(&out).contains("Usage:"),
            "{args:?}: {}",
            stdout(&out)
        );
        assert!(out.stderr.is_empty(), "{args:?}: {}", stderr(&out));
    }
    let out = imu_ar(&["--version"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(stdout(&out).starts_with("imu-ar "), "{}", stdout(&out));
}

/// Every other kind of command-line error is one line that names the argument and what is
/// wrong with it, an argument that is not UTF-8 included.
#[test]
fn every_kind_of_argument_error_is_one_informative_line() {
    let file = ar2("kinds.csv");
    let f = file.to_str().unwrap();
    let fit = |extra: &[&'static str]| {
        let mut args = vec!["fit", f, "--column", "x", "--method", "ls", "--order", "1"];
        args.extend_from_slice(extra);
        args
    };
    let simulate = ["simulate", "--sigma", "1", "--n", "3", "--seed", "1", "--a"];
    for (args, expected) in [
        (fit(&["--json=yes"]), "unexpected value 'yes' for '--json'"),
        (fit(&["--rate"]), "a value is required for '--rate <RATE>'"),
        (
            fit(&["--scalar", "f16"]),
            "invalid value 'f16' for '--scalar <SCALAR>'",
        ),
        (
            [&simulate[..], &["0.5,"]].concat(),
            "invalid value '' for '--a <A>'",
        ),
        (vec!["parity", "extra"], "unexpected argument 'extra'"),
        (
            vec!["help", "frobnicate"],
            "unrecognized subcommand 'frobnicate'",
        ),
    ] {
        misused(&args, expected);
    }
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStrExt;
        let out = command()
            .args(["fit", f, "--column"])
            .arg(std::ffi::OsStr::from_bytes(b"g\xffx"))
            .args(["--method", "ls", "--order", "1"])
            .output()
            .unwrap();
        assert_one_line_failure(&out);
        assert!(
            stderr(&out).contains("invalid UTF-8") && stderr(&out).contains("argument 4 ("),
            "{}",
            stderr(&out)
        );
        assert!(
            stderr(&out).contains("after '--column'"),
            "{}",
            stderr(&out)
        );
    }
}

/// `--prior-a` with a negative first coefficient is read (clap took `-1.5,0.7` for a flag);
/// `--settle` over the whole record says so (it said "no finite model"); `--prior-a 0,..,0
/// --prior-weight D` is `--delta D`; `--gate` reports the outliers.
#[test]
fn prior_settle_and_gate_flags() {
    let file = ar2("prior-flags.csv");
    let f = file.to_str().unwrap();
    let base = [
        "fit", f, "--column", "x", "--method", "lattice", "--order", "2", "--json",
    ];
    let with = |extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        imu_ar(&args)
    };
    let out = with(&["--prior-a", "-1.5,0.7"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let a = with(&["--prior-a", "0,0", "--prior-weight", "3"]);
    let b = with(&["--delta", "3"]);
    assert_eq!(stdout(&a), stdout(&b));
    let out = with(&["--settle", "1000000"]);
    assert_one_line_failure(&out);
    assert!(
        stderr(&out).contains("--settle 1000000"),
        "{}",
        stderr(&out)
    );
    let out = with(&["--gate", "5"]);
    assert!(stdout(&out).contains("\"outliers\":"), "{}", stdout(&out));
    misused(&[&base[..], &["--gate", "0"]].concat(), "--gate 0");
}
