//! Every recursive estimator fed arbitrary bytes as samples (each 4 bytes an `f32` bit
//! pattern, each 8 an `f64`: NaN, infinities, subnormals and extremes included): every error
//! returned is finite, every published model is finite, and the counters add up.
#![no_main]

use imu_ar::fixed_point::{FixedConfig, FixedLattice};
use imu_ar::recursive::{Config, Health, Lattice, Rls, RlsInit, Sftf};
use libfuzzer_sys::fuzz_target;

fn counted(h: Health, n: usize) {
    assert_eq!(h.samples + h.non_finite + h.saturated, n as u64, "{h:?}");
}

fuzz_target!(|data: &[u8]| {
    let Some((&head, data)) = data.split_first() else {
        return;
    };
    // The first byte picks the forgetting factor and whether the mean is removed.
    let lambda = [0.9f32, 0.99, 0.999, 1.0][usize::from(head & 3)];
    let demean = head & 4 != 0;
    let config = Config::new(lambda, 0.01, 0.01).unwrap().with_demean(demean);
    let f32s: Vec<f32> = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let mut lattice = Lattice::<f32, 4>::new(&config);
    let mut rls = Rls::<f32, 4>::new(&config, RlsInit::ShiftConsistent);
    let mut sftf = Sftf::<f32, 4>::new(&config);
    let fixed_config = FixedConfig::new(&config, 1.0).unwrap();
    let mut fixed = FixedLattice::<4>::new(&fixed_config);
    for &x in &f32s {
        if let Some(e) = lattice.update(&config, x) {
            assert!(e.is_finite());
        }
        if let Some(e) = rls.update(&config, x) {
            assert!(e.is_finite());
        }
        if let Some(e) = sftf.update(&config, x) {
            assert!(e.is_finite());
        }
        fixed.update(&fixed_config, x);
    }
    for m in [
        lattice.model(&config),
        rls.model(&config),
        sftf.model(&config),
    ]
    .into_iter()
    .flatten()
    {
        assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
    }
    if let Some(m) = fixed.model(&fixed_config) {
        assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
    }
    counted(lattice.health(), f32s.len());
    counted(rls.health(), f32s.len());
    counted(sftf.health(), f32s.len());
    counted(fixed.health(), f32s.len());

    let config = Config::new(f64::from(lambda), 0.01, 0.01)
        .unwrap()
        .with_demean(demean);
    let mut lattice = Lattice::<f64, 8>::new(&config);
    let mut sftf = Sftf::<f64, 8>::new(&config);
    let f64s: Vec<f64> = data
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    for &x in &f64s {
        if let Some(e) = lattice.update(&config, x) {
            assert!(e.is_finite());
        }
        if let Some(e) = sftf.update(&config, x) {
            assert!(e.is_finite());
        }
    }
    for m in [lattice.model(&config), sftf.model(&config)]
        .into_iter()
        .flatten()
    {
        assert!(m.a().iter().all(|a| a.is_finite()) && m.noise_variance().is_finite());
    }
    counted(lattice.health(), f64s.len());
    counted(sftf.health(), f64s.len());
});
