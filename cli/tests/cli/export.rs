//! `imu_ar_cli::export`: the parameter files of an IMU's six axes, read back and checked. The
//! model comes from real fits of simulated records (white noise, random walk and one or two
//! Gauss-Markov terms per axis); each file is parsed, its numbers turned back into continuous
//! `N` and `K` with its target's own convention, a record simulated from them, and its Allan
//! deviation compared with what the file claims.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::OnceLock;

use imu_ar::noise::{Estimator, FitConfig, NoiseModel, NoiseType, Octaves};
use imu_ar::sim::StandardNormal;
use imu_ar_cli::export::params::ekf2_step;
use imu_ar_cli::export::{AxisModel, Format, ImuModel, write};
use imu_ar_host::composite::Composite;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

/// The IMU's rate, Hz.
const RATE: f64 = 100.0;

/// The truth of the six axes: `(N, K, [(sigma, T)])`, SI.
fn truths() -> [Composite; 6] {
    let axis = |white: f64, random_walk: f64, gm: &[(f64, f64)]| Composite {
        dt: 1.0 / RATE,
        white,
        quantization: 0.0,
        gm: gm.to_vec(),
        random_walk,
    };
    [
        axis(2e-4, 2e-6, &[(3e-5, 50.0)]),
        axis(3e-4, 1e-6, &[(4e-5, 100.0), (2e-5, 5.0)]),
        axis(1.5e-4, 3e-6, &[(2e-5, 30.0)]),
        axis(1e-3, 3e-5, &[(2e-4, 20.0)]),
        axis(2e-3, 5e-5, &[(3e-4, 100.0), (1e-4, 4.0)]),
        axis(1.5e-3, 2e-5, &[(1.5e-4, 40.0)]),
    ]
}

/// The model of the six axes, fitted once.
fn model() -> &'static ImuModel {
    static MODEL: OnceLock<ImuModel> = OnceLock::new();
    MODEL.get_or_init(|| {
        let axes = truths().map(|truth| {
            let x = truth.simulate(1 << 20, 7 + (truth.white * 1e6) as u64);
            let octaves = Octaves::<32>::overlapping(&x, truth.dt).unwrap();
            let fit = NoiseModel::<1, 8>::fit(&octaves, None, &FitConfig::new(3)).unwrap();
            let span = x.len() as f64 * truth.dt;
            let p0 = fit.random_walk().powi(2) * span;
            AxisModel::from_noise(&fit, 1.0, truth.dt, p0, 21).unwrap_or_else(|e| panic!("{}", e.0))
        });
        ImuModel {
            axes,
            rate_hz: RATE,
            topic: Some("/imu\"0".into()),
            filter_rate_hz: None,
            loop_rate_hz: None,
            sysid: None,
            imu_integ_rate_hz: None,
            origin: None,
        }
    })
}

/// A fresh temp directory for one test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = crate::common::temp_root().join(format!("export-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The `key: value` (YAML), `NAME,VALUE` (ArduPilot) and tab-separated QGC lines of a file,
/// comments dropped.
fn values(text: &str) -> HashMap<String, String> {
    let mut out = HashMap::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap().trim();
        if line.is_empty() || line.starts_with('%') {
            continue;
        }
        let fields: Vec<&str> = line.split('\t').collect();
        let (key, value) = if fields.len() == 5 {
            (fields[2], fields[3])
        } else if let Some(kv) = line.split_once(": ") {
            kv
        } else if let Some(kv) = line.split_once(',') {
            kv
        } else {
            continue;
        };
        out.insert(key.trim().to_string(), value.trim().to_string());
    }
    out
}

fn number(map: &HashMap<String, String>, key: &str) -> f64 {
    let v = map
        .get(key)
        .unwrap_or_else(|| panic!("no {key} in {map:?}"));
    // A YAML 1.1 float: a point, and a sign on the exponent.
    let float = v.contains('.') && (v.contains("e-") || v.contains("e+"));
    assert!(key == "EKF2_PREDICT_US" || float, "{key}: {v}");
    v.parse().unwrap()
}

