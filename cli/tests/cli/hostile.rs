//! Error messages that must name the right thing.

use crate::common;

use common::{imu_ar, simulated, stderr};

/// An output directory that cannot be made is the output's problem, not the input file's:
/// the message starts with the directory, not `in.csv: `.
#[test]
fn an_uncreatable_out_dir_is_not_blamed_on_the_input() {
    let input = simulated("out_dir_input.csv", "0.5", "400", "1");
    let input = input.to_str().unwrap();
    let out = imu_ar(&[
        "report",
        input,
        "--column",
        "x",
        "--order",
        "2",
        "--rate",
        "100",
        "--out",
        "/dev/null/x",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let err = stderr(&out);
    assert!(
        err.starts_with("imu-ar: /dev/null/x: cannot create"),
        "the message blames the input file: {err}"
    );
}

/// A negative `--n` names the argument it was meant for.
#[test]
fn a_negative_count_names_its_argument() {
    let out = imu_ar(&[
        "simulate", "--a", "0.5", "--sigma", "1", "--n", "-3", "--seed", "1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty());
    let err = stderr(&out);
    assert!(err.contains("--n"), "the message does not name --n: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

/// An `--out` that is a file is named as such.
#[test]
fn an_out_folder_that_is_a_file_is_named_as_such() {
    let file = common::temp_file("out-is-a-file", "not a folder");
    let input = common::temp_file(
        "out-is-a-file.csv",
        "gx,gy,gz,ax,ay,az\n1,2,3,4,5,6\n2,3,4,5,6,7\n",
    );
    let out = imu_ar(&[
        "characterise",
        input.to_str().unwrap(),
        "--rate",
        "100",
        "--out",
        file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert_eq!(
        err.trim_end(),
        format!("imu-ar: --out {}: is a file, not a folder", file.display())
    );
}
