//! The stabilised fast transversal filter on the cases of numerics.md section 8 and on the real
//! records: where it diverges the monitor fires, every output stays finite and the published
//! model is the last good one; where it does not, it never fires. The tests print the restarts
//! per 10^6 samples of SFTF, lattice and RLS that `tools/readme-tables.sh sftf` puts into
//! docs/estimators.md.

use imu_ar::ArModel;
use imu_ar::recursive::{
    Channel, Config, Estimator, FloatArith, Lattice, Rls, Sftf, snapshot_interval,
};
use imu_ar_cli::input::csv::read_column;
use imu_ar_host::fixtures::{AXES, add, ar, real_records};
use imu_ar_host::reference::{Regularisation, Section0};

const N: usize = 1_000_000;

/// What one SFTF run did.
#[derive(Default)]
struct Rescues {
    restarts: u64,
    /// Rescues the last-good check was made at (those outside the hold of an earlier one).
    checked: u64,
    /// Largest `max_k |a_k - a_ref,k|` of the model held through a checked rescue (the last
    /// snapshot), against the direct solve of the problem the filter was solving then.
    worst: f64,
    /// Largest [`Sftf::disagreement`] after a sample that passed the monitor.
    largest: f64,
}

/// Runs an order-`P` SFTF in `T` over `x` and checks, sample by sample: every error it returns
/// is finite and it returns none only when it rescues; the model is finite after every sample;
/// a rescue keeps publishing the model of the filter's last snapshot (the model after the last
/// sample whose count is a multiple of `snapshot_interval(P)`, outside a hold) for
/// `3/(1 - lambda)` samples.
///
/// Without mean removal it also solves, in `f64`, the problem the filter solves (restarted with
/// it), and measures the model held through each rescue against it.
fn sftf_run<T: FloatArith, const P: usize>(
    x: &[f64],
    lambda: f64,
    delta: f64,
    demean: bool,
) -> Rescues {
    let config = Config::new(T::from_f64(lambda), T::from_f64(0.01))
        .unwrap()
        .with_demean(demean);
    let channel = Channel::new(T::from_f64(delta)).unwrap();
    // The hold is 3/(1 - lambda) of lambda in T.
    let hold = (3.0 / (1.0 - config.lambda().to_f64())) as usize;
    let mut sftf = Sftf::<T, P>::new(&config, &channel);
    let mut reference = (!demean).then(|| Section0::new(P, lambda, delta));
    let mut out = Rescues::default();
    // The last snapshot, with the reference's solution at its sample.
    let mut snapshot: Option<(ArModel<T, P>, Option<Vec<f64>>)> = None;
    let mut held: Option<(ArModel<T, P>, usize)> = None;
    for (n, &v) in x.iter().enumerate() {
        let restarts = sftf.health().restarts;
        let e = sftf.update(&config, T::from_f64(v));
        let rescued = sftf.health().restarts > restarts;
        match e {
            Some(e) => {
                assert!(e.is_finite() && !rescued, "sample {n}: error {e:?}");
                out.largest = out.largest.max(sftf.disagreement(&config).to_f64());
            }
            None => assert!(rescued, "sample {n}: a finite sample was rejected"),
        }
        if rescued {
            let (last, a_ref) = snapshot
                .clone()
                .expect("a snapshot before the first rescue");
            if held.is_none_or(|(_, until)| n >= until) {
                if let Some(a_ref) = a_ref {
                    let err = last
                        .a()
                        .iter()
                        .zip(&a_ref)
                        .fold(0.0f64, |m, (a, b)| m.max((a.to_f64() - b).abs()));
                    out.worst = out.worst.max(err);
                    out.checked += 1;
                }
                held = Some((last, n + hold));
            }
            // The rescued filter starts the problem again, without sample n.
            if let Some(r) = &mut reference {
                *r = Section0::new(P, lambda, delta);
            }
        } else if let Some(r) = &mut reference {
            r.push(v);
        }
        let model = sftf.model(&config).expect("a model after every sample");
        let finite = model.a().iter().all(|a| a.is_finite()) && model.noise_variance().is_finite();
        assert!(finite, "sample {n}: {model:?}");
        if let Some((m, until)) = held
            && n < until
        {
            assert_eq!(model, m, "sample {n}: the held model changed");
        }
        let settled = held.is_none_or(|(_, until)| n >= until);
        if !rescued && settled && sftf.health().samples.is_multiple_of(snapshot_interval(P)) {
            let a_ref = reference
                .as_ref()
                .map(|r| r.solve(P, Regularisation::ShiftConsistent).0);
            snapshot = Some((model, a_ref));
        }
    }
    out.restarts = sftf.health().restarts;
    out
}