/// The continuous `(N, K)` of the gyroscope and of the accelerometer that `format`'s file
/// in `dir` stands for, by its target's convention.
fn continuous(format: Format, text: &str) -> [(f64, f64); 2] {
    let m = values(text);
    let n = |k: &str| number(&m, k);
    match format {
        Format::Kalibr | Format::OpenVins => [
            (n("gyroscope_noise_density"), n("gyroscope_random_walk")),
            (
                n("accelerometer_noise_density"),
                n("accelerometer_random_walk"),
            ),
        ],
        Format::OrbSlam3 => {
            // An integer: ORB-SLAM3's reader (without File.version) refuses 1.0e+02.
            assert_eq!(m["IMU.Frequency"], format!("{RATE:.0}"));
            [
                (n("IMU.NoiseGyro"), n("IMU.GyroWalk")),
                (n("IMU.NoiseAcc"), n("IMU.AccWalk")),
            ]
        }
        // Per sample: Var(step) = 0.5 n^2 dt^2 and w^2 dt^2 (integration_base.h).
        Format::Vins => {
            // Each value's unit (gyr_w and acc_w were said to be the bias's step a sample,
            // gyr_n a sample's deviation: pass 47 F7).
            for (key, unit) in [
                ("gyr_n", "rad/s:"),
                ("gyr_w", "rad/s^2:"),
                ("acc_w", "m/s^3:"),
            ] {
                let line = text.lines().find(|l| l.starts_with(key)).unwrap();
                assert!(line.contains(&format!("# {unit}")), "{line}");
            }
            let dt = 1.0 / RATE;
            let back = |w: f64, b: f64| (w * (dt / 2.0).sqrt(), b * dt.sqrt());
            [back(n("gyr_n"), n("gyr_w")), back(n("acc_n"), n("acc_w"))]
        }
        // (dt value)^2 per prediction step.
        Format::Px4 => {
            let dt = n("EKF2_PREDICT_US") * 1e-6;
            let back = |w: f64, b: f64| (w * dt.sqrt(), b * dt.sqrt());
            [
                back(n("EKF2_GYR_NOISE"), n("EKF2_GYR_B_NOISE")),
                back(n("EKF2_ACC_NOISE"), n("EKF2_ACC_B_NOISE")),
            ]
        }
        // EKF3's step at the default 400 Hz loop: 5 samples of 2.5 ms.
        Format::ArduPilot => {
            let dt: f64 = 0.0125;
            let back = |w: f64, b: f64| (w * dt.sqrt(), b * dt.sqrt());
            [
                back(n("EK3_GYRO_P_NSE"), n("EK3_GBIAS_P_NSE")),
                back(n("EK3_ACC_P_NSE"), n("EK3_ABIAS_P_NSE")),
            ]
        }
        Format::StateSpace => unreachable!(),
    }
}

/// The six parameter formats.
const SIX: [Format; 6] = [
    Format::Kalibr,
    Format::OpenVins,
    Format::Vins,
    Format::OrbSlam3,
    Format::Px4,
    Format::ArduPilot,
];

/// The largest `f` over the three axes of sensor `s` (0 gyro, 1 accelerometer).
fn worst(s: usize, f: fn(&AxisModel) -> f64) -> f64 {
    model().axes[3 * s..3 * s + 3]
        .iter()
        .map(f)
        .fold(0.0, f64::max)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs()
}

