//! `imu-ar characterise` and the readers under every command: a EuRoC file needs no flag but
//! the column; a bag and an MCAP file of the same data give the same model as the CSV; the
//! Kalibr file carries the model's N and K; bad recordings exit 2 with one line, and skipped
//! messages are counted.

use crate::common;
use crate::ros;

use std::fmt::Write as _;
use std::path::Path;

use common::{assert_one_line_failure, imu_ar, json, stderr};
use imu_ar_cli::input::frame::Frame;
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use ros::{edited_bag, fixture, fixture_bytes, fixture_dir, noise_frames, temp_dir};

/// A standard normal deviate (Box-Muller).
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u = |r: &mut ChaCha8Rng| ((r.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64;
    let (a, b) = (u(rng), u(rng));
    (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
}

/// The noise of the six axes of a static IMU, SI: white noise `N`, random walk `K` and one
/// Gauss-Markov term (`sigma`, correlation time `T` in s) per axis.
struct Noise {
    white: [f64; 6],
    walk: [f64; 6],
    gm_sigma: [f64; 6],
    gm_t: f64,
}

/// `n` frames of a static IMU at `rate` Hz: white noise, a random walk and a Gauss-Markov term
/// per axis (gyros in rad/s, accelerometers in m/s^2 about gravity on z), stamps in ns with a
/// jitter of up to +-20 us.
fn imu_frames(n: usize, rate: f64, seed: u64) -> Vec<Frame> {
    let noise = Noise {
        white: [1e-3, 1.2e-3, 0.8e-3, 2e-2, 2.5e-2, 3e-2],
        walk: [2e-5, 1e-5, 3e-5, 4e-4, 2e-4, 5e-4],
        gm_sigma: [3e-4, 2e-4, 4e-4, 5e-3, 4e-3, 6e-3],
        gm_t: 5.0,
    };
    noise_frames_of(&noise, n, rate, seed)
}

/// `n` frames of a static IMU with `noise` at `rate` Hz, as [`imu_frames`].
fn noise_frames_of(noise: &Noise, n: usize, rate: f64, seed: u64) -> Vec<Frame> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let dt = 1.0 / rate;
    let mean = [0.01, -0.02, 0.005, 0.1, -0.2, 9.81];
    let phi: f64 = (-dt / noise.gm_t).exp();
    let mut rw = [0.0; 6];
    let mut gm = [0.0; 6];
    (0..n)
        .map(|i| {
            let jitter = (rng.next_u32() % 40_001) as i64 - 20_000;
            let stamp_ns = 1_403_636_579_758_555_392 + (i as f64 * dt * 1e9) as i64 + jitter;
            let axes = std::array::from_fn(|k| {
                rw[k] += noise.walk[k] * dt.sqrt() * normal(&mut rng);
                gm[k] =
                    phi * gm[k] + noise.gm_sigma[k] * (1.0 - phi * phi).sqrt() * normal(&mut rng);
                mean[k] + noise.white[k] / dt.sqrt() * normal(&mut rng) + rw[k] + gm[k]
            });
            Frame {
                stamp_ns,
                axes,
                ..Frame::default()
            }
        })
        .collect()
}

/// `frames` as a EuRoC/ASL `imu0/data.csv`.
fn write_euroc(path: &Path, frames: &[Frame]) {
    let header = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],\
                  a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]";
    write_with(path, header, frames, |i| frames[i].stamp_ns.to_string());
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `characterise ARGS --json --out DIR`, parsed.
fn characterise(input: &[&str], out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["characterise"];
    args.extend_from_slice(input);
    args.extend_from_slice(&["--out", path(out), "--json"]);
    args.extend_from_slice(extra);
    json(&imu_ar(&args))
}

#[test]
fn a_euroc_file_needs_no_flag_but_the_column() {
    let dir = temp_dir("euroc");
    let file = dir.join("data.csv");
    write_euroc(&file, &imu_frames(60_000, 200.0, 1));
    let noise = json(&imu_ar(&[
        "noise",
        path(&file),
        "--column",
        "w_RS_S_x",
        "--json",
    ]));
    let rate = noise["rate_hz"].as_f64().unwrap();
    assert!((rate / 200.0 - 1.0).abs() < 1e-3, "rate {rate}");
    assert_eq!(noise["timing"]["unit"], "ns");
    assert_eq!(noise["timing"]["gaps"], 0);
    // The bracket says rad/s; --unit deg/s converts.
    let deg = json(&imu_ar(&[
        "noise",
        path(&file),
        "--column",
        "w_RS_S_x",
        "--unit",
        "deg/s",
        "--json",
    ]));
    let ratio = deg["white_noise"].as_f64().unwrap() / noise["white_noise"].as_f64().unwrap();
    assert!(
        (ratio - 180.0 / std::f64::consts::PI).abs() < 1e-9,
        "{ratio}"
    );
    // By index, and without the command naming anything but the output.
    let by_index = json(&imu_ar(&["adev", path(&file), "--column", "1", "--json"]));
    assert!((by_index["rate_hz"].as_f64().unwrap() - rate).abs() < 1e-9);
    let all = characterise(&[path(&file)], &dir.join("out"), &[]);
    assert_eq!(all["axes"].as_array().unwrap().len(), 6);
    assert_eq!(all["axes"][0]["column"], "w_RS_S_x");
    assert_eq!(all["axes"][5]["unit"], "m/s^2");
    assert!((all["rate_hz"].as_f64().unwrap() - rate).abs() < 1e-9);
}

