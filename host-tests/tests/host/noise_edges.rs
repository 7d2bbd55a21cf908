//! The noise-model fit at its edges: the degrees of freedom of the check, a model far above
//! the data, magnitudes across the range of f64, exact curves, capacities, intervals and filter
//! steps that overflow.

use imu_ar::ArModel;
use imu_ar::noise::{Estimator, FitConfig, NoiseError, NoiseModel, NoiseType, Octaves, component};
use rand_core::SeedableRng;

/// `avar[j] = f(2^j)` for `j < l`.
fn curve(l: usize, f: impl Fn(u64) -> f64) -> Vec<f64> {
    (0..l).map(|j| f(1u64 << j)).collect()
}

/// White noise `N^2 = n2` and random walk `K^2 = k2` at `dt`.
fn white_and_walk(dt: f64, n2: f64, k2: f64) -> impl Fn(u64) -> f64 {
    move |m| n2 * component::white(dt, m) + k2 * component::random_walk(dt, m)
}

#[test]
fn overlapping_edf_follows_riley_table_5_at_m_1() {
    // NIST SP 1065, table 5, flicker frequency noise at m = 1: 2 (N - 2)^2 / (2.3 N - 4.9)
    // for N phase points (n + 1 for n frequency samples).
    let n = 1_000_000u64;
    let big = (n + 1) as f64;
    let want = 2.0 * (big - 2.0) * (big - 2.0) / (2.3 * big - 4.9);
    let got = Estimator::Overlapping { n }.edf(1, NoiseType::FlickerFrequency);
    assert!((got / want - 1.0).abs() < 1e-12, "{got} against {want}");
    // The same order as the other noise types there, not 1.
    let white = Estimator::Overlapping { n }.edf(1, NoiseType::WhiteFrequency);
    assert!(got > 0.5 * white, "{got} against white {white}");
}

#[test]
fn the_check_refuses_a_doubled_first_octave() {
    // A Gauss-Markov term with T = dt dominates the first octave; a model fitted to the true
    // curve must not pass against data whose deviation there is twice as large.
    let dt = 0.01;
    let truth = |m| component::gauss_markov(dt, dt, m) + 1e-6 * component::white(dt, m);
    let avar = curve(20, truth);
    let estimator = Estimator::Overlapping { n: 1 << 21 };
    let octaves = Octaves::<20>::new(dt, &avar, estimator).unwrap();
    let model = NoiseModel::<1, 3>::fit(&octaves, None, &FitConfig::new(3)).unwrap();
    assert!(model.check(&octaves).unwrap().holds());
    let mut doubled = avar.clone();
    doubled[0] *= 4.0;
    let doubled = Octaves::<20>::new(dt, &doubled, estimator).unwrap();
    let row = model.check(&doubled).unwrap().rows()[0];
    assert!(!row.agrees, "{row:?}");
    assert!(row.tolerance < 0.2, "{row:?}");
}

#[test]
fn a_model_far_above_the_data_fails_however_wide_the_tolerance() {
    // Few samples: the last octaves have tolerances above 1.
    let dt = 0.01;
    let avar = curve(6, white_and_walk(dt, 1e-4, 0.0));
    let octaves = Octaves::<6>::new(dt, &avar, Estimator::NonOverlapping { n: 80 }).unwrap();
    let model = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(0)).unwrap();
    let check = model.check(&octaves).unwrap();
    assert!(check.rows().iter().any(|r| r.tolerance >= 1.0));
    assert!(check.holds());
    // The same model against data 1000 times smaller in variance.
    let small: Vec<f64> = avar.iter().map(|v| v * 1e-6).collect();
    let small = Octaves::<6>::new(dt, &small, Estimator::NonOverlapping { n: 80 }).unwrap();
    let check = model.check(&small).unwrap();
    assert!(check.rows().iter().all(|r| !r.agrees), "{:?}", check.rows());
}

