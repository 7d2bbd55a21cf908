//! The f32 recursive cores against the f64 direct solve of numerics.md section 0: the four
//! processes of section 8 and both real records. The test prints the table that
//! `tools/readme-tables.sh` puts into docs/estimators.md.

use imu_ar::recursive::{Channel, Config, Estimator, Lattice, Rls, Sftf};
use imu_ar_cli::input::csv::read_column;
use imu_ar_host::fixtures::{AXES, add, ar, real_records};
use imu_ar_host::reference::{Regularisation, Section0, running_mean_removed};

/// Max |a_f32 - a_ref| after the whole record, over the listed orders of an order-`P` lattice
/// and for an order-`P` RLS and SFTF; `run` panics on a lattice or RLS restart or a non-finite
/// output. The SFTF's rescues are counted instead (its error is then not comparable).
struct Errors {
    lattice: f64,
    rls: f64,
    sftf: f64,
    sftf_rescues: u64,
}

fn run<const P: usize>(
    x: &[f64],
    lambda: f64,
    delta: f64,
    demean: bool,
    orders: &[usize],
) -> Errors {
    let config = Config::new(lambda as f32, 0.01)
        .unwrap()
        .with_demean(demean);
    let channel = Channel::new(delta as f32).unwrap();
    let mut lattice = Lattice::<f32, P>::new(&config, &channel);
    let mut rls = Rls::<f32, P>::new(&config, &channel);
    let mut sftf = Sftf::<f32, P>::new(&config, &channel);
    let y = if demean {
        running_mean_removed(x, lambda)
    } else {
        x.to_vec()
    };
    let mut reference = Section0::new(P, lambda, delta);
    for (&xn, &yn) in x.iter().zip(&y) {
        reference.push(yn);
        let e = lattice
            .update(&config, xn as f32)
            .expect("lattice accepted the sample");
        assert!(e.is_finite());
        let e = rls
            .update(&config, xn as f32)
            .expect("RLS accepted the sample");
        assert!(e.is_finite());
        if let Some(e) = sftf.update(&config, xn as f32) {
            assert!(e.is_finite());
        }
    }
    assert_eq!(lattice.health().restarts, 0, "lattice restarted");
    assert_eq!(rls.health().restarts, 0, "RLS restarted");
    let mut worst = Errors {
        lattice: 0.0,
        rls: 0.0,
        sftf: 0.0,
        sftf_rescues: sftf.health().restarts,
    };
    for &m in orders {
        let (a_ref, _) = reference.solve(m, Regularisation::ShiftConsistent);
        let a = lattice.coefficients(m).unwrap();
        for k in 0..m {
            assert!(a[k].is_finite());
            worst.lattice = worst.lattice.max((f64::from(a[k]) - a_ref[k]).abs());
        }
    }
    let (a_ref, _) = reference.solve(P, Regularisation::ShiftConsistent);
    for (a, b) in rls.coefficients().iter().zip(&a_ref) {
        worst.rls = worst.rls.max((f64::from(*a) - b).abs());
    }
    for (a, b) in sftf.coefficients().iter().zip(&a_ref) {
        worst.sftf = worst.sftf.max((f64::from(*a) - b).abs());
    }
    worst
}

#[test]
fn section_8_processes_after_two_million_samples() {
    const N: usize = 2_000_000;
    let white = ar([0.0], 1.0, N, 10);
    let gm = ar([0.999], 0.05, N, 11);
    let gm_white = add(&gm, &white);
    let sine: Vec<f64> = (0..N)
        .map(|n| (2.0 * std::f64::consts::PI * 0.1 * n as f64).sin())
        .collect();
    let gm_white_sine = add(&gm_white, &sine);
    let pw = ar([2.7607, -3.8106, 2.6535, -0.9238], 1.0, N, 12);
    // AR(2) with poles 0.89 exp(+-i pi/4).
    let r = 0.89f64;
    let resonant = ar(
        [2.0 * r * (std::f64::consts::FRAC_PI_4).cos(), -r * r],
        1.0,
        N,
        13,
    );
    println!("| process | p | lambda | lattice f32 | RLS f32 | SFTF f32 |");
    println!("|---|---|---|---|---|---|");
    for lambda in [0.99, 0.999, 0.9999] {
        let rows = [
            (
                "GM(0.999) + white",
                4,
                run::<4>(&gm_white, lambda, 0.1, false, &[4]),
            ),
            (
                "Percival-Walden AR(4)",
                4,
                run::<4>(&pw, lambda, 100.0, false, &[4]),
            ),
            (
                "AR(2), poles 0.89, fitted with p = 1",
                1,
                run::<1>(&resonant, lambda, 0.1, false, &[1]),
            ),
            (
                "GM + white + sinusoid",
                4,
                run::<4>(&gm_white_sine, lambda, 0.1, false, &[4]),
            ),
        ];
        for (name, p, e) in rows {
            let sftf = match e.sftf_rescues {
                0 => format!("{:.1e}", e.sftf),
                n => format!("{n} rescues"),
            };
            println!(
                "| {name} | {p} | {lambda} | {:.1e} | {:.1e} | {sftf} |",
                e.lattice, e.rls
            );
            // The SFTF under-fitting a resonance diverges (sftf.rs); elsewhere it holds.
            if p == 4 {
                assert_eq!(e.sftf_rescues, 0, "{name}, lambda {lambda}: SFTF rescued");
                assert!(
                    e.sftf <= 1e-3,
                    "{name}, lambda {lambda}: SFTF error {:e}",
                    e.sftf
                );
            }
            assert!(
                e.lattice <= 1e-4,
                "{name}, lambda {lambda}: lattice error {:e}",
                e.lattice
            );
            assert!(
                e.rls <= 1e-3,
                "{name}, lambda {lambda}: RLS error {:e}",
                e.rls
            );
        }
    }
}

