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

/// One real recording of `../shared/data/imu` (see its SOURCES.md).
pub struct Record {
    /// The sensor.
    pub name: &'static str,
    /// Its CSV files, read as one record.
    pub files: Vec<std::path::PathBuf>,
    /// Gyro units (deg/s) per count: the values are exact multiples of it.
    pub gyro_lsb: f64,
    /// Accelerometer units (g) per count.
    pub accel_lsb: f64,
}

impl Record {
    /// Units per count of `axis` (`gx`..`gz` or `ax`..`az`).
    pub fn lsb(&self, axis: &str) -> f64 {
        if axis.starts_with('g') {
            self.gyro_lsb
        } else {
            self.accel_lsb
        }
    }
}

/// The six axes of every record.
pub const AXES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

/// The folder of the real records, found at build time (`host-tests/build.rs`):
/// `../shared/data/imu` beside the repository, or the folder named by `IMU_AR_DATA`. `None`
/// (saying so) when it was absent; the tests that need it are then ignored through
/// `cfg(imu_ar_data)`.
pub fn data_dir() -> Option<std::path::PathBuf> {
    match option_env!("IMU_AR_DATA_DIR") {
        Some(dir) => Some(dir.into()),
        None => {
            println!("skipped: the real records were absent at build time");
            None
        }
    }
}

/// The ADIS16405 record (both parts) and the MPU-6050 record, or `None` without the data.
pub fn real_records() -> Option<[Record; 2]> {
    let dir = data_dir()?;
    Some([
        Record {
            name: "ADIS16405",
            files: vec![
                dir.join("adis16405_imu1_part1.csv"),
                dir.join("adis16405_imu1_part2.csv"),
            ],
            gyro_lsb: 0.05,
            accel_lsb: 0.00333,
        },
        Record {
            name: "MPU-6050",
            files: vec![dir.join("mpu6050_static_10min.csv")],
            gyro_lsb: 1.0 / 131.0,
            accel_lsb: 1.0 / 4096.0,
        },
    ])
}
