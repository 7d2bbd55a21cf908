//! Batch estimators against the independent f64 reference and against the literature.

use imu_ar::allan::{AllanError, AllanStream, octave_avar, overlapping_avar};
use imu_ar::batch::{BatchConfig, BatchError, Fit, burg, covariance, yule_walker};
use imu_ar::sim::ArSimulator;
use imu_ar::{ArModel, Scalar};
use imu_ar_host::reference::covariance_ls;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

fn simulate<const P: usize>(a: [f64; P], variance: f64, n: usize, seed: u64) -> Vec<f64> {
    let model = ArModel::new(a, variance, 0.0, 0.01).unwrap();
    let mut sim = ArSimulator::new(model);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    sim.burn_in(&mut rng, 5_000);
    (0..n).map(|_| sim.next(&mut rng)).collect()
}

fn config() -> BatchConfig<f64> {
    BatchConfig::new(0.01).unwrap()
}

/// `max |a - a_ref| / max |a_ref|` and the relative variance error, for order `P`.
fn covariance_vs_reference<const P: usize>(x: &[f64]) -> (f64, f64) {
    let fit = covariance::<f64, P>(x, &config()).unwrap();
    let (a_ref, var_ref) = covariance_ls(x, P, true);
    let scale = a_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let err = fit
        .model
        .a()
        .iter()
        .zip(&a_ref)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let var_err = (fit.model.noise_variance() - var_ref).abs() / var_ref;
    (err / scale, var_err)
}

#[test]
fn covariance_method_equals_the_svd_least_squares_solve() {
    // A near-white AR(1), a well-damped AR(4) and a Gauss-Markov drift plus white noise.
    let gm: Vec<f64> = simulate([0.999], 1e-4, 20_000, 3)
        .iter()
        .zip(simulate([0.0], 1.0, 20_000, 4))
        .map(|(d, w)| d + 0.1 * w)
        .collect();
    let processes: [(&str, Vec<f64>); 3] = [
        ("AR(1) 0.3", simulate([0.3], 1.0, 20_000, 1)),
        (
            "AR(4) 1.2 -0.5 0.1 0.05",
            simulate([1.2, -0.5, 0.1, 0.05], 1.0, 20_000, 2),
        ),
        ("GM(0.999) + white", gm),
    ];
    for (name, x) in &processes {
        let results = [
            covariance_vs_reference::<1>(x),
            covariance_vs_reference::<2>(x),
            covariance_vs_reference::<3>(x),
            covariance_vs_reference::<4>(x),
            covariance_vs_reference::<5>(x),
            covariance_vs_reference::<6>(x),
            covariance_vs_reference::<7>(x),
            covariance_vs_reference::<8>(x),
        ];
        for (p, (a_err, var_err)) in results.iter().enumerate() {
            assert!(
                a_err < &1e-9,
                "{name}, p = {}: relative coefficient error {a_err:e}",
                p + 1
            );
            assert!(
                var_err < &1e-9,
                "{name}, p = {}: relative variance error {var_err:e}",
                p + 1
            );
        }
    }
}

#[test]
fn covariance_lower_order_variances_equal_fits_on_the_common_sample() {
    // Fit::variances[m-1] is the order-m LS residual variance on the sample n = P..N-1.
    let x = simulate([1.2, -0.5, 0.1, 0.05], 1.0, 5_000, 9);
    let fit = covariance::<f64, 6>(&x, &config()).unwrap();
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    for m in 1..=6 {
        // The order-m reference on the same rows: drop the first 6 - m samples of the record
        // but keep the full-sample mean by passing demeaned data.
        let y: Vec<f64> = x[6 - m..].iter().map(|v| v - mean).collect();
        let (_, var_ref) = covariance_ls(&y, m, false);
        let got = fit.innovation_variance(m).unwrap();
        assert!(
            (got - var_ref).abs() < 1e-9 * var_ref,
            "order {m}: {got} vs {var_ref}"
        );
    }
}

/// Percival & Walden AR(4) (numerics.md section 7 vector 4), 50 seeded realisations of
/// N = 1024: RMS error per coefficient.
type Estimator = fn(&[f64], &BatchConfig<f64>) -> Result<Fit<f64, 4>, BatchError>;