#[test]
fn the_fit_scales_with_the_data_across_the_range_of_f64() {
    let dt = 0.01;
    // A random walk that the curve shows over its last octaves (at 1e-8 it would show in the
    // last alone, and an identified fit leaves it out).
    let base = curve(20, |m| {
        1e-4 * component::white(dt, m)
            + 1e-7 * component::random_walk(dt, m)
            + 1e-2 * component::gauss_markov(dt, 2.0, m)
    });
    let fit = |scale: f64| {
        let avar: Vec<f64> = base.iter().map(|v| v * scale).collect();
        let octaves = Octaves::<20>::new(dt, &avar, Estimator::Overlapping { n: 1 << 21 }).unwrap();
        let model = NoiseModel::<1, 3>::fit(&octaves, None, &FitConfig::new(3)).unwrap();
        // The whole curve at 95 %: the random walk shows in the last octave alone.
        assert!(
            model.check_whole(&octaves).unwrap().holds(),
            "scale {scale:e}"
        );
        (
            model.white_noise(),
            model.random_walk(),
            model.gauss_markov().len(),
        )
    };
    let reference = fit(1.0);
    for scale in [1e-300, 1e-200, 1e-80, 1e-30, 1e30, 1e80, 1e200, 1e290] {
        let (n, k, terms) = fit(scale);
        let root = scale.sqrt();
        assert!(
            (n / root / reference.0 - 1.0).abs() < 1e-9,
            "scale {scale:e}: N {n:e}"
        );
        assert!(
            (k / root / reference.1 - 1.0).abs() < 1e-9,
            "scale {scale:e}: K {k:e}"
        );
        assert_eq!(terms, reference.2, "scale {scale:e}");
    }
}

