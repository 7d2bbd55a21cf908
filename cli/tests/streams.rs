//! `imu-ar` on pipes: `simulate` streams any length, and a reader that closes stdout early
//! ends a command with status 0.

use std::io::Read;
use std::process::Stdio;

mod common;

use common::{ar2, command, stderr};

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
