//! Seeded test records shared by the integration tests.

use imu_ar::ArModel;
use imu_ar::sim::ArSimulator;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

/// `n` samples of the AR process `a` with innovation sigma `sigma`, after 20,000 samples of
/// burn-in, from `ChaCha8Rng::seed_from_u64(seed)`.
pub fn ar<const P: usize>(a: [f64; P], sigma: f64, n: usize, seed: u64) -> Vec<f64> {
    let model = ArModel::new(a, sigma * sigma, 0.0, 0.01).expect("a valid model");
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    sim.burn_in(&mut rng, 20_000);
    (0..n).map(|_| sim.next(&mut rng)).collect()
}

/// The element-wise sum of two records.
pub fn add(x: &[f64], y: &[f64]) -> Vec<f64> {
    x.iter().zip(y).map(|(a, b)| a + b).collect()
}
