//! Hostile inputs through the `Estimator` trait: `update` never panics nor returns NaN,
//! `model()` is a pure getter, and the held model does not depend on `model()` calls.

use imu_ar::recursive::{
    Channel, Config, ConfigError, Estimator, FixedChannel, FixedConfig, FixedLattice, Lattice, Rls,
    Sftf,
};

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

/// A stream of ordinary AR(2) samples with hostile ones mixed in.
fn hostile_f64(n: usize, big: f64) -> Vec<f64> {
    let mut seed = 7u64;
    let (mut x1, mut x2) = (0.0, 0.0);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let x = 0.6 * x1 - 0.2 * x2 + lcg(&mut seed);
        x2 = x1;
        x1 = x;
        let v = match i % 97 {
            13 => f64::NAN,
            29 => f64::INFINITY,
            31 => f64::NEG_INFINITY,
            47 => big,
            48 => -big,
            61 => 0.0,
            71 => f64::MIN_POSITIVE / 4.0, // subnormal
            _ => x,
        };
        out.push(v);
    }
    out
}

fn check_stream<T, E, const P: usize>(name: &str, mk: impl Fn() -> E, cfg: &E::Config, xs: &[T])
where
    T: imu_ar::Scalar + core::fmt::Debug + PartialEq,
    E: Estimator<T, P> + Clone,
{
    let mut asked = mk();
    let mut quiet = mk();
    for (i, &x) in xs.iter().enumerate() {
        let before = asked.model(cfg);
        let again = asked.model(cfg);
        assert_eq!(
            format!("{before:?}"),
            format!("{again:?}"),
            "{name}: model() not pure at {i}"
        );
        let e1 = asked.update(cfg, x);
        let e2 = quiet.update(cfg, x);
        if let Some(e) = e1 {
            assert!(
                !e.to_f64().is_nan(),
                "{name}: update returned NaN at sample {i} (x = {x:?})"
            );
        }
        assert_eq!(
            format!("{e1:?}"),
            format!("{e2:?}"),
            "{name}: update differs at {i}"
        );
        if let Some(m) = asked.model(cfg) {
            assert!(
                m.a().iter().all(|v| v.to_f64().is_finite()),
                "{name}: non-finite model at {i}"
            );
            assert!(
                m.noise_variance().to_f64().is_finite(),
                "{name}: non-finite variance at {i}"
            );
        }
        if let Some(v) = asked.noise_variance() {
            assert!(!v.to_f64().is_nan(), "{name}: NaN noise_variance at {i}");
        }
        assert!(!asked.mean().to_f64().is_nan(), "{name}: NaN mean at {i}");
    }
    assert_eq!(
        format!("{:?}", asked.model(cfg)),
        format!("{:?}", quiet.model(cfg)),
        "{name}: the model depends on whether model() was called"
    );
}

fn all_float<T>(lambda: T, delta: T, big: T, sat: Option<T>)
where
    T: imu_ar::Scalar + imu_ar::recursive::FloatArith + core::fmt::Debug + PartialEq,
{
    let xs: Vec<T> = hostile_f64(20_000, big.to_f64())
        .into_iter()
        .map(|v| {
            if v == big.to_f64() {
                big
            } else if v == -big.to_f64() {
                T::ZERO - big
            } else {
                T::from_f64(v)
            }
        })
        .collect();
    let config = Config::new(lambda, T::from_f64(0.01)).unwrap();
    let mut channel = Channel::new(delta).unwrap();
    if let Some(s) = sat {
        channel = channel.with_saturation(s).unwrap();
    }
    for demean in [true, false] {
        let cfg = config.with_demean(demean);
        check_stream::<T, _, 3>(
            "Lattice",
            || Lattice::<T, 3>::new(&cfg, &channel),
            &cfg,
            &xs,
        );
        check_stream::<T, _, 3>("Rls", || Rls::<T, 3>::new(&cfg, &channel), &cfg, &xs);
        check_stream::<T, _, 3>("Sftf", || Sftf::<T, 3>::new(&cfg, &channel), &cfg, &xs);
    }
}