/// The octaves at which the Allan deviations of `x` disagree with `claim(m)` (an Allan
/// variance), among those with 8 or more degrees of freedom `nu` (of the overlapping estimator
/// and the noise type `kind(m)` that dominates the claim there): more than three standard
/// errors `1 / sqrt(2 nu)` or 10 %, whichever is larger, apart. (The library's check takes
/// two: an interval that one octave in twenty leaves by chance; this test reads about 130
/// octaves, so two standard errors would fail it by chance alone.)
fn agrees(
    x: &[f64],
    claim: impl Fn(usize) -> f64,
    kind: impl Fn(usize) -> NoiseType,
) -> Vec<String> {
    let octaves = Octaves::<32>::overlapping(x, 1.0 / RATE).unwrap();
    let estimator = Estimator::Overlapping { n: x.len() as u64 };
    let mut bad = Vec::new();
    for (j, measured) in octaves.avar().iter().enumerate() {
        let m = 1usize << j;
        let nu = estimator.edf(m as u64, kind(m));
        if nu < 8.0 {
            continue;
        }
        let tolerance = (3.0 / (2.0 * nu).sqrt()).max(0.1);
        let ratio = (measured / claim(m)).sqrt();
        if (ratio - 1.0).abs() > tolerance {
            bad.push(format!(
                "tau {} s: data/claim {ratio:.3}, tolerance {tolerance:.3}",
                m as f64 / RATE
            ));
        }
    }
    bad
}

/// Simulates white noise `n` and random walk `k` and checks its Allan deviation against the
/// curve they claim.
fn white_rw_round_trip(n: f64, k: f64, seed: u64) -> Vec<String> {
    let c = Composite {
        dt: 1.0 / RATE,
        white: n,
        quantization: 0.0,
        gm: vec![],
        random_walk: k,
    };
    let x = c.simulate(1 << 19, seed);
    let kind = |m: usize| {
        let tau = m as f64 / RATE;
        if n * n / tau >= k * k * tau / 3.0 {
            NoiseType::WhiteFrequency
        } else {
            NoiseType::RandomWalkFrequency
        }
    };
    agrees(&x, |m| c.avar(m as u32), kind)
}

/// The octaves `(tau, model AVAR)` of sensor `s`'s three axes with `tau` in `[1 s, upper]`.
fn octaves_up_to(imu: &ImuModel, s: usize, upper: f64) -> Vec<(f64, f64)> {
    imu.axes[3 * s..3 * s + 3]
        .iter()
        .flat_map(|a| {
            a.model_avar
                .iter()
                .enumerate()
                .map(|(j, v)| (a.dt * 2f64.powi(j as i32), *v))
        })
        .filter(|(tau, _)| (1.0..=upper).contains(tau))
        .collect()
}

/// The model's longest octave, s.
fn longest(imu: &ImuModel) -> f64 {
    let a = &imu.axes[0];
    a.dt * 2f64.powi(a.model_avar.len() as i32 - 1)
}

/// `sqrt(n^2/tau + k^2 tau/3)` at or above the Allan deviation of every row.
fn covers(n: f64, k: f64, rows: &[(f64, f64)]) -> bool {
    rows.iter()
        .all(|(tau, v)| n * n / tau + k * k * tau / 3.0 >= *v)
}

/// The smallest `N' K'` with `N' >= n`, `K' >= k` whose curve covers `rows`, searched on a log
/// grid (100 steps per decade of `N'` and of `K'`, four decades each).
fn grid_minimum(n: f64, k: f64, rows: &[(f64, f64)]) -> f64 {
    let mut best = f64::INFINITY;
    for i in 0..400 {
        let np = n * 10f64.powf(f64::from(i) / 100.0);
        for j in 0..400 {
            let kp = k * 10f64.powf(f64::from(j) / 100.0);
            if np * kp < best && covers(np, kp, rows) {
                best = np * kp;
            }
        }
    }
    best
}

