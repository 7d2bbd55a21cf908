//! The fixed-point lattice against the f64 direct solve of numerics.md section 0, on the
//! section-8 processes and on both real records as raw counts; and at the edges of its formats.
//! Prints the table that `tools/readme-tables.sh` puts into docs/estimators.md.

use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
use imu_ar_cli::input::csv::read_column;
use imu_ar_host::fixtures::{AXES, add, ar, real_records};
use imu_ar_host::reference::{Regularisation, Section0, running_mean_removed};

/// Max coefficient error of an order-`P` fixed lattice after `x` (scaled to unit RMS, no mean
/// removal) against the direct solve with the lattice's own rounded `lambda`.
fn fixed_error<const P: usize>(x: &[f64], lambda: f64) -> f64 {
    let rms = (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
    let delta = 0.1 * rms * rms;
    let config = Config::new(lambda as f32, 0.01).unwrap().with_demean(false);
    let channel = Channel::new(delta as f32).unwrap();
    let fixed = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, (1.0 / rms) as f32).unwrap();
    let mut lattice = FixedLattice::<P>::new(&fixed, &fixed_channel);
    let mut reference = Section0::new(P, fixed.lambda(), f64::from(delta as f32));
    for &v in x {
        reference.push(v);
        lattice.update(&fixed, v as f32).expect("sample accepted");
    }
    let h = lattice.health();
    assert_eq!((h.saturated, h.clipped, h.restarts), (0, 0, 0), "{h:?}");
    let (a_ref, _) = reference.solve(P, Regularisation::ShiftConsistent);
    let a = lattice.coefficients(P).unwrap();
    a.iter()
        .zip(&a_ref)
        .fold(0.0, |m, (a, b)| m.max((f64::from(*a) - b).abs()))
}

#[test]
fn section_8_processes_after_a_million_samples() {
    const N: usize = 1_000_000;
    let white = ar([0.0], 1.0, N, 20);
    let gm_white = add(&ar([0.999], 0.05, N, 21), &white);
    let sine: Vec<f64> = (0..N)
        .map(|n| (2.0 * std::f64::consts::PI * 0.1 * n as f64).sin())
        .collect();
    let gm_white_sine = add(&gm_white, &sine);
    let pw = ar([2.7607, -3.8106, 2.6535, -0.9238], 1.0, N, 22);
    let r = 0.89f64;
    let resonant = ar(
        [2.0 * r * std::f64::consts::FRAC_PI_4.cos(), -r * r],
        1.0,
        N,
        23,
    );
    let processes: [(&str, &[f64]); 4] = [
        ("GM(0.999) + white", &gm_white),
        ("Percival-Walden AR(4)", &pw),
        ("AR(2), poles 0.89", &resonant),
        ("GM + white + sinusoid", &gm_white_sine),
    ];
    println!("| process | lambda | p = 1 | p = 2 | p = 4 | p = 8 |");
    println!("|---|---|---|---|---|---|");
    for (name, x) in processes {
        for lambda in [0.99, 0.999, 0.9999] {
            let errors = [
                fixed_error::<1>(x, lambda),
                fixed_error::<2>(x, lambda),
                fixed_error::<4>(x, lambda),
                fixed_error::<8>(x, lambda),
            ];
            let cells: Vec<String> = errors.iter().map(|e| format!("{e:.1e}")).collect();
            println!("| {name} | {lambda} | {} |", cells.join(" | "));
            for (p, e) in [1, 2, 4, 8].iter().zip(errors) {
                assert!(e <= 1e-5, "{name}, lambda {lambda}, p = {p}: error {e:e}");
            }
        }
    }
}

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn real_records_as_raw_counts() {
    let records = real_records()
        .expect("the real records: ../shared/data/imu or IMU_AR_DATA (see docs/reliability.md)");
    println!(
        "| record | axis | counts per unit | lambda | fixed, p = 1..8 | median of 10 | clipped |"
    );
    println!("|---|---|---|---|---|---|---|");
    for record in &records {
        let name = record.name;
        for axis in AXES {
            let lsb = record.lsb(axis);
            let x = read_column(&record.files, axis).unwrap();
            let counts: Vec<i16> = x.iter().map(|v| (v / lsb).round() as i16).collect();
            let mean = x.iter().sum::<f64>() / x.len() as f64;
            let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / x.len() as f64;
            for lambda in [0.99, 0.999, 0.9999] {
                // delta = the record's variance: smaller values let the order-1 reflection
                // coefficient of the first few samples pass the +-4 of its format (the LS value
                // there is y_2 y_3 / (y_2^2 + delta)); that would be clipped and counted.
                let config = Config::new(lambda as f32, 0.01).unwrap();
                let channel = Channel::new(var as f32).unwrap();
                let fixed = FixedConfig::new(&config).unwrap();
                let fixed_channel = FixedChannel::for_counts(&channel, lsb as f32).unwrap();
                let mut lattice = FixedLattice::<8>::new(&fixed, &fixed_channel);
                let delta = f64::from(channel.delta());
                let mut reference = Section0::new(8, fixed.lambda(), delta);
                let exact: Vec<f64> = counts.iter().map(|&c| f64::from(c) * lsb).collect();
                // The largest error over orders 1..8, at the end and at the ends of the last
                // ten twentieths of the record: a single value of a noise (the rounding of the
                // errors, docs/fixed-point.md) moves with any change of the last bits; the
                // median of ten is steadier.
                let worst = |lattice: &FixedLattice<8>, reference: &Section0| {
                    let mut worst = 0.0f64;
                    for m in 1..=8 {
                        let (a_ref, _) = reference.solve(m, Regularisation::ShiftConsistent);
                        let a = lattice.coefficients(m).unwrap();
                        for k in 0..m {
                            worst = worst.max((f64::from(a[k]) - a_ref[k]).abs());
                        }
                    }
                    worst
                };
                let mut checkpoints = Vec::new();
                for (n, (&c, y)) in counts
                    .iter()
                    .zip(running_mean_removed(&exact, fixed.lambda()))
                    .enumerate()
                {
                    reference.push(y);
                    lattice
                        .update_counts(&fixed, c)
                        .expect("no reading at the rails");
                    if n + 1 > counts.len() / 2 && (n + 1) % (counts.len() / 20) == 0 {
                        checkpoints.push(worst(&lattice, &reference));
                    }
                }
                let h = lattice.health();
                assert_eq!((h.saturated, h.restarts), (0, 0), "{name} {axis}: {h:?}");
                let worst = worst(&lattice, &reference);
                assert_eq!(checkpoints.len(), 10, "{name} {axis}");
                checkpoints.sort_by(f64::total_cmp);
                let median = (checkpoints[4] + checkpoints[5]) / 2.0;
                println!(
                    "| {name} | {axis} | {:.0} | {lambda} | {worst:.1e} | {median:.1e} | {} |",
                    1.0 / lsb,
                    h.clipped
                );
                assert_eq!(
                    h.clipped, 0,
                    "{name} {axis} lambda {lambda}: internal saturation"
                );
                assert!(
                    worst <= 1e-3,
                    "{name} {axis} lambda {lambda}: error {worst:e}"
                );
            }
        }
    }
}