/// Every number of two JSON values equal to `rel` relative.
fn assert_close(a: &serde_json::Value, b: &serde_json::Value, rel: f64, at: &str) {
    use serde_json::Value::*;
    match (a, b) {
        (Number(x), Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(
                (x - y).abs() <= rel * x.abs().max(y.abs()),
                "{at}: {x} against {y}"
            );
        }
        (Array(x), Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}");
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                assert_close(p, q, rel, &format!("{at}[{i}]"));
            }
        }
        (Object(x), Object(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: keys");
            for (k, p) in x {
                assert_close(p, &y[k], rel, &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

#[test]
fn every_recording_kind_gives_the_model_of_the_csv() {
    let dir = temp_dir("same-model");
    let frames = noise_frames();
    let csv = dir.join("frames.csv");
    write_with(&csv, "t_ns,gx,gy,gz,ax,ay,az", &frames, |i| {
        frames[i].stamp_ns.to_string()
    });
    // The same frames, written by Python's rosbags (tests/fixtures/write_ros.py).
    let bag = fixture("noise-bz2.bag");
    let mcap = fixture("noise-zstd.mcap");
    // ROS 2: rosbag2 folders of both storages, and a bare SQLite storage file.
    let folder_mcap = fixture_dir("rosbag2-mcap");
    let folder_sqlite = fixture_dir("rosbag2-sqlite3");
    let db3 = fixture("noise.db3");
    // The CSV has no unit brackets: the bag's SI units are given.
    let units = ["--gyro-unit", "rad/s", "--accel-unit", "m/s^2"];
    let from_csv = characterise(&[path(&csv)], &dir.join("csv"), &units);
    for (file, name) in [
        (&bag, "bag"),
        (&mcap, "mcap"),
        (&folder_mcap, "rosbag2 mcap"),
        (&folder_sqlite, "rosbag2 sqlite3"),
        (&db3, "db3"),
    ] {
        let got = characterise(
            &[path(file), "--topic", "/imu0"],
            &dir.join(name.replace(' ', "-")),
            &[],
        );
        assert_close(&got["axes"], &from_csv["axes"], 1e-12, name);
        assert_eq!(got["n"], 1_200);
        // One axis through `noise`, as the CSV's column.
        let one = json(&imu_ar(&[
            "noise",
            path(file),
            "--topic",
            "/imu0",
            "--column",
            "gz",
            "--json",
        ]));
        let csv_one = json(&imu_ar(&[
            "noise",
            path(&csv),
            "--column",
            "gz",
            "--unit",
            "rad/s",
            "--json",
        ]));
        assert_close(&one["white_noise"], &csv_one["white_noise"], 1e-12, name);
        assert_close(&one["allan"], &csv_one["allan"], 1e-12, name);
    }
}

/// The value of `key:` in a YAML file written by the tool.
fn yaml_value(text: &str, key: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.starts_with(&format!("{key}:")))
        .unwrap_or_else(|| panic!("no {key}"));
    let value = line[key.len() + 1..].split('#').next().unwrap().trim();
    value.parse().unwrap()
}

/// The model's Allan variance of `axis` (of `characterise --json`) at its octaves with `tau`
/// in `[1 s, upper]`: `(tau, AVAR)`.
fn model_octaves(model: &serde_json::Value, axis: usize, upper: f64) -> Vec<(f64, f64)> {
    model["axes"][axis]["model"]["allan"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let (tau, adev) = (
                r["tau_s"].as_f64().unwrap(),
                r["model_adev"].as_f64().unwrap(),
            );
            (tau, adev * adev)
        })
        .filter(|(tau, _)| (1.0..=upper).contains(tau))
        .collect()
}

/// The octaves of `rows` where `sqrt(n^2/tau + k^2 tau/3)` is below the model's deviation.
fn uncovered(n: f64, k: f64, rows: &[(f64, f64)]) -> Vec<f64> {
    rows.iter()
        .filter(|(tau, v)| n * n / tau + k * k * tau / 3.0 < v * (1.0 - 1e-9))
        .map(|(tau, _)| *tau)
        .collect()
}

/// The Kalibr keys of the gyroscope and of the accelerometer: `(N key, K key, axes)`.
const KALIBR_KEYS: [(&str, &str, std::ops::Range<usize>); 2] = [
    ("gyroscope_noise_density", "gyroscope_random_walk", 0..3),
    (
        "accelerometer_noise_density",
        "accelerometer_random_walk",
        3..6,
    ),
];

#[test]
fn the_kalibr_file_carries_the_models_overbound_in_si() {
    let dir = temp_dir("kalibr");
    let file = dir.join("data.csv");
    write_euroc(&file, &imu_frames(100_000, 200.0, 3));
    let out = dir.join("out");
    let model = characterise(&[path(&file)], &out, &["--format", "kalibr"]);
    let text = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
    let worst = |axes: std::ops::Range<usize>, key: &str| {
        axes.map(|i| model["axes"][i]["model"][key].as_f64().unwrap_or(0.0))
            .fold(0.0, f64::max)
    };
    for (n_key, k_key, axes) in KALIBR_KEYS {
        let (n, k) = (yaml_value(&text, n_key), yaml_value(&text, k_key));
        // At or above the worst axis's fitted values, never zero.
        assert!(
            n >= worst(axes.clone(), "white_noise") && n > 0.0,
            "{n_key}: {n}"
        );
        assert!(
            k >= worst(axes.clone(), "random_walk") && k > 0.0,
            "{k_key}: {k}"
        );
        // Without a horizon: the overbound reaches every octave the record resolves.
        for i in axes {
            let rows = model_octaves(&model, i, f64::INFINITY);
            assert!(rows.len() >= 5, "axis {i}: {} octaves", rows.len());
            let below = uncovered(n, k, &rows);
            assert!(
                below.is_empty(),
                "axis {i}: ({n}, {k}) below the model at {below:?}"
            );
        }
    }
    assert!((yaml_value(&text, "update_rate") - 200.0).abs() < 0.2);
}

/// Six seeds of white + random walk, one hour at 100 Hz, `--horizon 600`: in the median over
/// the seeds, `K_H / K_true` is at most 2 and `N_H / N_true` at most 1.2, for the gyro and the
/// accelerometer, and every seed's overbound holds at every octave up to the horizon.
/// `cargo test -p imu-ar-cli --test cli -- characterise::a_white --nocapture` prints the ratios.
#[test]
fn a_white_and_random_walk_record_exports_close_to_its_truth() {
    // The random walk crosses the white noise at sqrt(3) N / K = 43 s and rules the last 1.5
    // decades of the octaves the record resolves (to about 1300 s).
    let (gyro, accel) = ((1e-3, 4e-5), (2e-2, 8e-4));
    let noise = Noise {
        white: [gyro.0, gyro.0, gyro.0, accel.0, accel.0, accel.0],
        walk: [gyro.1, gyro.1, gyro.1, accel.1, accel.1, accel.1],
        gm_sigma: [0.0; 6],
        gm_t: 1.0,
    };
    let horizon = 600.0;
    let mut ratios = [const { Vec::new() }; 2];
    for seed in 12..18 {
        let dir = temp_dir(&format!("white-rw-{seed}"));
        let file = dir.join("data.csv");
        write_euroc(&file, &noise_frames_of(&noise, 360_000, 100.0, seed));
        let out = dir.join("out");
        let model = characterise(
            &[path(&file)],
            &out,
            &["--format", "kalibr", "--horizon", "600"],
        );
        let text = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
        assert!(
            text.contains("to H = 6.0000e2 s, the horizon asked for (log N_H/N"),
            "{text}"
        );
        let sensors = KALIBR_KEYS.into_iter().zip([gyro, accel]);
        for (s, ((n_key, k_key, axes), (n_true, k_true))) in sensors.enumerate() {
            let (n, k) = (yaml_value(&text, n_key), yaml_value(&text, k_key));
            ratios[s].push((n / n_true, k / k_true));
            for i in axes {
                let rows = model_octaves(&model, i, horizon);
                assert!(
                    rows.len() >= 9,
                    "seed {seed} axis {i}: {} octaves",
                    rows.len()
                );
                let below = uncovered(n, k, &rows);
                assert!(
                    below.is_empty(),
                    "seed {seed} axis {i}: ({n}, {k}) below the model at {below:?}"
                );
            }
        }
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2 - 1] + v[v.len() / 2]) / 2.0
    };
    for (name, r) in ["gyro", "accelerometer"].into_iter().zip(ratios) {
        println!("{name}: (N_H / N, K_H / K) by seed {r:.3?}");
        let n = median(r.iter().map(|p| p.0).collect());
        let k = median(r.iter().map(|p| p.1).collect());
        println!("{name}: median N_H / N {n:.3}, K_H / K {k:.3}");
        assert!(n <= 1.2, "{name}: median N_H / N = {n}");
        assert!(k <= 2.0, "{name}: median K_H / K = {k}");
    }
}

