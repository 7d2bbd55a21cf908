//! What the tests of the `imu-ar` tool share: running it, temp files, and the checks of its
//! output and of its one-line errors.
// Each test file uses some of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The `imu-ar` binary of this package, to be given arguments.
pub fn command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_imu-ar"))
}

/// Runs `imu-ar ARGS` to its end.
pub fn imu_ar(args: &[&str]) -> Output {
    command().args(args).output().expect("run imu-ar")
}

/// This process's folder for the tests' files, in cargo's folder for them (`target/tmp`,
/// which `cargo clean` empties): the folders of test processes no longer running are removed
/// the first time (where `/proc` tells which run).
pub fn temp_root() -> &'static Path {
    static ROOT: OnceLock<PathBuf> = OnceLock::new();
    ROOT.get_or_init(|| {
        let base = Path::new(env!("CARGO_TARGET_TMPDIR")).join("imu-ar-cli");
        let proc = Path::new("/proc/self");
        for entry in std::fs::read_dir(&base).into_iter().flatten().flatten() {
            let gone = entry
                .file_name()
                .to_str()
                .and_then(|n| n.parse::<u32>().ok())
                .is_some_and(|pid| proc.exists() && !Path::new(&format!("/proc/{pid}")).exists());
            if gone {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
        let dir = base.join(std::process::id().to_string());
        std::fs::create_dir_all(&dir).expect("the tests' folder");
        dir
    })
}

/// A path in [`temp_root`] ending in `name`, not given out before in this process (the tests
/// share one process and run in parallel).
pub fn temp_path(name: &str) -> PathBuf {
    static CALLS: AtomicUsize = AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, Ordering::Relaxed);
    temp_root().join(format!("{call}-{name}"))
}

/// A file in the temp directory with the given contents.
pub fn temp_file(name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let path = temp_path(name);
    std::fs::write(&path, contents).unwrap();
    path
}

/// The one JSON object of a successful run.
pub fn json(out: &Output) -> serde_json::Value {
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
pub fn drift_record(name: &str, n: &str) -> PathBuf {
    let out = imu_ar(&[
        "simulate", "--a", "1.5,-0.7", "--a-end", "1.0,-0.7", "--sigma", "1", "--n", n, "--seed",
        "4", "--rate", "100",
    ]);
    assert!(out.status.success());
    temp_file(name, String::from_utf8(out.stdout).unwrap())
}

/// `imu-ar fit FILE --column x --method M --order P --json EXTRA..`, parsed.
pub fn fit_json(file: &Path, method: &str, order: &str, extra: &[&str]) -> serde_json::Value {
    let file = file.to_str().unwrap();
    let mut args = vec![
        "fit", file, "--column", "x", "--method", method, "--order", order,
    ];
    args.extend_from_slice(extra);
    args.push("--json");
    json(&imu_ar(&args))
}

/// `imu-ar simulate --a A --sigma 1 --n N --seed K` as a temp file `name`.
pub fn simulated(name: &str, a: &str, n: &str, seed: &str) -> PathBuf {
    let out = imu_ar(&[
        "simulate", "--a", a, "--sigma", "1", "--n", n, "--seed", seed,
    ]);
    assert!(out.status.success());
    temp_file(name, String::from_utf8(out.stdout).unwrap())
}

/// A temp file `name` with column `x` holding `values`.
pub fn column_file(name: &str, values: impl IntoIterator<Item = String>) -> PathBuf {
    let mut s = String::from("x\n");
    for v in values {
        s += &v;
        s.push('\n');
    }
    temp_file(name, &s)
}

/// `imu-ar ARGS` exits with status 2, prints nothing on stdout and one line on stderr that
/// contains `expected`.
pub fn misused(args: &[&str], expected: &str) {
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

/// A run's stderr, as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A run's stdout, as text.
pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Status 2, nothing on stdout, exactly one line on stderr.
pub fn assert_one_line_failure(out: &Output) {
    assert_eq!(out.status.code(), Some(2), "stderr: {}", stderr(out));
    assert!(out.stdout.is_empty(), "stdout: {}", stdout(out));
    assert_eq!(
        stderr(out).trim_end_matches('\n').lines().count(),
        1,
        "not one line: {:?}",
        stderr(out)
    );
}

/// No NaN or infinity in `text`.
pub fn no_nan_inf(text: &str) {
    let lower = text.to_ascii_lowercase();
    assert!(
        !lower.contains("nan") && !lower.contains("inf"),
        "NaN/inf in output: {text}"
    );
}

/// A 5000-sample AR(2) record (column `x`).
pub fn ar2(name: &str) -> PathBuf {
    let out = imu_ar(&[
        "simulate", "--a", "0.7,-0.2", "--sigma", "1", "--n", "5000", "--seed", "5",
    ]);
    assert!(out.status.success());
    temp_file(name, &out.stdout)
}

/// `imu-ar fit FILE --column x --method burg --order 1`.
pub fn fit_burg(file: &Path) -> Output {
    imu_ar(&[
        "fit",
        file.to_str().unwrap(),
        "--column",
        "x",
        "--method",
        "burg",
        "--order",
        "1",
    ])
}

/// The names in the folder `dir`.
pub fn names_in(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}