fn pw_rms_error(estimator: Estimator) -> ([f64; 4], [f64; 4]) {
    let truth = [2.7607, -3.8106, 2.6535, -0.9238];
    let mut sq = [0.0; 4];
    let mut bias = [0.0; 4];
    for seed in 0..50 {
        let x = simulate(truth, 1.0, 1024, 1000 + seed);
        let fit = estimator(&x, &config()).unwrap();
        for k in 0..4 {
            let e = fit.model.a()[k] - truth[k];
            sq[k] += e * e / 50.0;
            bias[k] += e / 50.0;
        }
    }
    (sq.map(f64::sqrt), bias)
}

#[test]
fn percival_walden_ar4_accuracy() {
    let (burg_rms, _) = pw_rms_error(burg::<f64, 4>);
    let (ls_rms, _) = pw_rms_error(covariance::<f64, 4>);
    let (yw_rms, yw_bias) = pw_rms_error(yule_walker::<f64, 4>);
    println!("RMS error per coefficient: burg {burg_rms:?}, ls {ls_rms:?}, yule-walker {yw_rms:?}");
    for k in 0..4 {
        assert!(
            burg_rms[k] <= 0.033,
            "burg a_{}: rms {}",
            k + 1,
            burg_rms[k]
        );
        assert!(ls_rms[k] <= 0.033, "ls a_{}: rms {}", k + 1, ls_rms[k]);
        // Yule-Walker's windowing bias near the unit circle (Tjostheim & Paulsen 1983):
        // an order of magnitude larger, and systematic (bias explains most of the error).
        assert!(
            yw_rms[k] > 10.0 * burg_rms[k],
            "yule-walker a_{}: rms {}",
            k + 1,
            yw_rms[k]
        );
        assert!(
            yw_bias[k].abs() > 0.8 * yw_rms[k],
            "yule-walker a_{}: bias {}",
            k + 1,
            yw_bias[k]
        );
    }
}

#[test]
fn bad_slices_are_typed_errors_never_panics() {
    let c = config();
    let nan = [1.0, 2.0, f64::NAN, 3.0, 4.0, 5.0];
    let constant = [2.5; 100];
    let cases: [(&str, &[f64]); 5] = [
        ("empty", &[]),
        ("short", &[1.0, 2.0]),
        ("nan", &nan),
        ("constant", &constant),
        ("infinite", &[1.0, f64::INFINITY, 0.0, 1.0, 2.0, 3.0]),
    ];
    for (name, x) in cases {
        let results = [
            ("ls", covariance::<f64, 2>(x, &c).err()),
            ("yule-walker", yule_walker::<f64, 2>(x, &c).err()),
            ("burg", burg::<f64, 2>(x, &c).err()),
        ];
        for (method, err) in results {
            let expected_kind = match name {
                "empty" | "short" => matches!(err, Some(BatchError::TooShort { .. })),
                "nan" => err == Some(BatchError::NonFinite { index: 2 }),
                "infinite" => err == Some(BatchError::NonFinite { index: 1 }),
                _ => matches!(
                    err,
                    Some(BatchError::ZeroVariance | BatchError::Singular { .. })
                ),
            };
            assert!(expected_kind, "{method} on {name}: {err:?}");
        }
    }
    // f32 input takes the same paths.
    assert_eq!(
        burg::<f32, 1>(&[f32::NAN, 1.0, 2.0], &BatchConfig::new(1.0).unwrap()).err(),
        Some(BatchError::NonFinite { index: 0 })
    );
    // An exactly periodic record has singular normal equations at order 3.
    let sine: Vec<f64> = (0..64).map(|n| (0.3 * n as f64).sin()).collect();
    assert!(matches!(
        covariance::<f64, 3>(&sine, &c.with_demean(false)),
        Err(BatchError::Singular { order: 3 })
    ));
    // Allan variance.
    assert_eq!(
        overlapping_avar::<f64>(&[], 1),
        Err(AllanError::TooShort {
            needed: 2,
            given: 0
        })
    );
    assert_eq!(
        overlapping_avar(&[1.0, 2.0], 0),
        Err(AllanError::ZeroAveraging)
    );
    assert_eq!(
        overlapping_avar(&nan, 1),
        Err(AllanError::NonFinite { index: 2 })
    );
    assert_eq!(overlapping_avar(&constant, 4), Ok(0.0));
    let mut out = [0.0; 8];
    assert_eq!(
        octave_avar(&[1.0f64], &mut out),
        Err(AllanError::TooShort {
            needed: 2,
            given: 1
        })
    );
}