#[test]
fn a_parameter_beyond_f64_is_a_typed_error() {
    let big = [f64::MAX, f64::MAX];
    let octaves = Octaves::<2>::new(0.01, &big, Estimator::Overlapping { n: 4 }).unwrap();
    let got = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(1));
    // The curve fit that fills the budget needs a parameter beyond f64: a typed error. The
    // identified fit explains the two octaves with white noise alone, a finite model.
    let old = NoiseModel::<1, 1>::fit(
        &octaves,
        None,
        &FitConfig::new(1).with_identification(false),
    );
    assert!(matches!(old, Err(NoiseError::Overflow)), "{old:?}");
    match got {
        Err(NoiseError::Overflow) => {}
        Ok(model) => {
            let c = model.coefficients();
            assert!(
                [c.white, c.quantization, c.random_walk, c.ramp]
                    .iter()
                    .all(|v| v.is_finite()),
                "{model:?}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn exact_white_and_walk_curves_always_fit() {
    // 400 random mixtures over eight decades each: the NNLS must converge on noise-free data.
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for trial in 0..400 {
        let n2 = 10f64.powf(-8.0 + 8.0 * uniform());
        let k2 = 10f64.powf(-10.0 + 8.0 * uniform());
        let avar = curve(20, white_and_walk(0.01, n2, k2));
        let octaves =
            Octaves::<20>::new(0.01, &avar, Estimator::Overlapping { n: 1 << 21 }).unwrap();
        let model = NoiseModel::<1, 3>::fit(&octaves, None, &FitConfig::new(3))
            .unwrap_or_else(|e| panic!("trial {trial}: N^2 {n2:e} K^2 {k2:e}: {e}"));
        assert!(model.check(&octaves).unwrap().holds(), "trial {trial}");
        // Identified, judged as the identification judges it: the whole curve at 95 % (a
        // random walk seen in the last octave alone, one degree of freedom, is not identified).
        let config = FitConfig::new(3).with_identification(true);
        let model = NoiseModel::<1, 3>::fit(&octaves, None, &config)
            .unwrap_or_else(|e| panic!("trial {trial}: N^2 {n2:e} K^2 {k2:e}: {e}"));
        let check = model.check_whole(&octaves).unwrap();
        assert!(
            check.holds(),
            "trial {trial} identified: N^2 {n2:e} K^2 {k2:e}"
        );
    }
}

#[test]
fn a_capacity_too_small_for_the_columns_is_a_typed_error() {
    // L = 2 holds four columns: quantisation, white, random walk, ramp and an AR part are five.
    // The AR part is short-term colouring at the first octave (its Allan variance times `tau`
    // 0.96 of its white equivalent), so that the fit takes it.
    let ar = ArModel::new([0.02], 1.0, 0.0, 0.01).unwrap();
    let octaves = Octaves::<2>::new(0.01, &[1e-2, 5e-3], Estimator::Overlapping { n: 4 }).unwrap();
    let config = FitConfig::new(0).with_ramp(true);
    let got = NoiseModel::<1, 1>::fit(&octaves, Some(&ar), &config);
    assert_eq!(got.err(), Some(NoiseError::Capacity));
    // Without the ramp the four fit.
    assert!(NoiseModel::<1, 1>::fit(&octaves, Some(&ar), &FitConfig::new(0)).is_ok());
}

#[test]
fn intervals_whose_tau_squared_overflows_are_refused() {
    let avar = curve(20, white_and_walk(1.0, 1e-4, 1e-8));
    for dt in [1e-200, 1e200] {
        let octaves = Octaves::<20>::new(dt, &avar, Estimator::Overlapping { n: 1 << 21 }).unwrap();
        let got = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(1));
        assert_eq!(got.err(), Some(NoiseError::Interval), "dt {dt:e}");
    }
}

#[test]
fn a_filter_step_that_overflows_a_variance_is_refused() {
    let dt = 0.01;
    let avar = curve(20, |m| {
        1e-6 * component::quantization(dt, m) + 1e-4 * component::white(dt, m)
    });
    let octaves = Octaves::<20>::new(dt, &avar, Estimator::Overlapping { n: 1 << 21 }).unwrap();
    let model = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(1)).unwrap();
    assert!(model.quantization() > 0.0);
    assert_eq!(model.kalman(1e-300, 0.0).err(), Some(NoiseError::Interval));
    let form = model.kalman(0.01, 0.0).unwrap();
    assert!(form.measurement_variance.is_finite());
}

#[test]
fn the_one_second_reading_is_a_number_or_none() {
    // Zero Allan variance at the octaves around 1 s: no reading rather than NaN.
    let octaves =
        Octaves::<4>::new(1.0, &[2.0, 0.0, 0.0], Estimator::Overlapping { n: 16 }).unwrap();
    let model = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(1)).unwrap();
    let reading = model.ieee952(&octaves).white_noise_at_1s;
    assert!(reading.is_none_or(f64::is_finite), "{reading:?}");
}

#[test]
fn constant_short_and_non_finite_records_are_typed_errors() {
    let fit = |x: &[f64]| -> Result<NoiseModel<1, 2>, NoiseError> {
        let octaves = Octaves::<20>::overlapping(x, 0.01)?;
        NoiseModel::<1, 2>::fit(&octaves, None, &FitConfig::new(2))
    };
    assert_eq!(fit(&[1.5; 1000]).err(), Some(NoiseError::Constant));
    // Three samples: one octave (m = 1).
    assert_eq!(
        fit(&[1.0, 2.0, 4.0]).err(),
        Some(NoiseError::TooFewOctaves { given: 1 })
    );
    let mut x: Vec<f64> = (0..1000).map(|i| f64::from((i * 37) % 11)).collect();
    x[500] = f64::NAN;
    assert_eq!(fit(&x).err(), Some(NoiseError::NonFinite { index: 500 }));
    x[500] = f64::INFINITY;
    assert_eq!(fit(&x).err(), Some(NoiseError::NonFinite { index: 500 }));
    // A stream that rejected its non-finite samples has nothing to report for them: its
    // octaves are those of the finite ones.
    let mut stream = imu_ar::allan::AllanStream::<20>::new();
    for v in &x {
        stream.push(*v);
    }
    assert_eq!(stream.rejected(), 1);
    let octaves = Octaves::from_stream(&stream, 0.01).unwrap();
    assert!(NoiseModel::<1, 2>::fit(&octaves, None, &FitConfig::new(2)).is_ok());
    // A constant stream is a typed error too.
    let mut flat = imu_ar::allan::AllanStream::<20>::new();
    (0..1000).for_each(|_| {
        flat.push(2.0f32);
    });
    let octaves = Octaves::from_stream(&flat, 0.01).unwrap();
    let got = NoiseModel::<1, 2>::fit(&octaves, None, &FitConfig::new(2));
    assert_eq!(got.err(), Some(NoiseError::Constant));
}

