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
    // The octaves are tested at 5 % over the eight together: about 1 record in 20 flagged.
    let flagged = (0..RECORDS)
        .filter(|&seed| {
            let octaves = Octaves::<16>::overlapping(&white(1.0, N, seed), DT).unwrap();
            (0..DRIFT_OCTAVES).any(|j| octaves.drift(j) > 0.0)
        })
        .count();
    println!("stationary records flagged: {flagged} of {RECORDS}");
    // At most three binomial standard deviations above 5 %.
    let expected = 0.05 * RECORDS as f64;
    let bound = expected + 3.0 * (expected * 0.95).sqrt();
    assert!(
        flagged as f64 <= bound,
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
    // At least 85 % with the parts; at most half without them.
    assert!(100 * with as u64 >= 85 * RECORDS, "{with} of {RECORDS}");
    assert!(2 * without as u64 <= RECORDS, "{without} of {RECORDS}");
}

#[test]
fn a_stuck_eighth_is_the_largest_move() {
    // An eighth of zero variance (a stuck sensor) was taken for an eighth not measured, and
    // N's interval, from the other seven, excluded the live level.
    let mut x = white(1.0, N, 3);
    x[3 * N / 8..4 * N / 8].iter_mut().for_each(|v| *v = 5.0);
    let octaves = Octaves::<16>::overlapping(&x, DT).unwrap();
    assert!(octaves.drift(0) > 0.0);
    let config = FitConfig::new(2).with_identification(true);
    let model = NoiseModel::<8, 2>::identify(&octaves, None, &config)
        .unwrap()
        .model;
    let n = model.uncertainty(&octaves).unwrap().white_noise;
    assert!(n.contains(1.0), "{n:?}");
}

#[test]
fn parts_near_the_largest_double_move_as_small_ones_do() {
    let drift = |big: f64| {
        let still = [big; DRIFT_OCTAVES];
        let moved = [1.7 * big; DRIFT_OCTAVES];
        let mut parts = [(1u64 << 20, &still[..]); 8];
        parts[5].1 = &moved[..];
        let octaves = Octaves::<16>::new(
            DT,
            &[1.0; 16],
            imu_ar::noise::Estimator::Overlapping { n: 1 << 23 },
        )
        .unwrap()
        .with_parts(&parts);
        (0..DRIFT_OCTAVES)
            .map(|j| octaves.drift(j))
            .collect::<Vec<_>>()
    };
    let small = drift(1.0);
    assert!(small.iter().all(|d| *d > 0.0), "{small:?}");
    let big = drift(1e308);
    for (a, b) in big.iter().zip(&small) {
        assert!((a - b).abs() <= 1e-12 * b, "{big:?} vs {small:?}");
    }
}

#[test]
fn a_warm_up_of_the_mean_is_no_move_of_the_level() {
    // The mean settles by 100 standard deviations of the noise with a 100 s time constant: a
    // rate ramp to the Allan variance (growing as tau^2) in the first eighth, which the test
    // at tau of a second took for a move of the white level (N's interval -22 %, +40 % on a
    // record whose white level never moved).
    let flagged = (0..RECORDS)
        .filter(|&seed| {
            let mut x = white(1.0, N, seed);
            for (i, v) in x.iter_mut().enumerate() {
                *v += 100.0 * (-(i as f64) * DT / 100.0).exp();
            }
            let octaves = Octaves::<16>::overlapping(&x, DT).unwrap();
            (0..DRIFT_OCTAVES).any(|j| octaves.drift(j) > 0.0)
        })
        .count();
    println!("warmed-up records flagged: {flagged} of {RECORDS}");
    // As often as stationary records are.
    let expected = 0.05 * RECORDS as f64;
    let bound = expected + 3.0 * (expected * 0.95).sqrt();
    assert!(flagged as f64 <= bound, "{flagged} of {RECORDS} flagged");
}
