//! The fixed-point lattice against the f64 lattice on arbitrary in-range sequences (proptest),
//! and the inputs of issue 22 as regression tests: a large first sample must not ruin the
//! fixed-point running mean (or panic where overflow checks are on), nor pin the float one.
//!
//! Built in the test profile, which keeps overflow checks on (`Cargo.toml`, `[profile.dev]`):
//! an arithmetic overflow on the fixed-point path is a test failure here, not a silent wrap.
//! `PROPTEST_CASES` sets the number of cases (256 unless given).

use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
use imu_ar::recursive::{Lattice, Rls, Sftf};
use imu_ar_host::differential::differential;
use imu_ar_host::fixtures::ar;
use proptest::prelude::*;

/// The order of the differential property.
const P: usize = 3;
/// Samples stay strictly inside the fixed format's +-16 (at `scale = 1`).
const EDGE: f64 = 15.99;

fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(256)
}

/// One segment of a record: `n` samples around `level`, uniform noise of half-width `noise`.
#[derive(Clone, Debug)]
struct Segment {
    n: usize,
    level: f64,
    noise: f64,
}

/// An in-range record: a first sample anywhere in the range (its ends included), then segments
/// with steps in the level between them, and spikes anywhere in the range.
fn record() -> impl Strategy<Value = Vec<f64>> {
    let first = prop_oneof![
        1 => Just(EDGE),
        1 => Just(-EDGE),
        1 => Just(0.0),
        4 => -EDGE..EDGE,
    ];
    let segment = (
        1..400usize,
        -8.0..8.0f64,
        prop_oneof![
            1 => Just(0.0),
            1 => 1e-3..1e-2f64,
            4 => 1e-2..3.0f64,
        ],
    )
        .prop_map(|(n, level, noise)| Segment { n, level, noise });
    let spikes = prop_oneof![
        1 => prop::collection::vec((0..2000usize, -EDGE..EDGE), 0..4),
        2 => prop::collection::vec((0..2000usize, -8.0..8.0f64), 0..4),
    ];
    (
        first,
        prop::collection::vec(segment, 1..5),
        spikes,
        any::<u64>(),
    )
        .prop_map(|(first, segments, spikes, seed)| {
            let mut state = seed | 1;
            let mut uniform = move || {
                // xorshift64*: a fixed, cheap noise source inside the record.
                state ^= state >> 12;
                state ^= state << 25;
                state ^= state >> 27;
                let bits = state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11;
                bits as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
            };
            let mut x = vec![first];
            for s in &segments {
                x.extend((0..s.n).map(|_| s.level + s.noise * uniform()));
            }
            for (at, v) in spikes {
                let n = x.len();
                x[at % n] = v;
            }
            x.iter().map(|v| v.clamp(-EDGE, EDGE)).collect()
        })
}

fn lambda() -> impl Strategy<Value = f32> {
    prop_oneof![
        2 => Just(1.0f32),
        1 => Just(0.999),
        1 => Just(0.99),
        1 => Just(0.9),
        2 => 0.9..1.0f32,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(cases()))]

    /// Every in-range record gives the f64 lattice's model within `TOL`, or counted restarts
    /// with the last good model held: never a silently wrong model.
    #[test]
    fn fixed_lattice_matches_the_f64_lattice_or_restarts(
        x in record(),
        lambda in lambda(),
        demean in any::<bool>(),
    ) {
        differential::<P>(&x, lambda, demean).map_err(TestCaseError::fail)?;
    }
}

/// The 13 bytes the `estimators` fuzz target found (`lambda = 1`, mean removal, samples
/// `-11.999999`, `1.4e-37`, `-3.3e-33`): an overflow panic in the running mean's rounding.
#[test]
fn fuzz_input_with_a_large_first_sample() {
    let bytes = [
        0xff, 0xff, 0xff, 0x3f, 0xc1, 0xf9, 0xe1, 0x3f, 0x02, 0xff, 0x60, 0x89, 0x89,
    ];
    let x: Vec<f64> = bytes[1..]
        .chunks_exact(4)
        .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .collect();
    assert_eq!(x.len(), 3);
    assert!((x[0] + 11.999999).abs() < 1e-5, "{x:?}");
    // As the fuzz target runs it: order 4, `scale = 1`.
    let config = Config::new(1.0f32, 0.01).unwrap();
    let channel = Channel::new(0.01).unwrap();
    let fixed_config = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, 1.0).unwrap();
    let mut fixed = FixedLattice::<4>::new(&fixed_config, &fixed_channel);
    for &v in &x {
        assert!(fixed.update(&fixed_config, v as f32).is_some());
    }
    let h = fixed.health();
    assert_eq!((h.samples, h.clipped, h.restarts), (3, 0, 0), "{h:?}");
    let mean = f64::from(fixed.mean());
    // The weighted mean of the three samples at lambda = 1 - 2^-32: their plain mean.
    assert!((mean - (-11.999999 / 3.0)).abs() < 1e-6, "{mean}");
    // And through the differential property, at the order it uses.
    assert_eq!(differential::<P>(&x, 1.0, true), Ok(0));
}