#[test]
fn non_overlapping_degrees_of_freedom_match_a_monte_carlo_count() {
    // 4000 records of 201 white samples: 200 consecutive differences at m = 1. The estimate's
    // degrees of freedom, 2 mean^2 / variance, against 2 K^2 / (3 K - 1) = 133.6, not 200.
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut normal = imu_ar::sim::StandardNormal::new();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let estimates: Vec<f64> = (0..4000)
        .map(|_| {
            let mut stream = imu_ar::allan::AllanStream::<2>::new();
            for _ in 0..201 {
                seed = seed.wrapping_add(1);
                stream.push(normal.sample(&mut rng));
            }
            stream.avar(0).unwrap()
        })
        .collect();
    let mean = estimates.iter().sum::<f64>() / 4000.0;
    let var = estimates.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 3999.0;
    let measured = 2.0 * mean * mean / var;
    let claimed = Estimator::NonOverlapping { n: 201 }.edf(1, NoiseType::WhiteFrequency);
    assert!(
        (claimed - 2.0 * 200.0 * 200.0 / 599.0).abs() < 1e-9,
        "{claimed}"
    );
    // The Monte Carlo count has a relative standard error of about 5 % here.
    assert!(
        (measured / claimed - 1.0).abs() < 0.15,
        "{measured} against {claimed}"
    );
}

#[test]
fn octaves_beyond_what_the_samples_give_are_refused_and_never_agree() {
    let avar = curve(6, white_and_walk(0.01, 1e-4, 0.0));
    // Four samples give two octaves (m = 1 and 2).
    let got = Octaves::<6>::new(0.01, &avar, Estimator::Overlapping { n: 4 });
    assert_eq!(got.err(), Some(NoiseError::TooManyOctaves { capacity: 2 }));
    // Riley's formulas on tiny records stay within the differences there are.
    for (n, m) in [(2u64, 1u64), (3, 1), (4, 1), (4, 2)] {
        let nu = Estimator::Overlapping { n }.edf(m, NoiseType::RandomWalkFrequency);
        assert!(
            nu.is_finite() && nu <= (n - 2 * m + 1) as f64,
            "n {n} m {m}: {nu}"
        );
    }
}

#[test]
fn allan_variances_that_overflow_are_a_typed_error() {
    let x: Vec<f64> = (0..1000)
        .map(|i| 1e153 * f64::from((i * 37) % 11))
        .collect();
    let got = Octaves::<20>::overlapping(&x, 0.01);
    assert_eq!(got.err(), Some(NoiseError::Overflow));
}

#[test]
fn an_extreme_range_across_octaves_gives_no_silent_zero_model() {
    for dt in [1.0, 0.01, 1e-4] {
        let octaves = Octaves::<4>::new(
            dt,
            &[1.0, 1e-300, 1e-300, 1e-300],
            Estimator::Overlapping { n: 16 },
        )
        .unwrap();
        if let Ok(model) = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(1)) {
            let parameters = [
                model.quantization(),
                model.white_noise(),
                model.random_walk(),
                model.ramp(),
            ];
            let any = parameters.iter().any(|p| *p > 0.0) || !model.gauss_markov().is_empty();
            assert!(any, "dt {dt}: an all-zero model of non-zero data");
        }
    }
}