/// `imu-ar ARGS` fails with status 2, one line containing `want`, and nothing on stdout.
#[test]
fn header_stamps_coarser_than_the_messages_are_read_as_the_csv_reads_them() {
    // A driver stamping 200 Hz messages to 10 ms: every other header stamp repeats the one
    // before, in a bag and a CSV of the same stamps. Read as the CSV is (refused as "not
    // after the one before", even with --rate, before; --drop-backward then read a 100 Hz
    // record): 200 Hz, every message.
    let dir = temp_dir("coarse-header-stamps");
    let out = dir.join("out");
    let mut frames = noise_frames();
    let base = frames[0].stamp_ns / 10_000_000 * 10_000_000;
    for (i, f) in frames.iter_mut().enumerate() {
        f.stamp_ns = base + i as i64 * 5_000_000 / 10_000_000 * 10_000_000;
    }
    assert!(frames.windows(2).any(|w| w[0].stamp_ns == w[1].stamp_ns));
    let bag = edited_bag(&dir, "noise.bag", "coarse.bag", &frames);
    let csv = dir.join("coarse.csv");
    write_euroc(&csv, &frames);
    let from_csv = characterise(&[path(&csv)], &out, &[]);
    for extra in [&[][..], &["--rate", "200"][..]] {
        let from_bag = characterise(&[path(&bag), "--topic", "/imu0"], &out, extra);
        assert_eq!(from_bag["n"], 1_200, "{extra:?}");
        assert_eq!(from_bag["rate_hz"], 200.0, "{extra:?}");
        assert_eq!(from_bag["timing"]["repeated"], 600, "{extra:?}");
        assert_eq!(
            from_bag["axes"][0]["model"]["white_noise"],
            from_csv["axes"][0]["model"]["white_noise"],
            "{extra:?}"
        );
    }
    assert_eq!(from_csv["rate_hz"], 200.0);
    // Dropping them would halve the rate: refused, as for the CSV.
    refused(
        &[
            "characterise",
            path(&bag),
            "--topic",
            "/imu0",
            "--drop-backward",
            "--out",
            path(&out),
        ],
        "read it without --drop-backward",
    );
    // A fine clock's message repeated: named as such.
    let mut twice = noise_frames();
    twice[700].stamp_ns = twice[699].stamp_ns;
    let bag = edited_bag(&dir, "noise.bag", "twice.bag", &twice);
    refused(
        &[
            "characterise",
            path(&bag),
            "--topic",
            "/imu0",
            "--out",
            path(&out),
        ],
        "1 timestamps equal the one before",
    );
}

