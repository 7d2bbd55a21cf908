//! Every recursive estimator fed arbitrary bytes as samples (each 4 bytes an `f32` bit
//! pattern, each 8 an `f64`: NaN, infinities, subnormals and extremes included): every error
//! returned is finite, every published model is finite, and the counters add up.
#![no_main]

use imu_ar::Scalar;
use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
use imu_ar::recursive::{Lattice, Rls, Sftf};
use libfuzzer_sys::fuzz_target;

/// Every sample of `x` through `e`: finite errors, a finite model (if any), every sample
/// counted once.
fn run<T: Scalar, E: Estimator<T, P>, const P: usize>(mut e: E, config: &E::Config, x: &[T]) {
    for &v in x {
        if let Some(err) = e.update(config, v) {
            assert!(err.is_finite());
        }
    }
    if let Some(m) = e.model(config) {
        assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
    }
    let h = e.health();
    assert_eq!(h.samples + h.non_finite + h.saturated, x.len() as u64, "{h:?}");
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, data)) = data.split_first() else {
        return;
    };
    // The first byte picks the forgetting factor and whether the mean is removed.
    let lambda = [0.9f32, 0.99, 0.999, 1.0][usize::from(head & 3)];
    let demean = head & 4 != 0;
    let config = Config::new(lambda, 0.01).unwrap().with_demean(demean);
    let channel = Channel::new(0.01).unwrap();
    let f32s: Vec<f32> = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    run(Lattice::<f32, 4>::new(&config, &channel), &config, &f32s);
    run(Rls::<f32, 4>::new(&config, &channel), &config, &f32s);
    run(Sftf::<f32, 4>::new(&config, &channel), &config, &f32s);
    let fixed_config = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, 1.0).unwrap();
    let fixed = FixedLattice::<4>::new(&fixed_config, &fixed_channel);
    run(fixed, &fixed_config, &f32s);

    let config = Config::new(f64::from(lambda), 0.01)
        .unwrap()
        .with_demean(demean);
    let channel = Channel::new(0.01).unwrap();
    let f64s: Vec<f64> = data
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    run(Lattice::<f64, 8>::new(&config, &channel), &config, &f64s);
    run(Sftf::<f64, 8>::new(&config, &channel), &config, &f64s);
});
