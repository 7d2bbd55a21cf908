//! `N`'s interval on records whose short-term level moves: white noise whose level wanders
//! from one sixteenth of the record to the next (log-normal, 6 % standard deviation), as the
//! gyro of one ADIS16405 record does. Its intervals, which count the movement the record's
//! parts show ([`Octaves::with_parts`]), must cover the sensor's level (the root of the
//! average white variance over the wander); those of a stationary record must not move.

use imu_ar::noise::{DRIFT_OCTAVES, FitConfig, NoiseModel, Octaves};
use imu_ar::sim::StandardNormal;
use imu_ar_host::composite::Composite;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

const DT: f64 = 0.01;
const N: usize = 1 << 17;
const SEGMENTS: usize = 16;
const RECORDS: u64 = 40;
/// The standard deviation of the level's logarithm between segments.
const WANDER: f64 = 0.06;

fn white(level: f64, n: usize, seed: u64) -> Vec<f64> {
    Composite {
        dt: DT,
        white: level,
        quantization: 0.0,
        gm: Vec::new(),
        random_walk: 0.0,
    }
    .simulate(n, seed)
}

/// White noise of `N = 1`, each sixteenth at the level `exp(WANDER z)`.
fn wandering(seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
    let mut z = StandardNormal::new();
    (0..SEGMENTS)
        .flat_map(|s| {
            let level = (WANDER * z.sample(&mut rng)).exp();
            white(level, N / SEGMENTS, seed * 100 + s as u64)
        })
        .collect()
}

/// Whether `N`'s interval holds `truth`, with and without what the parts say.
fn covers(x: &[f64], truth: f64) -> (bool, bool) {
    let octaves = Octaves::<16>::overlapping(x, DT).unwrap();
    let config = FitConfig::new(2).with_identification(true);
    let with = |o: &Octaves<16>| {
        let model = NoiseModel::<8, 2>::identify(o, None, &config)
            .unwrap()
            .model;
        model.uncertainty(o).unwrap().white_noise.contains(truth)
    };
    (with(&octaves), with(&octaves.with_parts(&[])))
}

#[test]
fn a_stationary_record_shows_no_drift() {
    // Each octave is tested at 1 % over the eight together: about 1 record in 100 flagged.
    let flagged = (0..RECORDS)
        .filter(|&seed| {
            let octaves = Octaves::<16>::overlapping(&white(1.0, N, seed), DT).unwrap();
            (0..DRIFT_OCTAVES).any(|j| octaves.drift(j) > 0.0)
        })
        .count();
    println!("stationary records flagged: {flagged} of {RECORDS}");
    assert!(
        flagged <= 2,
        "{flagged} of {RECORDS} stationary records flagged"
    );
}

#[test]
fn intervals_of_n_cover_a_wandering_level() {
    // E[exp(2 WANDER z)] = exp(2 WANDER^2): the average white variance.
    let truth = (WANDER * WANDER).exp();
    let (mut with, mut without) = (0, 0);
    for seed in 0..RECORDS {
        let x = wandering(seed);
        let octaves = Octaves::<16>::overlapping(&x, DT).unwrap();
        assert!(
            octaves.drift(0) > 0.0,
            "seed {seed}: the wander is not seen"
        );
        let (a, b) = covers(&x, truth);
        with += usize::from(a);
        without += usize::from(b);
    }
    println!("N's interval covers the level: {with} of {RECORDS} ({without} without the parts)");
    assert!(with >= 34, "{with} of {RECORDS}");
    assert!(without <= 20, "{without} of {RECORDS}");
}