#[test]
fn a_run_ended_by_a_signal_leaves_no_folder_behind() {
    // A folder `.imu-ar-PID` of a process that no longer runs (killed with SIGKILL mid-write)
    // is swept by the next run; SIGTERM removes the run's own (both were left in `--out`).
    let dir = temp_dir("signal");
    let out = dir.join("out");
    let stale = out.join(".imu-ar-999999999");
    std::fs::create_dir_all(&stale).unwrap();
    std::fs::write(stale.join("imu.yaml"), "old").unwrap();
    let file = dir.join("data.csv");
    write_euroc(&file, &imu_frames(400_000, 200.0, 3));
    characterise(&[path(&file)], &out, &[]);
    let leftovers = |out: &Path| -> Vec<String> {
        std::fs::read_dir(out)
            .map(|entries| {
                entries
                    .flatten()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .filter(|n| n.starts_with(".imu-ar-"))
                    .collect()
            })
            .unwrap_or_default()
    };
    assert!(leftovers(&out).is_empty(), "{:?}", leftovers(&out));
    // SIGTERM while the files are being written (or, if the run is done by then, after).
    let signalled = dir.join("signalled");
    std::fs::create_dir_all(&signalled).unwrap();
    let mut child = spawned(&file, &signalled);
    let start = std::time::Instant::now();
    while leftovers(&signalled).is_empty() && start.elapsed().as_secs() < 60 {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    let kill = terminated(&child);
    let status = child.wait().unwrap();
    assert!(
        !kill.success() || status.code() == Some(130) || status.success(),
        "{status:?}"
    );
    assert!(
        leftovers(&signalled).is_empty(),
        "{:?}",
        leftovers(&signalled)
    );
    // Status 130 is a run whose output is not in place (exit 130 with the whole set written,
    // a signal just after the moves, before).
    if status.code() == Some(130) {
        assert!(!signalled.join("imu.yaml").exists());
    }
    // SIGTERM while the record is read into folders the run made for --out: they go too
    // (fresh/a/b was left, empty, before).
    let fresh = dir.join("fresh");
    let deep = fresh.join("a").join("b");
    let mut child = spawned(&file, &deep);
    let start = std::time::Instant::now();
    while !deep.exists() && start.elapsed().as_secs() < 60 && child.try_wait().unwrap().is_none() {
        std::thread::sleep(std::time::Duration::from_micros(200));
    }
    let kill = terminated(&child);
    let status = child.wait().unwrap();
    if kill.success() && status.code() == Some(130) {
        assert!(!fresh.exists(), "{:?}", std::fs::read_dir(&fresh).ok());
    } else {
        assert!(
            status.success() && deep.join("imu.yaml").is_file(),
            "{status:?}"
        );
    }
}

/// `characterise` of `file` into `out`, running, its output discarded.
fn spawned(file: &Path, out: &Path) -> std::process::Child {
    common::command()
        .args(["characterise", path(file), "--out", path(out)])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// Whether SIGTERM reached `child` (not if it had ended).
fn terminated(child: &std::process::Child) -> std::process::ExitStatus {
    std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap()
}

fn refused(args: &[&str], want: &str) {
    let out = imu_ar(args);
    assert_one_line_failure(&out);
    assert!(stderr(&out).contains(want), "{args:?}: {}", stderr(&out));
}

#[test]
fn bad_recordings_exit_2_with_one_line() {
    let dir = temp_dir("bad");
    let out = dir.join("out");
    // 1200 frames at 100 Hz on /imu0, strings on /chatter.
    let frames = noise_frames();
    let bag = fixture("noise.bag");
    let b = path(&bag);
    let o = path(&out);
    // A bag without the topic, or without --topic: the IMU topics it has.
    refused(
        &["characterise", b, "--topic", "/imu", "--out", o],
        "IMU topics: /imu0",
    );
    refused(&["noise", b, "--column", "gx"], "/imu0");
    // A message's units are SI: a unit flag of what the axis does not measure is refused in
    // the words of a message, not of a CSV header; a --rate the header stamps disagree with
    // names them.
    refused(
        &[
            "characterise",
            b,
            "--topic",
            "/imu0",
            "--gyro-unit",
            "m/s^2",
            "--out",
            o,
        ],
        "--gyro-unit m/s^2: a sensor_msgs/Imu message gives gx in rad/s (SI units, REP 103)",
    );
    refused(
        &[
            "characterise",
            b,
            "--topic",
            "/imu0",
            "--rate",
            "200",
            "--out",
            o,
        ],
        "--rate 200: the messages' stamps give 100",
    );
    // A number too small to write out is shown in exponent form.
    refused(
        &[
            "characterise",
            b,
            "--topic",
            "/imu0",
            "--rate",
            "1e-300",
            "--out",
            o,
        ],
        "--rate 1e-300: ",
    );
    // A truncated bag.
    let bytes = fixture_bytes("noise.bag");
    let cut = dir.join("cut.bag");
    std::fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    refused(
        &["characterise", path(&cut), "--topic", "/imu0", "--out", o],
        "truncated or corrupt bag",
    );
    // An MCAP file with an encoding other than CDR.
    let json_mcap = fixture("json.mcap");
    refused(
        &[
            "characterise",
            path(&json_mcap),
            "--topic",
            "/imu",
            "--out",
            o,
        ],
        "unknown encoding 'json'",
    );
    // Timestamps going backwards: refused, or dropped and counted.
    let mut back = frames.clone();
    back[600].stamp_ns = back[300].stamp_ns;
    back[900].stamp_ns -= 1_000_000_000;
    let back_bag = edited_bag(&dir, "noise.bag", "back.bag", &back);
    refused(
        &[
            "characterise",
            path(&back_bag),
            "--topic",
            "/imu0",
            "--out",
            o,
        ],
        "2 timestamps are not after the one before",
    );
    let dropped = characterise(
        &[path(&back_bag), "--topic", "/imu0", "--drop-backward"],
        &out,
        &[],
    );
    assert_eq!(dropped["skipped"]["backward"], 2);
    assert_eq!(dropped["n"], 1_198);
    let back_csv = dir.join("back.csv");
    write_euroc(&back_csv, &back);
    refused(
        &["noise", path(&back_csv), "--column", "w_RS_S_x"],
        "is not after the one before",
    );
    // Mixed rates: the second half at twice the rate.
    let mut mixed = frames.clone();
    for (i, f) in mixed.iter_mut().enumerate().skip(600) {
        f.stamp_ns = frames[600].stamp_ns + (i as i64 - 600) * 5_000_000;
    }
    let mixed_csv = dir.join("mixed.csv");
    write_euroc(&mixed_csv, &mixed);
    refused(
        &["characterise", path(&mixed_csv), "--out", o],
        "mixed rates",
    );
    let mixed_bag = edited_bag(&dir, "noise.bag", "mixed.bag", &mixed);
    refused(
        &[
            "noise",
            path(&mixed_bag),
            "--topic",
            "/imu0",
            "--column",
            "ax",
        ],
        "mixed rates",
    );
}

#[test]
fn skipped_messages_are_counted_in_the_summary() {
    let dir = temp_dir("skipped");
    let mut frames = noise_frames();
    for i in [10, 20, 1000] {
        frames[i].axes[4] = f64::NAN;
    }
    frames[30].axes[0] = f64::INFINITY;
    let bag = edited_bag(&dir, "noise.bag", "nan.bag", &frames);
    let got = characterise(&[path(&bag), "--topic", "/imu0"], &dir.join("out"), &[]);
    assert_eq!(got["skipped"]["non_finite"], 4);
    assert_eq!(got["n"], 1_196);
    let text = imu_ar(&[
        "characterise",
        path(&bag),
        "--topic",
        "/imu0",
        "--out",
        path(&dir.join("out")),
    ]);
    assert!(
        String::from_utf8_lossy(&text.stdout).contains("4 not finite"),
        "{}",
        String::from_utf8_lossy(&text.stdout)
    );
}

/// `frames` as CSV with `header` (seven names) and the stamp column written by `stamp`.
fn write_with(path: &Path, header: &str, frames: &[Frame], stamp: impl Fn(usize) -> String) {
    let mut s = format!("{header}\n");
    for (i, f) in frames.iter().enumerate() {
        s += &stamp(i);
        for v in f.axes {
            write!(s, ",{v:?}").unwrap();
        }
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn time_units_are_stated_or_epoch_sized() {
    let dir = temp_dir("time-units");
    let frames = imu_frames(4_000, 250.0, 6);
    let plain = "timestamp,gx,gy,gz,ax,ay,az";
    // Microseconds since boot: no unit, no epoch. Refused, not read as seconds.
    let boot = dir.join("boot.csv");
    write_with(&boot, plain, &frames, |i| {
        (263_000_000 + i * 4000).to_string()
    });
    refused(
        &["noise", path(&boot), "--column", "gx"],
        "does not say its unit",
    );
    // Stated in the bracket (msec, usec spelled out), the rate is right.
    for (bracket, scale) in [("[usec]", 1.0), ("[msec]", 1e-3)] {
        let file = dir.join("stated.csv");
        let header = plain.replace("timestamp", &format!("timestamp {bracket}"));
        write_with(&file, &header, &frames, |i| {
            format!("{}", (263_000_000.0 + i as f64 * 4000.0) * scale)
        });
        let got = json(&imu_ar(&["adev", path(&file), "--column", "gx", "--json"]));
        assert!(
            (got["rate_hz"].as_f64().unwrap() / 250.0 - 1.0).abs() < 1e-6,
            "{bracket}"
        );
    }
    let hours = dir.join("hours.csv");
    write_with(
        &hours,
        &plain.replace("timestamp", "timestamp [h]"),
        &frames,
        |i| i.to_string(),
    );
    refused(
        &["noise", path(&hours), "--column", "gx"],
        "is not a time unit",
    );
    // A given rate is checked against the stamps.
    let euroc = dir.join("euroc.csv");
    write_euroc(&euroc, &frames);
    refused(
        &[
            "characterise",
            path(&euroc),
            "--rate",
            "400",
            "--out",
            path(&dir),
        ],
        "--rate 400: the timestamps give",
    );
}

#[test]
fn rows_files_and_flags_that_would_shift_or_mix_units_are_refused() {
    let dir = temp_dir("shift");
    let o = dir.join("out");
    let frames = imu_frames(2_000, 200.0, 7);
    // One row with a field too many.
    let good = dir.join("good.csv");
    write_euroc(&good, &frames);
    let text = std::fs::read_to_string(&good).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[500] = format!("{},0", lines[500]);
    let shifted = dir.join("shifted.csv");
    std::fs::write(&shifted, lines.join("\n")).unwrap();
    refused(
        &["characterise", path(&shifted), "--out", path(&o)],
        "shifted.csv:501: 8 fields, the header has 7",
    );
    // A trailing comma on every line is one empty field everywhere: read.
    let trailing = dir.join("trailing.csv");
    std::fs::write(&trailing, text.replace('\n', ",\n")).unwrap();
    let got = characterise(&[path(&trailing)], &o, &["--format", "kalibr"]);
    assert_eq!(got["n"], 2_000);
    // Two parts with different unit brackets.
    let second = dir.join("second.csv");
    std::fs::write(&second, text.replacen("[rad s^-1]", "[deg s^-1]", 3)).unwrap();
    refused(
        &["noise", path(&good), path(&second), "--column", "w_RS_S_x"],
        "unit brackets differ",
    );
    // A flag that contradicts the header, one of the wrong kind, a column named twice.
    refused(
        &[
            "characterise",
            path(&good),
            "--gyro-unit",
            "deg/s",
            "--out",
            path(&o),
        ],
        "--gyro-unit deg/s: the header of column 'w_RS_S_x' says rad/s",
    );
    let plain = dir.join("plain.csv");
    write_with(&plain, "t_ns,gx,gy,gz,ax,ay,az", &frames, |i| {
        frames[i].stamp_ns.to_string()
    });
    refused(
        &[
            "characterise",
            path(&plain),
            "--gyro-unit",
            "m/s^2",
            "--accel-unit",
            "g",
            "--out",
            path(&o),
        ],
        "not a unit of what gx measures",
    );
    refused(
        &[
            "characterise",
            path(&good),
            "--columns",
            "1,1,3,4,5,6",
            "--out",
            path(&o),
        ],
        "is named twice",
    );
    // A first line of numbers is no header.
    let headless = dir.join("headless.csv");
    std::fs::write(&headless, "1,2\n3,4\n").unwrap();
    refused(
        &["adev", path(&headless), "--column", "0", "--rate", "1"],
        "header row",
    );
}

#[test]
fn parameter_files_are_written_all_or_none() {
    let dir = temp_dir("all-or-none");
    let file = dir.join("data.csv");
    write_euroc(&file, &imu_frames(20_000, 200.0, 8));
    let out = dir.join("out");
    // PX4's EKF2 cannot step at 10 Hz: no file at all, not the ones before it.
    refused(
        &[
            "characterise",
            path(&file),
            "--filter-rate",
            "10",
            "--out",
            path(&out),
        ],
        "EKF2_PREDICT_US",
    );
    let left: Vec<_> = std::fs::read_dir(&out).map_or(Vec::new(), |d| d.collect());
    assert!(left.is_empty(), "{left:?}");
    refused(
        &[
            "characterise",
            path(&file),
            "--horizon",
            "0.5",
            "--out",
            path(&out),
        ],
        "--horizon 0.5",
    );
}

#[test]
fn uptime_clocks_rounded_stamps_and_unknown_units() {
    let dir = temp_dir("second-pass");
    let frames = imu_frames(20_000, 200.0, 9);
    let plain = "timestamp,gx,gy,gz,ax,ay,az";
    // A micros() counter past 2e9 looks like epoch seconds: the rate it gives is refused.
    let uptime = dir.join("uptime.csv");
    write_with(&uptime, plain, &frames, |i| {
        (2_000_000_000 + i * 5000).to_string()
    });
    refused(
        &["adev", path(&uptime), "--column", "gx"],
        "not an IMU's rate",
    );
    // Stamps rounded to whole ms: 180 Hz and 400 Hz come out right.
    for rate in [180.0, 400.0] {
        let rounded = dir.join("rounded.csv");
        write_with(&rounded, "t [ms],gx,gy,gz,ax,ay,az", &frames, |i| {
            ((i as f64 / rate * 1000.0).floor() as i64).to_string()
        });
        let got = json(&imu_ar(&[
            "adev",
            path(&rounded),
            "--column",
            "gx",
            "--json",
        ]));
        let r = got["rate_hz"].as_f64().unwrap();
        assert!((r / rate - 1.0).abs() < 1e-3, "{rate}: {r}");
    }
    // A stated unit that is not converted is not relabelled; gauss is not g.
    let mrad = dir.join("mrad.csv");
    write_with(&mrad, "t [s],g [mrad/s],a [mG],x,y,z,w", &frames, |i| {
        format!("{}", i as f64 / 200.0)
    });
    refused(
        &["noise", path(&mrad), "--column", "g", "--unit", "deg/s"],
        "is in [mrad/s]",
    );
    refused(
        &["noise", path(&mrad), "--column", "a", "--unit", "m/s^2"],
        "is in [mG]",
    );
    // A parameter file blocked by a directory: none is written.
    let euroc = dir.join("euroc.csv");
    write_euroc(&euroc, &frames);
    let out = dir.join("out");
    std::fs::create_dir_all(out.join("px4.params")).unwrap();
    refused(
        &["characterise", path(&euroc), "--out", path(&out)],
        "px4.params: is a directory",
    );
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
}

/// One gyro axis shows a walk; another, a hundred times noisier, shows none and leaves room for
/// a larger one. The Kalibr file's gyro random walk is the larger: the file never carries less
/// than an axis's record allows (before, the fitted walk of the first axis alone).
#[test]
fn an_axis_without_a_walk_lends_the_file_its_bound() {
    let noise = Noise {
        white: [1e-3, 5e-2, 1e-3, 2e-2, 2e-2, 2e-2],
        walk: [4e-5, 0.0, 4e-5, 8e-4, 8e-4, 8e-4],
        gm_sigma: [0.0; 6],
        gm_t: 1.0,
    };
    let dir = temp_dir("axis-without-walk");
    let file = dir.join("data.csv");
    write_euroc(&file, &noise_frames_of(&noise, 360_000, 100.0, 5));
    let out = dir.join("out");
    let model = characterise(&[path(&file)], &out, &["--format", "kalibr"]);
    let gy = &model["axes"][1]["model"];
    assert!(gy["random_walk"].is_null(), "{gy}");
    let bound = gy["intervals"]["random_walk"]["high"].as_f64().unwrap();
    let fitted = model["axes"][0]["model"]["random_walk"].as_f64().unwrap();
    assert!(bound > fitted, "gy's bound {bound}, gx's K {fitted}");
    let text = std::fs::read_to_string(out.join("imu.yaml")).unwrap();
    let k = yaml_value(&text, "gyroscope_random_walk");
    assert!(k >= bound, "{k} < gy's bound {bound}: {text}");
    assert!(
        text.contains("An axis without a random walk leaves room for more"),
        "{text}"
    );
}

#[test]
fn accelerometers_in_g_or_mg_are_told_by_gravity() {
    // A static record reads gravity's 9.81 m/s^2 in magnitude: values of about 1 or 1000
    // under m/s^2 (a header that says m/s^2, a driver that publishes g despite REP 103) are
    // g or mg, refused naming the unit and how to give it (read as m/s^2, with noise 9.8
    // times too small, before). A driver's g given with --accel-unit reads as the same
    // record in m/s^2 does.
    let dir = temp_dir("gravity");
    let out = dir.join("out");
    let frames = noise_frames();
    let scaled = |by: f64| -> Vec<Frame> {
        frames
            .iter()
            .map(|f| Frame {
                stamp_ns: f.stamp_ns,
                axes: std::array::from_fn(|k| if k < 3 { f.axes[k] } else { f.axes[k] * by }),
                ..*f
            })
            .collect()
    };
    let g = 1.0 / 9.806_65;
    for (by, unit) in [(g, "g"), (1000.0 * g, "mg")] {
        let csv = dir.join(format!("{unit}.csv"));
        write_euroc(&csv, &scaled(by));
        refused(
            &["characterise", path(&csv), "--out", path(&out)],
            &format!(
                "the values are in {unit}, not m/s^2: say so in the header's bracket ([{unit}])"
            ),
        );
    }
    // The other way: m/s^2 under a [g] header reads 96 "m/s^2", mg under [g] 9807, m/s^2
    // under [mg] 0.0098; each is named for the unit it is in.
    for (by, header, unit, read) in [
        (1.0, "g", "m/s^2", "g"),
        (1000.0 * g, "g", "mg", "g"),
        (1.0, "mg", "m/s^2", "mg"),
    ] {
        let csv = dir.join(format!("{unit}-as-{header}.csv").replace('/', "_"));
        let columns = "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],\
                       w_RS_S_z [rad s^-1]";
        let header =
            format!("{columns},a_RS_S_x [{header}],a_RS_S_y [{header}],a_RS_S_z [{header}]");
        let frames = scaled(by);
        write_with(&csv, &header, &frames, |i| frames[i].stamp_ns.to_string());
        refused(
            &["characterise", path(&csv), "--out", path(&out)],
            &format!("the values are in {unit}, not {read}: say so in the header's bracket"),
        );
    }
    let bag = edited_bag(&dir, "noise.bag", "g.bag", &scaled(g));
    let topic = ["--topic", "/imu0"];
    // `characterise BAG --topic /imu0 EXTRA --out OUT`.
    let of_bag = |bag: &Path, extra: &[&str]| {
        let mut args = vec!["characterise", path(bag), topic[0], topic[1]];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", path(&out)]);
        imu_ar(&args)
    };
    // A bag in m/s^2 (REP 103) read with --accel-unit g is refused (after the flag's
    // warnings), naming the file.
    let si_bag = fixture("noise.bag");
    let wrong = of_bag(&si_bag, &["--accel-unit", "g"]);
    assert_eq!(wrong.status.code(), Some(2));
    let last = stderr(&wrong).lines().last().unwrap_or_default().to_owned();
    assert!(
        last.starts_with(&format!(
            "imu-ar: {}: the accelerometers read 96.2",
            path(&si_bag)
        )) && last.ends_with(
            "the values are in m/s^2, not g (the messages' own unit, REP 103): leave \
                 --accel-unit g out"
        ),
        "{last}"
    );
    let in_g = of_bag(&bag, &[]);
    assert_one_line_failure(&in_g);
    assert!(
        stderr(&in_g).contains(
            "the values are in g, not m/s^2 (a driver that does not keep REP 103): \
             --accel-unit g reads them so"
        ),
        "{}",
        stderr(&in_g)
    );
    let si = characterise(
        &[path(&fixture("noise.bag")), topic[0], topic[1]],
        &out,
        &[],
    );
    let read = of_bag(&bag, &["--accel-unit", "g", "--json"]);
    assert!(
        stderr(&read).contains("--accel-unit g: ax read in g, not in the m/s^2"),
        "{}",
        stderr(&read)
    );
    let read = json(&read);
    for k in 3..6 {
        let n = |v: &serde_json::Value| v["axes"][k]["model"]["white_noise"].as_f64().unwrap();
        assert!((n(&read) / n(&si) - 1.0).abs() < 1e-9, "{k}: {read} {si}");
    }
}

#[test]
fn files_given_out_of_time_order_are_named_so() {
    // Two pieces of one record, the later first (as a shell's glob orders rec_10 before
    // rec_2): refused as files out of order (a stamp not after the one before, with
    // --drop-backward as the remedy, before); in time order, read.
    let dir = temp_dir("file-order");
    let out = dir.join("out");
    let frames = imu_frames(8_000, 200.0, 3);
    let (early, late) = (dir.join("rec_2.csv"), dir.join("rec_10.csv"));
    write_euroc(&early, &frames[..4_000]);
    write_euroc(&late, &frames[4_000..]);
    refused(
        &[
            "characterise",
            path(&late),
            path(&early),
            "--out",
            path(&out),
        ],
        &format!(
            "rec_2.csv:2: the file's first timestamp, {} ns, is before the first of the file \
             before ({} ns): the files are out of order",
            frames[0].stamp_ns, frames[4_000].stamp_ns
        ),
    );
    // A file given twice, or pieces that overlap: named so (out of order before).
    let middle = dir.join("rec_1b.csv");
    write_euroc(&middle, &frames[2_000..6_000]);
    // With --rate too (read as one record, the samples twice, before: the stamps only check
    // a rate given).
    for (second, first_at, rate) in [
        (&early, frames[0].stamp_ns, None),
        (&middle, frames[2_000].stamp_ns, None),
        (&early, frames[0].stamp_ns, Some("200")),
        (&middle, frames[2_000].stamp_ns, Some("200")),
    ] {
        let mut args = vec![
            "characterise",
            path(&early),
            path(second),
            "--out",
            path(&out),
        ];
        args.extend(rate.map(|r| ["--rate", r]).iter().flatten());
        refused(
            &args,
            &format!(
                "the file's first timestamp, {first_at} ns, lies within the file before ({} \
                 to {} ns): the files overlap",
                frames[0].stamp_ns, frames[3_999].stamp_ns
            ),
        );
    }
    refused(
        &[
            "characterise",
            path(&late),
            path(&early),
            "--rate",
            "200",
            "--out",
            path(&out),
        ],
        "the files are out of order",
    );
    let read = characterise(&[path(&early), path(&late)], &out, &[]);
    assert_eq!(read["n"], 8_000, "{read}");
    // With --drop-backward, files out of order or given twice are refused as well (the
    // second dropped whole, exit 0, before); pieces that share a short stretch are read, the
    // stretch dropped once.
    for (a, b, want) in [
        (&late, &early, "the files are out of order"),
        (&early, &early, "the files overlap"),
    ] {
        let args = [
            "characterise",
            path(a),
            path(b),
            "--drop-backward",
            "--out",
            path(&out),
        ];
        refused(&args, want);
    }
    let next = dir.join("rec_3.csv");
    write_euroc(&next, &frames[3_990..6_000]);
    let shared = characterise(&[path(&early), path(&next)], &out, &["--drop-backward"]);
    assert_eq!(
        (&shared["n"], &shared["skipped"]["backward"]),
        (&6_000.into(), &10.into()),
        "{shared}"
    );
    // Within a file, at a rate given, samples stamped before the one before are kept in file
    // order (the stamps only check the rate), counted and warned of (kept silently before).
    let again = dir.join("again.csv");
    let mut rows = frames[..3_000].to_vec();
    rows.extend_from_slice(&frames[2_000..2_100]);
    rows.extend_from_slice(&frames[3_000..6_000]);
    write_euroc(&again, &rows);
    let kept = imu_ar(&[
        "characterise",
        path(&again),
        "--rate",
        "200",
        "--out",
        path(&out),
        "--json",
    ]);
    assert!(
        stderr(&kept).contains(
            "100 samples stamped before the one before kept in file order, as the rate given \
             reads them (--drop-backward drops them)"
        ),
        "{}",
        stderr(&kept)
    );
    let kept = json(&kept);
    assert_eq!(
        (&kept["n"], &kept["skipped"]["backward_kept"]),
        (&6_100.into(), &100.into()),
        "{kept}"
    );
    // The same of bags (refused as a stamp not after the one before, with --drop-backward
    // as the remedy, before).
    let frames = noise_frames();
    let later: Vec<Frame> = frames
        .iter()
        .map(|f| Frame {
            stamp_ns: f.stamp_ns + 12_000_000_000,
            ..*f
        })
        .collect();
    let (one, two) = (
        edited_bag(&dir, "noise.bag", "one.bag", &frames),
        edited_bag(&dir, "noise.bag", "two.bag", &later),
    );
    let bag_args = |a: &Path, b: &Path| -> Vec<String> {
        [
            "characterise",
            path(a),
            path(b),
            "--topic",
            "/imu0",
            "--out",
            path(&out),
        ]
        .map(String::from)
        .to_vec()
    };
    for (a, b, want) in [
        (&two, &one, "one.bag: the file's first timestamp, "),
        (&two, &one, "the files are out of order"),
        (&one, &one, "one.bag: the file's first timestamp, "),
        (&one, &one, "the files overlap"),
    ] {
        let args = bag_args(a, b);
        refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), want);
    }
    let args = bag_args(&one, &two);
    let read = json(&imu_ar(
        &args
            .iter()
            .map(String::as_str)
            .chain(["--json"])
            .collect::<Vec<_>>(),
    ));
    assert_eq!(read["n"], 2_400, "{read}");
}

#[test]
fn an_axis_whose_allan_variance_underflows_is_named_so() {
    // Values of about 1e-300 that differ: their Allan variance underflows to zero, named so
    // (refused as "the input is constant" before), as `noise` names it.
    let dir = temp_dir("underflow");
    let mut frames = imu_frames(6_000, 200.0, 4);
    frames.iter_mut().for_each(|f| f.axes[0] *= 1e-298);
    let file = dir.join("tiny.csv");
    write_euroc(&file, &frames);
    refused(
        &["characterise", path(&file), "--out", path(&dir.join("out"))],
        "gx (w_RS_S_x): the Allan variance underflows f64",
    );
}

#[test]
fn a_spectral_line_the_model_cannot_take_is_refused_not_read_as_white_noise() {
    // White noise of 1e-3 per sqrt(Hz) with a 3 Hz line of 0.05 (a fan on the bench), 200 Hz
    // for 20 minutes: without oscillators a short Gauss-Markov term (or a white level 20
    // times too large) covered the line's hump, the model's Allan deviation 9 times the
    // record's at 1.28 s, and was written into every file; refused, naming the line and
    // --oscillators, with which N is read.
    let dir = temp_dir("line");
    let noise = Noise {
        white: [1e-3, 1e-3, 1e-3, 2e-2, 2e-2, 2e-2],
        walk: [0.0; 6],
        gm_sigma: [0.0; 6],
        gm_t: 5.0,
    };
    let mut frames = noise_frames_of(&noise, 240_000, 200.0, 5);
    for (i, f) in frames.iter_mut().enumerate() {
        let line = (std::f64::consts::TAU * 3.0 * i as f64 / 200.0).sin();
        f.axes[0] += 0.05 * line;
    }
    let file = dir.join("line.csv");
    write_euroc(&file, &frames);
    let out = dir.join("out");
    refused(
        &["characterise", path(&file), "--out", path(&out)],
        "it claims noise the record does not hold, to cover a hump at shorter times",
    );
    let read = characterise(&[path(&file)], &out, &["--oscillators"]);
    let n = read["axes"][0]["model"]["white_noise"].as_f64().unwrap();
    assert!((n / 1e-3 - 1.0).abs() < 0.1, "{read}");
}

#[test]
fn stretches_far_apart_are_not_read_as_one_run() {
    // Two stretches of 20 s, 2 h apart, as two files (or as one): the Allan variance of
    // samples taken as one run joins biases that walked apart over the gap (a random walk
    // 2 to 4 times the sensor's, exit 0, before); refused, naming the gaps. The same with
    // samples missing under a tenth of those held, read.
    let dir = temp_dir("far-apart");
    let out = dir.join("out");
    let mut frames = imu_frames(8_000, 200.0, 6);
    frames[4_000..]
        .iter_mut()
        .for_each(|f| f.stamp_ns += 7_200_000_000_000);
    let (early, late) = (dir.join("a.csv"), dir.join("b.csv"));
    write_euroc(&early, &frames[..4_000]);
    write_euroc(&late, &frames[4_000..]);
    refused(
        &[
            "characterise",
            path(&early),
            path(&late),
            "--out",
            path(&out),
        ],
        "1 gaps miss 1439999 samples",
    );
    refused(
        &["noise", path(&early), path(&late), "--column", "w_RS_S_x"],
        "the Allan variance takes the samples as one run",
    );
    let mut frames = imu_frames(8_000, 200.0, 6);
    frames[4_000..]
        .iter_mut()
        .for_each(|f| f.stamp_ns += 3_000_000_000);
    let near = dir.join("near.csv");
    write_euroc(&near, &frames);
    let read = characterise(&[path(&near)], &out, &[]);
    assert_eq!(read["timing"]["missing_samples"], 600, "{read}");
}

#[test]
fn a_rate_given_must_fit_the_samples_in_their_stamps_span() {
    // Every row written twice, its stamp too: read at 400 Hz (a FIFO of two) from the
    // stamps; --rate 200 packed the 12,000 samples into 30 s, as if 60 s (N 33 % high, exit
    // 0, before): refused, naming the rows written twice.
    let dir = temp_dir("rate-fits");
    let frames = imu_frames(6_000, 200.0, 5);
    let twice: Vec<Frame> = frames.iter().flat_map(|f| [*f, *f]).collect();
    let file = dir.join("twice.csv");
    write_euroc(&file, &twice);
    let column = ["--column", "w_RS_S_x"];
    let run = |rate: &str| imu_ar(&["noise", path(&file), column[0], column[1], "--rate", rate]);
    let refused = run("200");
    assert_one_line_failure(&refused);
    assert!(
        stderr(&refused).contains(
            "--rate 200: the 12000 samples would span 59.995 s at it, where their stamps span 29.9"
        ) && stderr(&refused).contains("(rows written twice, or stretches at a faster rate?)"),
        "{}",
        stderr(&refused)
    );
    assert_eq!(run("400").status.code(), Some(0));
    let once = dir.join("once.csv");
    write_euroc(&once, &frames);
    let read = imu_ar(&["noise", path(&once), column[0], column[1], "--rate", "200"]);
    assert_eq!(read.status.code(), Some(0), "{}", stderr(&read));
    // A rate the stamps do not give is named so first (read as rows written twice before).
    let half = imu_ar(&["noise", path(&once), column[0], column[1], "--rate", "100"]);
    assert_one_line_failure(&half);
    assert!(
        stderr(&half).contains("--rate 100: the timestamps give 200"),
        "{}",
        stderr(&half)
    );
    // One row written twice: read at the rate given, warned of (silently before).
    let mut one = frames.clone();
    one.insert(3_000, frames[2_999]);
    let file = dir.join("one-twice.csv");
    write_euroc(&file, &one);
    let read = imu_ar(&["noise", path(&file), column[0], column[1], "--rate", "200"]);
    assert_eq!(read.status.code(), Some(0), "{}", stderr(&read));
    assert!(
        stderr(&read).contains("warning") && stderr(&read).contains("read at --rate 200, but"),
        "{}",
        stderr(&read)
    );
    // Mixed rates (100 Hz, then 300 Hz), whose average a rate given matched: read as the
    // rate given says, warned of (silently before).
    let mut mixed = imu_frames(4_000, 100.0, 6);
    let end = mixed[3_999].stamp_ns;
    mixed.extend(imu_frames(12_000, 300.0, 7).into_iter().map(|f| Frame {
        stamp_ns: f.stamp_ns - frames[0].stamp_ns + end + 3_333_333,
        ..f
    }));
    let file = dir.join("mixed.csv");
    write_euroc(&file, &mixed);
    let read = imu_ar(&["noise", path(&file), column[0], column[1], "--rate", "200"]);
    assert_eq!(read.status.code(), Some(0), "{}", stderr(&read));
    assert!(
        stderr(&read).contains("warning")
            && stderr(&read).contains("read at --rate 200, but the timestamps show mixed rates"),
        "{}",
        stderr(&read)
    );
}

#[test]
fn two_imus_side_by_side_in_one_csv_are_named_and_read_by_number() {
    // gx .. az twice (two IMUs side by side): "no EuRoC or gx .. az columns" before, though
    // they are there. Named, and either IMU read by the columns' numbers.
    let dir = temp_dir("side-by-side");
    let frames = imu_frames(20_000, 100.0, 3);
    let mut text = "t [ns],gx,gy,gz,ax,ay,az,gx,gy,gz,ax,ay,az\n".to_string();
    for f in &frames {
        write!(text, "{}", f.stamp_ns).unwrap();
        for _ in 0..2 {
            for v in f.axes {
                write!(text, ",{v:e}").unwrap();
            }
        }
        text.push('\n');
    }
    let file = dir.join("two.csv");
    std::fs::write(&file, text).unwrap();
    let out = dir.join("out");
    let units = ["--gyro-unit", "rad/s", "--accel-unit", "m/s^2"];
    let run = imu_ar(
        &[
            &["characterise", path(&file), "--out", path(&out)][..],
            &units,
        ]
        .concat(),
    );
    assert_one_line_failure(&run);
    assert!(
        stderr(&run)
            .contains("the header names column 'gx' 2 times: name the six to read with --columns"),
        "{}",
        stderr(&run)
    );
    let second = characterise(
        &[path(&file)],
        &out,
        &[&["--columns", "7,8,9,10,11,12"][..], &units].concat(),
    );
    assert_eq!(second["axes"].as_array().map(Vec::len), Some(6), "{second}");
}