#[test]
fn full_scale_constant_and_alternating_inputs() {
    let config = Config::new(0.99f32, 0.01).unwrap();
    let channel = Channel::new(1.0).unwrap();
    let fixed = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::for_counts(&channel, 1.0).unwrap();
    // Readings at the rails are rejected and counted, never wrapped.
    let mut lattice = FixedLattice::<4>::new(&fixed, &fixed_channel);
    for c in [i16::MAX, i16::MIN, -32767] {
        assert_eq!(lattice.update_counts(&fixed, c), None);
    }
    assert_eq!(lattice.health().saturated, 3);
    // Constant input, then alternating full scale just inside the rails, then the top of the
    // range held: every output is in range, the model stays finite, saturations are counted.
    let inputs = (0..20_000)
        .map(|_| 12_345i16)
        .chain((0..20_000).map(|n| if n % 2 == 0 { 32_766 } else { -32_766 }))
        .chain((0..20_000).map(|_| 32_766));
    let mut clipped_after = [0; 3];
    for (n, c) in inputs.enumerate() {
        lattice.update_counts(&fixed, c).expect("inside the rails");
        clipped_after[n / 20_000] = lattice.health().clipped;
    }
    let h = lattice.health();
    assert_eq!((h.samples, h.saturated), (60_000, 3));
    // Alternating full scale drives errors past +-16 internal units: saturated, counted, and
    // the lattice restarts (holding its last good model) rather than publish that state.
    assert!(clipped_after[1] > clipped_after[0], "{clipped_after:?}");
    assert!(h.restarts > 0, "{h:?}");
    let model = lattice.model(&fixed).unwrap();
    assert!(
        model.a().iter().all(|a| a.is_finite() && a.abs() < 100.0),
        "{:?}",
        model.a()
    );
    assert!(model.noise_variance().is_finite());
    println!("after the edge cases: {h:?}, a = {:?}", model.a());
    // The float input: beyond +-16 internal units is saturated, NaN is non-finite.
    let fixed = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, 1.0).unwrap();
    let mut lattice = FixedLattice::<2>::new(&fixed, &fixed_channel);
    assert_eq!(lattice.update(&fixed, 16.0), None);
    assert_eq!(lattice.update(&fixed, -1e30), None);
    assert_eq!(lattice.update(&fixed, f32::NAN), None);
    assert!(lattice.update(&fixed, 15.9).is_some());
    let h = lattice.health();
    assert_eq!((h.saturated, h.non_finite, h.samples), (2, 1, 1));
}