#[test]
fn f32_huge_samples_never_nan() {
    all_float::<f32>(0.99, 0.01, f32::MAX, None);
}

#[test]
fn f32_large_samples_never_nan() {
    all_float::<f32>(0.99, 0.01, 1e20, None);
}

#[test]
fn f64_huge_samples_never_nan() {
    all_float::<f64>(0.99, 0.01, f64::MAX, None);
}

#[test]
fn f64_large_samples_never_nan() {
    all_float::<f64>(0.999, 0.01, 1e150, None);
}

#[test]
fn f32_lambda_one_never_nan() {
    all_float::<f32>(1.0, 1e-3, 1e30, None);
}

#[test]
fn f32_tiny_lambda_never_nan() {
    all_float::<f32>(1e-30, 0.01, 1e10, None);
}

#[test]
fn f32_saturated_never_nan() {
    all_float::<f32>(0.99, 0.01, f32::MAX, Some(10.0));
}

#[test]
fn fixed_huge_samples_never_nan() {
    let xs: Vec<f32> = hostile_f64(20_000, 1e30)
        .into_iter()
        .map(|v| v as f32)
        .collect();
    for demean in [true, false] {
        let config = Config::new(0.99f32, 0.01).unwrap().with_demean(demean);
        let fixed = FixedConfig::new(&config).unwrap();
        for scale in [0.5f32, 8.0, 1e-3] {
            let Ok(ch) = FixedChannel::new(&Channel::new(0.01).unwrap(), scale) else {
                continue;
            };
            check_stream::<f32, _, 3>(
                "FixedLattice",
                || FixedLattice::<3>::new(&fixed, &ch),
                &fixed,
                &xs,
            );
        }
    }
}

#[test]
fn constructors_refuse_hostile_values() {
    for bad in [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        -1.0,
        1.5,
    ] {
        assert_eq!(
            Config::new(bad, 0.01f32),
            Err(ConfigError::Lambda),
            "lambda {bad}"
        );
    }
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.0, -0.0, -1.0] {
        assert_eq!(
            Config::new(0.99f32, bad),
            Err(ConfigError::Interval),
            "dt {bad}"
        );
        assert_eq!(Channel::new(bad), Err(ConfigError::Delta), "delta {bad}");
    }
    assert_eq!(Channel::new(1e-45f32), Err(ConfigError::Delta));
    assert_eq!(Channel::new(5e-324f64), Err(ConfigError::Delta));
    let ch = Channel::new(0.01f32).unwrap();
    for bad in [f32::NAN, f32::NEG_INFINITY, 0.0, -0.0, -1.0] {
        assert_eq!(
            ch.with_saturation(bad),
            Err(ConfigError::Saturation),
            "limit {bad}"
        );
    }
    for bad in [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        -1.0,
        1e-45,
    ] {
        assert_eq!(
            FixedChannel::new(&ch, bad),
            Err(ConfigError::Scale),
            "scale {bad}"
        );
        assert_eq!(
            FixedChannel::for_counts(&ch, bad),
            Err(ConfigError::Scale),
            "lsb {bad}"
        );
    }
    assert_eq!(
        FixedConfig::new(&Config::new(0.5f32, 0.01).unwrap()),
        Err(ConfigError::FixedLambda)
    );
}

/// A subnormal or huge `dt` is accepted by `Config::new`; then every model must still be
/// made (a `dt` that `Config` accepts must be one `ArModel` accepts).
#[test]
fn extreme_dt_still_gives_a_model() {
    for dt in [1e-45f32, f32::MIN_POSITIVE, f32::MAX] {
        let config = Config::new(0.99f32, dt).unwrap();
        let ch = Channel::new(0.01f32).unwrap();
        let mut l = Lattice::<f32, 2>::new(&config, &ch);
        let mut seed = 3u64;
        for _ in 0..2000 {
            l.update(&config, lcg(&mut seed) as f32);
        }
        assert!(l.model(&config).is_some(), "dt {dt}: no model");
    }
}