#[test]
fn k_intervals_cover_the_truth_where_the_record_shows_little_of_it() {
    // White noise and a random walk that rises over the last few octaves only: the identified
    // fit often leaves K out, and then its interval must still reach the truth (the room the
    // record leaves, not the information at zero alone).
    let truth = imu_ar_host::composite::Composite {
        dt: 0.01,
        white: 0.01,
        quantization: 0.0,
        gm: Vec::new(),
        random_walk: 1e-4,
    };
    let config = FitConfig::new(3).with_identification(true);
    let (mut covered, mut absent, runs) = (0, 0, 40);
    for seed in 0..runs {
        let x = truth.simulate(1 << 18, 5000 + seed);
        let octaves = Octaves::<24>::overlapping(&x, truth.dt).unwrap();
        let model = NoiseModel::<1, 3>::fit(&octaves, None, &config).unwrap();
        let u = model.uncertainty(&octaves).unwrap();
        covered += usize::from(u.random_walk.contains(truth.random_walk));
        absent += usize::from(model.random_walk() == 0.0);
    }
    println!("K interval covers {covered} of {runs}; K absent on {absent}");
    assert!(covered * 100 >= 85 * runs as usize, "{covered} of {runs}");
}

#[test]
fn the_bias_instability_interval_is_finite_with_one_degree_of_freedom() {
    // A stream of 16 samples: its last octave has one difference.
    let mut stream = imu_ar::allan::AllanStream::<8>::new();
    for i in 0..16u32 {
        stream.push(f64::from(i % 3) - 1.0 + 0.1 * f64::from(i % 5));
    }
    let octaves = Octaves::<8>::from_stream(&stream, 0.01).unwrap();
    let model = NoiseModel::<1, 1>::fit(&octaves, None, &FitConfig::new(1)).unwrap();
    let u = model.uncertainty(&octaves).unwrap();
    let b = model.ieee952(&octaves).bias_instability.0;
    let i = u.bias_instability;
    // chi^2 with one degree of freedom: its 2.5 % quantile is 9.8e-4, so at most about 32 B.
    assert!(
        i.low <= b && b <= i.high && i.high < 50.0 * b,
        "{i:?} B {b}"
    );
}

#[test]
fn the_identified_fit_keeps_a_random_walk_that_its_refinement_would_lose() {
    // White noise N = 0.01 and K = 5e-5 at 100 Hz, 2^19 samples (a record where reweighting
    // by the model talked K down to zero): the octaves rise 14-fold above white noise at the
    // end.
    let avar = [
        0.01000653908896288,
        0.00499464414607713,
        0.002510146887716419,
        0.0012532346834268873,
        0.0006230300275974956,
        0.0003148619986764805,
        0.00015346768259834185,
        7.680105461171744e-5,
        3.817220073374792e-5,
        2.0358616451068154e-5,
        1.022074424722609e-5,
        4.984327675528299e-6,
        2.6421002630611324e-6,
        1.1034266323256883e-6,
        5.53863145425887e-7,
        6.544419877436536e-7,
        1.1810137874700784e-6,
        3.3858489749510543e-6,
        7.897885142395927e-6,
    ];
    let octaves = Octaves::<24>::new(0.01, &avar, Estimator::Overlapping { n: 1 << 19 }).unwrap();
    let config = FitConfig::new(3).with_identification(true);
    let model = NoiseModel::<1, 3>::fit(&octaves, None, &config).unwrap();
    assert!(model.random_walk() > 0.0, "{model:?}");
    assert!(model.check_whole(&octaves).unwrap().holds(), "{model:?}");
}