/// The first CLI record of issue 22: `-7.9`, then 20,000 standard normal samples; order 2,
/// `lambda = 0.999`, the CLI's default scale `8 / max |x|`.
#[test]
fn cli_record_with_a_large_first_sample() {
    let mut x = vec![-7.9];
    x.extend(ar([0.0], 1.0, 20_000, 1));
    let max = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (fixed, float) = fit_both(&x, 0.999, 8.0 / max);
    close(fixed, float);
}

/// The second: `-12, 0, 0, 0.5`, then standard normal samples, `scale = 1`, `lambda = 1`.
#[test]
fn cli_record_at_lambda_1() {
    let mut x = vec![-12.0, 0.0, 0.0, 0.5];
    x.extend(ar([0.0], 1.0, 20_000, 2));
    let (fixed, float) = fit_both(&x, 1.0, 1.0);
    close(fixed, float);
}

/// The order-2 fixed and f64 lattice models (coefficients and mean) after `x`, as
/// `imu-ar fit --method lattice` makes them (mean removal on, `delta = 0.1 Var`).
fn fit_both(x: &[f64], lambda: f32, scale: f64) -> (([f32; 2], f32), ([f64; 2], f64)) {
    let config = Config::new(lambda, 0.01).unwrap();
    let channel = Channel::new(0.01).unwrap();
    let fixed_config = FixedConfig::new(&config).unwrap();
    let fixed_channel = FixedChannel::new(&channel, scale as f32).unwrap();
    let mut fixed = FixedLattice::<2>::new(&fixed_config, &fixed_channel);
    let float_config = Config::new(fixed_config.lambda(), 0.01).unwrap();
    let float_config_channel = Channel::new(f64::from(0.01f32)).unwrap();
    let mut float = Lattice::<f64, 2>::new(&float_config, &float_config_channel);
    for &v in x {
        assert!(fixed.update(&fixed_config, v as f32).is_some());
        float.update(&float_config, f64::from(v as f32));
    }
    let h = fixed.health();
    assert_eq!((h.clipped, h.restarts), (0, 0), "{h:?}");
    let m = fixed.model(&fixed_config).expect("a model");
    let r = float.model(&float_config).expect("a model");
    ((*m.a(), m.mean()), (*r.a(), r.mean()))
}

fn close((a, mean): ([f32; 2], f32), (a_ref, mean_ref): ([f64; 2], f64)) {
    println!("fixed a {a:?} mean {mean}; f64 a {a_ref:?} mean {mean_ref}");
    for (a, b) in a.iter().zip(&a_ref) {
        assert!((f64::from(*a) - b).abs() < 0.01, "{a} against {b}");
    }
    assert!(
        (f64::from(mean) - mean_ref).abs() < 0.01,
        "{mean} against {mean_ref}"
    );
}

/// Issue 22's float case: a first sample of `1e6`, then 50,000 samples of an AR(1) with
/// `a = 0.5` and unit noise, `lambda = 0.999`: the f32 lattice, RLS and SFTF within 0.01 of
/// the f64 lattice (and so of each other), once the start is forgotten.
#[test]
fn float_running_mean_forgets_a_large_first_sample() {
    let mut x = vec![1e6];
    x.extend(ar([0.5], 1.0, 50_000, 3));
    let c64 = Config::new(0.999f64, 0.01).unwrap();
    let c64_channel = Channel::new(0.01).unwrap();
    let c32 = Config::new(0.999f32, 0.01).unwrap();
    let c32_channel = Channel::new(0.01).unwrap();
    let mut reference = Lattice::<f64, 2>::new(&c64, &c64_channel);
    let mut lattice = Lattice::<f32, 2>::new(&c32, &c32_channel);
    let mut rls = Rls::<f32, 2>::new(&c32, &c32_channel);
    let mut sftf = Sftf::<f32, 2>::new(&c32, &c32_channel);
    for &v in &x {
        reference.update(&c64, v);
        lattice.update(&c32, v as f32);
        rls.update(&c32, v as f32);
        sftf.update(&c32, v as f32);
    }
    let r = reference.model(&c64).unwrap();
    println!("f64 a {:?} mean {}", r.a(), r.mean());
    assert!((r.a()[0] - 0.5).abs() < 0.05, "{:?}", r.a());
    for (name, m) in [
        ("lattice", lattice.model(&c32)),
        ("rls", rls.model(&c32)),
        ("sftf", sftf.model(&c32)),
    ] {
        let m = m.unwrap_or_else(|| panic!("{name}: no model"));
        println!("f32 {name} a {:?} mean {}", m.a(), m.mean());
        for (a, b) in m.a().iter().zip(r.a()) {
            assert!((f64::from(*a) - b).abs() < 0.01, "{name}: {a} against {b}");
        }
        assert!(
            (f64::from(m.mean()) - r.mean()).abs() < 0.01,
            "{name}: mean {} against {}",
            m.mean(),
            r.mean()
        );
    }
}
