//! `imu-ar` on pipes: `-` reads standard input, `simulate` streams any length, and a reader
//! that closes stdout early ends a command with status 0.

use std::io::{Read, Write};
use std::process::{Output, Stdio};

use crate::common;

use common::{ar2, column_file, command, imu_ar, json, stderr, stdout, temp_file};

/// Issue 23 item 7: `simulate` streams its output, so a huge `--n` starts writing at once
/// instead of aborting on an allocation.
#[test]
fn simulate_streams_any_length() {
    use std::io::{BufRead, BufReader};
    for n in ["1000000000000", "800000000000000000"] {
        let mut child = command()
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

// Formerly: `simulate` into a pipe closed early (`| head -c 100`) exits with status 1, though
// the code means a closed pipe to end the run quietly (status 0): simulate swallows
// BrokenPipe, then main's flush of the leftover stdout buffer fails.
#[test]
fn simulate_into_a_closed_pipe_exits_zero() {
    let mut child = command()
        .args([
            "simulate", "--a", "0.5", "--sigma", "1", "--n", "1000000", "--seed", "1",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut head = [0u8; 100];
    child
        .stdout
        .as_mut()
        .unwrap()
        .read_exact(&mut head)
        .unwrap();
    drop(child.stdout.take());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(0), "status {status:?} on a closed pipe");
}

/// Output cut short by a closed pipe ends with status 0 for a command that prints its result
/// at the end too.
#[test]
fn closed_pipe_after_the_result_exits_zero() {
    let file = ar2("pipe-adev.csv");
    let mut child = command()
        .args([
            "order",
            file.to_str().unwrap(),
            "--column",
            "x",
            "--max-order",
            "32",
            "--method",
            "burg",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(out.stderr.is_empty(), "{}", stderr(&out));
}

/// Runs `imu-ar ARGS` with `input` on its standard input.
fn piped(args: &[&str], input: &[u8]) -> Output {
    let mut child = command()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let out = child.wait_with_output().unwrap();
    writer
        .join()
        .unwrap()
        .expect("imu-ar reads all of its input");
    out
}

/// `-` as a file name reads standard input: every command that reads a record prints what it
/// prints for the file itself.
#[test]
fn a_dash_reads_standard_input() {
    let file = ar2("stdin.csv");
    let csv = std::fs::read(&file).unwrap();
    let f = file.to_str().unwrap();
    let dir = crate::common::temp_path("cli-stdin");
    let d = dir.to_str().unwrap();
    let cases: [&[&str]; 7] = [
        &[
            "fit", "-", "--column", "x", "--method", "burg", "--order", "2",
        ],
        &[
            "fit", "-", "--column", "x", "--method", "lattice", "--order", "2", "--json",
        ],
        &[
            "order",
            "-",
            "--column",
            "x",
            "--max-order",
            "4",
            "--method",
            "ls",
        ],
        &["adev", "-", "--column", "x", "--rate", "1"],
        &["compare", "-", "--column", "x", "--order", "2", "--json"],
        &[
            "kalman", "-", "--column", "x", "--order", "2", "--rate", "100",
        ],
        &[
            "report", "-", "--column", "x", "--order", "2", "--rate", "100", "--out", d,
        ],
    ];
    for args in cases {
        let from_file: Vec<&str> = args.iter().map(|&a| if a == "-" { f } else { a }).collect();
        let (piped, direct) = (piped(args, &csv), imu_ar(&from_file));
        assert!(
            direct.status.success(),
            "{from_file:?}: {}",
            stderr(&direct)
        );
        assert_eq!(piped.status.code(), Some(0), "{args:?}: {}", stderr(&piped));
        assert_eq!(stdout(&piped), stdout(&direct), "{args:?}");
        assert!(piped.stderr.is_empty(), "{args:?}: {}", stderr(&piped));
    }
    std::fs::remove_dir_all(dir).unwrap();
    std::fs::remove_file(file).unwrap();
}

/// Standard input is read once: `-` named twice is the same record twice, and a published
/// Allan table (`report --reference -`, three columns) reads from it as from a file.
#[test]
fn standard_input_is_read_once() {
    let file = ar2("stdin-twice.csv");
    let csv = std::fs::read(&file).unwrap();
    let f = file.to_str().unwrap();
    // Its stamps (1 Hz, `simulate`) go back to the start in the second copy: refused alike,
    // as files that overlap.
    let once = imu_ar(&["adev", f, f, "--column", "x", "--rate", "1", "--json"]);
    let twice = piped(
        &["adev", "-", "-", "--column", "x", "--rate", "1", "--json"],
        &csv,
    );
    for run in [&once, &twice] {
        assert_eq!(run.status.code(), Some(2));
        assert!(stderr(run).contains("the files overlap"), "{}", stderr(run));
    }
    // Without stamps, the record twice.
    let bare = column_file(
        "stdin-twice-bare.csv",
        (0..2000).map(|k| format!("{}", (k * 7919) % 101)),
    );
    let b = bare.to_str().unwrap();
    let once = imu_ar(&["adev", b, b, "--column", "x", "--rate", "1", "--json"]);
    let twice = piped(
        &["adev", "-", "-", "--column", "x", "--rate", "1", "--json"],
        &std::fs::read(&bare).unwrap(),
    );
    assert!(once.status.success(), "{}", stderr(&once));
    assert_eq!(stdout(&twice), stdout(&once));
    assert_eq!(json(&once)["n"], 4_000, "{}", stdout(&once));

    let table = temp_file(
        "stdin-table.csv",
        "channel,tau_s,adev\nx,0.01,1.0\ny,0.01,7.0\nx,0.1,0.5\n",
    );
    let dir = crate::common::temp_path("cli-table");
    let d = dir.to_str().unwrap();
    let report = |reference| {
        let mut args = vec![
            "report", f, "--column", "x", "--order", "1", "--rate", "100",
        ];
        args.extend(["--out", d, "--reference", reference]);
        args
    };
    let direct = imu_ar(&report(table.to_str().unwrap()));
    let piped = piped(&report("-"), &std::fs::read(&table).unwrap());
    assert!(direct.status.success(), "{}", stderr(&direct));
    assert_eq!(stdout(&piped), stdout(&direct));
    std::fs::remove_dir_all(dir).unwrap();
    std::fs::remove_file(table).unwrap();
    std::fs::remove_file(file).unwrap();
}

/// An error in standard input names `-` and the line, on one line.
#[test]
fn errors_in_standard_input_name_the_dash() {
    for (input, expected) in [
        (
            &b"x\n1\nabc\n"[..],
            "imu-ar: -:3: column 'x': 'abc' is not a number\n",
        ),
        (b"t,y\n1,2\n", "imu-ar: -: no column 'x' (columns: t, y)\n"),
        (b"", "imu-ar: -: empty file (no header row)\n"),
    ] {
        let out = piped(
            &[
                "fit", "-", "--column", "x", "--method", "ls", "--order", "1",
            ],
            input,
        );
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        assert!(out.stdout.is_empty());
        assert_eq!(stderr(&out), expected);
    }
}