/// The written `(nh, kh)` of sensor `s` is the smallest overbound of its model from 1 s to
/// `upper` from its worst axis's `N` and `K`: at or above them, covering every octave, and no
/// grid point does better.
fn smallest_overbound(imu: &ImuModel, s: usize, upper: f64, (nh, kh): (f64, f64), at: &str) {
    let worst =
        |f: fn(&AxisModel) -> f64| imu.axes[3 * s..3 * s + 3].iter().map(f).fold(0.0, f64::max);
    let (n, k) = (worst(|a| a.white_noise), worst(|a| a.random_walk));
    assert!(nh >= n && kh >= k, "{at}: ({nh}, {kh}) below ({n}, {k})");
    let rows = octaves_up_to(imu, s, upper);
    assert!(rows.len() >= 3 * 9, "{at}: {} octaves", rows.len());
    assert!(
        covers(nh, kh, &rows),
        "{at}: ({nh}, {kh}) does not overbound the model"
    );
    let searched = grid_minimum(n, k, &rows);
    assert!(
        nh * kh <= searched * (1.0 + 1e-9),
        "{at}: N_H K_H {} > the grid's {searched}",
        nh * kh
    );
    assert!(
        searched <= nh * kh * 1.05,
        "{at}: the grid's {searched} against {}",
        nh * kh
    );
}

#[test]
fn kalibr_values_are_the_smallest_overbound_up_to_the_longest_octave() {
    let dir = temp_dir("kalibr");
    let path = write(Format::Kalibr, model(), None, &dir).unwrap_or_else(|e| panic!("{}", e.0));
    let text = std::fs::read_to_string(path).unwrap();
    let [gyro, accel] = continuous(Format::Kalibr, &text);
    let h = longest(model());
    smallest_overbound(model(), 0, h, gyro, "gyro");
    smallest_overbound(model(), 1, h, accel, "accel");
    // The Gauss-Markov terms raise the pair above the fitted one.
    assert!(gyro.0 * gyro.1 > 1.01 * worst(0, |a| a.white_noise) * worst(0, |a| a.random_walk));
    assert!(text.contains("rostopic: \"/imu\\\"0\""), "{text}");
    assert!(text.contains("update_rate: 1.0e+02"), "{text}");
    // The statement: the range, the objective, the fitted values beside the written ones.
    for want in [
        "the smallest overbound of the model's Allan deviation from tau = 1 s to H = ",
        ", the model's longest octave (log N_H/N + log K_H/K minimal)",
        "fitted N = ",
        "fitted K = ",
        "K_H/K = ",
        "alone: N_H = ",
        "sqrt(N_H^2/tau + K_H^2 tau/3) stays at or above the model's Allan deviation of every \
         axis at every octave from 1 s to the last",
    ] {
        assert!(text.contains(want), "{want:?} not in {text}");
    }
    assert!(!text.contains("falls short"), "{text}");
}