/// Restarts of an order-`P` f32 lattice and f32 RLS over `x`; every returned error finite.
fn others<const P: usize>(x: &[f64], lambda: f64, delta: f64, demean: bool) -> (u64, u64) {
    let config = Config::new(lambda as f32, 0.01)
        .unwrap()
        .with_demean(demean);
    let channel = Channel::new(delta as f32).unwrap();
    let mut lattice = Lattice::<f32, P>::new(&config, &channel);
    let mut rls = Rls::<f32, P>::new(&config, &channel);
    for &v in x {
        for e in [
            lattice.update(&config, v as f32),
            rls.update(&config, v as f32),
        ]
        .into_iter()
        .flatten()
        {
            assert!(e.is_finite());
        }
    }
    (lattice.health().restarts, rls.health().restarts)
}

/// One row of the table: SFTF in f32 and f64, lattice and RLS in f32.
struct Row {
    sftf32: Rescues,
    sftf64: Rescues,
    lattice: u64,
    rls: u64,
}

fn row<const P: usize>(x: &[f64], lambda: f64, delta: f64, demean: bool) -> Row {
    let (lattice, rls) = others::<P>(x, lambda, delta, demean);
    Row {
        sftf32: sftf_run::<f32, P>(x, lambda, delta, demean),
        sftf64: sftf_run::<f64, P>(x, lambda, delta, demean),
        lattice,
        rls,
    }
}

/// Restarts per 10^6 samples.
fn per_million(restarts: u64, samples: usize) -> String {
    let rate = restarts as f64 * 1e6 / samples as f64;
    if rate == 0.0 || rate >= 10.0 {
        format!("{rate:.0}")
    } else {
        format!("{rate:.1}")
    }
}

#[test]
fn section_8_cases() {
    let white = ar([0.0], 1.0, N, 10);
    let gm = ar([0.999], 0.05, N, 11);
    let gm_white = add(&gm, &white);
    let sine = |amplitude: f64, cycles: f64| -> Vec<f64> {
        let w = 2.0 * std::f64::consts::PI * cycles;
        (0..N).map(|n| amplitude * (w * n as f64).sin()).collect()
    };
    let weak_sine = add(&gm_white, &sine(1.0, 0.1));
    let strong_sine = add(&gm_white, &sine(3.0, 0.05));
    let pw = ar([2.7607, -3.8106, 2.6535, -0.9238], 1.0, N, 12);
    let r = 0.89f64;
    let resonant = ar(
        [2.0 * r * std::f64::consts::FRAC_PI_4.cos(), -r * r],
        1.0,
        N,
        13,
    );
    // case!(process, name, p, lambda, delta, whether the SFTF is expected to diverge)
    macro_rules! case {
        ($x:expr, $name:expr, $p:literal, $lambda:expr, $delta:expr, $diverges:expr) => {
            (
                $name,
                $p,
                $lambda,
                row::<$p>($x, $lambda, $delta, false),
                $diverges,
            )
        };
    }
    let mut rows = Vec::new();
    for lambda in [0.99, 0.999, 0.9999] {
        rows.push(case!(&gm_white, "GM(0.999) + white", 4, lambda, 0.1, false));
        rows.push(case!(&pw, "Percival-Walden AR(4)", 4, lambda, 100.0, false));
    }
    let weak = "GM + white + sinusoid (amplitude 1, 0.1 cycles/sample)";
    let strong = "GM + white + sinusoid (amplitude 3, 0.05 cycles/sample)";
    let under = "Percival-Walden AR(4), under-fitted";
    rows.extend([
        case!(&weak_sine, weak, 3, 0.99, 0.1, false),
        case!(&weak_sine, weak, 4, 0.99, 0.1, false),
        case!(
            &resonant,
            "AR(2), poles 0.89, under-fitted",
            1,
            0.99,
            0.1,
            true
        ),
        case!(&pw, under, 1, 0.99, 100.0, true),
        case!(&pw, under, 2, 0.99, 100.0, true),
        case!(&pw, under, 3, 0.99, 100.0, true),
        case!(&strong_sine, strong, 3, 0.99, 0.1, true),
        case!(&strong_sine, strong, 4, 0.99, 0.1, true),
        case!(&white, "white, lambda < 1 - 1/(2p)", 10, 0.94, 0.1, true),
        case!(&gm, "GM(0.999), lambda < 1 - 1/(2p)", 10, 0.94, 0.1, true),
    ]);
    println!(
        "| process (10^6 samples) | p | lambda | SFTF f32 | SFTF f64 | lattice f32 | RLS f32 \
         | largest d (f32 / f64) | SFTF model before a rescue, max abs error (f32 / f64) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, p, lambda, r, _) in &rows {
        let last_good = if r.sftf32.checked + r.sftf64.checked > 0 {
            format!("{:.1e} / {:.1e}", r.sftf32.worst, r.sftf64.worst)
        } else {
            "no rescue".into()
        };
        println!(
            "| {name} | {p} | {lambda} | {} | {} | {} | {} | {:.1e} / {:.1e} | {last_good} |",
            per_million(r.sftf32.restarts, N),
            per_million(r.sftf64.restarts, N),
            per_million(r.lattice, N),
            per_million(r.rls, N),
            r.sftf32.largest,
            r.sftf64.largest,
        );
    }
    for (name, p, lambda, r, diverges) in &rows {
        let case = format!("{name}, p = {p}, lambda = {lambda}");
        assert_eq!(
            (r.lattice, r.rls),
            (0, 0),
            "{case}: lattice / RLS restarted"
        );
        for (scalar, s) in [("f32", &r.sftf32), ("f64", &r.sftf64)] {
            if *diverges {
                assert!(s.restarts > 0, "{case}: the {scalar} monitor never fired");
                assert!(s.checked > 0, "{case}: {scalar}: no rescue outside a hold");
                // Section 8 calls a run diverged once its error passes 0.05: the model held
                // through a rescue has not.
                assert!(
                    s.worst < 0.05,
                    "{case}: {scalar}: the model before a rescue is {:e} off",
                    s.worst
                );
            } else {
                assert_eq!(s.restarts, 0, "{case}: {scalar}: a healthy run was rescued");
            }
        }
    }
}

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn real_records_every_axis() {
    let records = real_records()
        .expect("the real records: ../shared/data/imu or IMU_AR_DATA (see docs/reliability.md)");
    println!(
        "| record (six axes, mean removed) | p | lambda | samples | SFTF f32 | SFTF f64 \
         | lattice f32 | RLS f32 |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for record in &records {
        let axes: Vec<Vec<f64>> = AXES
            .iter()
            .map(|axis| read_column(&record.files, axis).unwrap())
            .collect();
        let samples: usize = axes.iter().map(Vec::len).sum();
        for lambda in [0.99, 0.999, 0.9999] {
            for p in [4, 8] {
                let mut total = [0u64; 4];
                for x in &axes {
                    let mean = x.iter().sum::<f64>() / x.len() as f64;
                    let var =
                        x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / x.len() as f64;
                    let delta = 0.1 * var;
                    let r = match p {
                        4 => row::<4>(x, lambda, delta, true),
                        _ => row::<8>(x, lambda, delta, true),
                    };
                    for (t, v) in total.iter_mut().zip([
                        r.sftf32.restarts,
                        r.sftf64.restarts,
                        r.lattice,
                        r.rls,
                    ]) {
                        *t += v;
                    }
                }
                let [s32, s64, lattice, rls] = total.map(|t| per_million(t, samples));
                println!(
                    "| {} | {p} | {lambda} | {samples} | {s32} | {s64} | {lattice} | {rls} |",
                    record.name
                );
                assert_eq!(
                    (total[2], total[3]),
                    (0, 0),
                    "{}: lattice / RLS restarted",
                    record.name
                );
            }
        }
    }
}