#[test]
fn octave_and_streaming_allan_variance_agree_with_the_model() {
    // AR(1) phi = 0.9: the overlapping estimate over 400k samples is within a few percent of
    // the model's Allan variance; the streaming (non-overlapping) one within a wider band.
    let x = simulate([0.9], 1.0, 400_000, 11);
    let model = ArModel::new([0.9f64], 1.0, 0.0, 0.01).unwrap();
    let mut avar = [0.0; 8];
    assert_eq!(octave_avar(&x, &mut avar), Ok(8));
    let mut stream = AllanStream::<8>::new();
    for &v in &x {
        stream.push(v);
    }
    assert!(!stream.push(f64::NAN));
    assert_eq!((stream.samples(), stream.rejected()), (400_000, 1));
    for (j, est) in avar.iter().enumerate() {
        let truth = model.allan_variance(1 << j).unwrap();
        let streamed = stream.avar(j).unwrap();
        assert!(
            (est - truth).abs() < 0.03 * truth,
            "m = {}: {est} vs {truth}",
            1 << j
        );
        assert!(
            (streamed - truth).abs() < 0.06 * truth,
            "m = {}: stream {streamed} vs {truth}",
            1 << j
        );
    }
    let _ = Scalar::to_f64(avar[0]);
}

/// Issue 23 item 6: `[1, 2]` with the mean removed is `[-0.5, 0.5]`, which `a_1 = -1` fits
/// exactly (Burg's reflection is 1): zero residual degrees of freedom. Every estimator keeps
/// at least one: `2P + 1` samples for the covariance method, `P + 1` for Burg and Yule-Walker,
/// one more with mean removal.
#[test]
fn fits_keep_one_residual_degree_of_freedom() {
    let c = config();
    let raw = c.with_demean(false);
    let short = |needed, given| Some(BatchError::TooShort { needed, given });
    assert_eq!(covariance::<f64, 1>(&[1.0, 2.0], &c).err(), short(4, 2));
    assert_eq!(
        covariance::<f64, 1>(&[1.0, 2.0, 3.0], &c).err(),
        short(4, 3)
    );
    assert_eq!(burg::<f64, 1>(&[1.0, 2.0], &c).err(), short(3, 2));
    assert_eq!(yule_walker::<f64, 1>(&[1.0, 2.0], &c).err(), short(3, 2));
    assert_eq!(
        covariance::<f64, 2>(&[1.0, 2.0, 4.0, 3.0], &raw).err(),
        short(5, 4)
    );
    assert_eq!(burg::<f64, 2>(&[1.0, 2.0], &raw).err(), short(3, 2));
    // At the bound the residual is not zero.
    let ls = covariance::<f64, 1>(&[1.0, 2.0, 3.0, 5.0], &c).unwrap();
    assert!(ls.model.noise_variance() > 0.0);
    let b = burg::<f64, 1>(&[1.0, 2.0, 4.0], &c).unwrap();
    assert!(b.reflection.unwrap()[0].abs() < 1.0);
    assert!(b.model.noise_variance() > 0.0);
    let b = burg::<f64, 1>(&[1.0, 2.0], &raw).unwrap();
    assert!(b.model.noise_variance() > 0.0);
}

/// Issue 23 item 10: values around 1e160 square to infinity. That is an overflow, not "zero
/// variance" or "singular".
#[test]
fn overflowing_energy_is_its_own_error() {
    let x: Vec<f64> = (0..200).map(|n| 1e160 * (1.0 + (n % 7) as f64)).collect();
    let c = config();
    assert_eq!(
        covariance::<f64, 2>(&x, &c).err(),
        Some(BatchError::Overflow)
    );
    assert_eq!(burg::<f64, 2>(&x, &c).err(), Some(BatchError::Overflow));
    assert_eq!(
        yule_walker::<f64, 2>(&x, &c).err(),
        Some(BatchError::Overflow)
    );
    // Large but representable data still fit.
    let y: Vec<f64> = x.iter().map(|v| v * 1e-20).collect();
    assert!(burg::<f64, 2>(&y, &c).is_ok());
}
