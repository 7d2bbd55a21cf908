//! The soak: the real gyro records looped through the f32 lattice (p = 8, lambda = 0.999, the
//! innovation gate on at 6 sigma) with injected faults, then compared with the f64 direct solve
//! of the samples it took.
//!
//! `cargo test` runs 10^6 samples; `.ci/run` runs 10^8 with an optimised build:
//!
//! ```sh
//! IMU_AR_SOAK_SAMPLES=100000000 cargo test -p imu-ar-host --test host -- soak:: --nocapture
//! ```

use imu_ar::recursive::{Channel, Config, Estimator, Gate, Lattice};
use imu_ar_cli::input::csv::read_column;
use imu_ar_host::fixtures::real_records;
use imu_ar_host::reference::{Regularisation, Section0};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

const P: usize = 8;
const LAMBDA: f64 = 0.999;
/// Saturation limit of the soak's configuration, in deg/s (inside both sensors' ranges).
const LIMIT: f32 = 200.0;

/// What the fault injector did, to compare with the lattice's counters.
#[derive(Debug, Default, PartialEq)]
struct Injected {
    non_finite: u64,
    saturated: u64,
    spikes: u64,
    stuck_samples: u64,
}

#[test]
#[cfg_attr(
    not(imu_ar_data),
    ignore = "needs the real records (../shared/data/imu or IMU_AR_DATA)"
)]
fn soak_real_records_with_faults() {
    let records = real_records()
        .expect("the real records: ../shared/data/imu or IMU_AR_DATA (see docs/reliability.md)");
    let total: u64 = std::env::var("IMU_AR_SOAK_SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    // One pass: every gyro axis of both records, one after the other (level steps included).
    let mut base = Vec::new();
    for record in &records {
        for axis in ["gx", "gy", "gz"] {
            base.extend(read_column(&record.files, axis).unwrap());
        }
    }
    let delta = 0.01;
    let gate = Gate::new(6.0, 16).unwrap();
    let config = Config::new(LAMBDA as f32, 0.01).unwrap().with_gate(gate);
    let channel = Channel::new(delta as f32)
        .unwrap()
        .with_saturation(LIMIT)
        .unwrap();
    let mut lattice = Lattice::<f32, P>::new(&config, &channel);
    let mut reference = Section0::new(P, LAMBDA, delta);
    // The running mean the lattice removes, in f64 (`running_mean_removed`, streamed).
    let (mut mean, mut weight) = (None::<f64>, 0.0f64);
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let mut injected = Injected::default();
    let (mut fed, mut stuck, mut last) = (0u64, 0u64, 0.0f64);
    let mut source = base.iter().cycle();
    while fed < total {
        // Per sample: a stuck run (1 in 20,000, 100 to 5,000 samples long), a burst of NaN
        // or infinities (1 in 20,000), a sample beyond the limit (1 in 20,000), an accepted
        // spike of +-50 deg/s (1 in 20,000); otherwise the record.
        let x = if stuck > 0 {
            stuck -= 1;
            injected.stuck_samples += 1;
            last
        } else {
            let v = *source.next().unwrap();
            match rng.next_u32() % 20_000 {
                0 => {
                    stuck = 100 + u64::from(rng.next_u32() % 4_900);
                    v
                }
                1 => {
                    let burst = 1 + rng.next_u32() % 10;
                    for k in 0..burst {
                        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][k as usize % 3];
                        assert_eq!(lattice.update(&config, bad), None);
                    }
                    injected.non_finite += u64::from(burst);
                    fed += u64::from(burst);
                    v
                }
                2 => {
                    assert_eq!(lattice.update(&config, 1e4), None);
                    injected.saturated += 1;
                    fed += 1;
                    v
                }
                3 => {
                    injected.spikes += 1;
                    v + if rng.next_u32() % 2 == 0 { 50.0 } else { -50.0 }
                }
                _ => v,
            }
        };
        last = x;
        fed += 1;
        let outliers = lattice.health().outliers;
        let e = lattice.update(&config, x as f32);
        if e.is_none() {
            // Only the gate may refuse a finite sample inside the limit, and it counts it.
            assert_eq!(lattice.health().outliers, outliers + 1, "sample {fed}");
            continue;
        }
        assert!(e.is_some_and(f32::is_finite), "sample {fed}: {e:?}");
        let m = *mean.get_or_insert(f64::from(x as f32));
        let y = f64::from(x as f32) - m;
        weight = LAMBDA * weight + 1.0;
        mean = Some(m + y / weight);
        reference.push(y);
    }
    let h = lattice.health();
    println!("soak: {fed} samples, injected {injected:?}, lattice {h:?}");
    assert_eq!(h.restarts, 0, "no restart was provoked");
    assert_eq!(h.non_finite, injected.non_finite);
    assert_eq!(h.saturated, injected.saturated);
    assert_eq!(h.samples + h.rejected(), fed);
    // The +-50 deg/s spikes are outliers (unless the gate was open after a stuck run).
    assert!(h.outliers * 10 >= injected.spikes * 9, "{h:?} {injected:?}");
    let mut worst = 0.0f64;
    for m in 1..=P {
        let (a_ref, _) = reference.solve(m, Regularisation::ShiftConsistent);
        let a = lattice.coefficients(m).unwrap();
        for k in 0..m {
            worst = worst.max((f64::from(a[k]) - a_ref[k]).abs());
        }
    }
    println!("soak: max |a_f32 - a_f64| over orders 1..={P}: {worst:.2e}");
    assert!(worst <= 1e-4, "coefficient error {worst:e}");
    let model = lattice.model(&config).expect("a model");
    assert!(model.a().iter().all(|a| a.is_finite()));
}