#[test]
fn every_format_round_trips_to_the_curve_it_claims_and_writes_the_worst_axis() {
    let dir = temp_dir("round-trip");
    let kalibr = std::fs::read_to_string(
        write(Format::Kalibr, model(), None, &dir).unwrap_or_else(|e| panic!("{}", e.0)),
    )
    .unwrap();
    let pairs = continuous(Format::Kalibr, &kalibr);
    let mut failures = Vec::new();
    for (f, format) in SIX.into_iter().enumerate() {
        let path = write(format, model(), None, &dir).unwrap_or_else(|e| panic!("{}", e.0));
        let text = std::fs::read_to_string(path).unwrap();
        assert!(text.contains("worst (largest)"), "{format}: {text}");
        for (s, (n, k)) in continuous(format, &text).into_iter().enumerate() {
            // The same pair in every target's convention and back.
            assert!(close(n, pairs[s].0, 1e-9), "{format} {s}: N {n}");
            assert!(close(k, pairs[s].1, 1e-9), "{format} {s}: K {k}");
            for line in white_rw_round_trip(n, k, 100 + 2 * f as u64 + s as u64) {
                failures.push(format!("{format} sensor {s}: {line}"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The lower Cholesky factor of a small covariance (a zero pivot gives a zero column).
fn cholesky(a: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let d = a.len();
    let mut l = vec![vec![0.0; d]; d];
    for i in 0..d {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            l[i][j] = match (i == j, l[j][j] > 0.0) {
                (true, _) => (a[i][i] - s).max(0.0).sqrt(),
                (false, true) => (a[i][j] - s) / l[j][j],
                (false, false) => 0.0,
            };
        }
    }
    l
}

/// `l e` for standard normal `e`.
fn correlated(l: &[Vec<f64>], rng: &mut ChaCha8Rng, z: &mut StandardNormal) -> Vec<f64> {
    let e: Vec<f64> = l.iter().map(|_| z.sample(rng)).collect();
    l.iter()
        .map(|row| row.iter().zip(&e).map(|(a, b)| a * b).sum())
        .collect()
}

/// `n` samples of `h x_k` for the states `x_{k+1} = phi x_k + w_k`, `Cov(w) = q`, plus white
/// noise of the measurement variance; the states start from `p0`, the random walk at 0 (its
/// turn-on variance does not show in the Allan deviation).
fn state_space_record(axis: &serde_json::Value, n: usize, seed: u64) -> Vec<f64> {
    let matrix =
        |key: &str| -> Vec<Vec<f64>> { serde_json::from_value(axis[key].clone()).unwrap() };
    let (phi, q, mut p0) = (matrix("phi"), matrix("q"), matrix("p0"));
    let states = axis["states"].as_array().unwrap();
    if let Some(i) = states.iter().position(|s| s == "random_walk") {
        p0[i][i] = 0.0;
    }
    let h: Vec<f64> = serde_json::from_value(axis["h"].clone()).unwrap();
    assert_eq!(h.len(), states.len());
    let r = axis["measurement_variance"].as_f64().unwrap().sqrt();
    let (lq, lp) = (cholesky(&q), cholesky(&p0));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut z = StandardNormal::new();
    let mut x = correlated(&lp, &mut rng, &mut z);
    (0..n)
        .map(|_| {
            let w = correlated(&lq, &mut rng, &mut z);
            x = phi
                .iter()
                .zip(&w)
                .map(|(row, w)| row.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>() + w)
                .collect();
            h.iter().zip(&x).map(|(a, b)| a * b).sum::<f64>() + r * z.sample(&mut rng)
        })
        .collect()
}

#[test]
fn the_state_space_round_trips_to_the_models_allan_deviation() {
    let dir = temp_dir("state-space");
    let path = write(Format::StateSpace, model(), None, &dir).unwrap_or_else(|e| panic!("{}", e.0));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let axes = doc["axes"].as_array().unwrap();
    assert_eq!(axes.len(), 6);
    let mut failures = Vec::new();
    for (i, (axis, truth)) in axes.iter().zip(model().axes.iter()).enumerate() {
        assert_eq!(axis["dt"].as_f64().unwrap(), 1.0 / RATE);
        assert!(!axis["states"].as_array().unwrap().is_empty());
        let x = state_space_record(axis, 1 << 19, 300 + i as u64);
        let (n, k) = (truth.white_noise, truth.random_walk);
        let kind = |m: usize| {
            let tau = m as f64 / RATE;
            let (white, walk) = (n * n / tau, k * k * tau / 3.0);
            let rest = truth.model_avar[m.trailing_zeros() as usize] - white - walk;
            if rest > white.max(walk) {
                NoiseType::FlickerFrequency
            } else if white >= walk {
                NoiseType::WhiteFrequency
            } else {
                NoiseType::RandomWalkFrequency
            }
        };
        let claim = |m: usize| truth.model_avar[m.trailing_zeros() as usize];
        for line in agrees(&x, claim, kind) {
            failures.push(format!("axis {i}: {line}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_horizon_writes_the_smallest_overbound_up_to_it() {
    let horizon = 600.0;
    let dir = temp_dir("horizon");
    for format in SIX {
        let path =
            write(format, model(), Some(horizon), &dir).unwrap_or_else(|e| panic!("{}", e.0));
        let text = std::fs::read_to_string(path).unwrap();
        assert!(
            text.contains("to H = 6.0000e2 s, the horizon asked for (log N_H/N"),
            "{format}: {text}"
        );
        for (s, pair) in continuous(format, &text).into_iter().enumerate() {
            smallest_overbound(model(), s, horizon, pair, &format!("{format} {s}"));
        }
    }
    // Below 1 s, where the overbound starts: refused.
    assert!(write(Format::Kalibr, model(), Some(0.5), &dir).is_err());
}

#[test]
fn a_model_without_random_walk_or_white_noise_writes_no_zero() {
    let dir = temp_dir("no-zero");
    let mut imu = model().clone();
    for a in &mut imu.axes[3..] {
        a.random_walk = 0.0;
    }
    for a in &mut imu.axes[..3] {
        a.white_noise = 0.0;
    }
    for (format, horizon) in [(Format::Kalibr, None), (Format::ArduPilot, Some(600.0))] {
        let text = std::fs::read_to_string(
            write(format, &imu, horizon, &dir).unwrap_or_else(|e| panic!("{}", e.0)),
        )
        .unwrap();
        for (s, (n, k)) in continuous(format, &text).into_iter().enumerate() {
            assert!(n > 0.0 && k > 0.0, "{format} {s}: ({n}, {k})");
            let rows = octaves_up_to(&imu, s, horizon.unwrap_or_else(|| longest(&imu)));
            assert!(covers(n, k, &rows), "{format} {s}: ({n}, {k})");
        }
        assert!(
            text.contains("The model has no random walk: K is taken as "),
            "{format}: {text}"
        );
        assert!(
            text.contains("The model has no white noise: N is taken as "),
            "{format}: {text}"
        );
    }
}

#[test]
fn the_filter_rate_sets_the_autopilots_step_and_bad_models_are_refused() {
    let dir = temp_dir("rates");
    let mut imu = model().clone();
    let kalibr = std::fs::read_to_string(
        write(Format::Kalibr, &imu, None, &dir).unwrap_or_else(|e| panic!("{}", e.0)),
    )
    .unwrap();
    let [(gn, _), (_, ak)] = continuous(Format::Kalibr, &kalibr);
    // EKF2 steps whole vehicle_imu messages (IMU_INTEG_RATE, 200 Hz by default, in whole
    // samples): the step nearest the filter rate's, written, its values at it (a 4 ms step
    // of a 100 Hz IMU was written as asked, its values 1.58 times too large).
    for (integ, filter, written, asked) in [
        (None, 250.0, 10_000, true),
        (None, 100.0, 10_000, false),
        (Some(100.0), 50.0, 20_000, false),
        (Some(1000.0), 60.0, 20_000, true),
    ] {
        (imu.imu_integ_rate_hz, imu.filter_rate_hz) = (integ, Some(filter));
        let text = std::fs::read_to_string(
            write(Format::Px4, &imu, None, &dir).unwrap_or_else(|e| panic!("{}", e.0)),
        )
        .unwrap();
        let m = values(&text);
        assert_eq!(m["EKF2_PREDICT_US"], written.to_string(), "{filter}");
        let dt = f64::from(written) * 1e-6;
        assert!(close(number(&m, "EKF2_GYR_NOISE"), gn / dt.sqrt(), 1e-12));
        assert_eq!(text.contains("us asked"), asked, "{text}");
    }
    // Faster IMUs: a whole number of samples a vehicle_imu message, of those a step.
    for (rate, integ, asked, step) in [
        (1000.0, 200.0, 4000.0, 5000.0),
        (1000.0, 200.0, 3003.0, 5000.0),
        (1000.0, 250.0, 4000.0, 4000.0),
        (952.0, 200.0, 10_000.0, 2.0 * 5e6 / 952.0),
        (8000.0, 400.0, 1000.0, 2500.0),
    ] {
        let (got, _) = ekf2_step(asked, rate, integ);
        assert!(close(got, step, 1e-12), "{rate} {integ} {asked}: {got}");
    }
    imu.imu_integ_rate_hz = Some(50.0);
    let e = write(Format::Px4, &imu, None, &dir).unwrap_err().0;
    assert!(e.contains("IMU_INTEG_RATE 50 Hz is outside"), "{e}");
    // An INT32 parameter: 100.5 Hz was taken, the file saying "1.0000e4 us apart at
    // IMU_INTEG_RATE 100.5 Hz" (pass 47 F6).
    imu.imu_integ_rate_hz = Some(100.5);
    let e = write(Format::Px4, &imu, None, &dir).unwrap_err().0;
    assert!(
        e.contains("IMU_INTEG_RATE 100.5 Hz is not a whole number"),
        "{e}"
    );
    (imu.imu_integ_rate_hz, imu.filter_rate_hz) = (None, Some(250.0));
    // EKF3's step is not the filter rate: its loop rate sets it (EKF_TARGET_DT 12 ms less
    // half a loop, in whole loops), 12.5 ms at the default 400 Hz.
    for (loop_rate, dt) in [(None, 0.0125f64), (Some(500.0), 0.012), (Some(50.0), 0.02)] {
        imu.loop_rate_hz = loop_rate;
        let text = std::fs::read_to_string(
            write(Format::ArduPilot, &imu, None, &dir).unwrap_or_else(|e| panic!("{}", e.0)),
        )
        .unwrap();
        assert!(
            close(
                number(&values(&text), "EK3_ABIAS_P_NSE"),
                ak / dt.sqrt(),
                1e-12
            ),
            "{loop_rate:?}: {text}"
        );
        assert!(
            text.contains("--filter-rate 250 Hz is not EKF3's step"),
            "{text}"
        );
    }
    imu.loop_rate_hz = Some(10.0);
    assert!(write(Format::ArduPilot, &imu, None, &dir).is_err());
    imu.loop_rate_hz = None;
    // PX4's file names its vehicle: 1 unless asked, never 0.
    imu.sysid = Some(7);
    let text = std::fs::read_to_string(
        write(Format::Px4, &imu, None, &dir).unwrap_or_else(|e| panic!("{}", e.0)),
    )
    .unwrap();
    let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    assert!(
        rows.len() == 5 && rows.iter().all(|l| l.starts_with("7\t1\t")),
        "{text}"
    );
    assert!(
        text.contains("# Onboard parameters for Vehicle 7"),
        "{text}"
    );
    imu.sysid = Some(0);
    assert!(write(Format::Px4, &imu, None, &dir).is_err());
    imu.sysid = None;
    imu.filter_rate_hz = Some(20.0);
    assert!(write(Format::Px4, &imu, None, &dir).is_err());
    // Nothing that is not finite is written.
    let mut bad = model().clone();
    bad.axes[4].random_walk = f64::NAN;
    for format in Format::ALL {
        assert!(write(format, &bad, None, &dir).is_err(), "{format}");
        assert!(
            write(format, model(), Some(f64::INFINITY), &dir).is_err(),
            "{format}"
        );
    }
    let mut bad = model().clone();
    bad.topic = Some("/imu\n0".into());
    assert!(write(Format::Kalibr, &bad, None, &dir).is_err());
    assert_eq!(
        Format::list("kalibr,px4,kalibr").unwrap_or_default(),
        vec![Format::Kalibr, Format::Px4]
    );
    assert_eq!(Format::list("all").unwrap_or_default().len(), 7);
    assert!(Format::list("kalibr,yaml").is_err());
    assert_eq!(
        "state-space".parse::<Format>().ok(),
        Some(Format::StateSpace)
    );
}

#[test]
fn all_in_a_list_of_formats_is_said_to_stand_alone() {
    // `--format px4,all` said "all" was not one of the formats, then listed it (pass 51 F9).
    let e = "all".parse::<Format>().unwrap_err().0;
    assert!(e.contains("\"all\" stands alone"), "{e}");
    let e = "kalbr".parse::<Format>().unwrap_err().0;
    assert!(e.contains("one of kalibr"), "{e}");
}