fn ramp_streams() -> Vec<Vec<f64>> {
    let mut v = Vec::new();
    // growing magnitudes up to the edge of f64, alternating sign
    v.push(
        (0..700)
            .map(|k| {
                if k % 2 == 0 {
                    10f64.powi(k / 2)
                } else {
                    -(10f64.powi(k / 2))
                }
            })
            .collect(),
    );
    // constant huge
    v.push(vec![1e300; 3000]);
    // alternating huge
    v.push(
        (0..3000)
            .map(|k| if k % 2 == 0 { 1e300 } else { -1e300 })
            .collect(),
    );
    // tiny (subnormal) values
    v.push(
        (0..3000)
            .map(|k| if k % 3 == 0 { 5e-324 } else { -1e-310 })
            .collect(),
    );
    // a step from quiet to loud and back
    v.push(
        (0..6000)
            .map(|k| {
                if (2000..4000).contains(&k) {
                    1e200 * ((k % 7) as f64 - 3.0)
                } else {
                    (k % 5) as f64 - 2.0
                }
            })
            .collect(),
    );
    v
}

fn ramps<T>(lambda: T, delta: T)
where
    T: imu_ar::Scalar + imu_ar::recursive::FloatArith + core::fmt::Debug + PartialEq,
{
    for (k, s) in ramp_streams().into_iter().enumerate() {
        let xs: Vec<T> = s
            .into_iter()
            .map(|v| {
                let t = T::from_f64(v);
                if t.to_f64().is_finite() {
                    t
                } else if v > 0.0 {
                    T::from_f64(3.0e38)
                } else {
                    T::from_f64(-3.0e38)
                }
            })
            .collect();
        let config = Config::new(lambda, T::from_f64(0.01)).unwrap();
        let channel = Channel::new(delta).unwrap();
        for demean in [true, false] {
            let cfg = config.with_demean(demean);
            let tag = format!("stream {k} demean {demean}");
            check_stream::<T, _, 1>(
                &format!("Lattice1 {tag}"),
                || Lattice::<T, 1>::new(&cfg, &channel),
                &cfg,
                &xs,
            );
            check_stream::<T, _, 1>(
                &format!("Rls1 {tag}"),
                || Rls::<T, 1>::new(&cfg, &channel),
                &cfg,
                &xs,
            );
            check_stream::<T, _, 1>(
                &format!("Sftf1 {tag}"),
                || Sftf::<T, 1>::new(&cfg, &channel),
                &cfg,
                &xs,
            );
            check_stream::<T, _, 8>(
                &format!("Lattice8 {tag}"),
                || Lattice::<T, 8>::new(&cfg, &channel),
                &cfg,
                &xs,
            );
            check_stream::<T, _, 8>(
                &format!("Rls8 {tag}"),
                || Rls::<T, 8>::new(&cfg, &channel),
                &cfg,
                &xs,
            );
            check_stream::<T, _, 8>(
                &format!("Sftf8 {tag}"),
                || Sftf::<T, 8>::new(&cfg, &channel),
                &cfg,
                &xs,
            );
        }
    }
}

#[test]
fn f64_extreme_ramps_never_nan() {
    ramps::<f64>(0.99, 1.0);
    ramps::<f64>(1.0, 1e-200);
}

#[test]
fn f32_extreme_ramps_never_nan() {
    ramps::<f32>(0.99, 1.0);
    ramps::<f32>(1.0, 1e-30);
    ramps::<f32>(0.5, 1e30);
}

#[test]
fn fixed_extreme_ramps_never_nan() {
    for (k, s) in ramp_streams().into_iter().enumerate() {
        let xs: Vec<f32> = s
            .into_iter()
            .map(|v| (v as f32).clamp(f32::MIN, f32::MAX))
            .collect();
        for lambda in [0.9f32, 1.0] {
            let config = Config::new(lambda, 0.01).unwrap();
            let fixed = FixedConfig::new(&config).unwrap();
            let ch = FixedChannel::new(&Channel::new(0.01).unwrap(), 1.0).unwrap();
            check_stream::<f32, _, 4>(
                &format!("Fixed {k} {lambda}"),
                || FixedLattice::<4>::new(&fixed, &ch),
                &fixed,
                &xs,
            );
        }
    }
}