/// An order-`P` f32 RLS over the whole record against the order-`P` solution of `reference`.
fn rls_error<const P: usize>(
    x: &[f64],
    (config, channel): (&Config<f32>, &Channel<f32>),
    reference: &Section0,
) -> f64 {
    let mut rls = Rls::<f32, P>::new(config, channel);
    for &v in x {
        let e = rls
            .update(config, v as f32)
            .expect("RLS accepted the sample");
        assert!(e.is_finite());
    }
    assert_eq!(rls.health().restarts, 0, "RLS p = {P} restarted");
    let (a_ref, _) = reference.solve(P, Regularisation::ShiftConsistent);
    rls.coefficients()
        .iter()
        .zip(&a_ref)
        .fold(0.0, |m, (a, b)| m.max((f64::from(*a) - b).abs()))
}

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn real_records_every_axis() {
    let records = real_records()
        .expect("the real records: ../shared/data/imu or IMU_AR_DATA (see docs/reliability.md)");
    println!("| record | axis | lambda | lattice f32, p = 1..8 | RLS f32, p = 1..8 |");
    println!("|---|---|---|---|---|");
    for record in &records {
        let name = record.name;
        for axis in AXES {
            let x = read_column(&record.files, axis).unwrap();
            let mean = x.iter().sum::<f64>() / x.len() as f64;
            let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / x.len() as f64;
            // delta = 0.1 x the record's variance (any 0.01..1 x works; it only shapes the start).
            let delta = 0.1 * var;
            for lambda in [0.99, 0.999, 0.9999] {
                let config = Config::new(lambda as f32, 0.01).unwrap();
                let channel = Channel::new(delta as f32).unwrap();
                let mut lattice = Lattice::<f32, 8>::new(&config, &channel);
                let mut reference = Section0::new(8, lambda, delta);
                for (&v, y) in x.iter().zip(running_mean_removed(&x, lambda)) {
                    reference.push(y);
                    let e = lattice
                        .update(&config, v as f32)
                        .expect("lattice accepted the sample");
                    assert!(e.is_finite(), "{name} {axis}: non-finite error");
                }
                assert_eq!(
                    lattice.health().restarts,
                    0,
                    "{name} {axis} lambda {lambda}: restart"
                );
                let mut lat = 0.0f64;
                for m in 1..=8 {
                    let (a_ref, _) = reference.solve(m, Regularisation::ShiftConsistent);
                    let a = lattice.coefficients(m).unwrap();
                    for k in 0..m {
                        lat = lat.max((f64::from(a[k]) - a_ref[k]).abs());
                    }
                }
                let rls = [
                    rls_error::<1>(&x, (&config, &channel), &reference),
                    rls_error::<2>(&x, (&config, &channel), &reference),
                    rls_error::<3>(&x, (&config, &channel), &reference),
                    rls_error::<4>(&x, (&config, &channel), &reference),
                    rls_error::<5>(&x, (&config, &channel), &reference),
                    rls_error::<6>(&x, (&config, &channel), &reference),
                    rls_error::<7>(&x, (&config, &channel), &reference),
                    rls_error::<8>(&x, (&config, &channel), &reference),
                ]
                .into_iter()
                .fold(0.0, f64::max);
                println!("| {name} | {axis} | {lambda} | {lat:.1e} | {rls:.1e} |");
                assert!(
                    lat <= 1e-3,
                    "{name} {axis} lambda {lambda}: lattice error {lat:e}"
                );
                assert!(
                    rls <= 1e-3,
                    "{name} {axis} lambda {lambda}: RLS error {rls:e}"
                );
            }
        }
    }
}