/// The variance of a record, for a `delta` in its units.
fn variance(x: &[f64]) -> f64 {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / x.len() as f64
}

/// A rescue shortly before the end of a record leaves the last good model, though `model` was
/// never called before it: the filter keeps its snapshot itself (issue 23, item 2).
#[test]
fn a_rescue_near_the_end_leaves_the_last_good_model() {
    // Order 1 under-fits this resonant AR(2): the filter is rescued now and then (section 8).
    let x = ar([1.78, -0.7921], 1.0, 18_000, 7);
    let config = Config::new(0.99, 0.01).unwrap();
    let channel = Channel::new(0.1 * variance(&x)).unwrap();
    let mut probe = Sftf::<f64, 1>::new(&config, &channel);
    let late: Vec<usize> = (0..x.len())
        .filter(|&n| probe.update(&config, x[n]).is_none() && n > 1_000)
        .collect();
    assert!(!late.is_empty(), "the under-fitted case is rescued");
    for &n in &late {
        let mut sftf = Sftf::<f64, 1>::new(&config, &channel);
        for &v in &x[..n + 10] {
            sftf.update(&config, v);
        }
        let model = sftf.model(&config);
        assert!(
            model.is_some_and(|m| m.a()[0].is_finite() && m.noise_variance() > 0.0),
            "no model 10 samples after the rescue at sample {n}"
        );
    }
}

/// At `lambda = 1` (`3/(1 - lambda)` is infinite) a rescue still leaves the last good model,
/// without any call to `model` before it (issue 23, item 2, the f32 `--lambda 1` case).
#[test]
fn at_lambda_one_a_rescue_leaves_the_last_good_model() {
    let x: Vec<f32> = ar([0.7, -0.2], 1.0, 10_000, 5)
        .iter()
        .map(|&v| v as f32)
        .collect();
    let config = Config::new(1.0f32, 0.01).unwrap();
    let channel = Channel::new(0.1).unwrap();
    let mut sftf = Sftf::<f32, 2>::new(&config, &channel);
    for &v in &x[..5_000] {
        sftf.update(&config, v);
    }
    // e^2 overflows f32: the filter is rescued.
    assert_eq!(sftf.update(&config, 3e30), None);
    for &v in &x[5_000..] {
        sftf.update(&config, v);
    }
    assert!(sftf.health().restarts >= 1);
    let model = sftf.model(&config).expect("a model after the rescue");
    assert!((model.a()[0] - 0.7).abs() < 0.1 && (model.a()[1] + 0.2).abs() < 0.1);
}
